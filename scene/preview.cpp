#include "scene/preview.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>

#include "common/units.hpp"

namespace radar_emu::scene {

namespace {

constexpr int kMaxSize_px = 16384;

void require(bool ok, const char* field, const char* expected) {
  if (!ok)
    throw std::invalid_argument(std::string("preview camera: ") + field + " " + expected);
}

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// sRGB transfer function (IEC 61966-2-1:1999), linear 0..1 to an 8-bit code.
std::uint8_t srgb8(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  const double e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(255.0 * e));
}

// The pixel colour of one primary ray (header), linear RGB.
glm::dvec3 shade(const Scene& scene, std::span<const Material> materials, const Ray& ray) {
  using Light = PreviewLighting;
  const double beta = 3.912 / Light::kVisibility_m;  // Koschmieder: exp(-beta V) = 0.02
  Hit hit;
  if (!scene.intersect(ray, hit))
    return Light::kSky;
  glm::dvec3 n = hit.normal;
  if (glm::dot(n, ray.direction) > 0.0)
    n = -n;  // the side the camera sees
  const glm::dvec3 base = hit.material_id < materials.size()
                              ? glm::dvec3(materials[hit.material_id].base_color)
                              : glm::dvec3(0.5);
  const glm::dvec3 lit =
      base * (Light::kAmbient + Light::kDiffuse * std::max(0.0, glm::dot(n, Light::kSun)));
  const double transmittance = std::exp(-beta * hit.t_m);
  return lit * transmittance + Light::kSky * (1.0 - transmittance);
}

// Shades a width x height grid of rays from `origin`, row-parallel: dir_of(i, j) gives pixel
// (column i, row j from the top) its world direction (unit).
template <class DirOf>
PreviewImage shade_grid(const Scene& scene, int width_px, int height_px, const glm::dvec3& origin,
                        const DirOf& dir_of) {
  PreviewImage image;
  image.width_px = width_px;
  image.height_px = height_px;
  image.rgb.assign(static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px) * 3, 0);
  const auto materials = scene.materials();
  tbb::parallel_for(
      tbb::blocked_range<int>(0, height_px), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
          std::uint8_t* out = image.rgb.data() +
                              static_cast<std::size_t>(j) * static_cast<std::size_t>(width_px) * 3;
          for (int i = 0; i < width_px; ++i) {
            Ray ray;
            ray.origin_m = origin;
            ray.direction = dir_of(i, j);
            const glm::dvec3 c = shade(scene, materials, ray);
            for (int k = 0; k < 3; ++k)
              out[3 * i + k] = srgb8(c[k]);
          }
        }
      });
  return image;
}

}  // namespace

PreviewImage render_preview(const Scene& scene, const PreviewCamera& cam) {
  require(cam.width_px >= 1 && cam.width_px <= kMaxSize_px, "width_px", "must be in 1..16384");
  require(cam.height_px >= 1 && cam.height_px <= kMaxSize_px, "height_px", "must be in 1..16384");
  require(std::isfinite(cam.vertical_fov_rad) && cam.vertical_fov_rad > 0.0 &&
              cam.vertical_fov_rad < std::numbers::pi,
          "vertical_fov_rad", "must be in (0, pi)");
  require(finite(cam.position_m) && finite(cam.look_at_m) && finite(cam.up), "position/look_at/up",
          "must be finite");
  const glm::dvec3 view = cam.look_at_m - cam.position_m;
  require(glm::length(view) > 0.0, "look_at_m", "must differ from position_m");
  const glm::dvec3 forward = glm::normalize(view);
  const glm::dvec3 side = glm::cross(forward, cam.up);
  require(glm::length(side) > 1e-9 * glm::length(cam.up), "up", "must not be parallel to the view");
  const glm::dvec3 right = glm::normalize(side);
  const glm::dvec3 up = glm::cross(right, forward);
  const double tan_half = std::tan(0.5 * cam.vertical_fov_rad);
  const double aspect = static_cast<double>(cam.width_px) / cam.height_px;

  return shade_grid(scene, cam.width_px, cam.height_px, cam.position_m, [&](int i, int j) {
    const double y = (1.0 - 2.0 * (j + 0.5) / cam.height_px) * tan_half;
    const double x = (2.0 * (i + 0.5) / cam.width_px - 1.0) * tan_half * aspect;
    return glm::normalize(forward + x * right + y * up);
  });
}

PreviewImage render_preview_angular(const Scene& scene, const AngularCamera& cam) {
  require(cam.width_px >= 1 && cam.width_px <= kMaxSize_px, "width_px", "must be in 1..16384");
  require(cam.height_px >= 1 && cam.height_px <= kMaxSize_px, "height_px", "must be in 1..16384");
  require(finite(cam.position_m), "position_m", "must be finite");
  const double half_pi = 0.5 * std::numbers::pi;
  require(std::isfinite(cam.azimuth_min_rad) && std::isfinite(cam.azimuth_max_rad) &&
              cam.azimuth_min_rad < cam.azimuth_max_rad && cam.azimuth_min_rad > -half_pi &&
              cam.azimuth_max_rad < half_pi,
          "azimuth_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  require(std::isfinite(cam.elevation_min_rad) && std::isfinite(cam.elevation_max_rad) &&
              cam.elevation_min_rad < cam.elevation_max_rad && cam.elevation_min_rad > -half_pi &&
              cam.elevation_max_rad < half_pi,
          "elevation_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  const double daz = (cam.azimuth_max_rad - cam.azimuth_min_rad) / cam.width_px;
  const double del = (cam.elevation_max_rad - cam.elevation_min_rad) / cam.height_px;
  return shade_grid(scene, cam.width_px, cam.height_px, cam.position_m, [&](int i, int j) {
    const double el = cam.elevation_max_rad - (j + 0.5) * del;
    const double az = cam.azimuth_min_rad + (i + 0.5) * daz;
    // Camera frame x forward, y right, z down (radar/em/sbr.hpp's antenna frame).
    const glm::dvec3 d{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el)};
    return glm::normalize(cam.world_from_camera * d);
  });
}

PreviewCamera default_preview_camera(const Scene& scene, int width_px, int height_px) {
  if (width_px < 1 || width_px > kMaxSize_px || height_px < 1 || height_px > kMaxSize_px) {
    throw std::invalid_argument("preview camera: width_px and height_px must be in 1..16384");
  }
  // Bounds of everything active, then of everything but ground plates (flat objects spanning
  // at least half the scene both ways), which would otherwise shrink the rest to a few pixels.
  glm::dvec3 all_lo(1e300), all_hi(-1e300);
  for (const ObjectState& o : scene.objects()) {
    if (!o.active)
      continue;
    all_lo = glm::min(all_lo, o.bounds_min_m);
    all_hi = glm::max(all_hi, o.bounds_max_m);
  }
  if (!(all_lo.x <= all_hi.x)) {  // nothing active: look at the origin
    all_lo = glm::dvec3(-1.0);
    all_hi = glm::dvec3(1.0);
  }
  const glm::dvec3 all = all_hi - all_lo;
  // A database's low-resolution surround (ObjectDesc::area "surround") frames nothing of
  // interest either: leave it out when anything else is there.
  const auto& objects_desc = scene.description().objects;
  bool any_inner = false;
  for (const ObjectDesc& d : objects_desc)
    any_inner |= d.area != "surround";
  glm::dvec3 lo(1e300), hi(-1e300);
  const auto states = scene.objects();
  for (std::size_t i = 0; i < states.size(); ++i) {
    const ObjectState& o = states[i];
    const glm::dvec3 e = o.bounds_max_m - o.bounds_min_m;
    const bool plate =
        e.x >= 0.5 * all.x && e.y >= 0.5 * all.y && e.z <= 0.01 * std::max(all.x, all.y);
    const bool surround =
        any_inner && i < objects_desc.size() && objects_desc[i].area == "surround";
    if (!o.active || plate || surround)
      continue;
    lo = glm::min(lo, o.bounds_min_m);
    hi = glm::max(hi, o.bounds_max_m);
  }
  if (!(lo.x <= hi.x)) {
    lo = all_lo;
    hi = all_hi;
  }
  PreviewCamera cam;
  cam.width_px = width_px;
  cam.height_px = height_px;
  cam.vertical_fov_rad = common::radians(40.0);
  cam.look_at_m = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * glm::length(hi - lo), 1.0);
  // The narrower of the two fields of view must hold the sphere.
  const double tan_half = std::tan(0.5 * cam.vertical_fov_rad) *
                          std::min(1.0, static_cast<double>(width_px) / height_px);
  const double distance = radius / std::sin(std::atan(tan_half));
  const double elevation = common::radians(35.0);
  const glm::dvec3 from_target(-std::cos(elevation) * std::sqrt(0.5),
                               -std::cos(elevation) * std::sqrt(0.5), std::sin(elevation));
  cam.position_m = cam.look_at_m + distance * from_target;
  cam.up = {0.0, 0.0, 1.0};
  return cam;
}

}  // namespace radar_emu::scene
