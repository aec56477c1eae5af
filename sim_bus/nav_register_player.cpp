#include "sim_bus/nav_register_player.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace radar_emu::sim_bus {

NavRegisterPlayer::NavRegisterPlayer(Trajectory trajectory, const NavPlayerConfig& config)
    : trajectory_(std::move(trajectory)),
      config_(config),
      encoder_(config.map),
      period_ns_(0),
      image_(encoder_.register_count(), 0) {
  if (!(config.rate_hz > 0.0) || !std::isfinite(config.rate_hz) || config.rate_hz > 1e6)
    throw std::invalid_argument("nav register player: rate_hz must be in (0, 1e6] Hz");
  if (image_.size() > io::kModbusMaxWriteRegisters ||
      static_cast<std::size_t>(config.map.base_address) + image_.size() > 65536) {
    throw std::invalid_argument("nav register player: the map does not fit in one write");
  }
  period_ns_ = std::llround(1e9 / config.rate_hz);
}

std::size_t NavRegisterPlayer::publish_until(double time_s, io::RegisterBank& bank) noexcept {
  if (!(time_s >= 0.0) || !std::isfinite(time_s))
    return 0;
  const std::int64_t until_ns = std::llround(time_s * 1e9);
  const std::int64_t due = until_ns / period_ns_;  // newest due update index
  if (due < next_index_)
    return 0;
  skipped_ += static_cast<std::uint64_t>(due - next_index_);
  next_index_ = due + 1;

  const double t_s = static_cast<double>(due * period_ns_) * 1e-9;
  const AircraftState a = trajectory_.at(t_s);
  io::modbus::NavState s;
  s.latitude_rad = a.latitude_rad;
  s.longitude_rad = a.longitude_rad;
  s.height_m = a.height_m;
  s.true_heading_rad = a.true_heading_rad;
  s.pitch_rad = a.pitch_rad;
  s.roll_rad = a.roll_rad;
  s.vel_east_mps = a.vel_east_mps;
  s.vel_north_mps = a.vel_north_mps;
  s.vel_up_mps = a.vel_up_mps;
  // The sender's millisecond clock wraps after 2^32 ms (docs/icd/modbus.md).
  const auto time_ms =
      static_cast<std::uint32_t>(static_cast<std::uint64_t>(std::llround(t_s * 1e3)) & 0xFFFFFFFFu);
  if (!encoder_.encode(s, config_.status, time_ms, image_))
    return 0;  // cannot happen: image_ is sized for the map
  if (bank.write_holding(config_.map.base_address, image_) != io::RegisterStatus::kOk) {
    ++write_failures_;
    return 0;
  }
  ++updates_;
  return 1;
}

}  // namespace radar_emu::sim_bus
