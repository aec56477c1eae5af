#pragma once
// Per-stage timing of every frame, summarised as p50 / p99 / max. Storage is reserved at setup;
// record() never allocates. Percentiles are over the last `capacity` frames (a ring); count,
// max and mean cover the whole run.

#include <array>
#include <cstddef>
#include <cstdint>
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

class StageProfiler {
 public:
  explicit StageProfiler(std::size_t capacity_frames);

  /// Stores one duration [ns] for `stage`. Real-time safe.
  void record(Stage stage, std::int64_t duration_ns) noexcept;

  /// Summary of one stage (teardown/report time: copies and sorts).
  [[nodiscard]] StageSummary summary(Stage stage) const;

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
};

/// Measures one stage: starts at construction, records at destruction. Real-time safe.
class ScopedStage {
 public:
  ScopedStage(StageProfiler& profiler, const Clock& clock, Stage stage) noexcept
      : profiler_(profiler), clock_(clock), stage_(stage), start_ns_(clock.now_ns()) {}
  ~ScopedStage() { profiler_.record(stage_, clock_.now_ns() - start_ns_); }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageProfiler& profiler_;
  const Clock& clock_;
  Stage stage_;
  std::int64_t start_ns_;
};

}  // namespace radar_emu::timing
