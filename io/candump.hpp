#pragma once
// candump log format (can-utils, `candump -L`): one frame per line,
//   "(1700000000.123456) can0 123#DEADBEEF"   classic, 11-bit id as 3 hex digits
//   "(1700000000.123456) can0 1ABCDEF0#00"     29-bit id as 8 hex digits
//   "(1700000000.123456) can0 123##1DEADBEEF"  CAN FD, the nibble after "##" holds the flags
// Readers: python-can's CanutilsLogReader, can-utils' canplayer.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/can_frame.hpp"

namespace radar_emu::io {

/// Longest line format_candump() can produce, including the terminating '\n'.
inline constexpr std::size_t kCandumpMaxLine = 200;

/// Formats `frame` as one candump line ending in '\n' into `out` (no allocation). The time stamp
/// is frame.timestamp_ns printed as seconds with microseconds. Returns the characters written,
/// or 0 when `out` is too small or the interface name is empty or longer than 15 characters.
[[nodiscard]] std::size_t format_candump(const CanFrame& frame, std::string_view interface_name,
                                         std::span<char> out) noexcept;

struct CandumpLine {
  CanFrame frame{};
  std::string interface_name;
};

/// Parses one candump line (trailing '\n'/'\r' allowed). Returns false and sets `error` (one
/// line, no newline) for anything malformed; never throws on bad input.
[[nodiscard]] bool parse_candump(std::string_view line, CandumpLine& out, std::string& error);

/// Records frames in memory during a run (capacity reserved up front; record() never allocates)
/// and writes them as a candump log afterwards.
class CandumpRecorder {
 public:
  CandumpRecorder(std::string interface_name, std::size_t capacity_frames);
  /// Real-time safe. False (and counted) when the reserved capacity is exhausted.
  bool record(const CanFrame& frame) noexcept;
  [[nodiscard]] std::size_t size() const noexcept { return frames_.size(); }
  [[nodiscard]] std::uint64_t overflowed() const noexcept { return overflowed_; }
  [[nodiscard]] std::span<const CanFrame> frames() const noexcept { return frames_; }
  /// Writes the log. Throws std::runtime_error naming the path on failure (setup/teardown only).
  void write_file(const std::filesystem::path& path) const;

 private:
  std::string interface_name_;
  std::vector<CanFrame> frames_;
  std::size_t capacity_;
  std::uint64_t overflowed_ = 0;
};

/// Reads a whole candump log. Throws std::runtime_error "FILE:LINE: reason" on the first bad line.
[[nodiscard]] std::vector<CandumpLine> read_candump_file(const std::filesystem::path& path);

}  // namespace radar_emu::io
