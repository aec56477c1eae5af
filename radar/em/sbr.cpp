#include "radar/em/sbr.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {

double sinc(double x) noexcept {
  return std::abs(x) < 1e-4 ? 1.0 - x * x / 6.0 : std::sin(x) / x;
}

void require(bool ok, const char* field, const char* what) {
  if (!ok)
    throw std::invalid_argument(std::string("SBR config: ") + field + " " + what);
}

// Vertical polarisation for a wave along `d`: antenna "up" projected perpendicular to d.
glm::dvec3 v_pol(const glm::dvec3& up, const glm::dvec3& boresight, const glm::dvec3& d) {
  glm::dvec3 v = up - glm::dot(up, d) * d;
  double n = glm::length(v);
  if (n < 1e-9) {  // looking along "up": fall back to the boresight's projection
    v = boresight - glm::dot(boresight, d) * d;
    n = glm::length(v);
  }
  return v / n;
}

}  // namespace

AzEl azel_from_direction(const glm::dvec3& d) noexcept {
  return {std::atan2(d.y, d.x), std::atan2(-d.z, std::hypot(d.x, d.y))};
}

glm::dvec3 direction_from_azel(const AzEl& a) noexcept {
  const double ce = std::cos(a.elevation_rad);
  return {ce * std::cos(a.azimuth_rad), ce * std::sin(a.azimuth_rad), -std::sin(a.elevation_rad)};
}

SbrTracer::SbrTracer(const scene::Scene& scene, const SbrConfig& config)
    : scene_(&scene), config_(config), materials_(resolve_materials(scene.materials())) {
  const SbrConfig& c = config;
  require(std::isfinite(c.carrier_hz) && c.carrier_hz > 0, "carrier_hz", "must be > 0");
  require(c.azimuth_min_rad < c.azimuth_max_rad && c.azimuth_min_rad > -kPi / 2 &&
              c.azimuth_max_rad < kPi / 2,
          "azimuth_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  require(c.elevation_min_rad < c.elevation_max_rad && c.elevation_min_rad > -kPi / 2 &&
              c.elevation_max_rad < kPi / 2,
          "elevation_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  require(c.terrain_ray_spacing_rad > 0, "terrain_ray_spacing_rad", "must be > 0");
  require(c.target_ray_spacing_m > 0, "target_ray_spacing_m", "must be > 0");
  require(c.max_rays_per_target >= 1, "max_rays_per_target", "must be >= 1");
  require(c.max_range_m > 0, "max_range_m", "must be > 0");
  require(c.max_bounces >= 1 && c.max_bounces <= 16, "max_bounces", "must be in 1..16");
  n_az_ = static_cast<std::size_t>(
      std::ceil((c.azimuth_max_rad - c.azimuth_min_rad) / c.terrain_ray_spacing_rad - 1e-9));
  n_el_ = static_cast<std::size_t>(
      std::ceil((c.elevation_max_rad - c.elevation_min_rad) / c.terrain_ray_spacing_rad - 1e-9));
  require(n_az_ * n_el_ <= 50'000'000, "terrain_ray_spacing_rad", "gives more than 5e7 rays");

  // Terrain-catalogue materials: their sigma0 tables at the carrier (setup only).
  {
    std::vector<clutter::SurfaceSpec> specs;
    sigma0_row_.assign(materials_.size(), -1);
    for (std::size_t i = 0; i < materials_.size(); ++i) {
      if (!materials_[i].terrain_catalogue)
        continue;
      const clutter::TerrainMaterial* t = clutter::find_terrain_material(materials_[i].name);
      sigma0_row_[i] = static_cast<int>(specs.size());
      specs.push_back(clutter::resolve_surface(*t, c.carrier_hz));
    }
    if (!specs.empty())
      sigma0_ = clutter::Sigma0Table(specs, clutter::Sigma0Model::kTotal, c.carrier_hz);
  }

  const auto& desc = scene.description();
  is_target_.assign(desc.objects.size(), 0);
  for (std::size_t i = 0; i < desc.objects.size(); ++i) {
    for (std::uint16_t m : desc.objects[i].mesh.triangle_material) {
      if (materials_[m].conductor) {
        is_target_[i] = 1;
        break;
      }
    }
    n_targets_ += is_target_[i];
  }
  bundles_.reserve(n_targets_);
  counts_.assign(n_az_ * n_el_ + n_targets_ * c.max_rays_per_target, 0);
}

std::size_t SbrTracer::max_contributions() const noexcept {
  return counts_.size() * static_cast<std::size_t>(config_.max_bounces);
}

void SbrTracer::trace_ray(const RadarPose& pose, double az, double el, double daz, double del,
                          std::uint32_t owner, bool terrain, Contribution* slot,
                          std::uint8_t& count, TraceStats& stats) const noexcept {
  const SbrConfig& c = config_;
  const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
  const glm::dmat3& r = pose.world_from_antenna;
  const glm::dvec3 boresight = r[0];
  const glm::dvec3 up = -r[2];  // antenna z is down
  const glm::dmat3 antenna_from_world = glm::transpose(r);
  const double ce = std::cos(el), se = std::sin(el), ca = std::cos(az), sa = std::sin(az);
  glm::dvec3 d = r * glm::dvec3(ce * ca, ce * sa, -se);
  // Tube edge vectors per unit distance: derivatives of the direction times the spacings
  // (Ling, Chou & Lee 1989: ray tubes). |u x v| = cos(el) daz del, the tube's solid angle.
  glm::dvec3 u = r * glm::dvec3(-ce * sa, ce * ca, 0.0) * daz;
  glm::dvec3 v = r * glm::dvec3(-se * ca, -se * sa, -ce) * del;
  glm::dvec3 e = v_pol(up, boresight, d);  // transmit polarisation V
  glm::dvec3 origin = pose.position_m;
  glm::dvec3 v_prev = pose.velocity_mps;
  double path_m = 0.0;     // unfolded path length from the radar to the current hit
  double path_rate = 0.0;  // d(path)/dt so far [m/s]
  count = 0;
  for (int bounce = 0; bounce < c.max_bounces; ++bounce) {
    scene::Ray ray;
    ray.origin_m = origin;
    ray.direction = d;
    ray.t_near_m = bounce == 0 ? 0.0 : 1e-3 * (1.0 + glm::length(origin) * 1e-3);
    // Range budget: a return counts only if half its total path is within max_range, so the
    // first segment may run max_range and later ones what is left of 2 max_range.
    ray.t_far_m = bounce == 0 ? c.max_range_m : 2.0 * c.max_range_m - path_m;
    if (ray.t_far_m <= ray.t_near_m)
      return;
    scene::Hit hit;
    if (!scene_->intersect(ray, hit))
      return;
    ++stats.hits;
    if (bounce == 0) {
      // Ownership: each surface is counted once, by the grid that samples it.
      if (terrain && is_target_[hit.object_id])
        return;
      if (!terrain && hit.object_id != owner)
        return;
    }
    const RadarMaterial& mat = materials_[hit.material_id];
    const glm::dvec3 v_obj = scene_->objects()[hit.object_id].velocity_mps;
    path_m += hit.t_m;
    path_rate += glm::dot(v_obj - v_prev, d);
    glm::dvec3 n = hit.normal;
    if (glm::dot(n, d) > 0.0)
      n = -n;  // the face the ray meets
    const double n_dot_d = glm::dot(n, d);
    if (-n_dot_d < 1e-3) {
      ++stats.grazing_skipped;
      return;
    }
    // Footprint of the tube on the facet: edge vectors at this distance, projected along d.
    const glm::dvec3 uu = u * path_m, vv = v * path_m;
    const glm::dvec3 up_m = uu - d * (glm::dot(n, uu) / n_dot_d);
    const glm::dvec3 vp_m = vv - d * (glm::dot(n, vv) / n_dot_d);
    if (!mat.conductor) {
      if (bounce == 0 && terrain) {
        // sigma = sigma0(theta_i) * footprint area, footprint = dA_perp / cos(theta_i) with
        // dA_perp = L^2 dOmega. Terrain-catalogue materials take sigma0 (VV, the tracer's
        // polarisation) from their setup-time table (radar/clutter/terrain.hpp); the others
        // are constant gamma, sigma0 = gamma cos(theta_i), so sigma = gamma dA_perp
        // (Richards 2010, sec. 5.3).
        const double d_omega = glm::length(glm::cross(u, v));
        const double cos_i = -n_dot_d;
        const int row = sigma0_row_[hit.material_id];
        const double sigma_m2 =
            row >= 0 ? static_cast<double>(sigma0_.lookup(static_cast<std::size_t>(row),
                                                          clutter::Sigma0Table::kVV, cos_i)) *
                           path_m * path_m * d_omega / cos_i
                     : mat.gamma * path_m * path_m * d_omega;
        Contribution& out = slot[count++];
        out.amplitude = {std::sqrt(sigma_m2), 0.0};
        out.range_m = path_m;
        out.range_spread_m = std::abs(glm::dot(up_m, d)) + std::abs(glm::dot(vp_m, d));
        out.radial_velocity_mps = path_rate;  // out and back along the same line
        const AzEl ae = azel_from_direction(antenna_from_world * d);
        out.azimuth_rad = ae.azimuth_rad;
        out.elevation_rad = ae.elevation_rad;
        out.object_id = hit.object_id;
        out.bounces = 1;
        out.coherent = false;
      }
      return;  // no bounce off non-conductors in this first pass
    }
    // PO radiation of the footprint back to the radar (Knott, Shaeffer & Tuley, Radar Cross
    // Section, 2nd ed., 2004, ch. 5: sqrt(sigma) = -j k/sqrt(pi) * int n.(e_r x h_i) e^{...} dS).
    const glm::dvec3 to_radar = pose.position_m - hit.position_m;
    const double back_m = glm::length(to_radar);
    const glm::dvec3 s = to_radar / back_m;
    bool visible = glm::dot(n, s) > 0.0;
    if (visible && bounce > 0) {
      scene::Ray shadow;
      const double off = 1e-3 * (1.0 + glm::length(hit.position_m) * 1e-3);
      shadow.origin_m = hit.position_m;
      shadow.direction = s;
      shadow.t_near_m = off;
      shadow.t_far_m = back_m - off;
      visible = !scene_->occluded(shadow);
    }
    if (visible) {
      const glm::dvec3 g = k * (d - s);  // phase gradient over the footprint
      const double area = glm::length(glm::cross(up_m, vp_m));
      const double taper = sinc(0.5 * glm::dot(g, up_m)) * sinc(0.5 * glm::dot(g, vp_m));
      const glm::dvec3 h_i = glm::cross(d, e);
      const glm::dvec3 e_r = v_pol(up, boresight, s);
      const double pol = glm::dot(n, glm::cross(e_r, h_i));
      const double total_m = path_m + back_m;
      const double phase = -k * total_m;
      const double mag = (k / std::sqrt(kPi)) * pol * area * taper;
      Contribution& out = slot[count++];
      // -j * mag * e^{j phase}
      out.amplitude = {mag * std::sin(phase), -mag * std::cos(phase)};
      out.range_m = 0.5 * total_m;
      out.range_spread_m = 0.0;
      out.radial_velocity_mps = 0.5 * (path_rate + glm::dot(pose.velocity_mps - v_obj, s));
      const AzEl ae = azel_from_direction(antenna_from_world * (-s));
      out.azimuth_rad = ae.azimuth_rad;
      out.elevation_rad = ae.elevation_rad;
      out.object_id = hit.object_id;
      out.bounces = static_cast<std::uint8_t>(bounce + 1);
      out.coherent = true;
    }
    // Specular reflection off a perfect conductor: direction, tube and field (E' = -E +
    // 2 (n.E) n: tangential E flips, normal E stays; R_perp = -1, R_par = +1).
    d = d - 2.0 * n_dot_d * n;
    u = u - 2.0 * glm::dot(n, u) * n;
    v = v - 2.0 * glm::dot(n, v) * n;
    e = -e + 2.0 * glm::dot(n, e) * n;
    origin = hit.position_m;
    v_prev = v_obj;
  }
}

std::size_t SbrTracer::trace(const RadarPose& pose, std::span<Contribution> out,
                             TraceStats& stats) noexcept {
  const SbrConfig& c = config_;
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  // Bundles for targets inside the field of view.
  bundles_.clear();
  std::size_t next_ray = n_az_ * n_el_;
  const auto objects = scene_->objects();
  for (std::uint32_t id = 0; id < objects.size(); ++id) {
    if (!is_target_[id])
      continue;
    const scene::ObjectState& o = objects[id];
    const glm::dvec3 nearest = glm::clamp(pose.position_m, o.bounds_min_m, o.bounds_max_m);
    const double range = glm::length(nearest - pose.position_m);
    if (range > c.max_range_m || range < 1e-6)
      continue;
    double az_lo = 1e9, az_hi = -1e9, el_lo = 1e9, el_hi = -1e9;
    bool behind = false;
    for (int corner = 0; corner < 8; ++corner) {
      const glm::dvec3 p((corner & 1) ? o.bounds_max_m.x : o.bounds_min_m.x,
                         (corner & 2) ? o.bounds_max_m.y : o.bounds_min_m.y,
                         (corner & 4) ? o.bounds_max_m.z : o.bounds_min_m.z);
      const glm::dvec3 a = antenna_from_world * (p - pose.position_m);
      if (a.x <= 0.0)
        behind = true;
      const AzEl ae = azel_from_direction(a);
      az_lo = std::min(az_lo, ae.azimuth_rad);
      az_hi = std::max(az_hi, ae.azimuth_rad);
      el_lo = std::min(el_lo, ae.elevation_rad);
      el_hi = std::max(el_hi, ae.elevation_rad);
    }
    if (behind) {  // straddles the antenna plane: cover the whole field of view
      az_lo = c.azimuth_min_rad;
      az_hi = c.azimuth_max_rad;
      el_lo = c.elevation_min_rad;
      el_hi = c.elevation_max_rad;
    }
    az_lo = std::max(az_lo, c.azimuth_min_rad);
    az_hi = std::min(az_hi, c.azimuth_max_rad);
    el_lo = std::max(el_lo, c.elevation_min_rad);
    el_hi = std::min(el_hi, c.elevation_max_rad);
    if (!(az_lo < az_hi) || !(el_lo < el_hi))
      continue;
    double spacing = c.target_ray_spacing_m / range;
    auto cells = [&](double span) {
      return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(span / spacing)));
    };
    std::size_t n_az = cells(az_hi - az_lo), n_el = cells(el_hi - el_lo);
    if (n_az * n_el > c.max_rays_per_target) {
      ++stats.coarsened_bundles;
      spacing *=
          std::sqrt(static_cast<double>(n_az * n_el) / static_cast<double>(c.max_rays_per_target));
      do {
        n_az = cells(az_hi - az_lo);
        n_el = cells(el_hi - el_lo);
        spacing *= 1.01;
      } while (n_az * n_el > c.max_rays_per_target);
    }
    Bundle b;
    b.object_id = id;
    b.n_az = n_az;
    b.n_el = n_el;
    b.daz_rad = (az_hi - az_lo) / static_cast<double>(n_az);
    b.del_rad = (el_hi - el_lo) / static_cast<double>(n_el);
    b.az0_rad = az_lo;
    b.el0_rad = el_lo;
    b.first_ray = next_ray;
    next_ray += n_az * n_el;
    bundles_.push_back(b);
    ++stats.target_bundles;
  }
  const std::size_t rays = next_ray;
  const auto per_ray = static_cast<std::size_t>(c.max_bounces);
  const std::size_t usable_rays = std::min(rays, out.size() / per_ray);
  stats.rays += rays;
  const double daz_t = (c.azimuth_max_rad - c.azimuth_min_rad) / static_cast<double>(n_az_);
  const double del_t = (c.elevation_max_rad - c.elevation_min_rad) / static_cast<double>(n_el_);

  std::atomic<std::uint64_t> hits{0}, grazing{0};
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, usable_rays, 256),
      [&](const tbb::blocked_range<std::size_t>& range) {
        TraceStats local;
        std::size_t b = 0;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          Contribution* slot = out.data() + i * per_ray;
          if (i < n_az_ * n_el_) {
            const std::size_t ia = i % n_az_, ie = i / n_az_;
            trace_ray(pose, c.azimuth_min_rad + (static_cast<double>(ia) + 0.5) * daz_t,
                      c.elevation_min_rad + (static_cast<double>(ie) + 0.5) * del_t, daz_t, del_t,
                      0, true, slot, counts_[i], local);
            continue;
          }
          while (b + 1 < bundles_.size() && i >= bundles_[b + 1].first_ray)
            ++b;
          const Bundle& bd = bundles_[b];
          const std::size_t j = i - bd.first_ray;
          const std::size_t ia = j % bd.n_az, ie = j / bd.n_az;
          trace_ray(pose, bd.az0_rad + (static_cast<double>(ia) + 0.5) * bd.daz_rad,
                    bd.el0_rad + (static_cast<double>(ie) + 0.5) * bd.del_rad, bd.daz_rad,
                    bd.del_rad, bd.object_id, false, slot, counts_[i], local);
        }
        hits += local.hits;
        grazing += local.grazing_skipped;
      });
  stats.hits += hits.load();
  stats.grazing_skipped += grazing.load();
  stats.dropped_contributions += (rays - usable_rays) * per_ray;  // upper bound, counted
  // Compact the fixed per-ray slots in ray order: deterministic whatever the threading.
  std::size_t n = 0;
  for (std::size_t i = 0; i < usable_rays; ++i) {
    for (std::uint8_t k = 0; k < counts_[i]; ++k)
      out[n++] = out[i * per_ray + k];
  }
  stats.contributions += n;
  return n;
}

}  // namespace radar_emu::radar
