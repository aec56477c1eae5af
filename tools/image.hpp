#pragma once
// `radar-emu image SCENARIO.toml`: the seed paper's forward-looking 94 GHz enhanced-vision image
// (radar/products/ev_image.hpp) from the scenario's ownship pose at a time, its antenna field
// (the [antenna] azimuth/elevation limits, one pixel per azimuth beam position), its [radar]
// tracer settings and its [weather] (ITU-R P.676 gases, P.838 rain, P.840 fog: the two-way loss
// of every return, as in `run`), with the optical preview of the same view on the same angular
// grid (scene/preview.hpp render_preview_angular) beside it.
//
// Outputs in --out (default ./image): image.csv (one row a pixel: row, column, azimuth_deg,
// elevation_deg, range_near_m, range_far_m, intensity_dbsm, mean_dbsm), image.json (the
// parameters, pose, weather, counts and timings) and with --plot image.png (the radar image and
// the optical preview side by side, axes in degrees). Errors are exceptions whose message is one
// line naming the option or file; main() prints them. The options are a plain struct;
// app/cmd_image.cpp reads them from the command line.

#include <cstdint>
#include <string>
#include <vector>

#include "common/work_control.hpp"
#include "loop/scenario.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/ev_image.hpp"
#include "scene/preview.hpp"

namespace radar_emu::tools {

struct ImageToolOptions {
  std::string scenario;  ///< TOML; "" = the embedded default scenario
  double time_s = 0.0;   ///< scenario time of the ownship pose [s]
  int looks = 10;        ///< uncorrelated looks averaged
  std::uint64_t seed = 20261124;
  int optical_scale = 4;  ///< optical preview pixels per radar pixel, each way
  std::string out_dir = "image";
  bool plot = false;
  bool quiet = false;
  /// Progress in image columns, the estimate before the work, and the stop flag polled between
  /// strips of columns (app/cmd_image.cpp draws and sets them).
  common::WorkControl control;
};

/// Everything the image command computes, without I/O (tests and benchmarks call this).
struct EvImageProduct {
  radar::EvImageConfig config;
  radar::RadarPose pose;
  radar::EvImage image;
  scene::PreviewImage optical;  ///< columns x rows times optical_scale each way
  int optical_scale = 1;
  double carrier_hz = 0.0;
  double weather_one_way_db_per_m = 0.0;  ///< 0: free space (no [weather] table)
  std::size_t contributions = 0;
  radar::TraceStats trace{};
  /// Terrain from the terrain engine (radar/clutter/terrain_engine.hpp): its statistics; false
  /// when the scene has no terrain (the image then holds the structures alone, said on stderr).
  bool terrain_engine = false;
  radar::clutter::TerrainStats terrain{};
  std::size_t terrain_facets = 0;
  /// Issue 28: the terrain's sigma0 values the catalogue flags (outside a model's validity,
  /// extrapolated, assumed): per sigma0 row what the image read (clutter::Sigma0Use), the rows'
  /// names, one line per flagged row (clutter::sigma0_use_lines), the OR of the flags, and the
  /// image's cells with terrain and those holding a flagged patch.
  std::vector<radar::clutter::Sigma0Use> sigma0_use;
  std::vector<std::string> sigma0_lines;
  std::uint32_t sigma0_flags = 0;
  std::uint64_t terrain_cells = 0, sigma0_flagged_cells = 0;
  double trace_s = 0.0, form_s = 0.0, optical_s = 0.0, total_s = 0.0;  ///< wall times
  /// Columns formed: image.columns unless a stop request ended the work early (the columns
  /// [0, columns_done) are whole, the rest zero, and no optical preview is rendered).
  int columns_done = 0;
  int stop_signal = 0;          ///< 0, or the signal that stopped it
  double estimate_bytes = 0.0;  ///< the memory estimate checked before the work [bytes]
};

/// Forms the image of `scenario` at `time_s` (ownship start + velocity t, the scenario's
/// attitude and antenna depression), in strips of columns: `control` hears of the estimate
/// (memory, and time scaled from the reference 2-core machine) before any large allocation, of
/// the columns done after each strip, and its stop flag ends the work between strips. The memory
/// estimate past config::memory_limit_bytes() (RADAR_EMU_MAX_MEMORY_MIB) is refused. Terrain comes
/// from the terrain engine, targets and metal structures (masts, lights) from the tracer's coherent
/// returns. The reference ground plane is the first non-target surface straight below the antenna
/// (0 when there is none). `optical_scale` 0: no optical preview. Throws std::runtime_error with
/// context for a bad scenario or option.
[[nodiscard]] EvImageProduct compute_ev_image(const loop::Scenario& scenario, double time_s,
                                              int looks, std::uint64_t seed, int optical_scale,
                                              const common::WorkControl& control = {});

/// Loads the scenario, computes, writes the outputs and prints a summary. Returns 0, or 128 +
/// the signal when options.control's stop flag ended the work early: image.csv then holds the
/// pixels of the columns done and ends "# incomplete: stopped by SIGINT after K of N columns (R
/// rows)", image.json says "incomplete": true, "stop_signal" and "columns_done", image.png (with
/// --plot) shows the columns done.
int run_image_tool(const ImageToolOptions& options);

}  // namespace radar_emu::tools
