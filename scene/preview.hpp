#pragma once
// Optical preview of a scene: one primary ray per pixel through Scene::intersect, Lambertian
// shading of each material's base colour under a fixed sun plus ambient light, a constant sky
// for rays that miss, and distance haze. For looking at generated scenes, not for physics.
//
// Pixel colour (linear RGB, then sRGB-encoded to 8 bits, IEC 61966-2-1):
//   hit:  c = base_color * (kAmbient + kDiffuse * max(0, n . sun)), with n the hit's geometric
//         normal turned toward the camera; then haze c' = c T + kSky (1 - T), T = exp(-t beta),
//         beta = 3.912 / kVisibility_m (Koschmieder: the range at which contrast falls to 2 %),
//         t the hit distance
//   miss: kSky
// Image rows run from the top of the picture down, pixels left to right, 3 bytes (R, G, B) each.

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "scene/scene.hpp"

namespace radar_emu::scene {

/// Fixed lighting of the preview (linear RGB).
struct PreviewLighting {
  /// Unit vector toward the sun (ENU): azimuth 135 deg (south-east), elevation 45 deg.
  static constexpr glm::dvec3 kSun{0.5, -0.5, 0.70710678118654752};
  static constexpr double kAmbient = 0.35;
  static constexpr double kDiffuse = 0.65;
  static constexpr glm::dvec3 kSky{0.55, 0.70, 0.90};
  static constexpr double kVisibility_m = 100e3;  ///< haze: meteorological visibility [m]
};

/// Pinhole camera in the world (ENU) frame.
struct PreviewCamera {
  glm::dvec3 position_m{0.0};     ///< camera centre [m]
  glm::dvec3 look_at_m{0.0};      ///< point on the optical axis [m]
  glm::dvec3 up{0.0, 0.0, 1.0};   ///< picture's up direction (need not be unit or orthogonal)
  double vertical_fov_rad = 0.7;  ///< full vertical field of view [rad], in (0, pi)
  int width_px = 640;             ///< image width [pixels], 1..16384
  int height_px = 480;            ///< image height [pixels], 1..16384
};

struct PreviewImage {
  int width_px = 0;
  int height_px = 0;
  std::vector<std::uint8_t> rgb;  ///< width_px * height_px * 3 bytes, row 0 at the top
};

/// Renders the scene at its current time (pixel (i, j), row j from the top, sees along
/// forward + x right + y up with x = (2 (i + 0.5) / width - 1) tan(fov/2) width/height and
/// y = (1 - 2 (j + 0.5) / height) tan(fov/2)). Rows are rendered in parallel (TBB). Throws
/// std::invalid_argument naming the field for a bad camera (non-finite values, position equal
/// to look_at, up parallel to the view, fov or size out of range). Setup/offline only.
[[nodiscard]] PreviewImage render_preview(const Scene& scene, const PreviewCamera& camera);

/// A camera on an azimuth-elevation grid (equiangular, like a scanning radar's image): pixel
/// (i, j), row j from the top, sees along azimuth az_min + (i + 0.5) (az_max - az_min) / width
/// (positive right) and elevation el_max - (j + 0.5) (el_max - el_min) / height (positive up),
/// in the camera frame x forward, y right, z down (radar/em/sbr.hpp's antenna frame), turned into
/// the world by world_from_camera. The same lighting as render_preview.
struct AngularCamera {
  glm::dvec3 position_m{0.0};
  glm::dmat3 world_from_camera{1.0};  ///< rotation world (ENU) from camera
  double azimuth_min_rad = -0.26;     ///< in (-pi/2, pi/2)
  double azimuth_max_rad = 0.26;
  double elevation_min_rad = -0.09;  ///< in (-pi/2, pi/2)
  double elevation_max_rad = 0.09;
  int width_px = 640;  ///< 1..16384
  int height_px = 200;
};
/// Renders the scene at its current time on the camera's grid (rows in parallel, TBB). Throws
/// std::invalid_argument naming the field for a bad camera. Setup/offline only.
[[nodiscard]] PreviewImage render_preview_angular(const Scene& scene, const AngularCamera& camera);

/// An oblique overview of the whole scene from the south-west, 35 degrees above the horizon,
/// with a 40 degree vertical field of view, looking at the centre of the bounds of every active
/// object at the current time and far enough that their enclosing sphere fits the picture.
/// Ground plates (flat objects spanning at least half the scene's extent both ways) are left
/// out of those bounds when anything else is left, so that a runway on a 10 km ground plate
/// does not shrink to a few pixels. Throws std::invalid_argument for a size out of 1..16384.
[[nodiscard]] PreviewCamera default_preview_camera(const Scene& scene, int width_px, int height_px);

}  // namespace radar_emu::scene
