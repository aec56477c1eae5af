#include "emulator/truth.hpp"

#include <cmath>

namespace radar_emu::emulator {

ObjectTruth point_truth(const radar::RadarPose& pose, const glm::dvec3& point_m,
                        const glm::dvec3& velocity_mps) noexcept {
  ObjectTruth t;
  const glm::dvec3 d = point_m - pose.position_m;
  t.range_m = glm::length(d);
  if (!(t.range_m > 0.0))
    return t;
  const glm::dvec3 u = d / t.range_m;
  // world_from_antenna is a rotation: its transpose takes world vectors into the antenna frame.
  const radar::AzEl a = radar::azel_from_direction(glm::transpose(pose.world_from_antenna) * u);
  t.azimuth_rad = a.azimuth_rad;
  t.elevation_rad = a.elevation_rad;
  // d(range)/dt = (v_point - v_radar) . u (the derivative of |p - r|).
  t.radial_velocity_mps = glm::dot(velocity_mps - pose.velocity_mps, u);
  return t;
}

}  // namespace radar_emu::emulator
