#pragma once
// The run's report: one description of a finished run (RunReport), written two ways by one
// writer: report.json in the output directory and the summary `radar-emu run` prints. Both read
// the same fields, so the two cannot disagree. The loop fills a RunReport
// (ClosedLoop::report()); this header sees the record types only (loop/frame_record.hpp), never
// the loop itself. Setup-side code: allocates, not for the frame path.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "io/modbus.hpp"
#include "loop/frame_record.hpp"
#include "loop/governor.hpp"
#include "loop/outputs/live_view.hpp"
#include "loop/scenario.hpp"
#include "sim_bus/fault_injector.hpp"

namespace radar_emu::loop {

/// The Modbus navigation source of a run (report.json "nav_modbus"), when there was one.
struct NavSourceReport {
  bool register_bank = false;  ///< true: the loopback register bank; false: the TCP/RTU poller
  io::modbus::NavDecoderCounters decoder{};
  // Register bank only.
  std::uint64_t read_failures = 0;  ///< reads that did not return the registers
  sim_bus::RegisterFaultCounters faults{};
  // Poller only.
  io::modbus::NavPollerCounters poller{};
  std::string link_json;  ///< nav_link_report_json() text
};

/// The one-way specific attenuation of the scenario's [weather] at the carrier.
struct WeatherFigures {
  double total_db_per_m = 0.0;  ///< what every return loses per metre, one way [dB/m]
  double gas_db_per_km = 0.0;   ///< ITU-R P.676 [dB/km]
  double rain_db_per_km = 0.0;  ///< ITU-R P.838 [dB/km]
  double fog_db_per_km = 0.0;   ///< ITU-R P.840 [dB/km]
};

/// The sensor's derived figures (radar::Sensor accessors).
struct SensorFigures {
  double range_bin_m = 0.0;
  double unambiguous_range_m = 0.0;
  double velocity_bin_mps = 0.0;
  double unambiguous_velocity_mps = 0.0;
  std::size_t beams = 0;
  double sum_beamwidth_az_rad = 0.0;
  double sum_beamwidth_el_rad = 0.0;
  double processing_gain = 1.0;  ///< linear power ratio
  std::size_t cfar_training_cells = 0;
};

/// The scene database the run used.
struct SceneFigures {
  std::size_t objects = 0;
  std::size_t triangles = 0;
  std::uint32_t lod_tiles = 0;  ///< terrain tiles (LOD groups)
  /// [scene.import]: how the GIS files became the scene (scene/geodata/import.hpp's report).
  struct Import {
    std::string vertical;  ///< how heights were converted, e.g. "EGM96 geoid (file) -> ellipsoid"
    double anchor_height_m = 0.0;      ///< ellipsoidal height of the anchor (ground)
    double anchor_undulation_m = 0.0;  ///< EGM96 N at the anchor (0 when not used)
    std::size_t dem_holes_filled = 0;
    std::size_t unknown_class_cells = 0;  ///< land-cover cells given the fallback material
    std::size_t osm_broken_ways = 0;      ///< dropped
    std::size_t osm_outside = 0;          ///< features off the terrain, dropped
    double seconds = 0.0;                 ///< import time
  };
  std::optional<Import> import;
};

/// Everything report.json and the summary say about a finished run. The pointers are the
/// loop's (valid while it lives).
struct RunReport {
  const Scenario* scenario = nullptr;  ///< as run (with the command line's ",fd" applied)
  const RunResult* result = nullptr;
  bool realtime = false;
  bool replay = false;
  std::size_t replay_log_frames = 0;  ///< frames in the replayed log
  std::string can;                    ///< "--can" as given ("replay" in a replay)
  std::string nav_modbus;             ///< "--nav-modbus" as given ("" = CANaerospace)
  std::string modbus_server_address;  ///< "" when not serving
  std::string can_backend_json;       ///< hardware CAN counters (JSON text); "" = software bus
  std::string modbus_server_json;     ///< table server counters (JSON text); "" = none
  std::optional<NavSourceReport> nav;
  std::size_t timing_frames_kept = 0;  ///< frames whose stage times were kept one by one
  std::filesystem::path trace_events_file;
  std::size_t trace_events = 0;  ///< stage spans kept for it
  SceneFigures scene{};
  WeatherFigures weather{};
  GovernorConfig governor{};  ///< as run (mode resolved)
  double governor_trace_factor = 1.0;
  double governor_sensor_factor = 1.0;
  SensorFigures sensor{};
  std::vector<std::string> object_names;  ///< scene objects by id (the outcome's names)
  std::filesystem::path out_dir;          ///< "" = no output files
  OutputCounters outputs;                 ///< complete once the streamed outputs finished
  std::optional<LiveViewCounters> live_view;
  /// Issue 28: the terrain's sigma0 values the catalogue flags (outside a model's validity,
  /// extrapolated or assumed curves), tracked by the terrain engine ([radar] terrain = "engine";
  /// the tracer's terrain rays, terrain = "rays", count their returns and OR the flags only:
  /// one line for all, the power share NaN): one line per flagged material
  /// (radar::clutter::sigma0_use_lines), the OR of the flags, and the shares of the terrain's
  /// patches (returns) and power that read them.
  bool sigma0_tracked = false;
  std::uint32_t sigma0_flags = 0;
  std::vector<std::string> sigma0_lines;
  double sigma0_patch_fraction = 0.0;
  double sigma0_power_fraction = 0.0;
};

/// Writes report.json to `path`. Throws std::runtime_error "PATH: write failed".
void write_report_json(const RunReport& report, const std::filesystem::path& path);

/// Prints the run's summary (the text `radar-emu run` prints without -q) to `out`.
void print_summary(const RunReport& report, std::FILE* out);

}  // namespace radar_emu::loop
