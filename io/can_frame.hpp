#pragma once
// A CAN or CAN FD frame as it travels through radar-emu, and the endpoint interface that every
// bus backend (sim_bus loopback, SocketCAN, gs_usb, log replay) implements.

#include <array>
#include <cstddef>
#include <cstdint>

namespace radar_emu::io {

inline constexpr std::size_t kCanClassicMaxBytes = 8;
inline constexpr std::size_t kCanFdMaxBytes = 64;

/// True when `n` bytes is a payload length a CAN FD frame can carry: 0..8, 12, 16, 20, 24, 32, 48
/// or 64 (the DLC codes 0..15, ISO 11898-1:2015 table 5).
[[nodiscard]] constexpr bool is_can_fd_length(std::size_t n) noexcept {
  return n <= 8 || n == 12 || n == 16 || n == 20 || n == 24 || n == 32 || n == 48 || n == 64;
}

/// One frame. Plain value type; copying it never allocates.
struct CanFrame {
  std::uint32_t id = 0;       ///< 11-bit (standard) or 29-bit (extended) identifier
  std::uint8_t len = 0;       ///< payload length in bytes: 0..8 classic, 0..64 FD
  bool extended = false;      ///< 29-bit identifier
  bool fd = false;            ///< CAN FD frame
  std::uint8_t fd_flags = 0;  ///< CAN FD flags as in candump's "##F" nibble (BRS = 1, ESI = 2)
  std::array<std::uint8_t, kCanFdMaxBytes> data{};  ///< payload; bytes past len are zero
  std::int64_t timestamp_ns = 0;  ///< time of transmission/reception on the run's clock [ns]
};

/// A node's connection to a CAN bus. Both calls are non-blocking and real-time safe
/// (no allocation, no locks held across I/O, no exceptions).
class CanEndpoint {
 public:
  virtual ~CanEndpoint() = default;
  /// Queues `frame` for transmission. False when the bus or its queue cannot take it (counted by
  /// the backend).
  [[nodiscard]] virtual bool send(const CanFrame& frame) noexcept = 0;
  /// Takes the oldest pending received frame into `out`. False when nothing is pending.
  [[nodiscard]] virtual bool receive(CanFrame& out) noexcept = 0;
};

}  // namespace radar_emu::io
