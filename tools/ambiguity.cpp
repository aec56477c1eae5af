#include "tools/ambiguity.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "loop/scenario.hpp"
#include "plot/charts.hpp"
#include "radar/sensor/waveform.hpp"

namespace radar_emu::tools {

using loop::default_scenario_toml;
using loop::load_scenario;
using loop::parse_scenario;
using loop::Scenario;
using plot::FigureBatch;
using plot::Heatmap;
using plot::LineChart;
using plot::Series;
using plot::single;

namespace {

double to_db(double x) {
  return 20.0 * std::log10(std::max(x, 1e-12));
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream f(path);
  if (!(f << text))
    throw std::runtime_error(path.string() + ": cannot write");
}

}  // namespace

int run_ambiguity_tool(const AmbiguityToolOptions& o) {
  if (o.points < 11 || o.points > 2001)
    throw std::invalid_argument("--points must be in [11, 2001]");
  if (!(o.delay_span > 0.0 && o.delay_span <= 100.0) ||
      !(o.doppler_span > 0.0 && o.doppler_span <= 1000.0))
    throw std::invalid_argument("--delay-span and --doppler-span must be positive (and sane)");
  if (o.oversample < 2 || o.oversample > 64)
    throw std::invalid_argument("--oversample must be in [2, 64]");
  const Scenario s = o.scenario.empty()
                         ? parse_scenario(default_scenario_toml(), "<default scenario>")
                         : load_scenario(o.scenario);
  radar::Waveform w = s.sensor.processing.waveform;
  if (o.bandwidth_hz)
    w.bandwidth_hz = *o.bandwidth_hz;
  if (o.pulse_width_s)
    w.pulse_width_s = *o.pulse_width_s;
  if (o.prf_hz)
    w.pri_s = 1.0 / *o.prf_hz;
  if (o.pulses)
    w.pulses = *o.pulses;
  if (!(w.bandwidth_hz > 0 && w.pulse_width_s > 0 && w.pri_s > 0 && w.pulses >= 1) ||
      !std::isfinite(w.bandwidth_hz * w.pulse_width_s * w.pri_s))
    throw std::invalid_argument("bandwidth, pulse width, PRF and pulses must be positive");
  const double bt = w.bandwidth_hz * w.pulse_width_s;
  if (bt * o.oversample > 2e6)
    throw std::invalid_argument("B T = " + std::to_string(bt) + " is too long to integrate");
  if (o.train && w.pri_s < 2.0 * w.pulse_width_s)
    throw std::invalid_argument("--train needs PRI >= 2 T (the closed form's validity)");
  const double k = radar::chirp_rate_hz_per_s(w);
  const double t = w.pulse_width_s;
  const int n = o.points;
  const double delay_half = o.train ? 2.0 * w.pri_s : o.delay_span * t;
  const double doppler_extent = o.train ? o.doppler_span / w.pri_s : o.doppler_span / t;
  std::vector<double> delays(static_cast<std::size_t>(n)), dopplers(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double u = -1.0 + 2.0 * i / (n - 1);
    delays[static_cast<std::size_t>(i)] = u * delay_half;
    dopplers[static_cast<std::size_t>(i)] = u * doppler_extent;
  }
  std::vector<double> af(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
  // Single pulse: the numerical integral of the sampled envelope (rows in parallel); train: the
  // closed form (a numerical train of this length would take minutes).
  tbb::parallel_for(0, n, [&](int j) {
    const auto ju = static_cast<std::size_t>(j);
    std::span<double> row(af.data() + ju * static_cast<std::size_t>(n),
                          static_cast<std::size_t>(n));
    if (o.train) {
      for (std::size_t i = 0; i < delays.size(); ++i)
        row[i] = radar::lfm_train_ambiguity(delays[i], dopplers[ju], t, k, w.pri_s, w.pulses);
    } else {
      radar::ambiguity_numerical(w, delays, std::span(&dopplers[ju], 1), row, o.oversample);
    }
  });

  std::filesystem::create_directories(o.out_dir);
  {
    std::string csv = "delay_s,doppler_hz,magnitude,magnitude_db\n";
    char line[128];
    for (std::size_t j = 0; j < dopplers.size(); ++j)
      for (std::size_t i = 0; i < delays.size(); ++i) {
        const double v = af[j * delays.size() + i];
        std::snprintf(line, sizeof line, "%.9g,%.9g,%.8g,%.4f\n", delays[i], dopplers[j], v,
                      to_db(v));
        csv += line;
      }
    write_text(o.out_dir / "ambiguity.csv", csv);
  }
  // Fine cuts through the origin (the surface's grid is too coarse for the main lobe): zero
  // Doppler over +-8/B (or +-T/2 for the train), zero delay over +-8/T (or +-2 PRF).
  const std::size_t nc = o.train ? 4001 : 801;
  std::vector<double> cut_delays(nc), cut_dopplers(nc), cut_d(nc), cut_f(nc);
  for (std::size_t i = 0; i < nc; ++i) {
    const double u = -1.0 + 2.0 * static_cast<double>(i) / static_cast<double>(nc - 1);
    cut_delays[i] = u * (o.train ? 0.5 * t : 8.0 / w.bandwidth_hz);
    cut_dopplers[i] = u * (o.train ? 2.0 / w.pri_s : 8.0 / t);
  }
  const double zero = 0.0;
  if (o.train) {
    for (std::size_t i = 0; i < cut_d.size(); ++i) {
      cut_d[i] = radar::lfm_train_ambiguity(cut_delays[i], 0.0, t, k, w.pri_s, w.pulses);
      cut_f[i] = radar::lfm_train_ambiguity(0.0, cut_dopplers[i], t, k, w.pri_s, w.pulses);
    }
  } else {
    radar::ambiguity_numerical(w, cut_delays, std::span(&zero, 1), cut_d, o.oversample);
    radar::ambiguity_numerical(w, std::span(&zero, 1), cut_dopplers, cut_f, o.oversample);
  }
  auto first_null_and_half_width = [](const std::vector<double>& x, const std::vector<double>& y) {
    const std::size_t m = x.size() / 2;
    double half = 0.0, null = 0.0;
    for (std::size_t i = m; i + 1 < x.size(); ++i) {
      if (half == 0.0 && y[i + 1] < std::sqrt(0.5)) {  // -3 dB by linear interpolation
        const double f = (y[i] - std::sqrt(0.5)) / (y[i] - y[i + 1]);
        half = x[i] + f * (x[i + 1] - x[i]);
      }
      if (null == 0.0 && i > m && y[i + 1] > y[i]) {
        null = x[i];
        break;
      }
    }
    return std::pair{null, half};
  };
  const auto [first_null, half_width] = first_null_and_half_width(cut_delays, cut_d);
  const auto [doppler_null, doppler_half] = first_null_and_half_width(cut_dopplers, cut_f);
  double sxy = 0.0, sxx = 0.0;
  int ridge_rows = 0;
  for (std::size_t j = 0; j < dopplers.size(); ++j) {
    const double fd = dopplers[j];
    if (std::abs(fd) > 0.5 * w.bandwidth_hz || std::abs(fd / k) > 0.9 * delay_half || o.train)
      continue;
    const double* row = af.data() + j * delays.size();
    const auto ip = static_cast<std::size_t>(std::max_element(row, row + n) - row);
    sxy += fd * delays[ip];
    sxx += fd * fd;
    ++ridge_rows;
  }
  const double ridge_slope = sxx > 0.0 ? sxy / sxx : 0.0;  // delay per Hz of Doppler
  nlohmann::json summary = {
      {"waveform", radar::waveform_name(w.kind)},
      {"bandwidth_hz", w.bandwidth_hz},
      {"pulse_width_s", t},
      {"time_bandwidth", bt},
      {"pri_s", w.pri_s},
      {"pulses", w.pulses},
      {"train", o.train},
      {"grid",
       {{"delay_step_s", delays[1] - delays[0]}, {"doppler_step_hz", dopplers[1] - dopplers[0]}}},
      {"measured",
       {{"zero_doppler_first_null_s", first_null},
        {"zero_doppler_3db_halfwidth_s", half_width},
        {"zero_delay_first_null_hz", doppler_null},
        {"zero_delay_3db_halfwidth_hz", doppler_half},
        {"ridge_delay_per_doppler_s_per_hz", ridge_slope},
        {"ridge_rows", ridge_rows}}},
      {"theory",
       {{"first_null_s", 1.0 / w.bandwidth_hz},
        {"zero_delay_first_null_hz", o.train ? 1.0 / (w.pulses * w.pri_s) : 1.0 / t},
        {"range_resolution_m", radar::range_resolution_m(w)},
        {"ridge_delay_per_doppler_s_per_hz", -1.0 / k},
        {"doppler_ambiguity_hz", 1.0 / w.pri_s},
        {"source",
         "Richards, Fundamentals of Radar Signal Processing 2nd ed., eqs. 4.98, 4.105-4.106"}}}};
  write_text(o.out_dir / "summary.json", summary.dump(2) + "\n");

  Heatmap map;
  map.title = std::string(o.train ? "coherent train of " + std::to_string(w.pulses) + " " : "") +
              "LFM, B " + std::to_string(w.bandwidth_hz / 1e6).substr(0, 6) + " MHz, T " +
              std::to_string(t * 1e6).substr(0, 6) + " us: ambiguity function |chi|";
  map.x_label = "delay [us]";
  map.y_label = o.train ? "Doppler [kHz]" : "Doppler [MHz]";
  map.value_label = "|chi| [dB]";
  for (double d : delays)
    map.x.push_back(d * 1e6);
  for (double f : dopplers)
    map.y.push_back(o.train ? f * 1e-3 : f * 1e-6);
  for (double v : af)
    map.values.push_back(to_db(v));
  map.value_max = 0.0;
  map.value_range = o.dynamic_range_db;
  FigureBatch figures;  // both figures by one renderer
  figures.add(single(std::move(map)), o.out_dir / "ambiguity.png");

  // Cuts: computed vs the single-pulse closed form (train: the train's closed form itself).
  LineChart cuts;
  cuts.title = "cuts through the origin: computed and closed form (Richards eq. 4.98)";
  cuts.x_label = o.train ? "delay [us] | Doppler x PRI [1]" : "delay x B | Doppler x T [1]";
  cuts.y_label = "|chi| [dB]";
  cuts.y_min = -o.dynamic_range_db;
  cuts.y_max = 3.0;
  Series s_delay{"delay", {}, {}}, s_delay_cf{"delay, closed", {}, {}};
  Series s_dopp{"Doppler", {}, {}}, s_dopp_cf{"Doppler, closed", {}, {}};
  std::string cuts_csv = "axis,value,computed,closed_form\n";
  char line[128];
  const double x_scale = o.train ? 1e6 : w.bandwidth_hz;  // delay in us (train) or in 1/B
  const double f_scale = o.train ? w.pri_s : t;           // Doppler in PRFs or in 1/T
  for (std::size_t i = 0; i < cut_delays.size(); ++i) {
    const double cf = o.train ? cut_d[i] : radar::lfm_ambiguity(cut_delays[i], 0.0, t, k);
    s_delay.x.push_back(cut_delays[i] * x_scale);
    s_delay.y.push_back(to_db(cut_d[i]));
    s_delay_cf.x.push_back(cut_delays[i] * x_scale);
    s_delay_cf.y.push_back(to_db(cf));
    std::snprintf(line, sizeof line, "delay_s,%.9g,%.8g,%.8g\n", cut_delays[i], cut_d[i], cf);
    cuts_csv += line;
  }
  for (std::size_t j = 0; j < cut_dopplers.size(); ++j) {
    const double cf = o.train ? cut_f[j] : radar::lfm_ambiguity(0.0, cut_dopplers[j], t, k);
    s_dopp.x.push_back(cut_dopplers[j] * f_scale);
    s_dopp.y.push_back(to_db(cut_f[j]));
    s_dopp_cf.x.push_back(cut_dopplers[j] * f_scale);
    s_dopp_cf.y.push_back(to_db(cf));
    std::snprintf(line, sizeof line, "doppler_hz,%.9g,%.8g,%.8g\n", cut_dopplers[j], cut_f[j], cf);
    cuts_csv += line;
  }
  s_delay_cf.dashed = s_dopp_cf.dashed = true;
  cuts.series = {s_delay, s_delay_cf, s_dopp, s_dopp_cf};
  write_text(o.out_dir / "cuts.csv", cuts_csv);
  figures.add(single(std::move(cuts)), o.out_dir / "cuts.png");
  figures.write();

  if (!o.quiet) {
    std::printf(
        "ambiguity of %s LFM%s: B %.4g MHz, T %.4g us (B T %.0f); first null %.4g us (1/B %.4g "
        "us); ridge %.4g s/Hz (-1/k %.4g); wrote %s/{ambiguity.csv,ambiguity.png,cuts.csv,"
        "cuts.png,summary.json}\n",
        radar::waveform_name(w.kind), o.train ? " train" : "", w.bandwidth_hz / 1e6, t * 1e6, bt,
        first_null * 1e6, 1e6 / w.bandwidth_hz, ridge_slope, -1.0 / k, o.out_dir.c_str());
  }
  return 0;
}

}  // namespace radar_emu::tools
