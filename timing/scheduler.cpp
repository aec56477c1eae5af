#include "timing/scheduler.hpp"

namespace radar_emu::timing {

Tick FixedRateScheduler::wait_next() noexcept {
  Tick tick{};
  const std::int64_t now = clock_->now_ns();
  if (frames_ > 0 && now > next_deadline_ns_) {
    // The previous frame overran this deadline. Skip every period that has already ended
    // entirely: deadline k is skipped when now >= deadline_k + period.
    tick.late = true;
    ++overruns_;
    const std::int64_t behind_ns = now - next_deadline_ns_;
    const auto skipped = static_cast<std::uint64_t>(behind_ns / period_ns_);
    if (skipped > 0) {
      next_deadline_ns_ += static_cast<std::int64_t>(skipped) * period_ns_;
      next_index_ += skipped;
      missed_periods_ += skipped;
      tick.missed_before = skipped;
    }
  }
  clock_->sleep_until_ns(next_deadline_ns_);
  tick.period_index = next_index_;
  tick.deadline_ns = next_deadline_ns_;
  tick.wake_ns = clock_->now_ns();
  ++frames_;
  ++next_index_;
  next_deadline_ns_ += period_ns_;
  return tick;
}

}  // namespace radar_emu::timing
