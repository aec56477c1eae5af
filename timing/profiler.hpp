#pragma once
// Per-stage timing of every frame, summarised as p50 / p99 / max. Storage is reserved at setup;
// record() never allocates. Percentiles are over the last `capacity` frames (a ring); count,
// max and mean cover the whole run.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "timing/clock.hpp"

namespace radar_emu::timing {

/// The stages of one frame (design.md data flow), plus the frame as a whole and the scheduler's
/// wake-up latency (actual start minus deadline).
enum class Stage : std::uint8_t {
  kInput = 0,
  kSceneUpdate,
  kTrace,
  kSensor,
  kOutput,
  kFrame,
  kWakeLatency,
  kCount
};
inline constexpr std::size_t kStageCount = static_cast<std::size_t>(Stage::kCount);

[[nodiscard]] std::string_view stage_name(Stage stage) noexcept;

/// Distribution of one series [s].
struct StageSummary {
  std::uint64_t count = 0;
  double p50_s = 0.0;
  double p99_s = 0.0;
  double max_s = 0.0;
  double mean_s = 0.0;
};

/// Nearest-rank percentile (p in [0, 100]) of `samples_ns` (sorted in place). 0 when empty.
[[nodiscard]] std::int64_t percentile_ns(std::vector<std::int64_t>& samples_ns, double p);

/// One timed span of one frame, for a trace-event timeline (Chrome trace-event "X" events).
struct StageEvent {
  std::uint64_t frame = 0;    ///< frame index (set_frame())
  std::int64_t start_ns = 0;  ///< clock time the stage started [ns]
  std::int64_t duration_ns = 0;
  Stage stage = Stage::kFrame;
};

class StageProfiler {
 public:
  /// `event_capacity`: spans kept for a timeline (0: none); more are counted, not kept.
  explicit StageProfiler(std::size_t capacity_frames, std::size_t event_capacity = 0);

  /// Stores one duration [ns] for `stage`. Real-time safe.
  void record(Stage stage, std::int64_t duration_ns) noexcept;
  /// Stores the duration of the span [start_ns, end_ns] and, when events are kept, the span
  /// itself under the current frame index. Real-time safe.
  void record_span(Stage stage, std::int64_t start_ns, std::int64_t end_ns) noexcept;
  /// Frame index the following spans belong to. Real-time safe.
  void set_frame(std::uint64_t frame) noexcept { frame_ = frame; }

  /// Summary of one stage (teardown/report time: copies and sorts).
  [[nodiscard]] StageSummary summary(Stage stage) const;
  /// The stored durations of one stage in recording order [ns] (the last capacity_frames;
  /// teardown/report time: copies).
  [[nodiscard]] std::vector<std::int64_t> history_ns(Stage stage) const;
  /// The kept spans, in recording order, and how many did not fit.
  [[nodiscard]] std::span<const StageEvent> events() const noexcept {
    return {events_.data(), events_used_};
  }
  [[nodiscard]] std::uint64_t events_dropped() const noexcept { return events_dropped_; }
  /// The duration last recorded for `stage` [ns] (0 before any). Real-time safe.
  [[nodiscard]] std::int64_t last_ns(Stage stage) const noexcept {
    const Series& s = series_[static_cast<std::size_t>(stage)];
    return s.count == 0 ? 0 : s.ring_ns[(s.next + capacity_ - 1) % capacity_];
  }

 private:
  struct Series {
    std::vector<std::int64_t> ring_ns;
    std::size_t next = 0;
    std::uint64_t count = 0;
    std::int64_t max_ns = 0;
    long double sum_ns = 0;
  };
  std::size_t capacity_;
  std::array<Series, kStageCount> series_;
  std::vector<StageEvent> events_;  ///< sized at construction
  std::size_t events_used_ = 0;
  std::uint64_t events_dropped_ = 0;
  std::uint64_t frame_ = 0;
};

/// Measures one stage: starts at construction, records at destruction. Real-time safe.
class ScopedStage {
 public:
  ScopedStage(StageProfiler& profiler, const Clock& clock, Stage stage) noexcept
      : profiler_(profiler), clock_(clock), stage_(stage), start_ns_(clock.now_ns()) {}
  ~ScopedStage() { profiler_.record_span(stage_, start_ns_, clock_.now_ns()); }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageProfiler& profiler_;
  const Clock& clock_;
  Stage stage_;
  std::int64_t start_ns_;
};

}  // namespace radar_emu::timing
