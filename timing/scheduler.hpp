#pragma once
// Fixed-rate scheduler on absolute deadlines (ros2_control / rt-tests practice, timing.md):
// deadline k is start + k * period, computed exactly; when a frame overruns so far that whole
// periods have passed, those periods are counted as missed and skipped, never replayed in a
// burst.

#include <cstdint>

#include "timing/clock.hpp"

namespace radar_emu::timing {

/// One scheduled frame.
struct Tick {
  std::uint64_t period_index = 0;   ///< k: this frame's deadline is start + k * period
  std::int64_t deadline_ns = 0;     ///< scheduled start of this frame [ns]
  std::int64_t wake_ns = 0;         ///< when wait_next() returned [ns]
  std::uint64_t missed_before = 0;  ///< periods skipped just before this frame
  bool late = false;                ///< the previous frame ended after this deadline (overrun)
};

class FixedRateScheduler {
 public:
  /// `period_ns` > 0 (checked by the caller at setup); the first deadline is `start_ns`.
  FixedRateScheduler(Clock& clock, std::int64_t period_ns, std::int64_t start_ns) noexcept
      : clock_(&clock), period_ns_(period_ns), next_deadline_ns_(start_ns) {}

  /// Waits for the next deadline and returns it. If the previous frame ended after that
  /// deadline, the frame starts at once and is marked late (an overrun); if it ended one or more
  /// whole periods after it, those periods are skipped and counted. Real-time safe.
  [[nodiscard]] Tick wait_next() noexcept;

  [[nodiscard]] std::int64_t period_ns() const noexcept { return period_ns_; }
  [[nodiscard]] std::uint64_t missed_periods() const noexcept { return missed_periods_; }
  [[nodiscard]] std::uint64_t overruns() const noexcept { return overruns_; }
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }

 private:
  Clock* clock_;
  std::int64_t period_ns_;
  std::int64_t next_deadline_ns_;
  std::uint64_t next_index_ = 0;
  std::uint64_t missed_periods_ = 0;
  std::uint64_t overruns_ = 0;
  std::uint64_t frames_ = 0;
};

}  // namespace radar_emu::timing
