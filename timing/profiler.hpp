#pragma once
// Per-stage timing of every frame, summarised as p50 / p99 / max. Storage is allocated (and
// touched) at setup, so neither record() nor a run of any length grows memory. Count, max, mean
// and the percentiles cover the whole run: exact while the run fits the ring of the last
// `capacity` frames, from a log-linear histogram of every frame beyond it (bins 1/128 of an
// octave wide: a percentile is within 0.4 % of the exact one). The ring keeps the last
// `capacity` durations in order (history_ns(), timing.png).

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
  bool percentiles_exact = true;  ///< false: from the whole-run histogram (within 0.4 %)
};

/// Log-linear histogram of non-negative durations [ns] (HDR-histogram layout): values below
/// 2^kSubBits have a bin each; above, every octave [2^e, 2^(e+1)) is split into 2^kSubBits
/// equal bins, so a bin is at most 1/128 of its value wide. Values from 2^41 ns (36 min) up share
/// the last bin. Fixed size; add() never allocates.
class DurationHistogram {
 public:
  static constexpr int kSubBits = 7;
  static constexpr int kMaxExponent = 41;
  static constexpr std::size_t kBins =
      (std::size_t{1} << kSubBits) * static_cast<std::size_t>(kMaxExponent - kSubBits + 1);

  void add(std::int64_t value_ns) noexcept;
  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  /// Nearest-rank percentile (p in [0, 100]): the midpoint of the bin holding the rank, clamped
  /// to [min, max] of the values added; the first and last ranks are the exact min and max.
  /// 0 when empty.
  [[nodiscard]] std::int64_t percentile_ns(double p) const noexcept;
  /// Bin of a value, and the lowest value and width of a bin (shared with tests).
  [[nodiscard]] static std::size_t bin_of(std::int64_t value_ns) noexcept;
  [[nodiscard]] static std::int64_t bin_low_ns(std::size_t bin) noexcept;
  [[nodiscard]] static std::int64_t bin_width_ns(std::size_t bin) noexcept;

 private:
  std::array<std::uint64_t, kBins> bins_{};
  std::uint64_t count_ = 0;
  std::int64_t min_ns_ = 0;
  std::int64_t max_ns_ = 0;
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

  /// Summary of one stage over the whole run (teardown/report time: copies and sorts).
  [[nodiscard]] StageSummary summary(Stage stage) const;
  /// The duration recorded last for `stage` [ns], -1 before any. Real-time safe.
  [[nodiscard]] std::int64_t last_ns(Stage stage) const noexcept {
    return series_[static_cast<std::size_t>(stage)].last_ns;
  }
  /// Frames the ring keeps (the constructor's capacity_frames).
  [[nodiscard]] std::size_t capacity_frames() const noexcept { return capacity_; }
  /// The stored durations of one stage in recording order [ns] (the last capacity_frames;
  /// teardown/report time: copies).
  [[nodiscard]] std::vector<std::int64_t> history_ns(Stage stage) const;
  /// The kept spans, in recording order, and how many did not fit.
  [[nodiscard]] std::span<const StageEvent> events() const noexcept {
    return {events_.data(), events_used_};
  }
  [[nodiscard]] std::uint64_t events_dropped() const noexcept { return events_dropped_; }

 private:
  struct Series {
    std::vector<std::int64_t> ring_ns;
    std::size_t next = 0;
    std::uint64_t count = 0;
    std::int64_t max_ns = 0;
    std::int64_t last_ns = -1;
    long double sum_ns = 0;
    DurationHistogram histogram;
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
