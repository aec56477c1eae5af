#pragma once
// A faulty CANaerospace node for tests and demonstrations: sends one malformed frame per call,
// cycling through the kinds a decoder must reject (CANaerospace v1.7 message format violated or
// values impossible). Issue 6's seeded fault injector generalises this.

#include <array>
#include <cstdint>

#include "io/can_frame.hpp"

namespace radar_emu::sim_bus {

enum class MalformedKind : std::uint8_t {
  kShortDlc = 0,     ///< DLC 3: not even the 4-byte header
  kUnknownDataType,  ///< data type 77 (reserved range 32..99)
  kNotANumber,       ///< FLOAT quiet NaN on pitch
  kOutOfRange,       ///< FLOAT latitude 123 deg
  kCount
};
inline constexpr std::size_t kMalformedKindCount = static_cast<std::size_t>(MalformedKind::kCount);

class FaultyNode {
 public:
  explicit FaultyNode(std::uint8_t node_id) noexcept : node_id_(node_id) {}
  /// Sends the next malformed frame, stamped `timestamp_ns`. Real-time safe.
  void send_next(io::CanEndpoint& bus, std::int64_t timestamp_ns) noexcept;
  /// Frames sent of each kind.
  [[nodiscard]] const std::array<std::uint64_t, kMalformedKindCount>& sent() const noexcept {
    return sent_;
  }

 private:
  std::uint8_t node_id_;
  std::size_t next_ = 0;
  std::uint8_t message_code_ = 0;
  std::array<std::uint64_t, kMalformedKindCount> sent_{};
};

}  // namespace radar_emu::sim_bus
