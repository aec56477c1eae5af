#pragma once
// Scripted navigation device with a Modbus interface: writes the navigation register map
// (docs/icd/modbus.md) from a trajectory at a fixed update rate into any RegisterBank, the
// in-process LoopbackRegisterBank or a ModbusServer's table (io/modbus.hpp).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "io/modbus_map.hpp"
#include "io/register_bank.hpp"
#include "sim_bus/aircraft_player.hpp"

namespace radar_emu::sim_bus {

struct NavPlayerConfig {
  io::modbus::NavMapConfig map{};                            ///< base address, word order, encoding
  double rate_hz = 50.0;                                     ///< state updates per second (> 0)
  std::uint16_t status = io::modbus::nav_status::kAllValid;  ///< status word sent
};

class NavRegisterPlayer {
 public:
  /// Throws std::invalid_argument on a rate that is not > 0 or a map that does not fit in one
  /// write (setup).
  NavRegisterPlayer(Trajectory trajectory, const NavPlayerConfig& config);

  /// Writes the newest update due at a scenario time <= `time_s` (due times k / rate_hz),
  /// carrying the trajectory's state at that due time and a time stamp of round(due * 1000) ms.
  /// Older due updates not yet written are skipped (counted), never replayed: the registers
  /// only hold the latest state. Returns 1 if it wrote, else 0. Real-time safe when the bank's
  /// write_holding is.
  std::size_t publish_until(double time_s, io::RegisterBank& bank) noexcept;

  [[nodiscard]] const Trajectory& trajectory() const noexcept { return trajectory_; }
  /// Update counter of the last image written.
  [[nodiscard]] std::uint16_t update_counter() const noexcept { return encoder_.update_counter(); }
  [[nodiscard]] std::uint64_t updates() const noexcept { return updates_; }
  [[nodiscard]] std::uint64_t skipped_updates() const noexcept { return skipped_; }
  [[nodiscard]] std::uint64_t write_failures() const noexcept { return write_failures_; }

 private:
  Trajectory trajectory_;
  NavPlayerConfig config_;
  io::modbus::NavEncoder encoder_;
  std::int64_t period_ns_;
  std::int64_t next_index_ = 0;
  std::vector<std::uint16_t> image_;
  std::uint64_t updates_ = 0;
  std::uint64_t skipped_ = 0;
  std::uint64_t write_failures_ = 0;
};

}  // namespace radar_emu::sim_bus
