#pragma once
// Scripted aircraft-state player: publishes CANaerospace frames from a trajectory, on the
// schedule of the spec's baseline (CANaerospace v1.7: attitude every 12.5 ms, navigation data
// every 100 ms; both configurable). Latitude and longitude go out as DOUBLEH/DOUBLEL pairs,
// everything else as FLOAT.

#include <array>
#include <cstdint>
#include <vector>

#include "io/can_frame.hpp"
#include "io/canaerospace.hpp"

namespace radar_emu::sim_bus {

/// Aircraft state at one time (SI units; the player converts to the bus's degrees).
struct AircraftState {
  double time_s = 0.0;        ///< scenario time
  double latitude_rad = 0.0;  ///< WGS84
  double longitude_rad = 0.0;
  double height_m = 0.0;  ///< above the WGS84 ellipsoid
  double pitch_rad = 0.0;
  double roll_rad = 0.0;
  double true_heading_rad = 0.0;
  double vel_east_mps = 0.0;
  double vel_north_mps = 0.0;
  double vel_up_mps = 0.0;
};

/// Linear interpolation between waypoints sorted by time (held constant outside them; headings
/// interpolated along the shorter arc).
class Trajectory {
 public:
  /// Throws std::invalid_argument if empty or times not strictly increasing (setup).
  explicit Trajectory(std::vector<AircraftState> waypoints);
  [[nodiscard]] AircraftState at(double time_s) const noexcept;

 private:
  std::vector<AircraftState> waypoints_;
};

/// The identifier of each ownship field (io::canas::Field order): by default the decoder's
/// default table (CANaerospace v1.7 appendix A).
[[nodiscard]] std::array<std::uint16_t, io::canas::kFieldCount> default_player_ids() noexcept;

struct PlayerConfig {
  std::uint8_t node_id = 1;          ///< CANaerospace node-ID of the simulated INS/GPS
  double attitude_rate_hz = 80.0;    ///< pitch, roll, true heading
  double navigation_rate_hz = 10.0;  ///< latitude, longitude, height, velocities
  std::int64_t epoch_ns = 0;         ///< bus time stamp of scenario time 0 [ns]
  /// Identifier per field, as the radar's decoder is configured to read them.
  std::array<std::uint16_t, io::canas::kFieldCount> can_ids = default_player_ids();
};

class AircraftStatePlayer {
 public:
  AircraftStatePlayer(Trajectory trajectory, const PlayerConfig& config);

  /// Publishes every message due at scenario times <= `time_s` that has not been published
  /// yet, each carrying the state at its own due time and stamped with it. Returns the number of
  /// frames sent. Real-time safe.
  std::size_t publish_until(double time_s, io::CanEndpoint& bus) noexcept;

  [[nodiscard]] const Trajectory& trajectory() const noexcept { return trajectory_; }
  [[nodiscard]] std::uint64_t send_failures() const noexcept { return send_failures_; }

 private:
  void send(io::CanEndpoint& bus, const io::CanFrame& frame) noexcept;
  void publish_attitude(double t_s, io::CanEndpoint& bus) noexcept;
  void publish_navigation(double t_s, io::CanEndpoint& bus) noexcept;
  std::uint8_t next_code(std::uint16_t can_id, std::uint8_t increment = 1) noexcept;

  Trajectory trajectory_;
  PlayerConfig config_;
  std::int64_t attitude_period_ns_;
  std::int64_t navigation_period_ns_;
  std::uint64_t attitude_index_ = 0;
  std::uint64_t navigation_index_ = 0;
  std::array<std::uint8_t, 2048> message_code_{};  ///< next message code per 11-bit identifier
  std::uint64_t send_failures_ = 0;
  std::size_t sent_in_call_ = 0;
};

}  // namespace radar_emu::sim_bus
