#include "tools/sigma0.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/units.hpp"
#include "plot/charts.hpp"
#include "radar/clutter/terrain.hpp"
#include "radar/constants.hpp"
#include "tools/rcs.hpp"

namespace radar_emu::tools {

using common::Polarisation;

using plot::Figure;
using plot::Heatmap;
using plot::LineChart;
using plot::Series;
using plot::series_colour;
using plot::write_line_chart_png;

namespace {

namespace cl = radar::clutter;

double sigma_of(const cl::Sigma0& s, Polarisation p) {
  switch (p) {
    case Polarisation::kHH:
      return s.hh;
    case Polarisation::kVV:
      return s.vv;
    case Polarisation::kHV:
      return s.hv;
    case Polarisation::kVH:
      return s.vh;
  }
  return 0.0;
}

int cl_pol(Polarisation p) {
  switch (p) {
    case Polarisation::kHH:
      return 0;
    case Polarisation::kVV:
      return 1;
    case Polarisation::kHV:
      return 2;
    case Polarisation::kVH:
      return 3;
  }
  return 1;
}

constexpr double kFloorDb = -300.0;  // written for "no power" (the model gives none)

double to_db(double linear) {
  return linear > 0.0 ? std::max(common::db_from_power(linear), kFloorDb) : kFloorDb;
}

cl::SurfaceSpec custom_surface(const Sigma0ToolOptions& o) {
  if (!o.eps_real || !o.eps_loss || !o.rms_height_m || !o.corr_length_m)
    throw std::invalid_argument(
        "give --material NAME, or all of --eps-r RE,IM --rms-height-m S --corr-length-m L");
  if (*o.eps_loss < 0.0)
    throw std::invalid_argument("--eps-r RE,IM: IM is the loss eps'' (eps = RE - j IM), >= 0");
  cl::SurfaceSpec s;
  s.surface.relative_permittivity = {*o.eps_real, -*o.eps_loss};
  s.surface.roughness.rms_height_m = *o.rms_height_m;
  s.surface.roughness.corr_length_m = *o.corr_length_m;
  s.surface.roughness.x_power = o.x_power;
  if (o.correlation == "gaussian")
    s.surface.roughness.correlation = cl::Correlation::kGaussian;
  else if (o.correlation == "exponential")
    s.surface.roughness.correlation = cl::Correlation::kExponential;
  else if (o.correlation == "xpower")
    s.surface.roughness.correlation = cl::Correlation::kXPower;
  else
    throw std::invalid_argument("--corr must be gaussian, exponential or xpower");
  cl::validate(s.surface, o.freq_hz);
  return s;
}

}  // namespace

int run_sigma0_tool(const Sigma0ToolOptions& o) {
  if (!(o.freq_hz > 0.0) || !std::isfinite(o.freq_hz))
    throw std::invalid_argument("--freq-hz must be a finite frequency > 0");
  const cl::Sigma0Model model = cl::parse_sigma0_model(o.model);
  const std::vector<Polarisation> pols = parse_pols(o.pols);
  for (double t : o.theta_deg)
    if (!(t >= 0.0 && t < 90.0))
      throw std::invalid_argument("--theta-deg: incidence angles must be in [0, 90) deg");
  for (double t : o.theta_s_deg)
    if (!(t >= 0.0 && t < 90.0))
      throw std::invalid_argument("--theta-s-deg: scattering angles must be in [0, 90) deg");
  if (!std::isfinite(o.phi_s_deg))
    throw std::invalid_argument("--phi-s-deg must be finite");

  cl::SurfaceSpec spec;
  std::string what;
  if (!o.material.empty()) {
    const cl::TerrainMaterial* m = cl::find_terrain_material(o.material);
    if (m == nullptr)
      throw std::invalid_argument("unknown material '" + o.material +
                                  "' (known: " + cl::terrain_material_names() + ")");
    if (o.eps_real || o.rms_height_m || o.corr_length_m)
      throw std::invalid_argument(
          "--material and a custom surface (--eps-r ...) exclude each other");
    spec = cl::resolve_surface(*m, o.freq_hz);
    if (spec.conductor)
      throw std::invalid_argument("material '" + o.material +
                                  "' is a perfect conductor: it reflects specularly and has no "
                                  "diffuse sigma0 (the SBR engine models it)");
    what = o.material;
  } else {
    spec = custom_surface(o);
    what = "custom surface";
  }
  const bool bistatic = !o.theta_s_deg.empty();
  if (model == cl::Sigma0Model::kEmpirical) {
    if (bistatic)
      throw std::invalid_argument("the empirical curves are backscatter only");
    if (spec.empirical == cl::EmpiricalClass::kNone)
      throw std::invalid_argument("no published empirical curve for " + what +
                                  " (Ulaby-Dobson classes here: soil, grass, crops, tall_grass, "
                                  "snow, snow_wet)");
    if (!cl::empirical_row(spec.empirical, o.freq_hz, 1))
      throw std::invalid_argument(
          "empirical: Ulaby-Dobson coefficients are available for L, S and C band (1-8 GHz) "
          "only; use --model total at --freq-hz " +
          [&] {
            char f[32];
            std::snprintf(f, sizeof f, "%g", o.freq_hz);
            return std::string(f);
          }());
  }
  if ((model == cl::Sigma0Model::kRt) && !spec.has_volume)
    throw std::invalid_argument("--model rt needs a material with a volume layer (" + what +
                                " has none)");

  struct Row {
    double theta, theta_s;
    cl::SurfaceScatter s;
  };
  std::vector<Row> rows;
  const std::vector<double> scatter = bistatic ? o.theta_s_deg : std::vector<double>{0.0};
  std::uint32_t seen = 0;
  for (double t : o.theta_deg) {
    for (double ts : scatter) {
      const cl::Geometry g = bistatic ? cl::Geometry{common::radians(t), common::radians(ts),
                                                     common::radians(o.phi_s_deg)}
                                      : cl::Geometry::backscatter(common::radians(t));
      Row r{t, ts, cl::evaluate_sigma0(spec, model, o.freq_hz, g)};
      if (model == cl::Sigma0Model::kTotal && !bistatic &&
          spec.curve != cl::CatalogueCurve::kNone) {
        // The catalogue's bits of the polarisations asked for only (evaluate_sigma0 ORs all four).
        r.s.invalid = 0;
        for (Polarisation p : pols)
          r.s.invalid |=
              cl::catalogue_sigma0(spec.curve, spec.sea_state, o.freq_hz,
                                   static_cast<cl::Sigma0Pol>(cl_pol(p)), common::radians(t))
                  .flags;
      }
      rows.push_back(r);
    }
  }
  bool cross_asked = false;
  for (Polarisation p : pols)
    cross_asked |= p == Polarisation::kHV || p == Polarisation::kVH;
  auto row_valid = [&](const Row& r) {
    std::uint32_t f = r.s.invalid;
    if (!cross_asked)
      f &= ~cl::kCrossPolNotModelled;
    return f;
  };

  FILE* f = std::fopen(o.out_csv.c_str(), "w");
  if (f == nullptr)
    throw std::runtime_error(o.out_csv + ": cannot open for writing");
  std::fprintf(f, "theta_deg");
  if (bistatic)
    std::fprintf(f, ",theta_s_deg,phi_s_deg");
  for (Polarisation p : pols)
    std::fprintf(f, ",sigma0_%s_db", std::string(common::polarisation_name(p)).c_str());
  std::fprintf(f, ",valid,flags\n");
  for (const Row& r : rows) {
    std::fprintf(f, "%.6g", r.theta);
    if (bistatic)
      std::fprintf(f, ",%.6g,%.6g", r.theta_s, o.phi_s_deg);
    for (Polarisation p : pols)
      std::fprintf(f, ",%.4f", to_db(sigma_of(r.s.incoherent, p)));
    const std::uint32_t flags = row_valid(r);
    seen |= flags;
    std::fprintf(f, ",%d,%u\n", flags == 0 ? 1 : 0, static_cast<unsigned>(flags));
  }
  const bool ok = std::fflush(f) == 0 && std::ferror(f) == 0;  // a full disk shows at flush
  if (std::fclose(f) != 0 || !ok)
    throw std::runtime_error(o.out_csv + ": write failed");

  const bool map = bistatic && o.theta_deg.size() > 1 && o.theta_s_deg.size() > 1;
  if (!o.plot_png.empty() && map) {
    // Two swept angles (incidence and scattering): a map per polarisation, one under the other;
    // invalid cells grey.
    std::vector<double> ti = o.theta_deg, ts = o.theta_s_deg;
    std::sort(ti.begin(), ti.end());
    std::sort(ts.begin(), ts.end());
    if (std::adjacent_find(ti.begin(), ti.end()) != ti.end() ||
        std::adjacent_find(ts.begin(), ts.end()) != ts.end())
      throw std::invalid_argument("--plot: the map needs distinct incidence and scattering angles");
    Figure fig;
    for (Polarisation p : pols) {
      Heatmap m;
      char title[200];
      std::snprintf(title, sizeof title,
                    "sigma0 %s of %s, %s model, %.4g GHz, phi_s %g deg (grey: outside validity)",
                    std::string(common::polarisation_name(p)).c_str(), what.c_str(),
                    cl::to_string(model), o.freq_hz * 1e-9, o.phi_s_deg);
      m.title = title;
      m.x_label = "scattering angle theta_s [deg]";
      m.y_label = "incidence angle theta_i [deg]";
      m.value_label = "sigma0 [dB]";
      m.equal_aspect = false;
      m.x = ts;
      m.y = ti;
      m.values.assign(ts.size() * ti.size(), std::nan(""));
      double peak = -400.0;
      for (const Row& r : rows) {
        const double y = to_db(sigma_of(r.s.incoherent, p));
        if (row_valid(r) != 0 || !(y > kFloorDb))
          continue;
        const auto i = static_cast<std::size_t>(std::lower_bound(ts.begin(), ts.end(), r.theta_s) -
                                                ts.begin());
        const auto j =
            static_cast<std::size_t>(std::lower_bound(ti.begin(), ti.end(), r.theta) - ti.begin());
        m.values[j * ts.size() + i] = y;
        peak = std::max(peak, y);
      }
      m.value_max = peak > -400.0 ? std::ceil(peak / 5.0) * 5.0 : 0.0;
      m.value_range = 60.0;
      fig.panels.emplace_back(std::move(m));
    }
    fig.width = 1000;  // panels one under the other
    fig.height = 560 * static_cast<int>(fig.panels.size());
    plot::write_figure(std::move(fig), o.plot_png);
  } else if (!o.plot_png.empty() && rows.size() > 1) {
    LineChart chart;
    char title[200];
    std::snprintf(title, sizeof title, "sigma0 of %s, %s model, %.4g GHz%s", what.c_str(),
                  cl::to_string(model), o.freq_hz * 1e-9, bistatic ? " (bistatic)" : "");
    chart.title = title;
    chart.x_label = bistatic ? "scattering angle theta_s [deg]" : "incidence angle [deg]";
    chart.y_label = "sigma0 [dB]";
    chart.y_min = -60.0;
    const double theta0 = rows.front().theta;
    // In backscatter HV = VH (reciprocity): one curve, labelled HV=VH, instead of two on top of
    // each other.
    const bool has_hv = std::find(pols.begin(), pols.end(), Polarisation::kHV) != pols.end();
    const bool has_vh = std::find(pols.begin(), pols.end(), Polarisation::kVH) != pols.end();
    const bool reciprocal = !bistatic && std::all_of(rows.begin(), rows.end(), [](const Row& r) {
      return r.s.incoherent.hv == r.s.incoherent.vh;
    });
    std::size_t colour_index = 0;
    for (Polarisation p : pols) {
      if (p == Polarisation::kVH && has_hv && reciprocal)
        continue;
      const std::string name = p == Polarisation::kHV && reciprocal && has_vh
                                   ? "HV=VH"
                                   : std::string(common::polarisation_name(p));
      Series inside, outside;
      inside.label = name;
      outside.label = name + " (invalid)";
      for (const Row& r : rows) {
        if (bistatic && r.theta != theta0)
          continue;  // one incidence angle per chart
        const double x = bistatic ? r.theta_s : r.theta;
        const double y = to_db(sigma_of(r.s.incoherent, p));
        const bool valid = row_valid(r) == 0 && y > kFloorDb;
        inside.x.push_back(x);
        inside.y.push_back(valid ? y : std::nan(""));
        outside.x.push_back(x);
        outside.y.push_back(!valid && y > kFloorDb ? y : std::nan(""));
      }
      // Outside the model's validity: the same colour, dashed.
      inside.colour = outside.colour = series_colour(colour_index++);
      outside.dashed = true;
      for (Series* series : {&inside, &outside}) {
        if (std::any_of(series->y.begin(), series->y.end(),
                        [](double y) { return std::isfinite(y); }))
          chart.series.push_back(std::move(*series));
      }
    }
    write_line_chart_png(chart, o.plot_png);
  }
  if (!o.quiet) {
    std::printf("%zu rows: %s, model %s, %.6g GHz, eps %.4g - j%.4g, s %.4g m, l %.4g m; wrote %s",
                rows.size(), what.c_str(), cl::to_string(model), o.freq_hz * 1e-9,
                spec.surface.relative_permittivity.real(),
                -spec.surface.relative_permittivity.imag(), spec.surface.roughness.rms_height_m,
                spec.surface.roughness.corr_length_m, o.out_csv.c_str());
    if (!o.plot_png.empty())
      std::printf(", %s", o.plot_png.c_str());
    std::printf("\n");
  }
  // A warning: on stderr whatever -q says (-q silences the summary only).
  if (seen != 0) {
    std::string reasons = cl::describe_validity(seen & ~cl::kEmpiricalOutside);
    if ((seen & cl::kEmpiricalOutside) != 0u)
      reasons += (reasons == "valid" ? std::string() : "; ") +
                 "empirical: no published row for some polarisations";
    std::fprintf(stderr, "radar-emu: warning: rows with valid=0 leave a model's domain: %s\n",
                 reasons.c_str());
  }
  return 0;
}

int run_catalogue_chart(const Sigma0ToolOptions& o) {
  std::vector<std::string> materials;
  {
    std::stringstream ss(o.chart_materials);
    std::string name;
    while (std::getline(ss, name, ','))
      if (!name.empty())
        materials.push_back(name);
  }
  if (materials.empty())
    throw std::invalid_argument("--chart-materials: give at least one material");
  for (const std::string& m : materials)
    (void)cl::terrain_material(m);  // unknown: one line naming the known ones
  struct Point {
    std::string material, pol;
    double freq_hz, theta_deg, db;
  };
  std::vector<Point> points;
  {
    std::ifstream in(o.points_csv);
    if (!in)
      throw std::runtime_error(o.points_csv + ": cannot open (--points)");
    std::string line;
    std::getline(in, line);
    int line_no = 1;
    while (std::getline(in, line)) {
      ++line_no;
      std::stringstream ss(line);
      std::string c[5];
      for (auto& x : c)
        std::getline(ss, x, ',');
      try {
        points.push_back({c[0], c[2], std::stod(c[1]), std::stod(c[3]), std::stod(c[4])});
      } catch (const std::exception&) {
        throw std::invalid_argument(o.points_csv + ":" + std::to_string(line_no) +
                                    ": expected material,freq_hz,pol,theta_deg,sigma0_db,...");
      }
    }
  }
  Figure fig;
  for (double f : {10e9, 35e9, 94e9}) {
    LineChart chart;
    char title[200];
    std::snprintf(title, sizeof title,
                  "sigma0 VV, catalogue (model total), %.0f GHz: dashed = assumed or "
                  "extrapolated; markers = published points",
                  f * 1e-9);
    chart.title = title;
    chart.x_label = "incidence angle [deg]";
    chart.y_label = "sigma0 [dB]";
    chart.y_min = -60.0;
    chart.y_max = 15.0;
    chart.x_min = 0.0;
    chart.x_max = 90.0;
    chart.legend_below = false;
    std::size_t colour = 0;
    for (const std::string& m : materials) {
      const cl::TerrainMaterial& mat = cl::terrain_material(m);
      Series inside, outside, pts;
      inside.label = m;
      inside.colour = outside.colour = pts.colour = series_colour(colour++);
      outside.dashed = true;
      pts.markers = true;
      pts.no_line = true;
      for (int i = 0; i <= 899; ++i) {
        const double th = i * 0.1;
        const cl::Sigma0Value v = cl::sigma0(mat, f, cl::Sigma0Pol::kVV, common::radians(th));
        const double y = to_db(v.linear);
        inside.x.push_back(th);
        outside.x.push_back(th);
        inside.y.push_back(v.flags == 0 ? y : std::nan(""));
        outside.y.push_back(v.flags != 0 ? y : std::nan(""));
      }
      if (std::none_of(inside.y.begin(), inside.y.end(), [](double y) { return std::isfinite(y); }))
        outside.label = m;  // the legend names the material even where all of it is flagged
      for (const Point& p : points) {
        if (p.material != m || p.pol != "VV" || std::abs(p.freq_hz - f) > 0.1 * f)
          continue;
        pts.x.push_back(p.theta_deg);
        pts.y.push_back(p.db);
        pts.x.push_back(p.theta_deg);
        pts.y.push_back(std::nan(""));
      }
      for (Series* series : {&inside, &outside, &pts}) {
        if (std::any_of(series->y.begin(), series->y.end(),
                        [](double y) { return std::isfinite(y); }))
          chart.series.push_back(std::move(*series));
      }
    }
    fig.panels.emplace_back(std::move(chart));
  }
  fig.width = 1000;  // one panel per frequency, one under the other
  fig.height = 1560;
  plot::write_figure(std::move(fig), o.catalogue_chart_png);
  if (!o.quiet)
    std::printf("catalogue chart of %s at 10, 35, 94 GHz with %s: wrote %s\n",
                o.chart_materials.c_str(), o.points_csv.c_str(), o.catalogue_chart_png.c_str());
  return 0;
}

}  // namespace radar_emu::tools
