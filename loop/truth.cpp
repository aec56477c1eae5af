#include "loop/truth.hpp"

#include <cmath>

namespace radar_emu::loop {

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

std::size_t objects_in_view(const radar::RadarPose& pose,
                            std::span<const scene::ObjectState> states,
                            std::span<const std::uint32_t> ids, const radar::SbrConfig& fov,
                            std::span<ObjectTruth> out) noexcept {
  std::size_t n = 0;
  for (std::uint32_t id : ids) {
    if (n == out.size())
      break;
    if (id >= states.size())
      continue;
    const scene::ObjectState& st = states[id];
    ObjectTruth t = point_truth(pose, 0.5 * (st.bounds_min_m + st.bounds_max_m), st.velocity_mps);
    if (t.range_m > fov.max_range_m || t.azimuth_rad < fov.azimuth_min_rad ||
        t.azimuth_rad > fov.azimuth_max_rad || t.elevation_rad < fov.elevation_min_rad ||
        t.elevation_rad > fov.elevation_max_rad) {
      continue;
    }
    t.object_id = id;
    out[n++] = t;
  }
  return n;
}

}  // namespace radar_emu::loop
