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
#include <string_view>
#include <vector>

#include "io/can_frame.hpp"
#include "io/canaerospace.hpp"
#include "io/detection_icd.hpp"
#include "loop/frame_record.hpp"
#include "loop/governor.hpp"
#include "loop/outputs/cube_writer.hpp"
#include "loop/outputs/live_view.hpp"
#include "loop/outputs/report.hpp"
#include "loop/scenario.hpp"
#include "loop/truth.hpp"
#include "radar/em/sbr.hpp"
#include "radar/sensor/sensor.hpp"
#include "scene/scene.hpp"
#include "sim_bus/fault_injector.hpp"
#include "timing/profiler.hpp"
#include "timing/realtime.hpp"

namespace radar_emu::scene::geodata {
struct ImportReport;
}

namespace radar_emu::loop {

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
  /// written while the run goes (loop/outputs/output_stream.hpp); report.json, detections.png and
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
  /// Bus backends (loop/bus_backends.hpp). `can`: "sim" (software loopback with the
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
  /// Live view (loop/outputs/live_view.hpp): serve the page on "HOST:PORT", ":PORT" or "PORT"
  /// (127.0.0.1; port 0 picks a free one, see live_view_address()); "" = off. The server is
  /// bound at setup and serves the last frame until the ClosedLoop is destroyed.
  std::string serve;
  /// Data cubes (loop/outputs/cube_writer.hpp, docs/cube.md): an HDF5 file of the raw samples
  /// and the range-Doppler-beam image of the frames cube_first_frame..cube_last_frame (frame
  /// indices, inclusive; clipped to the run), created at setup; "" = none. Setup refuses a range
  /// past the run or whose estimated size exceeds loop::kCubeMaxBytes.
  std::filesystem::path cube_file;
  std::uint64_t cube_first_frame = 0;
  std::uint64_t cube_last_frame = 3;
  /// Where cube_file and the range came from, for setup errors (see choose_cube()).
  std::string cube_file_source = "--cube";
  std::string cube_frames_source = "--cube-frames";
};

/// The cube of a run (docs/cube.md) into `o`: the scenario's [output] cube and cube_frames,
/// each replaced by the caller's when given (non-empty `file`, `frames`: the CLI's --cube and
/// --cube-frames, the Python Loop's cube= and cube_frames=; the caller wins). `file_option` and
/// `frames_option` name the caller's options in messages. Setup only: throws
/// std::runtime_error for `frames` that is not FIRST:LAST, or a range without a file.
void choose_cube(const Scenario& s, const std::string& file, const std::string& frames,
                 RunOptions& o, std::string_view file_option = "--cube",
                 std::string_view frames_option = "--cube-frames");

/// The ownship state of a stepped frame (ClosedLoop::step), given by the caller instead of the
/// bus, in the conventions of the scenario's [ownship]: position and velocity in the scene's
/// anchor ENU frame, attitude of the body (x forward, y right, z down) as heading, pitch and
/// roll [rad] (loop/ownship.hpp); the antenna is the body pitched down by the scenario's
/// depression.
struct OwnshipInput {
  glm::dvec3 position_enu_m{0.0};
  glm::dvec3 velocity_enu_mps{0.0};
  double heading_rad = 0.0;
  double pitch_rad = 0.0;
  double roll_rad = 0.0;
};

/// ITU-R P.838-3's polarisation tilt for the rain loss of a radar in `polarisation` [rad]:
/// 0 for HH (horizontal), pi/2 for VV (vertical), pi/4 for HV and VH (one way each: P.838's
/// k and alpha then average the two). Real-time safe.
[[nodiscard]] double rain_tilt_rad(radar::Polarisation polarisation) noexcept;

/// The scene database a [scene] table names (file, builtin with its seed, or [scene.import]
/// through loop/scene_import.hpp), without targets: what the loop, `image` and `sar` build.
/// Throws with context when a file cannot be loaded or imported.
/// `import_report` (optional) receives the import's report when [scene.import] names the scene.
[[nodiscard]] scene::SceneDescription scene_database(
    const SceneSource& source, scene::geodata::ImportReport* import_report = nullptr);

/// The scene database a scenario names ([scene] file or builtin, with its seed), as the loop
/// builds it. Throws with context when a file cannot be loaded.
[[nodiscard]] scene::SceneDescription scene_description(
    const Scenario& scenario, scene::geodata::ImportReport* import_report = nullptr);

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
  /// The run's report (loop/outputs/report.hpp) for `result`, as finish() returned it: what
  /// write_outputs() writes to report.json and `radar-emu run` prints. Points into this loop
  /// and `result` (both must outlive it). Setup-side: allocates.
  [[nodiscard]] RunReport report(const RunResult& result) const;
  /// What the cube file (RunOptions::cube_file) got and lost, complete once finish() has run;
  /// nullopt without one.
  [[nodiscard]] std::optional<CubeCounters> cube_counters() const;
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

}  // namespace radar_emu::loop
