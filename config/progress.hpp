#pragma once
// The progress line of radar-emu's long offline commands (sar, rcs, profile, image, tradeoff):
//   "sar: 37 % (1520/4096 pulses), 12 s elapsed, ~20 s left"
// redrawn in place on stderr at most four times a second, only when stderr is a terminal and
// the user did not ask for -q. It also remembers how far the work got, for the one-line message
// of an interrupted run.

#include <chrono>
#include <cstddef>
#include <string>

namespace radar_emu::config {

/// The line, without the carriage return: "CMD: P % (DONE/TOTAL UNIT), E s elapsed, ~L s left"
/// (the estimate left off until something is done and a second has passed).
[[nodiscard]] std::string format_progress(const std::string& command, const std::string& unit,
                                          std::size_t done, std::size_t total, double elapsed_s);

/// "1.5 GB", "320 MB", "12 kB": a byte count for the estimates printed before a long command.
[[nodiscard]] std::string format_bytes(double bytes);
/// "0.3 s", "45 s", "3 min", "1.2 h".
[[nodiscard]] std::string format_duration(double seconds);

class ProgressLine {
 public:
  /// Draws when `enabled` and stderr is a terminal. `unit` names the items ("pulses").
  ProgressLine(std::string command, std::string unit, bool enabled);
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// Records (done, total); redraws when 250 ms have passed since the last draw, or at the end
  /// (done == total), which also ends the line.
  void update(std::size_t done, std::size_t total);
  /// Records (done, total) without drawing (after a stop: the count for the final message).
  void record(std::size_t done, std::size_t total) noexcept {
    done_ = done;
    total_ = total;
  }
  /// Prints `text` (whole lines, ending with a newline) on stderr above the progress line: the
  /// drawn line is cleared, the text printed and the line drawn again below it.
  void print_above(const std::string& text);
  /// Ends the line (a newline) when one is drawn and not ended; update() may start a new one.
  void finish();
  /// Forgets a drawn line without ending it: something else (the stop handler's acknowledgement)
  /// already moved to a new line.
  void abandon() noexcept { drawn_ = false; }
  [[nodiscard]] bool drawing() const noexcept { return enabled_; }
  [[nodiscard]] std::size_t done() const noexcept { return done_; }
  [[nodiscard]] std::size_t total() const noexcept { return total_; }
  [[nodiscard]] const std::string& unit() const noexcept { return unit_; }

 private:
  std::string command_, unit_;
  bool enabled_;
  bool drawn_ = false;
  void draw(std::chrono::steady_clock::time_point now);
  std::size_t done_ = 0, total_ = 0, width_ = 0;
  std::chrono::steady_clock::time_point start_, last_;
};

/// The one-line message of a command stopped by `signal` (SIGINT, SIGTERM) after `progress`'s
/// last count, e.g. "radar-emu: rcs: interrupted by SIGINT after 37 of 400 directions; WRITTEN",
/// on stderr; returns the exit status 128 + signal.
int report_interrupted(const std::string& command, int signal, const ProgressLine& progress,
                       const std::string& written);

/// "SIGINT", "SIGTERM" or the number.
[[nodiscard]] std::string signal_name(int signal);

}  // namespace radar_emu::config
