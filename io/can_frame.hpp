#pragma once
// A CAN or CAN FD frame as it travels through radar-emu, and the endpoint interface that every
// bus backend (sim_bus loopback, SocketCAN, gs_usb, log replay) implements.

#include <array>
#include <cstddef>
#include <cstdint>

namespace radar_emu::io {

inline constexpr std::size_t kCanClassicMaxBytes = 8;
inline constexpr std::size_t kCanFdMaxBytes = 64;

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
