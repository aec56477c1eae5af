#pragma once
// An in-process bank of Modbus holding registers: the scripted peers write it, the radar reads
// it, as a Modbus device's register table would be read over the wire, but without the wire.
// Single-threaded and deterministic; never blocks.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "io/register_bank.hpp"

namespace radar_emu::sim_bus {

struct LoopbackRegisterCounters {
  std::uint64_t reads = 0;            ///< read_holding calls answered kOk
  std::uint64_t writes = 0;           ///< write_holding calls answered kOk
  std::uint64_t illegal_address = 0;  ///< outside the bank (Modbus exception 2)
  std::uint64_t bad_quantity = 0;     ///< 0 or more than one request may carry (exception 3)
};

/// Registers [start_address, start_address + count), all zero at start. Every call checks its
/// range as a Modbus server would (application protocol v1.1b3, sec. 6.3 and 6.12): quantity
/// 1..125 to read, 1..123 to write (else kError), the whole range inside the bank (else
/// kIllegalAddress). Not thread-safe: use it from one thread (the frame loop).
class LoopbackRegisterBank final : public io::RegisterBank {
 public:
  /// Throws std::invalid_argument if count is 0 or the bank passes address 65535 (setup).
  LoopbackRegisterBank(std::uint16_t start_address, std::size_t count);

  /// Real-time safe.
  [[nodiscard]] io::RegisterStatus read_holding(std::uint16_t address,
                                                std::span<std::uint16_t> out) noexcept override;
  /// Real-time safe.
  [[nodiscard]] io::RegisterStatus write_holding(
      std::uint16_t address, std::span<const std::uint16_t> values) noexcept override;

  [[nodiscard]] std::uint16_t start_address() const noexcept { return start_; }
  /// The whole bank, from start_address().
  [[nodiscard]] std::span<const std::uint16_t> registers() const noexcept { return regs_; }
  [[nodiscard]] const LoopbackRegisterCounters& counters() const noexcept { return counters_; }

 private:
  io::RegisterStatus check(std::uint16_t address, std::size_t n, std::size_t max_n) noexcept;

  std::uint16_t start_;
  std::vector<std::uint16_t> regs_;
  LoopbackRegisterCounters counters_{};
};

}  // namespace radar_emu::sim_bus
