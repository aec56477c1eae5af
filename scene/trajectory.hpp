#pragma once
// Waypoint trajectories (scene::Trajectory, types.hpp) precomputed at setup into straight legs and
// circular arcs, then evaluated at any time without allocation (binary search over the pieces).
//
// Geometry: at every inner waypoint W (every waypoint of a loop) the incoming direction d_in and
// the outgoing d_out are joined by an arc of radius r tangent to both legs, in their common plane
// (a fillet): it turns by theta = acos(d_in . d_out), starts and ends at the tangent length
// T = r tan(theta / 2) from W and has length r theta. (Derivation: the centre C, a tangent point
// A and W form a right triangle with the right angle at A, |CA| = r, and the angle at C is half
// the angle turned, theta / 2, since CA and CB are perpendicular to d_in and d_out; so
// |AW| = r tan(theta / 2).) Legs are the straight pieces between tangent points.

#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

#include "scene/types.hpp"

namespace radar_emu::scene {

/// Standard acceleration of gravity [m/s^2] (3rd CGPM, 1901; ISO 80000-3), for banked turns.
inline constexpr double kStandardGravity_mps2 = 9.80665;

/// Where a trajectory puts the body at one time.
struct TrajectorySample {
  glm::dvec3 position_m{0.0};    ///< world position of the body origin [m]
  glm::dvec3 velocity_mps{0.0};  ///< world velocity [m/s] (0 at rest beyond an open path's ends)
  /// Rotation world from body: columns body x (along the path), y (left), z (up).
  glm::dmat3 world_from_body{1.0};
  double path_m = 0.0;        ///< arc length from the start of the path (of the lap, loops) [m]
  std::uint32_t segment = 0;  ///< index into TrajectoryPath::segments()
  bool on_arc = false;
};

/// One piece of a precomputed trajectory: a straight leg or a circular arc.
struct TrajectorySegment {
  bool arc = false;
  double start_m = 0.0;                       ///< arc length of the path at its start [m]
  double length_m = 0.0;                      ///< [m], > 0
  glm::dvec3 start_position_m{0.0};           ///< [m]
  glm::dvec3 start_direction{1.0, 0.0, 0.0};  ///< unit tangent at the start
  glm::dvec3 centre_m{0.0};                   ///< arcs: turn centre [m]
  double radius_m = 0.0;                      ///< arcs: [m]
  glm::dvec3 centre_to_start{0.0};            ///< arcs: unit vector from the centre to the start
  double turn_rad = 0.0;                      ///< arcs: angle turned [rad], in (0, pi)
  double roll_rad = 0.0;                      ///< roll about body x on this piece [rad]
  glm::dvec3 fallback_left{0.0, 1.0, 0.0};    ///< body y if the tangent is vertical
};

class TrajectoryPath {
 public:
  /// Setup: precomputes the legs and arcs. Throws std::invalid_argument("trajectory: ...") for
  /// fewer than 2 waypoints, non-finite values, speed <= 0, a negative radius or rate, both a
  /// radius and a rate, coincident consecutive waypoints, a vertical leg, a reversal (U-turn) at
  /// a waypoint with a turn radius, or a radius too large for a leg (its two tangent lengths
  /// exceed it).
  explicit TrajectoryPath(const Trajectory& trajectory);

  /// The body at time `t_s` [s] (non-finite: as t = 0). Loops wrap modulo duration_s(); open
  /// paths rest (velocity 0) at their first waypoint for t < 0 and at the last for
  /// t > duration_s(). Real-time safe (no allocation; O(log segments)).
  [[nodiscard]] TrajectorySample at(double t_s) const noexcept;

  [[nodiscard]] double length_m() const noexcept { return length_m_; }  ///< one lap [m]
  [[nodiscard]] double duration_s() const noexcept { return length_m_ / speed_mps_; }
  [[nodiscard]] double speed_mps() const noexcept { return speed_mps_; }
  [[nodiscard]] double turn_radius_m() const noexcept { return radius_m_; }  ///< 0: corners
  [[nodiscard]] bool loop() const noexcept { return loop_; }
  [[nodiscard]] std::span<const TrajectorySegment> segments() const noexcept { return segments_; }

 private:
  std::vector<TrajectorySegment> segments_;
  std::vector<double> starts_m_;  // segments_[i].start_m, for the binary search
  double length_m_ = 0.0;
  double speed_mps_ = 0.0;
  double radius_m_ = 0.0;
  bool loop_ = false;
};

}  // namespace radar_emu::scene
