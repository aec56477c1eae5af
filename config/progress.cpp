// The progress line of the long offline commands (config/progress.hpp).

#include "config/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <utility>

namespace radar_emu::config {

std::string format_duration(double seconds) {
  char buf[32];
  if (seconds < 9.95)
    std::snprintf(buf, sizeof buf, "%.1f s", std::max(0.0, seconds));
  else if (seconds < 90.0)
    std::snprintf(buf, sizeof buf, "%.0f s", seconds);
  else if (seconds < 5400.0)
    std::snprintf(buf, sizeof buf, "%.0f min", seconds / 60.0);
  else
    std::snprintf(buf, sizeof buf, "%.1f h", seconds / 3600.0);
  return buf;
}

std::string format_bytes(double bytes) {
  char buf[32];
  if (bytes >= 1e9)
    std::snprintf(buf, sizeof buf, "%.1f GB", bytes / 1e9);
  else if (bytes >= 1e6)
    std::snprintf(buf, sizeof buf, "%.0f MB", bytes / 1e6);
  else
    std::snprintf(buf, sizeof buf, "%.0f kB", std::ceil(bytes / 1e3));
  return buf;
}

std::string format_progress(const std::string& command, const std::string& unit, std::size_t done,
                            std::size_t total, double elapsed_s) {
  const double frac = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s: %.0f %% (%zu/%zu %s), %s elapsed", command.c_str(),
                std::floor(100.0 * frac), done, total, unit.c_str(),
                format_duration(elapsed_s).c_str());
  std::string line = buf;
  if (done > 0 && done < total && elapsed_s >= 1.0)
    line += ", ~" + format_duration(elapsed_s * (1.0 - frac) / frac) + " left";
  return line;
}

ProgressLine::ProgressLine(std::string command, std::string unit, bool enabled)
    : command_(std::move(command)),
      unit_(std::move(unit)),
      enabled_(enabled && isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

ProgressLine::~ProgressLine() {
  finish();
}

void ProgressLine::update(std::size_t done, std::size_t total) {
  done_ = done;
  total_ = total;
  if (!enabled_)
    return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && done < total && now - last_ < std::chrono::milliseconds(250))
    return;
  draw(now);
  if (done >= total)
    finish();
}

void ProgressLine::draw(std::chrono::steady_clock::time_point now) {
  last_ = now;
  const std::string line = format_progress(command_, unit_, done_, total_,
                                           std::chrono::duration<double>(now - start_).count());
  // Padded over the previous line's tail (no terminal escapes: any terminal shows it right).
  const std::size_t pad = width_ > line.size() ? width_ - line.size() : 0;
  std::fprintf(stderr, "\r%s%*s", line.c_str(), static_cast<int>(pad), "");
  std::fflush(stderr);
  width_ = line.size();
  drawn_ = true;
}

void ProgressLine::print_above(const std::string& text) {
  if (!drawn_) {
    std::fputs(text.c_str(), stderr);
    std::fflush(stderr);
    return;
  }
  // Blank the drawn line, print the text from its start, draw the line again below.
  std::fprintf(stderr, "\r%*s\r%s", static_cast<int>(width_), "", text.c_str());
  width_ = 0;
  draw(std::chrono::steady_clock::now());
}

void ProgressLine::finish() {
  if (drawn_)
    std::fputc('\n', stderr);
  drawn_ = false;
  width_ = 0;
}

std::string signal_name(int signal) {
  return signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : std::to_string(signal);
}

int report_interrupted(const std::string& command, int signal, const ProgressLine& progress,
                       const std::string& written) {
  std::fflush(stdout);  // what the command printed first, then the one line (a shared terminal)
  std::fprintf(stderr, "radar-emu: %s: interrupted by %s after %zu of %zu %s; %s\n",
               command.c_str(), signal_name(signal).c_str(), progress.done(), progress.total(),
               progress.unit().c_str(), written.c_str());
  return 128 + signal;
}

}  // namespace radar_emu::config
