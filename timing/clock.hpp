#pragma once
// Clocks for the frame loop: the monotonic wall clock and an injected simulated clock (tests,
// as-fast-as-possible runs, replay). Time is a signed 64-bit count of nanoseconds: exact
// deadline arithmetic (next += period never drifts) for 292 years.

#include <cstdint>

namespace radar_emu::timing {

inline constexpr std::int64_t kNanosecondsPerSecond = 1'000'000'000;

/// Seconds from nanoseconds (for reports).
[[nodiscard]] constexpr double seconds_from_ns(std::int64_t ns) noexcept {
  return static_cast<double>(ns) * 1e-9;
}

class Clock {
 public:
  virtual ~Clock() = default;
  /// Current time [ns]. Real-time safe.
  [[nodiscard]] virtual std::int64_t now_ns() const noexcept = 0;
  /// Blocks until now_ns() >= deadline_ns (returns at once if already past). Never throws.
  virtual void sleep_until_ns(std::int64_t deadline_ns) noexcept = 0;
};

/// CLOCK_MONOTONIC; sleeps with clock_nanosleep(TIMER_ABSTIME) on absolute deadlines
/// (timing.md), retrying on EINTR.
class MonotonicClock final : public Clock {
 public:
  [[nodiscard]] std::int64_t now_ns() const noexcept override;
  void sleep_until_ns(std::int64_t deadline_ns) noexcept override;
};

/// Simulated time: starts at `start_ns`, moves only when told. sleep_until_ns() jumps to the
/// deadline, so a loop on this clock runs as fast as the machine allows, deterministically.
class SimulatedClock final : public Clock {
 public:
  explicit SimulatedClock(std::int64_t start_ns = 0) noexcept : now_ns_(start_ns) {}
  [[nodiscard]] std::int64_t now_ns() const noexcept override { return now_ns_; }
  void sleep_until_ns(std::int64_t deadline_ns) noexcept override {
    if (deadline_ns > now_ns_)
      now_ns_ = deadline_ns;
  }
  /// Moves time forward by `delta_ns` (>= 0; negative values are ignored: time never goes back).
  void advance_ns(std::int64_t delta_ns) noexcept {
    if (delta_ns > 0)
      now_ns_ += delta_ns;
  }

 private:
  std::int64_t now_ns_;
};

}  // namespace radar_emu::timing
