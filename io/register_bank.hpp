#pragma once
// A block of 16-bit Modbus holding registers, reached over some transport: the sim_bus loopback
// register bank, or a Modbus TCP/RTU client (io/modbus.hpp). Addresses are protocol addresses
// (0-based); the "40001"-style numbers of device manuals are 1-based (docs/icd/modbus.md).

#include <cstddef>
#include <cstdint>
#include <span>

namespace radar_emu::io {

/// Most registers one Modbus "read holding registers" request may return (Modbus application
/// protocol v1.1b3, sec. 6.3: 1 to 125).
inline constexpr std::size_t kModbusMaxReadRegisters = 125;
/// Most registers one "write multiple registers" request may carry (sec. 6.12: 1 to 123).
inline constexpr std::size_t kModbusMaxWriteRegisters = 123;

/// Outcome of one register transaction.
enum class RegisterStatus : std::uint8_t {
  kOk = 0,
  kTimeout,         ///< no answer in time (counted; the caller keeps its last state)
  kDisconnected,    ///< transport down (the backend reconnects by itself)
  kIllegalAddress,  ///< outside the bank (Modbus exception 2)
  kError,           ///< any other failure (Modbus exception or transport error)
};

/// Holding registers. Implementations say whether their calls block: the loopback bank never
/// does; a network client does and must be driven from a non-real-time thread.
class RegisterBank {
 public:
  virtual ~RegisterBank() = default;
  /// Reads `out.size()` (1..kModbusMaxReadRegisters) registers starting at `address`.
  [[nodiscard]] virtual RegisterStatus read_holding(std::uint16_t address,
                                                    std::span<std::uint16_t> out) noexcept = 0;
  /// Writes `values` (1..kModbusMaxWriteRegisters registers) starting at `address`.
  [[nodiscard]] virtual RegisterStatus write_holding(
      std::uint16_t address, std::span<const std::uint16_t> values) noexcept = 0;
};

}  // namespace radar_emu::io
