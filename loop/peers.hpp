#pragma once
// The simulated peers on the software buses: the scripted INS (CANaerospace on the CAN loopback,
// or the navigation register map on the loopback register bank), its stale sending side, a
// babbling node, the node that sends malformed frames, the replay of a recorded input log, and
// the avionics that read the radar's lists. They act at the start of each frame, before the
// radar reads its inputs; on a real bus they are silent.
//
// Units: scenario time [s], bus time [ns]. Setup throws with context; publish_until() and
// poll_avionics() are real-time safe.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "io/can_frame.hpp"
#include "io/modbus_map.hpp"
#include "loop/bus_side.hpp"
#include "loop/frame_record.hpp"
#include "loop/scenario.hpp"
#include "scene/geo.hpp"
#include "sim_bus/aircraft_player.hpp"
#include "sim_bus/avionics_sink.hpp"
#include "sim_bus/fault_injector.hpp"
#include "sim_bus/faulty_node.hpp"
#include "sim_bus/loopback_registers.hpp"
#include "sim_bus/nav_register_player.hpp"

namespace radar_emu::loop {

/// The scripted ownship: the scenario's straight line in anchor ENU, sampled every second as the
/// INS would report it (geodetic position; velocity and attitude in the local ENU frame).
[[nodiscard]] sim_bus::Trajectory ownship_trajectory(const Scenario& s,
                                                     const scene::wgs84::EnuFrame& enu);

class Peers {
 public:
  /// Setup: the peers of `scenario` on `bus` (which must outlive them). In a replay the
  /// `replay_input` frames (which must outlive the peers) replace the INS and the faulty node.
  /// `max_lists`: the lists the avionics keep.
  Peers(const Scenario& scenario, const scene::wgs84::EnuFrame& enu, BusSide& bus, bool replay,
        std::span<const io::CanFrame> replay_input, std::uint64_t max_lists);
  /// Setup: the INS also plays the navigation register map into `bank` (which must outlive it).
  void play_navigation(sim_bus::LoopbackRegisterBank& bank, const io::modbus::NavMapConfig& map,
                       double rate_hz);
  /// Setup: a real bus (hardware CAN or an external navigation source): the scripted peers stay
  /// silent.
  void silence() noexcept { silent_ = true; }

  /// Frame path: everything due by scenario time `t_s` [s] (bus time `bus_now_ns` [ns]) of frame
  /// number `frame` goes on the software buses. Counts replayed frames into `r`.
  void publish_until(double t_s, std::int64_t bus_now_ns, std::uint64_t frame,
                     RunResult& r) noexcept;
  /// Frame path: the avionics under test read what the radar sent.
  void poll_avionics() noexcept { (void)sink_.poll(bus_->avionics); }
  /// End of run: the peers' counters into `r`.
  void count(RunResult& r) const;

 private:
  const Scenario* scenario_;
  BusSide* bus_;
  bool replay_;
  bool silent_ = false;
  std::span<const io::CanFrame> replay_input_;
  std::size_t replay_next_ = 0;  ///< next frame of replay_input_ to put on the bus
  sim_bus::AircraftStatePlayer player_;
  sim_bus::FaultyNode faulty_;
  std::unique_ptr<sim_bus::StaleSender> stale_ins_;  ///< the INS's sending side, when stale
  std::unique_ptr<sim_bus::BabblingNode> babbler_;
  sim_bus::AvionicsSink sink_;
  std::unique_ptr<sim_bus::NavRegisterPlayer> nav_player_;  ///< the register map, when played
  sim_bus::LoopbackRegisterBank* nav_bank_ = nullptr;
  io::CanEndpoint* ins_out_ = nullptr;  ///< bound at setup: the INS endpoint or its stale side
};

}  // namespace radar_emu::loop
