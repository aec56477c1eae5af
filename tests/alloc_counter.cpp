#include "tests/alloc_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

// operator new is malloc and operator delete is free here, by design.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<std::uint64_t> g_count{0};
}  // namespace

namespace radar_emu::test {
void start_counting_allocations() noexcept {
  g_count.store(0);
  g_counting.store(true);
}
std::uint64_t stop_counting_allocations() noexcept {
  g_counting.store(false);
  return g_count.load();
}
std::function<void(std::uint64_t, std::uint64_t)> count_allocations_from_frame(
    std::uint64_t first_frame) {
  return [first_frame](std::uint64_t done, std::uint64_t total) {
    if (done == first_frame)
      start_counting_allocations();
    if (done == total)
      (void)stop_counting_allocations();
  };
}

}  // namespace radar_emu::test

void* operator new(std::size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_count.fetch_add(1, std::memory_order_relaxed);
    if (std::getenv("RADAR_EMU_ABORT_ON_ALLOCATION") != nullptr)
      std::abort();
  }
  if (void* p = std::malloc(n == 0 ? 1 : n))
    return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
// The nothrow forms too (std::stable_sort's temporary buffer uses them): without them the
// runtime's nothrow new would pair with the free() above, which AddressSanitizer reports as an
// alloc-dealloc mismatch.
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return operator new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return operator new(n);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
