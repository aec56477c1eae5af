#pragma once
// Wait-free hand-over of the latest value from one producer thread to one consumer thread:
// three slots, the producer writes one, the consumer reads another, the third (the "middle")
// holds the newest published value. publish() and update() are one atomic exchange each, so
// neither side ever blocks or waits for the other, and no publish is ever lost except by being
// superseded by a newer one (the consumer only wants the latest).

#include <array>
#include <atomic>
#include <cstdint>

namespace radar_emu::io {

template <typename T>
class TripleBuffer {
 public:
  /// Every slot starts as a copy of `initial` (setup: size containers here, so that writes into
  /// write_slot() never allocate).
  explicit TripleBuffer(const T& initial = T{}) : slots_{initial, initial, initial} {}
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  /// Producer: the slot to fill before publish(). Its content is whatever was there (not
  /// necessarily the last published value). Real-time safe.
  [[nodiscard]] T& write_slot() noexcept { return slots_[write_]; }
  /// Producer: makes write_slot() the newest value and takes a free slot for the next write.
  /// Returns true when the value it replaces had been published but never taken by update()
  /// (superseded unread: a consumer that counts what it missed counts these). Real-time safe
  /// (wait-free).
  bool publish() noexcept {
    const std::uint8_t old =
        middle_.exchange(static_cast<std::uint8_t>(write_ | kDirty), std::memory_order_acq_rel);
    write_ = static_cast<std::uint8_t>(old & kIndexMask);
    return (old & kDirty) != 0;
  }

  /// Consumer: takes the newest published value if there is one not yet taken; returns true
  /// then. read_slot() afterwards holds the newest value taken so far. Real-time safe.
  [[nodiscard]] bool update() noexcept {
    if ((middle_.load(std::memory_order_relaxed) & kDirty) == 0)
      return false;
    const std::uint8_t old = middle_.exchange(read_, std::memory_order_acq_rel);
    read_ = static_cast<std::uint8_t>(old & kIndexMask);
    return true;
  }
  /// Consumer: the value taken by the last successful update() (or the initial value).
  [[nodiscard]] const T& read_slot() const noexcept { return slots_[read_]; }

 private:
  static constexpr std::uint8_t kDirty = 0x4;
  static constexpr std::uint8_t kIndexMask = 0x3;

  std::array<T, 3> slots_;
  std::uint8_t write_ = 0;               // producer only
  std::uint8_t read_ = 1;                // consumer only
  std::atomic<std::uint8_t> middle_{2};  // index | kDirty
};

}  // namespace radar_emu::io
