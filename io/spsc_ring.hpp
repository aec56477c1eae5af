#pragma once
// A bounded single-producer single-consumer ring between two threads (the usual lock-free ring:
// the producer owns `tail_`, the consumer owns `head_`, each publishes with release and reads the
// other's index with acquire). Storage is allocated once, in the constructor; push() and pop()
// never allocate, block or throw. Used by the gs_usb backend between libusb's event thread and the
// frame thread.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>
#include <stdexcept>
#include <vector>

namespace radar_emu::io {

template <typename T>
class SpscRing {
 public:
  /// `capacity` slots, rounded up to a power of two (setup; allocates).
  explicit SpscRing(std::size_t capacity) {
    if (capacity == 0)
      throw std::invalid_argument("SpscRing: capacity must be at least 1");
    std::size_t n = 1;
    while (n < capacity)
      n <<= 1;
    slots_.resize(n);
    mask_ = n - 1;
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  [[nodiscard]] std::size_t capacity() const noexcept { return slots_.size(); }

  /// Producer only. Copies `value` into the ring; false when it is full. Real-time safe.
  [[nodiscard]] bool push(const T& value) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == slots_.size())
      return false;
    slots_[tail & mask_] = value;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Consumer only. Moves the oldest value into `out`; false when the ring is empty.
  /// Real-time safe.
  [[nodiscard]] bool pop(T& out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire))
      return false;
    out = slots_[head & mask_];
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Either side: values in the ring at some moment during the call.
  [[nodiscard]] std::size_t size() const noexcept {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire);
  }

 private:
  // Both indices run freely (wrap at 2^64); the slot is index & mask_.
  std::vector<T> slots_;
  std::size_t mask_ = 0;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace radar_emu::io
