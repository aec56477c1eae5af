#include "loop/accounting.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace radar_emu::loop {

namespace {

// Spans a frame puts on the --trace-events timeline: input, scene_update, trace, sensor, output,
// frame.
constexpr std::size_t kTimelineStagesPerFrame = 6;
// Bound on the truth entries RunResult keeps in memory (40 bytes each); beyond it they are
// counted (truth.json, streamed, has them all).
constexpr std::size_t kTruthEntriesMax = 1u << 20;

std::uint64_t timed_frames(const Scenario& s, std::uint64_t timing_frames_max) {
  return std::max<std::uint64_t>(std::min(s.frames, timing_frames_max), 1);
}

}  // namespace

Accounting::Accounting(const Scenario& s, std::uint64_t record_frames_max,
                       std::uint64_t timing_frames_max, bool trace_events)
    : profiler(static_cast<std::size_t>(timed_frames(s, timing_frames_max)),
               trace_events ? static_cast<std::size_t>(timed_frames(s, timing_frames_max)) *
                                  kTimelineStagesPerFrame
                            : 0),
      recorded_frames_(std::min<std::uint64_t>(s.frames, record_frames_max)),
      max_detections_(s.sensor.max_detections) {}

void Accounting::begin(const Scenario& s, bool realtime, const timing::RealtimeOptions& rt,
                       std::size_t truth_objects) {
  if (run_)
    throw std::logic_error("ClosedLoop: the run has already begun (a loop runs once)");
  run_ = std::make_unique<RunState>(s.epoch_unix_ns);
  RunState& rs = *run_;
  RunResult& r = rs.r;
  r.frames_planned = s.frames;
  r.records.reserve(static_cast<std::size_t>(recorded_frames_));
  r.detections.reserve(static_cast<std::size_t>(recorded_frames_) * max_detections_);
  r.sensor_detections.reserve(r.detections.capacity());
  r.truth.reserve(std::min<std::size_t>(static_cast<std::size_t>(recorded_frames_) * truth_objects,
                                        kTruthEntriesMax));
  r.governor.per_frame_level.reserve(
      static_cast<std::size_t>(std::min<std::uint64_t>(s.frames, RunResult::kGovernorFramesKept)));
  r.governor.per_frame_predicted_ms.reserve(r.governor.per_frame_level.capacity());
  r.detections_min = std::numeric_limits<std::uint64_t>::max();
  r.field_age_max_s.fill(0.0);
  r.field_stale_frames.fill(0);

  timing::Clock& sched_clock =
      realtime ? static_cast<timing::Clock&>(rs.wall) : static_cast<timing::Clock&>(rs.simulated);
  if (realtime)
    r.realtime = timing::bring_up_realtime(rt);
  rs.period_ns = std::llround(1e9 / s.rate_hz);
  // 20 ms to settle on the wall clock.
  rs.start_ns = realtime ? rs.wall.now_ns() + 20'000'000 : rs.simulated.now_ns();
  rs.scheduler.emplace(sched_clock, rs.period_ns, rs.start_ns);
  rs.timeout_ns = std::llround(s.state_timeout_s * 1e9);
  rs.run_start_wall = rs.wall.now_ns();
}

void Accounting::frame(FrameRecord rec, std::int64_t frame_start_wall, const FrameProducts& p,
                       RunOutputs& outputs) noexcept {
  RunState& rs = *run_;
  RunResult& r = rs.r;
  const std::int64_t frame_end_wall = rs.wall.now_ns();
  profiler.record_span(timing::Stage::kFrame, frame_start_wall, frame_end_wall);
  if (frame_end_wall - frame_start_wall > rs.period_ns)
    ++r.frames_over_budget;
  // The frame's record: to the writer thread, the live view (a copy into a preallocated
  // snapshot and one atomic exchange), and to memory for the first recorded frames.
  if (outputs.stream || outputs.view) {
    std::array<std::int64_t, timing::kStageCount> stage_ns{};
    for (std::size_t k = 0; k < timing::kStageCount; ++k)
      stage_ns[k] = profiler.last_ns(static_cast<timing::Stage>(k));
    if (outputs.stream)
      outputs.stream->frame(rec, stage_ns, p.detections, p.sensor_detections, p.truth);
    if (outputs.view)
      outputs.view->publish(rec, p.velocity_mps, stage_ns, p.detections, p.truth, p.outcome);
  }
  const std::size_t n_det = p.detections.size(), n_truth = p.truth.size();
  if (r.records.size() < recorded_frames_) {
    rec.first_detection = static_cast<std::uint32_t>(r.detections.size());
    rec.first_truth = static_cast<std::uint32_t>(r.truth.size());
    const std::size_t room = r.truth.capacity() - r.truth.size();
    rec.truth_count = static_cast<std::uint32_t>(std::min(n_truth, room));
    r.truth_overflows += n_truth - rec.truth_count;
    r.truth.insert(r.truth.end(), p.truth.begin(), p.truth.begin() + rec.truth_count);
    r.records.push_back(rec);
    r.detections.insert(r.detections.end(), p.detections.begin(), p.detections.end());
    r.sensor_detections.insert(r.sensor_detections.end(), p.sensor_detections.begin(),
                               p.sensor_detections.end());
  }
  ++r.frames;
  if (rec.ownship_valid)
    ++r.frames_valid;
  r.detections_total += n_det;
  r.detections_min = std::min<std::uint64_t>(r.detections_min, n_det);
  r.detections_max = std::max<std::uint64_t>(r.detections_max, n_det);
  ++rs.done;
}

void Accounting::finish(RunResult& r) const {
  const RunState& rs = *run_;
  r.wall_time_s = static_cast<double>(rs.wall.now_ns() - rs.run_start_wall) * 1e-9;
  r.overruns = rs.scheduler->overruns();
  r.missed_periods = rs.scheduler->missed_periods();
  r.trace_events_dropped = profiler.events_dropped();
  for (std::size_t k = 0; k < timing::kStageCount; ++k)
    r.stages[k] = profiler.summary(static_cast<timing::Stage>(k));
  if (r.frames == 0)
    r.detections_min = 0;
}

}  // namespace radar_emu::loop
