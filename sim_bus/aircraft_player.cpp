#include "sim_bus/aircraft_player.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/units.hpp"

namespace radar_emu::sim_bus {

namespace {

double lerp(double a, double b, double f) {
  return a + (b - a) * f;
}

double lerp_angle(double a, double b, double f) {
  double d = std::remainder(b - a, 2.0 * std::numbers::pi);  // shorter arc, in [-pi, pi]
  double r = a + d * f;
  r = std::fmod(r, 2.0 * std::numbers::pi);
  return r < 0 ? r + 2.0 * std::numbers::pi : r;
}
}  // namespace

Trajectory::Trajectory(std::vector<AircraftState> waypoints) : waypoints_(std::move(waypoints)) {
  if (waypoints_.empty())
    throw std::invalid_argument("trajectory: no waypoints");
  for (std::size_t i = 1; i < waypoints_.size(); ++i) {
    if (!(waypoints_[i].time_s > waypoints_[i - 1].time_s)) {
      throw std::invalid_argument("trajectory: waypoint " + std::to_string(i) +
                                  " time is not after the previous one");
    }
  }
}

AircraftState Trajectory::at(double time_s) const noexcept {
  if (time_s <= waypoints_.front().time_s) {
    AircraftState s = waypoints_.front();
    s.time_s = time_s;
    return s;
  }
  if (time_s >= waypoints_.back().time_s) {
    AircraftState s = waypoints_.back();
    s.time_s = time_s;
    return s;
  }
  std::size_t i = 1;
  while (waypoints_[i].time_s < time_s)
    ++i;
  const AircraftState& a = waypoints_[i - 1];
  const AircraftState& b = waypoints_[i];
  const double f = (time_s - a.time_s) / (b.time_s - a.time_s);
  AircraftState s;
  s.time_s = time_s;
  s.latitude_rad = lerp(a.latitude_rad, b.latitude_rad, f);
  s.longitude_rad = lerp(a.longitude_rad, b.longitude_rad, f);
  s.height_m = lerp(a.height_m, b.height_m, f);
  s.pitch_rad = lerp(a.pitch_rad, b.pitch_rad, f);
  s.roll_rad = lerp(a.roll_rad, b.roll_rad, f);
  s.true_heading_rad = lerp_angle(a.true_heading_rad, b.true_heading_rad, f);
  s.vel_east_mps = lerp(a.vel_east_mps, b.vel_east_mps, f);
  s.vel_north_mps = lerp(a.vel_north_mps, b.vel_north_mps, f);
  s.vel_up_mps = lerp(a.vel_up_mps, b.vel_up_mps, f);
  return s;
}

AircraftStatePlayer::AircraftStatePlayer(Trajectory trajectory, const PlayerConfig& config)
    : trajectory_(std::move(trajectory)), config_(config) {
  if (!(config.attitude_rate_hz > 0.0) || !(config.navigation_rate_hz > 0.0)) {
    throw std::invalid_argument("aircraft player: rates must be > 0 Hz");
  }
  attitude_period_ns_ = std::llround(1e9 / config.attitude_rate_hz);
  navigation_period_ns_ = std::llround(1e9 / config.navigation_rate_hz);
}

std::uint8_t AircraftStatePlayer::next_code(std::uint16_t can_id, std::uint8_t increment) noexcept {
  const std::uint8_t code = message_code_[can_id & 0x7FF];
  message_code_[can_id & 0x7FF] = static_cast<std::uint8_t>(code + increment);
  return code;
}

void AircraftStatePlayer::send(io::CanEndpoint& bus, const io::CanFrame& frame) noexcept {
  if (bus.send(frame)) {
    ++sent_in_call_;
  } else {
    ++send_failures_;
  }
}

std::array<std::uint16_t, io::canas::kFieldCount> default_player_ids() noexcept {
  std::array<std::uint16_t, io::canas::kFieldCount> ids{};
  const auto fields = io::canas::DecoderConfig::default_fields();
  for (std::size_t k = 0; k < ids.size(); ++k)
    ids[k] = fields[k].can_id;
  return ids;
}

void AircraftStatePlayer::publish_attitude(double t_s, io::CanEndpoint& bus) noexcept {
  namespace canas = io::canas;
  using canas::Field;
  auto id_of = [&](Field f) { return config_.can_ids[static_cast<std::size_t>(f)]; };
  const AircraftState s = trajectory_.at(t_s);
  const std::int64_t stamp = config_.epoch_ns + std::llround(t_s * 1e9);
  const std::uint8_t node = config_.node_id;
  auto put = [&](std::uint16_t id, double value_deg) {
    io::CanFrame f = canas::encode_float(id, node, next_code(id), static_cast<float>(value_deg));
    f.timestamp_ns = stamp;
    send(bus, f);
  };
  put(id_of(Field::kPitch), common::degrees(s.pitch_rad));
  put(id_of(Field::kRoll), common::degrees(s.roll_rad));
  put(id_of(Field::kTrueHeading), common::degrees(s.true_heading_rad));
}

void AircraftStatePlayer::publish_navigation(double t_s, io::CanEndpoint& bus) noexcept {
  namespace canas = io::canas;
  using canas::Field;
  auto id_of = [&](Field f) { return config_.can_ids[static_cast<std::size_t>(f)]; };
  const AircraftState s = trajectory_.at(t_s);
  const std::int64_t stamp = config_.epoch_ns + std::llround(t_s * 1e9);
  const std::uint8_t node = config_.node_id;
  auto put_double = [&](std::uint16_t id, double value) {
    auto [high, low] = canas::encode_double(id, node, next_code(id, 2), value);
    high.timestamp_ns = stamp;
    low.timestamp_ns = stamp;
    send(bus, high);
    send(bus, low);
  };
  auto put_float = [&](std::uint16_t id, double value) {
    io::CanFrame f = canas::encode_float(id, node, next_code(id), static_cast<float>(value));
    f.timestamp_ns = stamp;
    send(bus, f);
  };
  put_double(id_of(Field::kLatitude), common::degrees(s.latitude_rad));
  put_double(id_of(Field::kLongitude), common::degrees(s.longitude_rad));
  put_float(id_of(Field::kHeight), s.height_m);
  put_float(id_of(Field::kVelEast), s.vel_east_mps);
  put_float(id_of(Field::kVelNorth), s.vel_north_mps);
  put_float(id_of(Field::kVelUp), s.vel_up_mps);
}

std::size_t AircraftStatePlayer::publish_until(double time_s, io::CanEndpoint& bus) noexcept {
  sent_in_call_ = 0;
  const std::int64_t until_ns = std::llround(time_s * 1e9);
  // Interleave the two schedules in time order (attitude first on ties) so the bus sees the
  // frames in the order a real node would send them.
  for (;;) {
    const auto att_ns = static_cast<std::int64_t>(attitude_index_) * attitude_period_ns_;
    const auto nav_ns = static_cast<std::int64_t>(navigation_index_) * navigation_period_ns_;
    const std::int64_t next_ns = std::min(att_ns, nav_ns);
    if (next_ns > until_ns)
      break;
    if (att_ns <= nav_ns) {
      publish_attitude(static_cast<double>(att_ns) * 1e-9, bus);
      ++attitude_index_;
    } else {
      publish_navigation(static_cast<double>(nav_ns) * 1e-9, bus);
      ++navigation_index_;
    }
  }
  return sent_in_call_;
}

}  // namespace radar_emu::sim_bus
