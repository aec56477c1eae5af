#pragma once
// Ground truth of a run: where each scene object really is, seen from the radar, frame by frame
// (truth.json), to score the detections against.

#include <cstdint>
#include <glm/glm.hpp>

#include "radar/em/sbr.hpp"

namespace radar_emu::emulator {

/// One object at one frame, in the antenna frame.
struct ObjectTruth {
  std::uint32_t object_id = 0;       ///< index into scene::Scene::objects()
  double range_m = 0.0;              ///< antenna phase centre to the object's reference point
  double azimuth_rad = 0.0;          ///< radar::azel_from_direction: positive right of boresight
  double elevation_rad = 0.0;        ///< positive up
  double radial_velocity_mps = 0.0;  ///< range rate of the point, + receding (ownship included)
};

/// Truth of a point at `point_m` moving at `velocity_mps` (world ENU) seen from `pose`:
/// range |p - r|, the direction d = (p - r) / |p - r| rotated into the antenna frame
/// (world_from_antenna transposed) and converted by radar::azel_from_direction, and the range
/// rate (v - v_radar) . d. Real-time safe. A point at the antenna gives range 0, angles 0.
[[nodiscard]] ObjectTruth point_truth(const radar::RadarPose& pose, const glm::dvec3& point_m,
                                      const glm::dvec3& velocity_mps) noexcept;

}  // namespace radar_emu::emulator
