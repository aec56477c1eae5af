#include "tools/atten.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "plot/charts.hpp"
#include "radar/constants.hpp"
#include "radar/propagation/itu.hpp"

namespace radar_emu::tools {

using plot::LineChart;
using plot::Series;
using plot::write_line_chart_png;

int run_atten_tool(const AttenToolOptions& o) {
  if (o.freqs_hz.empty())
    throw std::invalid_argument("give --freq-hz F or START:STOP:N");
  const radar::Atmosphere air{o.dry_pressure_hpa, o.temperature_c + 273.15, o.water_vapour_gm3};
  if (!(o.veg_depth_m >= 0.0) || !std::isfinite(o.veg_depth_m))
    throw std::invalid_argument("--veg-depth-m must be a finite depth >= 0");
  struct Row {
    double f, dry, vapour, rain_h, rain_v, fog, veg;
  };
  std::size_t veg_outside = 0;
  std::vector<Row> rows;
  rows.reserve(o.freqs_hz.size());
  for (double f : o.freqs_hz) {
    const radar::GasAttenuation g = radar::gaseous_specific_attenuation(f, air);
    Row r{f, g.dry_db_per_km, g.vapour_db_per_km, 0.0, 0.0, 0.0, std::nan("")};
    r.rain_h = radar::rain_specific_attenuation_db_per_km(f, o.rain_mm_per_h, 0.0, 0.0);
    r.rain_v = radar::rain_specific_attenuation_db_per_km(f, o.rain_mm_per_h, 0.0, radar::kPi / 2);
    if (o.fog_gm3 > 0.0 || f <= 200e9)
      r.fog = radar::cloud_fog_specific_attenuation_db_per_km(f, o.fog_gm3, air.temperature_k);
    if (f >= 1e9 && f <= 30e9) {
      r.veg = radar::woodland_excess_attenuation_db(
          radar::woodland_specific_attenuation_db_per_m(f, !o.out_of_leaf),
          radar::woodland_max_attenuation_db(f), o.veg_depth_m);
    } else {
      ++veg_outside;
    }
    rows.push_back(r);
  }
  FILE* f = std::fopen(o.out_csv.c_str(), "w");
  if (f == nullptr)
    throw std::runtime_error(o.out_csv + ": cannot open for writing");
  std::fprintf(
      f, "freq_hz,gas_dry_db_km,gas_vapour_db_km,rain_h_db_km,rain_v_db_km,fog_db_km,veg_db\n");
  for (const Row& r : rows) {
    std::fprintf(f, "%.10g,%.8g,%.8g,%.8g,%.8g,%.8g,", r.f, r.dry, r.vapour, r.rain_h, r.rain_v,
                 r.fog);
    if (std::isfinite(r.veg))
      std::fprintf(f, "%.8g", r.veg);
    std::fprintf(f, "\n");
  }
  const bool ok = std::fflush(f) == 0 && std::ferror(f) == 0;  // a full disk shows at flush
  if (std::fclose(f) != 0 || !ok)
    throw std::runtime_error(o.out_csv + ": write failed");
  if (!o.plot_png.empty() && rows.size() > 1) {
    LineChart chart;
    char title[160];
    std::snprintf(
        title, sizeof title, "%.0f hPa, %.1f C, %.2f g/m3 vapour, rain %.3g mm/h, fog %.3g g/m3",
        o.dry_pressure_hpa, o.temperature_c, o.water_vapour_gm3, o.rain_mm_per_h, o.fog_gm3);
    chart.title = title;
    chart.x_label = "frequency [GHz]";
    chart.y_label = "specific attenuation [dB/km]";
    chart.log_y = true;
    auto series = [&](const char* label, double Row::*field) {
      Series s;
      s.label = label;
      for (const Row& r : rows) {
        s.x.push_back(r.f * 1e-9);
        s.y.push_back(r.*field > 0.0 ? r.*field : std::nan(""));
      }
      if (!s.y.empty())
        chart.series.push_back(std::move(s));
    };
    series("dry air", &Row::dry);
    series("water vapour", &Row::vapour);
    if (o.rain_mm_per_h > 0.0) {
      series("rain H", &Row::rain_h);
      series("rain V", &Row::rain_v);
    }
    if (o.fog_gm3 > 0.0)
      series("fog", &Row::fog);
    write_line_chart_png(chart, o.plot_png);
  }
  if (!o.quiet) {
    std::printf("%zu frequencies: ITU-R P.676-13 (gases), P.838-3 (rain), P.840-9 (fog)",
                rows.size());
    if (o.veg_depth_m > 0.0) {
      std::printf(
          ", P.833-10 (%.0f m of woodland %s leaf: gamma from the Figure 2 curve, A_m from "
          "the Mulhouse fit, measured 0.9-2.2 GHz and extrapolated above",
          o.veg_depth_m, o.out_of_leaf ? "out of" : "in");
      if (veg_outside > 0)
        std::printf("; veg_db empty at %zu frequencies outside 1-30 GHz", veg_outside);
      std::printf(")");
    }
    std::printf("; wrote %s", o.out_csv.c_str());
    if (!o.plot_png.empty())
      std::printf(", %s", o.plot_png.c_str());
    std::printf("\n");
  }
  return 0;
}

}  // namespace radar_emu::tools
