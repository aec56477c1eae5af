#include "tools/image.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/units.hpp"
#include "config/memory_limit.hpp"
#include "config/output_paths.hpp"
#include "config/progress.hpp"
#include "loop/closed_loop.hpp"
#include "plot/charts.hpp"
#include "radar/constants.hpp"
#include "radar/products/sar_terrain.hpp"
#include "radar/propagation/path.hpp"
#include "scene/scene.hpp"

namespace radar_emu::tools {

using config::check_output_dir;
using loop::default_scenario_toml;
using loop::load_scenario;
using loop::parse_scenario;
using loop::Scenario;
using loop::scene_description;
using loop::scripted_pose;
using loop::WeatherSpec;
using plot::Figure;
using plot::Heatmap;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// [weather]: the one-way specific attenuation at the carrier, as the closed loop builds it
// (loop/closed_loop.cpp setup_weather: P.676 gases + P.838 rain at vertical polarisation +
// P.840 fog, radar/propagation/path.hpp).
double weather_db_per_m(const Scenario& s) {
  const WeatherSpec& w = s.weather;
  if (!w.enabled)
    return 0.0;
  radar::MediumSpec medium;
  medium.name = w.condition;
  medium.atmosphere = radar::Atmosphere{w.pressure_hpa, w.temperature_k, w.humidity_gm3};
  medium.rain_mm_per_h = w.rain_mm_per_h;
  medium.liquid_water_gm3 = w.fog_water_gm3;
  try {
    const radar::PathAttenuation path(s.sbr.carrier_hz, loop::rain_tilt_rad(s.sbr.polarisation),
                                      std::span(&medium, 1));
    return path.specific_db_per_m(0);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("scenario: [weather] at carrier_hz " +
                             std::to_string(s.sbr.carrier_hz) + ": " + e.what());
  }
}

// The reference ground plane: the first surface straight below the antenna that is not a
// target (targets are passed through), 0 when nothing is below.
double ground_height_below(const scene::Scene& scene, const radar::SbrTracer& tracer,
                           const glm::dvec3& p) {
  scene::Ray ray;
  ray.origin_m = p;
  ray.direction = {0.0, 0.0, -1.0};
  for (int k = 0; k < 16; ++k) {
    scene::Hit hit;
    if (!scene.intersect(ray, hit))
      return 0.0;
    if (!tracer.is_target(hit.object_id))
      return hit.position_m.z;
    ray.t_near_m = hit.t_m + 1e-3;
  }
  return 0.0;
}

double db(double v) {
  return v > 0.0 ? common::db_from_power(v) : -400.0;
}

// The radar image (grey, dB over 40 dB below the 99.5th percentile, like the seed's figure 5)
// and the optical preview side by side, both at equal scales in degrees (docs/plotting.md).
void write_png(const EvImageProduct& p, const std::filesystem::path& path) {
  const radar::EvImage& im = p.image;
  const int s = std::max(1, p.optical_scale);
  std::vector<float> sorted;
  for (float v : im.intensity_m2)
    if (v > 0.0f)
      sorted.push_back(v);
  std::sort(sorted.begin(), sorted.end());
  const double top_db =
      sorted.empty() ? 0.0 : db(static_cast<double>(sorted[(sorted.size() - 1) * 995 / 1000]));
  constexpr double kRangeDb = 40.0;
  const radar::EvImageConfig& g = p.config;
  const double az0 = common::degrees(g.azimuth_min_rad), el1 = common::degrees(g.elevation_max_rad);
  const double px_deg = common::degrees(g.pixel_rad);
  const auto rows = static_cast<std::size_t>(im.rows), cols = static_cast<std::size_t>(im.columns);
  // Cell centres, elevation ascending (row 0 of the image is the top).
  auto grid = [&](Heatmap& m, std::size_t nx, std::size_t ny, double step) {
    for (std::size_t x = 0; x < nx; ++x)
      m.x.push_back(az0 + (static_cast<double>(x) + 0.5) * step);
    for (std::size_t y = 0; y < ny; ++y)
      m.y.push_back(el1 - (static_cast<double>(ny - 1 - y) + 0.5) * step);
    m.x_label = "azimuth [deg]";
    m.y_label = "elevation [deg]";
    m.width = 1000;
    m.height = 400;
  };
  Heatmap radar_map;
  grid(radar_map, cols, rows, px_deg);
  char title[160];
  std::snprintf(title, sizeof title, "%.0f GHz radar, %d looks, %.0f dB range (top %.1f dBsm)",
                p.carrier_hz * 1e-9, p.config.looks, kRangeDb, top_db);
  radar_map.title = title;
  if (p.columns_done < im.columns) {
    radar_map.title += ", INCOMPLETE: " + std::to_string(p.columns_done) + " of " +
                       std::to_string(im.columns) + " columns";
  }
  radar_map.value_label = "pixel [dBsm]";
  radar_map.grey = true;
  radar_map.value_max = top_db;
  radar_map.value_range = kRangeDb;
  for (std::size_t y = 0; y < rows; ++y) {
    for (std::size_t x = 0; x < cols; ++x)
      radar_map.values.push_back(
          db(static_cast<double>(im.at(static_cast<int>(rows - 1 - y), static_cast<int>(x)))));
  }
  Figure fig;
  fig.width = 1000;
  fig.height = 400;
  fig.panels.emplace_back(std::move(radar_map));
  const auto w = static_cast<std::size_t>(im.columns * s),
             h = static_cast<std::size_t>(im.rows * s);
  if (p.optical.width_px == static_cast<int>(w) && p.optical.height_px == static_cast<int>(h)) {
    Heatmap optical;
    grid(optical, w, h, px_deg / s);
    optical.title = "optical preview, same view";
    optical.rgb.resize(w * h * 3);
    for (std::size_t y = 0; y < h; ++y)
      std::copy_n(p.optical.rgb.data() + (h - 1 - y) * w * 3, w * 3,
                  optical.rgb.data() + y * w * 3);
    fig.panels.emplace_back(std::move(optical));
    fig.columns = 2;
    fig.width = 2000;
  }
  plot::write_figure(std::move(fig), path);
}

// The strips of columns the image is formed in, and the estimate checked before any work.
struct StripPlan {
  int strip_columns = 8;
  double bytes = 0.0;    ///< peak memory [bytes]
  double seconds = 0.0;  ///< rough wall time on the reference machine
  std::string what;      ///< "200 x 66 pixels, 10 looks, 25 strips of 8 columns, ..."
};

// Rates measured on the 2-core reference machine with examples/ev_radar_94ghz.toml, 200 x 66
// pixels, 10 looks, optical scale 4: the trace (0.5 s, 300 k rays), forming per pixel and look
// (3.3 s for 132 k, the terrain engine's patches), the optical preview per optical pixel (0.1 s
// for 211 k). Rough: the forming scales with the terrain under the view, not only the pixels.
constexpr double kImageTraceS = 0.5;
constexpr double kImageFormSPerPixelLook = 2.5e-5;
constexpr double kImageOpticalSPerPixel = 5e-7;

StripPlan plan_strips(int columns, int rows, int looks, int optical_scale,
                      std::size_t max_contributions) {
  StripPlan plan;
  // Blocks of 8 columns (the terrain engine's parallel unit): three a thread so that the threads
  // stay busy to the strip's end, but no more than an eighth of the image (the progress and the
  // stop's granularity), and no less than a 25th.
  const auto threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int blocks = (columns + 7) / 8;
  plan.strip_columns =
      8 * std::max((blocks + 24) / 25, std::min(3 * threads, std::max(1, (blocks + 7) / 8)));
  const double cells = static_cast<double>(columns) * rows;
  const double strip_cells = static_cast<double>(std::min(plan.strip_columns, columns)) * rows;
  const double optical = static_cast<double>(optical_scale) * optical_scale * cells;
  // The contributions, the image (two float maps and the range edges), a strip's work (per
  // pixel and look two complex fields and a look power, plus the mean maps), the optical preview
  // (RGB and the renderer's per-pixel rays and hits).
  plan.bytes = static_cast<double>(max_contributions) * sizeof(radar::Contribution) + cells * 16.0 +
               strip_cells * (looks * 36.0 + 64.0) + optical * 32.0;
  plan.seconds =
      kImageTraceS + kImageFormSPerPixelLook * cells * looks + kImageOpticalSPerPixel * optical;
  const int strips = (columns + plan.strip_columns - 1) / plan.strip_columns;
  plan.what = std::to_string(columns) + " x " + std::to_string(rows) + " pixels, " +
              std::to_string(looks) + " looks, " + std::to_string(strips) + " strips of " +
              std::to_string(std::min(plan.strip_columns, columns)) + " columns, optical " +
              std::to_string(columns * optical_scale) + " x " +
              std::to_string(rows * optical_scale);
  return plan;
}

}  // namespace

EvImageProduct compute_ev_image(const Scenario& s, double time_s, int looks, std::uint64_t seed,
                                int optical_scale, const common::WorkControl& control) {
  if (!std::isfinite(time_s) || time_s < 0.0)
    throw std::runtime_error("--time-s: must be finite and >= 0");
  if (looks < 1 || looks > 1000)
    throw std::runtime_error("--looks: " + std::to_string(looks) + " is outside [1, 1000]");
  const auto t0 = std::chrono::steady_clock::now();
  EvImageProduct p;
  p.optical_scale = optical_scale;
  p.carrier_hz = s.sbr.carrier_hz;
  scene::Scene scene(scene_description(s));
  scene.set_time(time_s);
  radar::SbrTracer tracer(scene, s.sbr);

  p.pose = scripted_pose(s, time_s);

  radar::EvImageConfig& g = p.config;
  g.azimuth_min_rad = s.sbr.azimuth_min_rad;
  g.azimuth_max_rad = s.sbr.azimuth_max_rad;
  g.elevation_min_rad = s.sbr.elevation_min_rad;
  g.elevation_max_rad = s.sbr.elevation_max_rad;
  g.pixel_rad = s.beam_spacing_rad;  // one pixel per beam position; rows as tall (square)
  g.looks = looks;
  g.seed = seed;
  g.ground_height_m = ground_height_below(scene, tracer, p.pose.position_m);
  if (p.pose.position_m.z <= g.ground_height_m) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "--time-s: the ownship at t = %g s is at height %.1f m, not above the ground "
                  "below it (%.1f m)",
                  time_s, p.pose.position_m.z, g.ground_height_m);
    throw std::runtime_error(buf);
  }
  int columns = 0, rows = 0;
  try {
    columns = radar::ev_image_columns(g);
    rows = radar::ev_image_rows(g);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("scenario [antenna]: ") + e.what());
  }
  p.weather_one_way_db_per_m = weather_db_per_m(s);
  const StripPlan plan =
      plan_strips(columns, rows, looks, optical_scale, tracer.max_contributions());
  p.estimate_bytes = plan.bytes;
  if (const auto over = config::over_memory_limit(plan.bytes, plan.what)) {
    throw std::runtime_error("image: the EV image " + *over +
                             ": fewer --looks, a smaller --optical-scale, or a coarser "
                             "[antenna] azimuth_cell_deg");
  }
  control.tell_estimate(plan.what + ": memory about " + config::format_bytes(plan.bytes) +
                        ", about " + config::format_duration(plan.seconds) +
                        " (rough: scaled from examples/ev_radar_94ghz.toml on the "
                        "2-core reference machine)");

  auto t = std::chrono::steady_clock::now();
  std::vector<radar::Contribution> contributions(tracer.max_contributions());
  const std::size_t n = tracer.trace(p.pose, contributions, p.trace);
  contributions.resize(n);
  // [weather]: every return loses the two-way attenuation of its path (as in `run`).
  radar::apply_two_way_loss(contributions, p.weather_one_way_db_per_m);
  p.contributions = n;
  p.trace_s = seconds_since(t);

  // Terrain: the terrain engine per pixel (the tracer's diffuse terrain returns are left out).
  t = std::chrono::steady_clock::now();
  std::optional<radar::clutter::TerrainEngine> engine;
  try {
    engine.emplace(radar::make_terrain_engine(scene, tracer, {}));
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "image: warning: %s: the image shows the structures alone\n", e.what());
  }
  radar::EvTerrain terrain;
  if (engine) {
    terrain.engine = &*engine;
    terrain.wavelength_m = radar::kSpeedOfLight_mps / s.sbr.carrier_hz;
    terrain.one_way_loss_db_per_m = p.weather_one_way_db_per_m;
    p.terrain_engine = true;
    p.terrain_facets = engine->facets().size();
  }
  // In strips of whole columns (each strip the same image as the whole would give there: the
  // column grid, range edges and speckle streams do not depend on the strip), so that a stop
  // request is heard between strips and the columns done are kept.
  radar::EvImage& im = p.image;
  im.columns = columns;
  im.rows = rows;
  const auto cells = static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows);
  im.intensity_m2.assign(cells, 0.0f);
  im.mean_m2.assign(cells, 0.0f);
  im.range_edges_m.assign(static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows + 1),
                          std::numeric_limits<double>::infinity());
  std::uint64_t placed = 0;  // contributions in a strip's columns (used or counted there)
  control.report(0, static_cast<std::size_t>(columns));
  for (int c0 = 0; c0 < columns; c0 += plan.strip_columns) {
    if ((p.stop_signal = control.stop_signal()) != 0)
      break;
    const int nc = std::min(plan.strip_columns, columns - c0);
    radar::EvImageConfig strip = g;
    strip.azimuth_min_rad = g.azimuth_min_rad + c0 * g.pixel_rad;
    strip.azimuth_max_rad = g.azimuth_min_rad + (c0 + nc) * g.pixel_rad;
    const radar::EvImage part = radar::form_ev_image(contributions, p.pose, strip, terrain);
    if (part.columns != nc || part.rows != rows)
      throw std::logic_error("image: a strip of " + std::to_string(nc) + " columns came out " +
                             std::to_string(part.columns) + " x " + std::to_string(part.rows));
    for (int r = 0; r < rows; ++r) {
      const auto from = static_cast<std::size_t>(r) * static_cast<std::size_t>(nc);
      const auto to = static_cast<std::size_t>(r) * static_cast<std::size_t>(columns) +
                      static_cast<std::size_t>(c0);
      std::copy_n(part.intensity_m2.begin() + static_cast<std::ptrdiff_t>(from), nc,
                  im.intensity_m2.begin() + static_cast<std::ptrdiff_t>(to));
      std::copy_n(part.mean_m2.begin() + static_cast<std::ptrdiff_t>(from), nc,
                  im.mean_m2.begin() + static_cast<std::ptrdiff_t>(to));
    }
    std::copy(
        part.range_edges_m.begin(), part.range_edges_m.end(),
        im.range_edges_m.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(c0) *
                                                               static_cast<std::size_t>(rows + 1)));
    im.contributions_used += part.contributions_used;
    im.nearer_than_field += part.nearer_than_field;
    im.farther_than_field += part.farther_than_field;
    im.no_ground += part.no_ground;
    placed +=
        part.contributions_used + part.nearer_than_field + part.farther_than_field + part.no_ground;
    p.columns_done = c0 + nc;
    control.report(static_cast<std::size_t>(p.columns_done), static_cast<std::size_t>(columns));
  }
  // Outside the field's azimuths: the contributions no strip placed (with the terrain engine,
  // the tracer's diffuse returns are not considered).
  std::uint64_t considered = 0;
  for (const radar::Contribution& q : contributions)
    considered += engine && !q.coherent ? 0u : 1u;
  if (p.columns_done == columns)
    im.outside_columns = considered - placed;
  p.terrain = terrain.stats;
  if (engine) {  // issue 28: the flagged sigma0 values the terrain read
    p.sigma0_use = terrain.sigma0_use;
    p.sigma0_lines = radar::clutter::sigma0_use_lines(
        p.sigma0_use, radar::clutter::sigma0_row_names(engine->materials()), s.sbr.carrier_hz);
    p.sigma0_flags = radar::clutter::sigma0_use_flags(p.sigma0_use);
    p.terrain_cells = terrain.terrain_cells;
    p.sigma0_flagged_cells = terrain.flagged_cells;
  }
  p.form_s = seconds_since(t);

  if (optical_scale > 0 && p.stop_signal == 0) {
    t = std::chrono::steady_clock::now();
    scene::AngularCamera cam;
    cam.position_m = p.pose.position_m;
    cam.world_from_camera = p.pose.world_from_antenna;
    cam.azimuth_min_rad = g.azimuth_min_rad;
    cam.azimuth_max_rad = g.azimuth_min_rad + p.image.columns * g.pixel_rad;
    cam.elevation_max_rad = g.elevation_max_rad;
    cam.elevation_min_rad = g.elevation_max_rad - p.image.rows * g.pixel_rad;
    cam.width_px = p.image.columns * optical_scale;
    cam.height_px = p.image.rows * optical_scale;
    p.optical = scene::render_preview_angular(scene, cam);
    p.optical_s = seconds_since(t);
  }
  p.total_s = seconds_since(t0);
  return p;
}

int run_image_tool(const ImageToolOptions& o) {
  const Scenario s = o.scenario.empty()
                         ? parse_scenario(default_scenario_toml(), "<default scenario>")
                         : load_scenario(o.scenario);
  const std::filesystem::path dir(o.out_dir);
  check_output_dir(o.out_dir, "--out");
  const EvImageProduct p =
      compute_ev_image(s, o.time_s, o.looks, o.seed, o.optical_scale, o.control);
  const bool incomplete = p.columns_done < p.image.columns;
  std::filesystem::create_directories(dir);
  const radar::EvImage& im = p.image;
  const radar::EvImageConfig& g = p.config;
  {
    std::ofstream f(dir / "image.csv");
    f << "row,column,azimuth_deg,elevation_deg,range_near_m,range_far_m,intensity_dbsm,"
         "mean_dbsm\n";
    char line[200];
    std::size_t written = 0;
    for (int r = 0; r < im.rows; ++r) {
      for (int col = 0; col < p.columns_done; ++col) {  // all of them unless stopped early
        const std::size_t i = static_cast<std::size_t>(r * im.columns + col);
        const double* e = im.range_edges_m.data() + static_cast<std::size_t>(col * (im.rows + 1));
        std::snprintf(line, sizeof line, "%d,%d,%.4f,%.4f,%.2f,%.2f,%.3f,%.3f\n", r, col,
                      common::degrees(radar::ev_column_azimuth_rad(g, col)),
                      common::degrees(radar::ev_row_elevation_rad(g, r)), e[r + 1], e[r],
                      db(static_cast<double>(im.intensity_m2[i])),
                      db(static_cast<double>(im.mean_m2[i])));
        f << line;
        ++written;
      }
    }
    if (incomplete) {
      f << "# incomplete: stopped by " << config::signal_name(p.stop_signal) << " after "
        << p.columns_done << " of " << im.columns << " columns (" << written << " rows)\n";
    }
    if (!f)
      throw std::runtime_error((dir / "image.csv").string() + ": write failed");
  }
  nlohmann::ordered_json j;
  j["scenario"] = o.scenario.empty() ? "<default scenario>" : o.scenario;
  j["name"] = s.name;
  j["time_s"] = o.time_s;
  j["carrier_hz"] = s.sbr.carrier_hz;
  j["ownship_enu_m"] = {p.pose.position_m.x, p.pose.position_m.y, p.pose.position_m.z};
  j["ground_height_m"] = g.ground_height_m;
  j["grid"] = {{"azimuth_min_deg", common::degrees(g.azimuth_min_rad)},
               {"elevation_max_deg", common::degrees(g.elevation_max_rad)},
               {"pixel_deg", common::degrees(g.pixel_rad)},
               {"columns", im.columns},
               {"rows", im.rows},
               {"row_mapping",
                "slant range R to the elevation band whose ray meets the ground plane at R: "
                "R = (z_antenna - z_ground) / (-w_z)"}};
  j["looks"] = g.looks;
  j["speckle"] =
      "independent exponential-intensity, uniform-phase speckle per clutter return "
      "and look (radar/clutter/speckle.hpp)";
  j["speckle_seed"] = g.seed;
  j["weather"] = {{"condition", s.weather.enabled ? s.weather.condition : "none (free space)"},
                  {"rain_mm_per_h", s.weather.rain_mm_per_h},
                  {"fog_water_gm3", s.weather.fog_water_gm3},
                  {"one_way_db_per_km", p.weather_one_way_db_per_m * 1e3}};
  j["pixel_value"] = "radar cross section of the cell [m^2] (range-compensated), dB in image.csv";
  j["counts"] = {{"contributions", p.contributions},
                 {"used", im.contributions_used},
                 {"outside_columns", im.outside_columns},
                 {"nearer_than_field", im.nearer_than_field},
                 {"farther_than_field", im.farther_than_field},
                 {"no_ground", im.no_ground},
                 {"rays", p.trace.rays},
                 {"dropped_contributions", p.trace.dropped_contributions}};
  j["terrain"] = {{"source", p.terrain_engine ? "terrain engine" : "none (no terrain)"},
                  {"facets", p.terrain_facets},
                  {"facets_considered", p.terrain.facets_considered},
                  {"patches", p.terrain.patches},
                  {"patches_lit", p.terrain.patches_lit},
                  {"patches_shadowed", p.terrain.patches_shadowed},
                  {"budget_cut", p.terrain.budget_cut}};
  // Issue 28: where the terrain read sigma0 values outside a model's validity (extrapolated or
  // assumed curves), and how much of the image that is.
  j["sigma0_validity"] = {
      {"flagged", p.sigma0_flags != 0},
      {"flags", p.sigma0_flags},
      {"description", radar::clutter::describe_validity(p.sigma0_flags)},
      {"terrain_cells", p.terrain_cells},
      {"flagged_cells", p.sigma0_flagged_cells},
      {"flagged_cell_fraction", p.terrain_cells > 0 ? static_cast<double>(p.sigma0_flagged_cells) /
                                                          static_cast<double>(p.terrain_cells)
                                                    : 0.0},
      {"flagged_patch_fraction", radar::clutter::sigma0_use_patch_fraction(p.sigma0_use)},
      {"flagged_power_fraction", radar::clutter::sigma0_use_power_fraction(p.sigma0_use)},
      {"materials", p.sigma0_lines}};
  j["incomplete"] = incomplete;
  if (incomplete) {
    j["stop_signal"] = config::signal_name(p.stop_signal);
    j["columns_done"] = p.columns_done;
    j["optical_preview"] = "not rendered (stopped)";
  }
  j["memory_estimate_bytes"] = p.estimate_bytes;
  j["timing_s"] = {
      {"trace", p.trace_s}, {"form", p.form_s}, {"optical", p.optical_s}, {"total", p.total_s}};
  // Issue 28: whatever -q says, like the other warnings.
  if (p.sigma0_flags != 0) {
    std::fprintf(stderr,
                 "image: warning: sigma0 outside model validity in %.1f %% of the image's terrain "
                 "cells (image.json sigma0_validity):\n",
                 p.terrain_cells > 0 ? 100.0 * static_cast<double>(p.sigma0_flagged_cells) /
                                           static_cast<double>(p.terrain_cells)
                                     : 0.0);
    for (const std::string& line : p.sigma0_lines)
      std::fprintf(stderr, "  %s\n", line.c_str());
  }
  {
    std::ofstream f(dir / "image.json");
    f << j.dump(2) << "\n";
    if (!f)
      throw std::runtime_error((dir / "image.json").string() + ": write failed");
  }
  if (o.plot)
    write_png(p, dir / "image.png");
  if (incomplete)
    return 128 + p.stop_signal;
  if (!o.quiet) {
    std::printf(
        "EV image %d x %d pixels of %.3g deg, %d looks (speckle seed %llu), ownship (%.1f, %.1f, "
        "%.1f) m, weather %s (%.3g dB/km one way)\n"
        "%zu returns (%llu used), %llu rays; trace %.2f s, image %.2f s, optical %.2f s, total "
        "%.2f s\nwrote %s\n",
        im.columns, im.rows, common::degrees(g.pixel_rad), g.looks,
        static_cast<unsigned long long>(g.seed), p.pose.position_m.x, p.pose.position_m.y,
        p.pose.position_m.z, s.weather.enabled ? s.weather.condition.c_str() : "none",
        p.weather_one_way_db_per_m * 1e3, p.contributions,
        static_cast<unsigned long long>(im.contributions_used),
        static_cast<unsigned long long>(p.trace.rays), p.trace_s, p.form_s, p.optical_s, p.total_s,
        dir.string().c_str());
  }
  return 0;
}

}  // namespace radar_emu::tools
