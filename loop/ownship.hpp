#pragma once
// From the decoded CANaerospace ownship state to the radar's pose in the scene's ENU frame.
//
// Frames (docs/architecture.md): world = ENU of the scene anchor; body = x forward, y right,
// z down; attitude as yaw (true heading) - pitch - roll, body from NED by Rz(heading) Ry(pitch)
// Rx(roll) (the aerospace convention, e.g. Stevens & Lewis, Aircraft Control and Simulation,
// sec. 1.3); the antenna is the body frame pitched down by the mount depression.

#include <cstdint>
#include <glm/glm.hpp>

#include "io/canaerospace.hpp"
#include "radar/em/sbr.hpp"
#include "scene/geo.hpp"

namespace radar_emu::loop {

/// World (ENU) from body rotation for the given Euler angles [rad].
[[nodiscard]] glm::dmat3 enu_from_body(double heading_rad, double pitch_rad,
                                       double roll_rad) noexcept;

/// Rotation from the local ENU frame at `at` to the anchor's ENU frame `anchor`: the two differ
/// by the meridian convergence and the tilt of the vertical (about 1.6e-4 rad per km), which
/// matters for sub-cell ranges and angles at several km.
[[nodiscard]] glm::dmat3 anchor_from_local(const scene::wgs84::EnuFrame& anchor,
                                           const scene::wgs84::Geodetic& at) noexcept;

struct EulerAngles {
  double heading_rad = 0.0;
  double pitch_rad = 0.0;
  double roll_rad = 0.0;
};
/// Inverse of enu_from_body() (pitch within +-90 deg).
[[nodiscard]] EulerAngles euler_from_enu_body(const glm::dmat3& enu_from_body_rotation) noexcept;

/// Antenna frame (x boresight, y right, z down) in body axes: pitched down by `depression_rad`.
[[nodiscard]] glm::dmat3 body_from_antenna(double depression_rad) noexcept;

/// Computes the radar pose at `now_ns` from `state`. Position is extrapolated from the time of
/// the last position fix with the decoded velocity (the navigation data arrive at 10 Hz; the
/// radar runs faster). Returns false (and leaves `pose` unspecified) when any field is missing
/// or older than `timeout_ns`. Real-time safe.
[[nodiscard]] bool radar_pose_from_state(const io::canas::OwnshipState& state, std::int64_t now_ns,
                                         std::int64_t timeout_ns, const scene::wgs84::EnuFrame& enu,
                                         double depression_rad, radar::RadarPose& pose) noexcept;

}  // namespace radar_emu::loop
