#pragma once
// Counts heap allocations (every operator new, on every thread) while counting is on: the frame
// path must not allocate (style.md). Link tests/alloc_counter.cpp into a test executable to
// replace its global operator new and delete. With RADAR_EMU_ABORT_ON_ALLOCATION set, an
// allocation while counting aborts, so that a debugger shows where it came from.

#include <cstdint>
#include <functional>

namespace radar_emu::test {

/// Resets the count to zero and starts counting.
void start_counting_allocations() noexcept;
/// Stops counting and returns how many allocations happened since the start.
std::uint64_t stop_counting_allocations() noexcept;
/// A closed loop's progress callback (loop::RunOptions::progress) that counts from frame
/// `first_frame` to the last one; read the count with stop_counting_allocations() after the run.
std::function<void(std::uint64_t, std::uint64_t)> count_allocations_from_frame(
    std::uint64_t first_frame);

}  // namespace radar_emu::test
