#include "sim_bus/loopback_registers.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace radar_emu::sim_bus {

LoopbackRegisterBank::LoopbackRegisterBank(std::uint16_t start_address, std::size_t count)
    : start_(start_address) {
  if (count == 0 || static_cast<std::size_t>(start_address) + count > 65536) {
    throw std::invalid_argument("loopback register bank: " + std::to_string(count) +
                                " registers from address " + std::to_string(start_address) +
                                " (expected 1 .. 65536 - start)");
  }
  regs_.assign(count, 0);
}

io::RegisterStatus LoopbackRegisterBank::check(std::uint16_t address, std::size_t n,
                                               std::size_t max_n) noexcept {
  if (n == 0 || n > max_n) {
    ++counters_.bad_quantity;
    return io::RegisterStatus::kError;
  }
  if (address < start_ || static_cast<std::size_t>(address - start_) + n > regs_.size()) {
    ++counters_.illegal_address;
    return io::RegisterStatus::kIllegalAddress;
  }
  return io::RegisterStatus::kOk;
}

io::RegisterStatus LoopbackRegisterBank::read_holding(std::uint16_t address,
                                                      std::span<std::uint16_t> out) noexcept {
  const io::RegisterStatus s = check(address, out.size(), io::kModbusMaxReadRegisters);
  if (s != io::RegisterStatus::kOk)
    return s;
  const auto from = regs_.begin() + (address - start_);
  std::copy(from, from + static_cast<std::ptrdiff_t>(out.size()), out.begin());
  ++counters_.reads;
  return s;
}

io::RegisterStatus LoopbackRegisterBank::write_holding(
    std::uint16_t address, std::span<const std::uint16_t> values) noexcept {
  const io::RegisterStatus s = check(address, values.size(), io::kModbusMaxWriteRegisters);
  if (s != io::RegisterStatus::kOk)
    return s;
  std::copy(values.begin(), values.end(), regs_.begin() + (address - start_));
  ++counters_.writes;
  return s;
}

}  // namespace radar_emu::sim_bus
