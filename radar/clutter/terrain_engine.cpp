#include "radar/clutter/terrain_engine.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace radar_emu::radar::clutter {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::size_t kMaxFacets = 20'000'000;

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("terrain engine: " + what);
}

// SplitMix64's finaliser (Steele, Lea & Flood, OOPSLA 2014): a facet's and subdivision's patch
// keys spread over 64 bits, so that keys of different facets never run into each other.
std::uint64_t mix64(std::uint64_t z) noexcept {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

using Poly = std::vector<glm::dvec3>;

// One Sutherland-Hodgman pass (Sutherland & Hodgman, CACM 17(1), 1974): keeps the part of the
// polygon where s * (p[axis] - bound) >= 0; new vertices on the boundary, z interpolated.
Poly clip(const Poly& in, int axis, double bound, double s) {
  Poly out;
  const std::size_t n = in.size();
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3& p = in[i];
    const glm::dvec3& q = in[(i + 1) % n];
    const double dp = s * (p[axis] - bound), dq = s * (q[axis] - bound);
    if (dp >= 0.0)
      out.push_back(p);
    if ((dp >= 0.0) != (dq >= 0.0)) {
      const double t = dp / (dp - dq);
      out.push_back(p + t * (q - p));
    }
  }
  return out;
}

}  // namespace

std::uint32_t patch_divisions(const TerrainFacet& f, double patch_m) noexcept {
  if (!(patch_m > 0.0))
    return 1;
  const double n = std::ceil(f.longest_edge_m / patch_m);
  if (!(n >= 1.0))
    return 1;
  return static_cast<std::uint32_t>(std::min(n, 65535.0));
}

TerrainPatch facet_patch(const TerrainFacet& f, std::uint32_t facet, std::uint32_t n,
                         std::uint32_t k) noexcept {
  // Row i of the subdivision (from vertex a toward b) holds n - i "up" triangles and n - i - 1
  // "down" ones; rows before i hold n^2 - (n - i)^2 patches.
  const std::uint64_t nn = static_cast<std::uint64_t>(n) * n;
  const std::uint64_t rest = nn - k;  // >= 1
  auto m = static_cast<std::uint64_t>(std::sqrt(static_cast<double>(rest)));
  while (m * m < rest)
    ++m;
  while (m > 0 && (m - 1) * (m - 1) >= rest)
    --m;
  const std::uint64_t i = n - m;                            // (n - i)^2 >= rest > (n - i - 1)^2
  const std::uint64_t r = k - (nn - m * m);                 // position in the row
  const double third = r % 2 == 0 ? 1.0 / 3.0 : 2.0 / 3.0;  // up or down triangle's centroid
  const double u = (static_cast<double>(i) + third) / n;
  const double v = (static_cast<double>(r / 2) + third) / n;
  TerrainPatch p;
  p.centre_m = f.a_m + u * (f.b_m - f.a_m) + v * (f.c_m - f.a_m);
  p.area_m2 = f.area_m2 / static_cast<double>(nn);
  p.key = mix64((static_cast<std::uint64_t>(facet) << 20) ^ n) + k;
  return p;
}

TerrainMaterials terrain_materials(std::span<const int> sigma0_rows, const Sigma0Table& table,
                                   std::span<const scene::Material> materials) {
  TerrainMaterials m;
  m.sigma0_row.assign(sigma0_rows.begin(), sigma0_rows.end());
  m.table = table;
  for (const scene::Material& mat : materials)
    m.names.push_back(mat.name);
  return m;
}

TerrainEngine::TerrainEngine(const scene::Scene& scene, TerrainMaterials materials,
                             std::span<const std::uint8_t> structures,
                             const TerrainEngineSpec& spec)
    : scene_(&scene), materials_(std::move(materials)), spec_(spec) {
  validate(spec_.speckle);
  if (!(spec_.max_facet_m > 0.0) || !std::isfinite(spec_.max_facet_m))
    fail("max_facet_m must be > 0");
  if (spec_.clip_to_region &&
      !(spec_.region_min_m.x < spec_.region_max_m.x && spec_.region_min_m.y < spec_.region_max_m.y))
    fail("the clip region is empty (min must be below max)");
  const auto mats = scene.materials();
  if (materials_.sigma0_row.size() != mats.size())
    fail("the material rows do not match the scene's " + std::to_string(mats.size()) +
         " materials");
  for (int row : materials_.sigma0_row)
    if (row >= 0 && static_cast<std::size_t>(row) >= materials_.table.materials())
      fail("a sigma0 row is outside the table");

  const scene::SceneDescription& d = scene.description();
  for (std::uint32_t id = 0; id < d.objects.size(); ++id) {
    const scene::ObjectDesc& o = d.objects[id];
    if (o.motion || o.trajectory || (o.lod_group >= 0 && o.lod_level != 0))
      continue;
    if (id < structures.size() && structures[id] != 0)
      continue;
    const glm::dmat4 w = scene.world_from_body(id);
    for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
      const std::uint16_t mat = o.mesh.triangle_material[t];
      const int row = mat < materials_.sigma0_row.size() ? materials_.sigma0_row[mat] : -1;
      if (row < 0)
        continue;
      const glm::uvec3 tri = o.mesh.triangles[t];
      Poly poly;
      for (int v = 0; v < 3; ++v)
        poly.push_back(glm::dvec3(w * glm::dvec4(glm::dvec3(o.mesh.positions_m[tri[v]]), 1.0)));
      const glm::dvec3 normal_raw = glm::cross(poly[1] - poly[0], poly[2] - poly[0]);
      if (!(glm::length(normal_raw) > 0.0))
        continue;  // degenerate
      const glm::dvec3 normal = glm::normalize(normal_raw);
      if (spec_.clip_to_region) {
        poly = clip(poly, 0, spec_.region_min_m.x, 1.0);
        if (poly.size() >= 3)
          poly = clip(poly, 0, spec_.region_max_m.x, -1.0);
        if (poly.size() >= 3)
          poly = clip(poly, 1, spec_.region_min_m.y, 1.0);
        if (poly.size() >= 3)
          poly = clip(poly, 1, spec_.region_max_m.y, -1.0);
        if (poly.size() < 3)
          continue;
      }
      // Fan-triangulate (a clipped triangle is convex), then halve the longest edge until every
      // edge is at most max_facet_m.
      std::vector<std::array<glm::dvec3, 3>> stack;
      for (std::size_t v = 1; v + 1 < poly.size(); ++v)
        stack.push_back({poly[0], poly[v], poly[v + 1]});
      while (!stack.empty()) {
        const auto tr = stack.back();
        stack.pop_back();
        const double e0 = glm::length(tr[1] - tr[0]), e1 = glm::length(tr[2] - tr[1]),
                     e2 = glm::length(tr[0] - tr[2]);
        const double longest = std::max({e0, e1, e2});
        if (longest > spec_.max_facet_m) {
          // Split edge (j, j + 1) at its midpoint: two triangles of the same winding.
          const std::size_t j = longest == e0 ? 0 : (longest == e1 ? 1 : 2);
          const glm::dvec3 p = tr[j], q = tr[(j + 1) % 3], r = tr[(j + 2) % 3];
          const glm::dvec3 mid = 0.5 * (p + q);
          stack.push_back({p, mid, r});
          stack.push_back({mid, q, r});
          continue;
        }
        const double area = 0.5 * glm::length(glm::cross(tr[1] - tr[0], tr[2] - tr[0]));
        if (!(area > 0.0))
          continue;
        if (facets_.size() >= kMaxFacets)
          fail("more than 2e7 terrain facets: raise max_facet_m or clip to a smaller region");
        TerrainFacet f;
        f.a_m = tr[0];
        f.b_m = tr[1];
        f.c_m = tr[2];
        f.normal = normal;
        f.area_m2 = area;
        f.longest_edge_m = longest;
        f.centroid_m = (tr[0] + tr[1] + tr[2]) / 3.0;
        f.radius_m = std::max({glm::length(tr[0] - f.centroid_m), glm::length(tr[1] - f.centroid_m),
                               glm::length(tr[2] - f.centroid_m)});
        f.sigma0_row = static_cast<std::uint32_t>(row);
        f.material = mat;
        f.object = id;
        facets_.push_back(f);
        area_m2_ += area;
      }
    }
  }
  if (!facets_.empty())
    build_tiles();
  if (facets_.empty()) {
    std::string names;
    for (std::size_t m = 0; m < materials_.names.size(); ++m)
      names += (names.empty() ? "" : ", ") + materials_.names[m] +
               (materials_.sigma0_row[m] >= 0 ? "" : " (no sigma0)");
    fail(std::string("the scene has no terrain") + (spec_.clip_to_region ? " in the region" : "") +
         ": no static non-structure triangle of a material with a sigma0 (materials: " + names +
         ")");
  }
}

void TerrainEngine::build_tiles() {
  glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const TerrainFacet& f : facets_) {
    lo = glm::min(lo, glm::dvec2(f.centroid_m));
    hi = glm::max(hi, glm::dvec2(f.centroid_m));
  }
  // Side 4 max_facet_m, widened so that there are at most 2^20 tiles.
  double side = 4.0 * spec_.max_facet_m;
  const glm::dvec2 extent = hi - lo;
  while ((std::floor(extent.x / side) + 1.0) * (std::floor(extent.y / side) + 1.0) > 1048576.0)
    side *= 2.0;
  const auto nx = static_cast<std::size_t>(std::floor(extent.x / side)) + 1;
  const auto ny = static_cast<std::size_t>(std::floor(extent.y / side)) + 1;
  auto tile_of = [&](const TerrainFacet& f) {
    const auto ix = std::min(nx - 1, static_cast<std::size_t>((f.centroid_m.x - lo.x) / side));
    const auto iy = std::min(ny - 1, static_cast<std::size_t>((f.centroid_m.y - lo.y) / side));
    return iy * nx + ix;
  };
  // Counting sort of the facet indices by tile (ascending index within a tile).
  std::vector<std::uint32_t> count(nx * ny + 1, 0);
  for (const TerrainFacet& f : facets_)
    ++count[tile_of(f) + 1];
  for (std::size_t t = 0; t < nx * ny; ++t)
    count[t + 1] += count[t];
  std::vector<std::uint32_t> order(facets_.size());
  std::vector<std::uint32_t> next(count.begin(), count.end() - 1);
  for (std::uint32_t i = 0; i < facets_.size(); ++i)
    order[next[tile_of(facets_[i])]++] = i;
  // Keep the non-empty tiles, each with the sphere around its facets' vertex box.
  tile_facets_ = std::move(order);
  tile_first_.clear();
  tiles_.clear();
  for (std::size_t t = 0; t < nx * ny; ++t) {
    if (count[t + 1] == count[t])
      continue;
    glm::dvec3 b_lo(std::numeric_limits<double>::infinity()), b_hi(-b_lo);
    for (std::uint32_t k = count[t]; k < count[t + 1]; ++k) {
      const TerrainFacet& f = facets_[tile_facets_[k]];
      b_lo = glm::min(glm::min(b_lo, f.a_m), glm::min(f.b_m, f.c_m));
      b_hi = glm::max(glm::max(b_hi, f.a_m), glm::max(f.b_m, f.c_m));
    }
    tile_first_.push_back(count[t]);
    tiles_.push_back({0.5 * (b_lo + b_hi), 0.5 * glm::length(b_hi - b_lo)});
  }
  tile_first_.push_back(static_cast<std::uint32_t>(tile_facets_.size()));
}

double TerrainEngine::sigma0(const TerrainFacet& f, double cos_incidence) const noexcept {
  return static_cast<double>(materials_.table.lookup(f.sigma0_row, spec_.channel, cos_incidence));
}

SpeckleSample TerrainEngine::speckle(const TerrainPatch& p, std::uint64_t look) const noexcept {
  return speckle_sample(spec_.speckle, p.key + look * kLookStride);
}

bool TerrainEngine::clear(const glm::dvec3& from_m, const glm::dvec3& normal,
                          const glm::dvec3& to_m) const noexcept {
  const glm::dvec3 d = to_m - from_m;
  const double dist = glm::length(d);
  if (!(dist > 0.0))
    return true;
  // Offsets relative to the coordinates' size and the path (float traversal: ~1e-7 relative).
  const double scale =
      std::max({std::abs(from_m.x), std::abs(from_m.y), std::abs(from_m.z)}) + dist;
  const double eps = 4e-7 * scale;
  const glm::dvec3 side = glm::dot(normal, d) >= 0.0 ? normal : -normal;
  scene::Ray ray{from_m + eps * side, d / dist, eps, dist - eps};
  if (!(ray.t_far_m > ray.t_near_m))
    return true;
  return !scene_->occluded(ray);
}

TerrainStats TerrainEngine::integrate(const TerrainView& view, const CellGrid& grid,
                                      std::span<std::complex<double>> field, std::span<double> mean,
                                      std::span<double> elevation_power) const noexcept {
  TerrainStats st;
  const std::size_t cells = grid.columns * grid.bins;
  const std::size_t looks = std::max<std::size_t>(view.looks, 1);
  const std::size_t edges_needed = (grid.per_column_edges ? grid.columns : 1) * (grid.bins + 1);
  if (cells == 0 || !(grid.azimuth_step_rad > 0.0) || grid.range_edges_m.size() < edges_needed ||
      mean.size() < cells || (!field.empty() && field.size() < looks * cells) ||
      (!elevation_power.empty() && elevation_power.size() < cells) || !(view.wavelength_m > 0.0) ||
      !(view.patch_min_m > 0.0) || !(view.patch_angle_rad >= 0.0) ||
      !(view.one_way_loss_db_per_m >= 0.0))
    return st;
  const glm::dmat3 antenna_from_world = glm::transpose(view.world_from_antenna);
  double r_min = std::numeric_limits<double>::infinity(), r_max = 0.0;
  for (std::size_t c = 0; c < (grid.per_column_edges ? grid.columns : 1); ++c) {
    const double* e = grid.range_edges_m.data() + c * (grid.bins + 1);
    r_min = std::min(r_min, e[0]);
    r_max = std::max(r_max, e[grid.bins]);
  }
  const double az_max =
      grid.azimuth_min_rad + grid.azimuth_step_rad * static_cast<double>(grid.columns);
  const double k2 = 4.0 * kPi / view.wavelength_m;

  // Whether a sphere (centre, radius) can meet the grid: range, then angles; its distance
  // from the radar in rc.
  auto sphere_meets_grid = [&](const glm::dvec3& centre_m, double radius_m, double& rc) {
    const glm::dvec3 dc = centre_m - view.position_m;
    rc = glm::length(dc);
    if (std::max(0.0, rc - radius_m) > r_max || rc + radius_m < r_min)
      return false;
    if (rc > radius_m) {  // angular bounds of the sphere against the grid's
      const glm::dvec3 a = antenna_from_world * (dc / rc);
      const double az = std::atan2(a.y, a.x);
      const double el = std::atan2(-a.z, std::hypot(a.x, a.y));
      const double ang = std::asin(std::min(1.0, radius_m / rc));
      if (az + ang < grid.azimuth_min_rad || az - ang > az_max ||
          el + ang < grid.elevation_min_rad || el - ang > grid.elevation_max_rad)
        return false;
    }
    return true;
  };

  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    double rt = 0.0;
    if (!sphere_meets_grid(tiles_[t].centre_m, tiles_[t].radius_m, rt))
      continue;
    for (std::uint32_t j = tile_first_[t]; j < tile_first_[t + 1]; ++j) {
      const std::uint32_t fi = tile_facets_[j];
      const TerrainFacet& f = facets_[fi];
      double rc = 0.0;
      if (!sphere_meets_grid(f.centroid_m, f.radius_m, rc))
        continue;
      const double r_near = std::max(0.0, rc - f.radius_m);
      ++st.facets_considered;
      const std::uint32_t n =
          patch_divisions(f, std::max(view.patch_min_m, r_near * view.patch_angle_rad));
      const std::uint64_t count = static_cast<std::uint64_t>(n) * n;
      if (st.patches + count > view.max_patches) {
        ++st.budget_cut;
        continue;
      }
      for (std::uint32_t k = 0; k < count; ++k) {
        const TerrainPatch p = facet_patch(f, fi, n, k);
        ++st.patches;
        const glm::dvec3 d = p.centre_m - view.position_m;
        const double range = glm::length(d);
        if (!(range > 0.0)) {
          ++st.patches_outside;
          continue;
        }
        const glm::dvec3 u = d / range;
        const glm::dvec3 a = antenna_from_world * u;
        const double az = std::atan2(a.y, a.x);
        const double col_f = (az - grid.azimuth_min_rad) / grid.azimuth_step_rad;
        const double el = std::atan2(-a.z, std::hypot(a.x, a.y));
        if (!(col_f >= 0.0 && col_f < static_cast<double>(grid.columns)) ||
            el < grid.elevation_min_rad || el > grid.elevation_max_rad) {
          ++st.patches_outside;
          continue;
        }
        const auto col = static_cast<std::size_t>(col_f);
        const double* e =
            grid.range_edges_m.data() + (grid.per_column_edges ? col * (grid.bins + 1) : 0);
        const double* it = std::upper_bound(e, e + grid.bins + 1, range);
        if (it == e || it == e + grid.bins + 1) {
          ++st.patches_outside;
          continue;
        }
        const auto bin = static_cast<std::size_t>(it - e - 1);
        const double cos_inc = std::abs(glm::dot(f.normal, u));
        if (!(cos_inc > 1e-9)) {
          ++st.patches_grazing;
          continue;
        }
        if (view.shadowing && !clear(p.centre_m, f.normal, view.position_m)) {
          ++st.patches_shadowed;
          continue;
        }
        double power = sigma0(f, cos_inc) * p.area_m2;
        if (view.one_way_loss_db_per_m > 0.0)
          power *= std::pow(10.0, -0.2 * view.one_way_loss_db_per_m * range);
        const std::size_t cell = bin * grid.columns + col;
        mean[cell] += power;
        if (!elevation_power.empty())
          elevation_power[cell] += power * el;
        ++st.patches_lit;
        if (field.empty())
          continue;
        const double path = -k2 * range;
        for (std::size_t l = 0; l < looks; ++l) {
          const SpeckleSample s = speckle(p, l);
          field[l * cells + cell] += std::polar(std::sqrt(power * static_cast<double>(s.intensity)),
                                                static_cast<double>(s.phase_rad) + path);
        }
      }
    }
  }
  return st;
}

}  // namespace radar_emu::radar::clutter
