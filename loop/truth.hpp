#pragma once
// Ground truth of a run: where each scene object really is, seen from the radar, frame by frame
// (truth.json), to score the detections against.

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>

#include "radar/em/sbr.hpp"
#include "scene/types.hpp"

namespace radar_emu::loop {

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

/// Ground truth of one frame: of the objects `ids` (indices into `states`), those whose
/// reference point, the centre of the world bounding box, is inside the field of view of `fov`
/// (azimuth and elevation limits, antenna frame) and within its max_range_m. Written to `out` in
/// `ids` order, at most out.size() of them; returns how many. Real-time safe.
[[nodiscard]] std::size_t objects_in_view(const radar::RadarPose& pose,
                                          std::span<const scene::ObjectState> states,
                                          std::span<const std::uint32_t> ids,
                                          const radar::SbrConfig& fov,
                                          std::span<ObjectTruth> out) noexcept;

}  // namespace radar_emu::loop
