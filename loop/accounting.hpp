#pragma once
// The run's accounting: its clocks and fixed-rate schedule, the stage profiler, the result so
// far (RunResult) with the frames it keeps in memory, and the hand-over of each frame to the
// outputs (the streamed files and the live view).
//
// Units: clock readings and spans in ns. Setup (the constructor, begin()) allocates everything
// the frame path uses; frame() is real-time safe (no allocation, no blocking, no exceptions).

#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <memory>
#include <optional>
#include <span>

#include "loop/frame_record.hpp"
#include "loop/outputs/live_view.hpp"
#include "loop/outputs/output_stream.hpp"
#include "loop/scenario.hpp"
#include "timing/clock.hpp"
#include "timing/profiler.hpp"
#include "timing/realtime.hpp"
#include "timing/scheduler.hpp"

namespace radar_emu::loop {

/// Where the frames go besides memory: either may be null.
struct RunOutputs {
  std::unique_ptr<OutputStream> stream;  ///< null without an output directory
  std::unique_ptr<LiveView> view;        ///< null without RunOptions::serve
};

/// What one frame produced, as the accounting takes it (spans into the loop's buffers).
struct FrameProducts {
  std::span<const io::icd::Detection> detections;       ///< as sent
  std::span<const radar::Detection> sensor_detections;  ///< same index
  std::span<const ObjectTruth> truth;                   ///< objects in the beam
  glm::dvec3 velocity_mps{0.0};                         ///< ownship (0 without a state) [m/s]
  OutcomeSoFar outcome{};                               ///< per target so far (the live view)
};

/// The run under way (begin() to finish()): its result so far, its clocks and its schedule.
struct RunState {
  explicit RunState(std::int64_t epoch_ns) : simulated(epoch_ns) {}
  RunResult r;
  timing::MonotonicClock wall;
  timing::SimulatedClock simulated;
  std::optional<timing::FixedRateScheduler> scheduler;
  std::int64_t period_ns = 0;       ///< frame period [ns]
  std::int64_t start_ns = 0;        ///< the first deadline on the schedule's clock [ns]
  std::int64_t timeout_ns = 0;      ///< ownship state timeout [ns]
  std::int64_t run_start_wall = 0;  ///< wall clock at begin() [ns]
  std::uint16_t frame_counter = 0;  ///< the ICD header's
  std::uint64_t done = 0;           ///< frames run
  bool finished = false;
};

class Accounting {
 public:
  /// Setup: sizes the profiler (RunOptions::timing_frames_max, with spans for trace events when
  /// `trace_events`) and the frames kept in memory (record_frames_max).
  Accounting(const Scenario& s, std::uint64_t record_frames_max, std::uint64_t timing_frames_max,
             bool trace_events);

  /// Starts the run: the result's memory (truth for `truth_objects` objects a frame), the clocks
  /// (the wall clock when `realtime`, with the real-time bring-up `rt`) and the schedule. Throws
  /// std::logic_error when run twice.
  void begin(const Scenario& s, bool realtime, const timing::RealtimeOptions& rt,
             std::size_t truth_objects);
  [[nodiscard]] bool begun() const noexcept { return run_ != nullptr; }
  [[nodiscard]] RunState& run() noexcept { return *run_; }
  [[nodiscard]] const RunState& run() const noexcept { return *run_; }

  /// Frame path: closes the frame's span (started at `frame_start_wall` [ns]), hands the frame
  /// to the outputs and keeps it in memory while there is room; counts it. Real-time safe.
  void frame(FrameRecord rec, std::int64_t frame_start_wall, const FrameProducts& products,
             RunOutputs& outputs) noexcept;
  /// Ends the run: the schedule's and the profiler's figures into the result.
  void finish(RunResult& r) const;

  timing::StageProfiler profiler;

 private:
  std::uint64_t recorded_frames_;  ///< frames RunResult keeps in memory
  std::size_t max_detections_;
  std::unique_ptr<RunState> run_;
};

}  // namespace radar_emu::loop
