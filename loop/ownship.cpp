#include "loop/ownship.hpp"

#include <algorithm>
#include <cmath>

namespace radar_emu::loop {

namespace {
// Column-major glm: glm::dmat3(c0, c1, c2) takes columns.
glm::dmat3 rot_x(double a) {
  const double c = std::cos(a), s = std::sin(a);
  return glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, c, s), glm::dvec3(0, -s, c));
}
glm::dmat3 rot_y(double a) {
  const double c = std::cos(a), s = std::sin(a);
  return glm::dmat3(glm::dvec3(c, 0, -s), glm::dvec3(0, 1, 0), glm::dvec3(s, 0, c));
}
glm::dmat3 rot_z(double a) {
  const double c = std::cos(a), s = std::sin(a);
  return glm::dmat3(glm::dvec3(c, s, 0), glm::dvec3(-s, c, 0), glm::dvec3(0, 0, 1));
}
}  // namespace

glm::dmat3 anchor_from_local(const scene::wgs84::EnuFrame& anchor,
                             const scene::wgs84::Geodetic& at) noexcept {
  const scene::wgs84::EnuFrame local(at);
  const glm::dvec3 origin = anchor.enu_from_ecef(local.ecef_from_enu(glm::dvec3(0.0)));
  glm::dmat3 r;
  for (int i = 0; i < 3; ++i) {
    glm::dvec3 axis(0.0);
    axis[i] = 1.0;
    r[i] = anchor.enu_from_ecef(local.ecef_from_enu(axis)) - origin;
  }
  return r;
}

EulerAngles euler_from_enu_body(const glm::dmat3& enu_from_body_rotation) noexcept {
  const glm::dmat3 enu_from_ned(glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1));
  const glm::dmat3 m = enu_from_ned * enu_from_body_rotation;  // NED from body (self-inverse)
  // m = Rz(psi) Ry(theta) Rx(phi); glm indexes m[column][row].
  EulerAngles e;
  e.pitch_rad = -std::asin(std::clamp(m[0][2], -1.0, 1.0));
  e.heading_rad = std::atan2(m[0][1], m[0][0]);
  e.roll_rad = std::atan2(m[1][2], m[2][2]);
  return e;
}

glm::dmat3 enu_from_body(double heading_rad, double pitch_rad, double roll_rad) noexcept {
  // NED from body: Rz(psi) Ry(theta) Rx(phi). ENU from NED swaps the first two axes and flips
  // the third: (e, n, u) = (n_y, n_x, -n_z).
  const glm::dmat3 ned_from_body = rot_z(heading_rad) * rot_y(pitch_rad) * rot_x(roll_rad);
  const glm::dmat3 enu_from_ned(glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1));
  return enu_from_ned * ned_from_body;
}

glm::dmat3 body_from_antenna(double depression_rad) noexcept {
  // A nose-down pitch of the antenna by the depression angle.
  return rot_y(-depression_rad);
}

bool radar_pose_from_state(const io::canas::OwnshipState& state, std::int64_t now_ns,
                           std::int64_t timeout_ns, const scene::wgs84::EnuFrame& enu,
                           double depression_rad, radar::RadarPose& pose) noexcept {
  using io::canas::Field;
  if (!state.all_fresh(now_ns, timeout_ns))
    return false;
  const scene::wgs84::Geodetic fix{state[Field::kLatitude].value, state[Field::kLongitude].value,
                                   state[Field::kHeight].value};
  // CANaerospace velocities and attitude refer to the local frame at the aircraft.
  const glm::dmat3 anchor_from_aircraft = anchor_from_local(enu, fix);
  const glm::dvec3 velocity =
      anchor_from_aircraft * glm::dvec3(state[Field::kVelEast].value, state[Field::kVelNorth].value,
                                        state[Field::kVelUp].value);
  // The fix is as old as the oldest of its three fields' reception times.
  const std::int64_t fix_ns =
      std::min({state[Field::kLatitude].updated_ns, state[Field::kLongitude].updated_ns,
                state[Field::kHeight].updated_ns});
  const double dt_s = static_cast<double>(now_ns - fix_ns) * 1e-9;
  pose.position_m = enu.enu_from_geodetic(fix) + velocity * dt_s;
  pose.velocity_mps = velocity;
  pose.world_from_antenna = anchor_from_aircraft *
                            enu_from_body(state[Field::kTrueHeading].value,
                                          state[Field::kPitch].value, state[Field::kRoll].value) *
                            body_from_antenna(depression_rad);
  return true;
}

}  // namespace radar_emu::loop
