#include "loop/peers.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "loop/ownship.hpp"

namespace radar_emu::loop {

namespace {

constexpr std::uint8_t kFaultyNodeId = 99;

sim_bus::PlayerConfig player_config(const Scenario& s) {
  sim_bus::PlayerConfig c;
  c.node_id = s.ins_node_id;
  c.attitude_rate_hz = s.attitude_rate_hz;
  c.navigation_rate_hz = s.navigation_rate_hz;
  c.epoch_ns = s.epoch_unix_ns;
  for (std::size_t k = 0; k < c.can_ids.size(); ++k)
    c.can_ids[k] = s.input.fields[k].can_id;
  return c;
}

}  // namespace

sim_bus::Trajectory ownship_trajectory(const Scenario& s, const scene::wgs84::EnuFrame& enu) {
  const double duration_s = static_cast<double>(s.frames) / s.rate_hz + 2.0;
  const auto samples = static_cast<std::size_t>(std::ceil(duration_s)) + 1;
  const glm::dmat3 anchor_from_body =
      enu_from_body(s.ownship_heading_rad, s.ownship_pitch_rad, s.ownship_roll_rad);
  std::vector<sim_bus::AircraftState> waypoints;
  waypoints.reserve(samples);
  for (std::size_t i = 0; i < samples; ++i) {
    const double t = static_cast<double>(i);
    const glm::dvec3 p = s.ownship_start_enu_m + s.ownship_velocity_enu_mps * t;
    const scene::wgs84::Geodetic g = enu.geodetic_from_enu(p);
    const glm::dmat3 local_from_anchor = glm::transpose(anchor_from_local(enu, g));
    const glm::dvec3 v_local = local_from_anchor * s.ownship_velocity_enu_mps;
    const EulerAngles e = euler_from_enu_body(local_from_anchor * anchor_from_body);
    sim_bus::AircraftState a;
    a.time_s = t;
    a.latitude_rad = g.latitude_rad;
    a.longitude_rad = g.longitude_rad;
    a.height_m = g.height_m;
    a.pitch_rad = e.pitch_rad;
    a.roll_rad = e.roll_rad;
    a.true_heading_rad = e.heading_rad < 0 ? e.heading_rad + 2.0 * std::numbers::pi : e.heading_rad;
    a.vel_east_mps = v_local.x;
    a.vel_north_mps = v_local.y;
    a.vel_up_mps = v_local.z;
    waypoints.push_back(a);
  }
  return sim_bus::Trajectory(std::move(waypoints));
}

Peers::Peers(const Scenario& s, const scene::wgs84::EnuFrame& enu, BusSide& bus, bool replay,
             std::span<const io::CanFrame> replay_input, std::uint64_t max_lists)
    : scenario_(&s),
      bus_(&bus),
      replay_(replay),
      replay_input_(replay_input),
      player_(ownship_trajectory(s, enu), player_config(s)),
      faulty_(kFaultyNodeId),
      sink_(max_lists) {
  ins_out_ = &bus.ins;
  if (s.stale_sender && !replay) {
    sim_bus::StaleConfig c = s.stale;
    c.epoch_ns = s.epoch_unix_ns;
    stale_ins_ = std::make_unique<sim_bus::StaleSender>(bus.ins, c);
    ins_out_ = stale_ins_.get();
  }
  if (s.babbling_node && !replay) {
    sim_bus::BabbleConfig c = s.babble;
    c.epoch_ns = s.epoch_unix_ns;
    babbler_ = std::make_unique<sim_bus::BabblingNode>(c);
  }
}

void Peers::play_navigation(sim_bus::LoopbackRegisterBank& bank,
                            const io::modbus::NavMapConfig& map, double rate_hz) {
  sim_bus::NavPlayerConfig pc;
  pc.map = map;
  pc.rate_hz = rate_hz;
  nav_player_ = std::make_unique<sim_bus::NavRegisterPlayer>(player_.trajectory(), pc);
  nav_bank_ = &bank;
}

void Peers::publish_until(double t_s, std::int64_t bus_now_ns, std::uint64_t frame,
                          RunResult& r) noexcept {
  if (replay_) {
    // The recorded frames the radar had received by now.
    while (replay_next_ < replay_input_.size() &&
           replay_input_[replay_next_].timestamp_ns <= bus_now_ns) {
      if (bus_->replay.send(replay_input_[replay_next_]))
        ++r.replay_frames_fed;
      ++replay_next_;
    }
    return;
  }
  if (silent_)
    return;
  if (nav_player_)
    (void)nav_player_->publish_until(t_s, *nav_bank_);
  (void)player_.publish_until(t_s, *ins_out_);
  if (babbler_)
    (void)babbler_->publish_until(t_s, *bus_->babbler);
  const std::uint64_t every = scenario_->malformed_every_n_frames;
  if (every > 0 && frame % every == 0)
    faulty_.send_next(bus_->faulty, bus_now_ns);
}

void Peers::count(RunResult& r) const {
  if (stale_ins_)
    r.stale_sender = stale_ins_->counters();
  if (babbler_)
    r.babble = babbler_->counters();
  if (replay_)
    r.replay_frames_left = replay_input_.size() - replay_next_;
  r.sink_lists = sink_.lists_completed();
  r.sink_malformed = sink_.decoder().malformed() + sink_.decoder().orphans();
  for (std::size_t k = 0; k < r.injected_malformed.size(); ++k)
    r.injected_malformed[k] = faulty_.sent()[k];
}

}  // namespace radar_emu::loop
