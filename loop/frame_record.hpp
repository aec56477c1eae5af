#pragma once
// What a run of the closed loop produces, frame by frame and in total: the record and result
// types shared by the loop (loop/closed_loop.hpp), its outputs (loop/outputs/), the tools and
// the Python module. The outputs include this header, never the loop's own.

#include <array>
#include <cstdint>
#include <glm/vec3.hpp>
#include <span>
#include <string>
#include <vector>

#include "io/canaerospace.hpp"
#include "io/detection_icd.hpp"
#include "loop/governor.hpp"
#include "loop/outcome.hpp"
#include "loop/truth.hpp"
#include "radar/clutter/terrain_engine.hpp"
#include "radar/em/sbr.hpp"
#include "radar/sensor/sensor.hpp"
#include "sim_bus/fault_injector.hpp"
#include "timing/profiler.hpp"
#include "timing/realtime.hpp"

namespace radar_emu::loop {

/// What one frame put on the bus.
struct FrameRecord {
  std::uint64_t frame_index = 0;  ///< scheduler period index
  double time_s = 0.0;            ///< scenario time
  io::icd::Header header{};
  std::uint32_t first_detection = 0;  ///< index into RunResult::detections
  std::uint32_t detection_count = 0;
  std::uint32_t first_truth = 0;  ///< index into RunResult::truth
  std::uint32_t truth_count = 0;  ///< objects in the beam (truth.json)
  bool late = false;
  bool sent = true;  ///< false: stale state with stale_output "silent", nothing was sent
  bool ownship_valid = false;
  glm::dvec3 ownship_enu_m{0.0};       ///< antenna position used by the frame (scene ENU) [m]
  int governor_level = 0;              ///< fidelity level the governor chose (0: the scenario's)
  double governor_predicted_ms = 0.0;  ///< its predicted trace + sensor time [ms]
  double governor_error_db = 0.0;      ///< its estimated SNR error at that level [dB]
  std::uint64_t rays = 0;              ///< rays traced
  // What the governor's cost model counts (loop/governor.hpp), for reading its predictions
  // against the stage times: its two terms, and the frame's figures they rest on.
  double governor_predicted_trace_ms = 0.0;
  double governor_predicted_sensor_ms = 0.0;
  std::uint64_t kept_returns = 0;       ///< returns re-evaluated from kept paths (static reuse)
  std::uint64_t returns = 0;            ///< returns handed to the sensor (the engine's included)
  std::uint64_t cells_synthesised = 0;  ///< image cells the sensor synthesised
  std::uint64_t terrain_patches = 0;    ///< the terrain engine's patches
  std::uint64_t terrain_facets = 0;     ///< the facets it cut into them
  std::uint64_t target_facets = 0;      ///< the bundled targets' facets (the facet pass)
  std::uint64_t terrain_returns = 0;    ///< of `returns`, the terrain engine's
  std::uint64_t merged_returns = 0;     ///< returns the sensor summed into another
};

/// What the streamed outputs (emulator/output_stream.hpp) wrote and lost.
struct OutputFileCounters {
  std::string name;  ///< file name in the output directory
  std::uint64_t bytes_written = 0;
  std::uint64_t write_errors = 0;  ///< failed writes (the data in them is lost)
  std::uint64_t bytes_lost = 0;
  std::string first_error;  ///< "" when none
};
struct OutputCounters {
  std::uint64_t frames_written = 0;      ///< frames in detections.json, truth.json, frames.csv
  std::uint64_t frames_dropped = 0;      ///< no room in the rings (real time only)
  std::uint64_t bus_frames_written = 0;  ///< candump lines, both logs
  std::uint64_t bus_frames_dropped = 0;  ///< no room in the ring (real time only)
  std::uint64_t detections_written = 0;
  std::uint64_t waits = 0;  ///< times the loop waited for the writer (simulated clock only)
  std::vector<OutputFileCounters> files;
  /// Every frame handed over was written, and every write succeeded.
  [[nodiscard]] bool complete() const noexcept {
    bool ok = frames_dropped == 0 && bus_frames_dropped == 0;
    for (const OutputFileCounters& f : files)
      ok = ok && f.write_errors == 0;
    return ok;
  }
};

struct RunResult {
  std::uint64_t frames = 0;
  std::uint64_t frames_planned = 0;      ///< the scenario's frames
  bool interrupted = false;              ///< stopped early by RunOptions::stop
  int stop_signal = 0;                   ///< its value (the signal number) when interrupted
  std::uint64_t frames_valid = 0;        ///< frames with a fresh ownship state
  std::uint64_t lists_suppressed = 0;    ///< stale frames that sent nothing (stale_output "silent")
  std::uint64_t frames_over_budget = 0;  ///< compute time of the frame exceeded the period
  std::uint64_t overruns = 0;            ///< scheduler: frames started late
  std::uint64_t missed_periods = 0;      ///< scheduler: periods skipped
  std::uint64_t detections_total = 0;
  std::uint64_t detections_min = 0;
  std::uint64_t detections_max = 0;
  io::canas::DecoderCounters decoder{};
  /// Per ownship field (io::canas::Field order): the largest age seen at a frame's time once the
  /// field had been received [s], and the frames at which it was missing or older than the
  /// timeout.
  std::array<double, io::canas::kFieldCount> field_age_max_s{};
  std::array<std::uint64_t, io::canas::kFieldCount> field_stale_frames{};
  std::uint64_t replay_frames_fed = 0;   ///< replay: log frames put on the bus
  std::uint64_t replay_frames_left = 0;  ///< replay: log frames after the last radar frame
  std::uint64_t icd_dropped = 0;
  std::uint64_t icd_truncated = 0;
  radar::TraceStats trace{};  ///< summed over frames
  /// [radar] terrain = "engine": the terrain engine's patches, summed over frames (all zero with
  /// terrain rays), and the cell returns that found no room in the contribution buffer.
  radar::clutter::TerrainStats terrain{};
  std::uint64_t terrain_dropped = 0;
  /// Scene culling and level of detail (scene::ViewStats), summed over the frames with a view.
  struct ViewTotals {
    std::uint64_t frames = 0;
    std::uint64_t lod_groups_in_view = 0;
    std::uint64_t lod_groups_culled = 0;
    std::array<std::uint64_t, 4> lod_groups_at_level{};
    std::uint64_t triangles_active = 0;
  } view{};
  radar::SensorStats sensor{};  ///< summed over frames
  /// The fidelity governor over the valid frames.
  struct GovernorTotals {
    std::array<std::uint64_t, FidelityGovernor::kMaxLevel + 1> level_frames{};  ///< by level
    std::uint64_t frames_degraded = 0;        ///< level > 0 (flagged DEGRADED)
    std::uint64_t frames_predicted_late = 0;  ///< even the coarsest level was predicted late
    int max_level = 0;
    std::vector<std::int8_t> per_frame_level;  ///< every frame (-1: no state), first kept
    std::vector<float> per_frame_predicted_ms;
  } governor{};
  /// Frames whose governor level and prediction RunResult keeps (report.json).
  static constexpr std::uint64_t kGovernorFramesKept = 1u << 20;
  std::uint64_t bus_frames_in = 0;   ///< frames the radar received
  std::uint64_t bus_frames_out = 0;  ///< frames the radar sent
  std::uint64_t bus_rx_overflows = 0;
  std::uint64_t record_overflows = 0;      ///< bus frames not written to the logs (no room)
  std::uint64_t trace_events_dropped = 0;  ///< stage spans not kept for --trace-events
  std::uint64_t truth_overflows = 0;       ///< in-beam objects not kept in `truth` (bound)
  std::uint64_t sink_lists = 0;            ///< detection lists the avionics sink reassembled
  std::uint64_t sink_malformed = 0;
  std::array<std::uint64_t, 4> injected_malformed{};  ///< by sim_bus::MalformedKind
  sim_bus::FaultCounters link_faults{};               ///< the radar's receiving side
  sim_bus::StaleCounters stale_sender{};
  sim_bus::BabbleCounters babble{};
  std::array<timing::StageSummary, timing::kStageCount> stages{};
  timing::RealtimeReport realtime{};
  double wall_time_s = 0.0;
  std::vector<FrameRecord> records;            ///< first record_frames_max frames (memory)
  std::vector<io::icd::Detection> detections;  ///< as sent (before ICD quantisation)
  /// The sensor's own view of each recorded detection (same index as `detections`): its
  /// one-sigma accuracies and ambiguity flags, which the ICD does not carry.
  std::vector<radar::Detection> sensor_detections;
  /// Objects in the beam per recorded frame (FrameRecord::first_truth / truth_count).
  std::vector<ObjectTruth> truth;
  /// The outcome per truth object (in truth.json's order) and the false alarms, over every
  /// frame with an ownship state (loop/outcome.hpp).
  OutcomeTotals outcome;
};

/// What one stepped frame produced. The spans point into the loop's own buffers: valid until
/// the next step(). record.truth_count and record.detection_count are the spans' sizes.
struct FrameOutput {
  FrameRecord record{};
  std::span<const io::icd::Detection> detections;       ///< as sent (before ICD quantisation)
  std::span<const radar::Detection> sensor_detections;  ///< the sensor's view, same index
  std::span<const ObjectTruth> truth;                   ///< objects in the beam
  /// Per detection (same index): the index into `truth` it was associated with, -1 for a false
  /// alarm (loop/outcome.hpp); empty in a frame without an ownship state.
  std::span<const int> association;
};

}  // namespace radar_emu::loop
