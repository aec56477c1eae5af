#pragma once
// How a long offline computation (tools/: rcs, profile, sar, image, tradeoff) reports its
// progress and hears a stop request, without doing any terminal I/O itself: the caller (app/)
// gives a callback that draws the progress line and the flag a SIGINT/SIGTERM handler sets.
// The computation polls the flag between work items (a direction, a pulse block, a frequency),
// writes what is done, marks it incomplete and returns.

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>

namespace radar_emu::common {

struct WorkControl {
  /// Called after each work item with (items done, items in all); may be empty. Called from the
  /// computing thread; not real-time safe.
  std::function<void(std::size_t done, std::size_t total)> progress;
  /// Receives the estimate of time and memory computed before the work starts, one line
  /// without the command's name ("4096 pulses x 2048 gates: raw 67 MB, ..."); may be empty.
  std::function<void(const std::string& line)> estimate;
  /// Receives a line of the computation's own log (with its newline), to be printed on stderr
  /// above the progress line; empty: the computation prints it on stderr itself.
  std::function<void(const std::string& line)> note;
  /// Non-zero (the signal number) once a stop was requested; null: never stops early.
  const std::atomic<int>* stop = nullptr;

  /// 0, or the signal that asked the computation to stop.
  [[nodiscard]] int stop_signal() const noexcept {
    return stop != nullptr ? stop->load(std::memory_order_relaxed) : 0;
  }
  void report(std::size_t done, std::size_t total) const {
    if (progress)
      progress(done, total);
  }
  void tell_estimate(const std::string& line) const {
    if (estimate)
      estimate(line);
  }
};

}  // namespace radar_emu::common
