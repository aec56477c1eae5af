#pragma once
// The closed loop: aircraft state in over the bus, SBR over the scene, sensor, detections out
// over the bus, on a fixed-rate schedule, with per-stage timing. This is where the modules meet.

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "emulator/governor.hpp"
#include "emulator/live_view.hpp"
#include "emulator/scenario.hpp"
#include "emulator/truth.hpp"
#include "io/can_frame.hpp"
#include "io/canaerospace.hpp"
#include "io/detection_icd.hpp"
#include "radar/em/sbr.hpp"
#include "radar/sensor/sensor.hpp"
#include "scene/scene.hpp"
#include "sim_bus/fault_injector.hpp"
#include "timing/profiler.hpp"
#include "timing/realtime.hpp"

namespace radar_emu::emulator {

struct RunOptions {
  bool realtime = false;         ///< pace frames on the monotonic wall clock
  timing::RealtimeOptions rt{};  ///< bring-up when realtime
  /// Frames whose records, detections and truth RunResult keeps in memory (for callers of the
  /// library; the files in out_dir hold every frame whatever this is). `radar-emu run` sets 0.
  std::uint64_t record_frames_max = 20'000;
  /// Frames whose stage times are kept one by one: the ring of the last ones (timing.png) and
  /// the first ones' spans for trace_events_file. Memory for them is taken at setup. Summaries
  /// (report.json) and frames.csv cover every frame whatever this is.
  std::uint64_t timing_frames_max = 20'000;
  /// Output directory: bus_in.log, bus_out.log, detections.json, truth.json and frames.csv are
  /// written while the run goes (emulator/output_stream.hpp); report.json, detections.png and
  /// timing.png by write_outputs(). Created and opened at setup. "" = no files.
  std::filesystem::path out_dir;
  /// Stop request, polled at every frame boundary (a signal handler sets it to the signal
  /// number): the run ends there, RunResult::interrupted. nullptr = never.
  const std::atomic<int>* stop = nullptr;
  /// Called between frames (outside every timed stage) with (frames done, frames total).
  std::function<void(std::uint64_t, std::uint64_t)> progress;
  /// Replay: input frames recorded by an earlier run (its bus_in.log, in reception order). When
  /// set, they replace the scripted INS and the faulty node: each frame is put on the bus at the
  /// first radar frame whose bus time has reached its time stamp, which is when the recording
  /// run received it, so the radar decodes the same frames at the same frames (deterministic).
  std::vector<io::CanFrame> replay_input;
  bool replay = false;  ///< use replay_input (even when it is empty)
  /// Bus backends (emulator/bus_backends.hpp). `can`: "sim" (software loopback with the
  /// scripted INS and avionics), "socketcan:IFACE[,fd]..." or "gsusb[:SERIAL][,fd]...".
  std::string can = "sim";
  /// Where the ownship state comes from: "" (CANaerospace on the CAN bus), "sim" (the
  /// navigation register map on the loopback register bank, played from the scenario), or a
  /// Modbus TCP/RTU server "tcp:HOST:PORT" / "rtu:DEV:BAUD" (polled by a background thread).
  std::string nav_modbus;
  /// Serve the detection table as Modbus holding registers: "" (off), "HOST:PORT", ":PORT"
  /// (127.0.0.1), "rtu:DEV:BAUD". Port 0 picks a free port (see modbus_server_address()).
  std::string modbus_server;
  /// Chrome trace-event JSON of every stage of the first timing_frames_max frames, written by
  /// write_trace_events() (the path is checked, and the file created, at setup); "" = none.
  std::filesystem::path trace_events_file;
  /// Live view (emulator/live_view.hpp): serve the page on "HOST:PORT", ":PORT" or "PORT"
  /// (127.0.0.1; port 0 picks a free one, see live_view_address()); "" = off. The server is
  /// bound at setup and serves the last frame until the ClosedLoop is destroyed.
  std::string serve;
};

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
};

/// The ownship state of a stepped frame (ClosedLoop::step), given by the caller instead of the
/// bus, in the conventions of the scenario's [ownship]: position and velocity in the scene's
/// anchor ENU frame, attitude of the body (x forward, y right, z down) as heading, pitch and
/// roll [rad] (emulator/ownship.hpp); the antenna is the body pitched down by the scenario's
/// depression.
struct OwnshipInput {
  glm::dvec3 position_enu_m{0.0};
  glm::dvec3 velocity_enu_mps{0.0};
  double heading_rad = 0.0;
  double pitch_rad = 0.0;
  double roll_rad = 0.0;
};

/// What one stepped frame produced. The spans point into the loop's own buffers: valid until
/// the next step(). record.truth_count and record.detection_count are the spans' sizes.
struct FrameOutput {
  FrameRecord record{};
  std::span<const io::icd::Detection> detections;       ///< as sent (before ICD quantisation)
  std::span<const radar::Detection> sensor_detections;  ///< the sensor's view, same index
  std::span<const ObjectTruth> truth;                   ///< objects in the beam
};

/// The scene database a scenario names ([scene] file or builtin, with its seed), as the loop
/// builds it. Throws with context when a file cannot be loaded.
[[nodiscard]] scene::SceneDescription scene_description(const Scenario& scenario);

class ClosedLoop {
 public:
  /// Setup: builds the scene, tracer, sensor, buses and peers; allocates every buffer the frame
  /// path uses. Throws std::runtime_error with context on any invalid input.
  ClosedLoop(const Scenario& scenario, const RunOptions& options);
  ~ClosedLoop();
  ClosedLoop(const ClosedLoop&) = delete;
  ClosedLoop& operator=(const ClosedLoop&) = delete;

  /// Runs scenario.frames frames, or fewer when options.stop is raised. Exactly begin(), then
  /// step() until it returns false, then finish().
  RunResult run();

  /// Stepping, frame by frame (scripts, the Python module). begin() starts the run (clocks,
  /// schedule, the result's memory); a loop runs once (a second begin() throws std::logic_error).
  void begin();
  /// Runs the next frame (begin() first if it has not run) and describes it in `out`. With
  /// `ownship` null the ownship state comes from the bus as in run(); otherwise it replaces the
  /// bus's state for this frame (the bus is still read, decoded and logged). Returns false, and
  /// runs nothing, once the scenario's frames are done, a stop was requested or finish() ran.
  /// Allocates nothing beyond what begin() reserved.
  bool step(FrameOutput& out, const OwnshipInput* ownship = nullptr);
  /// Ends the run and returns its result, as run() does (then write_outputs() may follow).
  /// Throws std::logic_error when called twice.
  RunResult finish();

  /// Completes the outputs in options.out_dir: waits for the writer to write what the run handed
  /// it (bus_in.log, bus_out.log, detections.json, truth.json, frames.csv, detections.png), then
  /// writes report.json and timing.png. Throws std::runtime_error when there is no out_dir or
  /// report.json cannot be written; the streamed files' failures are counted in the report.
  void write_outputs(const RunResult& result);
  /// What the streamed outputs wrote and lost (complete once write_outputs() has run).
  [[nodiscard]] OutputCounters output_counters() const;
  /// Writes the stage timeline as Chrome trace-event JSON ({"traceEvents": [...]}, "X" complete
  /// events, ts and dur in microseconds from the first frame's start, args.frame the frame index)
  /// to options.trace_events_file. Does nothing when that is empty.
  void write_trace_events() const;

  [[nodiscard]] const Scenario& scenario() const noexcept;
  /// "HOST:PORT" the live view is served on ("" when not serving).
  [[nodiscard]] std::string live_view_address() const;
  /// Before run(): waits until a browser has opened the live view, at most `timeout_s` (or
  /// until options.stop is raised). Returns whether one did (false without a live view).
  bool wait_for_viewer(double timeout_s) const;
  /// The live view's counters (nullopt without one). Thread-safe.
  [[nodiscard]] std::optional<LiveViewCounters> live_view_counters() const;
  /// "HOST:PORT" the Modbus detection table is served on ("" when not serving). The server
  /// keeps serving the last table until the ClosedLoop is destroyed.
  [[nodiscard]] std::string modbus_server_address() const;
  /// After run(): "" unless an external Modbus navigation source (--nav-modbus) never answered
  /// a read during the whole run; then one line saying so (the CLI exits with status 3).
  [[nodiscard]] std::string nav_source_failure() const;
  /// Warnings from backend setup (bit rate not set, ...), for the summary.
  [[nodiscard]] const std::vector<std::string>& setup_warnings() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace radar_emu::emulator
