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

// patch_divisions' body, inline: integrate() asks it once per facet of pass 2, where the call
// itself showed in the profile.
inline std::uint32_t divisions_of(const TerrainFacet& f, double patch_m) noexcept {
  if (!(patch_m > 0.0))
    return 1;
  const double n = std::ceil(f.longest_edge_m / patch_m);
  if (!(n >= 1.0))
    return 1;
  return static_cast<std::uint32_t>(std::min(n, 65535.0));
}

}  // namespace

std::uint32_t patch_divisions(const TerrainFacet& f, double patch_m) noexcept {
  return divisions_of(f, patch_m);
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

std::vector<std::string> sigma0_row_names(const TerrainMaterials& m) {
  std::vector<std::string> out(m.table.materials());
  for (std::size_t i = 0; i < m.sigma0_row.size(); ++i) {
    const int r = m.sigma0_row[i];
    if (r < 0 || static_cast<std::size_t>(r) >= out.size() || i >= m.names.size())
      continue;
    std::string& name = out[static_cast<std::size_t>(r)];
    name += (name.empty() ? "" : "/") + m.names[i];
  }
  for (std::size_t r = 0; r < out.size(); ++r)
    if (out[r].empty())
      out[r] = "row " + std::to_string(r);
  return out;
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

  if (spec_.lod_level < 0)
    fail("lod_level must be >= 0");
  const scene::SceneDescription& d = scene.description();
  // Each LOD group's level: spec.lod_level, or its coarsest below that.
  for (const scene::ObjectDesc& o : d.objects) {
    if (o.lod_group < 0)
      continue;
    const auto g = static_cast<std::size_t>(o.lod_group);
    if (lod_taken_.size() <= g)
      lod_taken_.resize(g + 1, 0);
    if (o.lod_level <= spec_.lod_level)
      lod_taken_[g] = std::max(lod_taken_[g], static_cast<int>(o.lod_level));
  }
  for (std::uint32_t id = 0; id < d.objects.size(); ++id) {
    const scene::ObjectDesc& o = d.objects[id];
    if (o.motion || o.trajectory || other_lod(o))
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
  if (!facets_.empty()) {
    build_tiles();
    collect_occluders(structures);
    mark_layers();
  }
  if (facets_.empty()) {
    std::string names;
    for (std::size_t m = 0; m < materials_.names.size(); ++m)
      names += (names.empty() ? "" : ", ") + materials_.names[m] +
               (materials_.sigma0_row[m] >= 0 ? "" : " (no sigma0)");
    throw NoTerrain(std::string("terrain engine: the scene has no terrain") +
                    (spec_.clip_to_region ? " in the region" : "") +
                    ": no static non-structure triangle of a material with a sigma0 (materials: " +
                    names + ")");
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

void TerrainEngine::collect_occluders(std::span<const std::uint8_t> structures) {
  // Static triangles outside the engine (structures, targets, triangles without a sigma0 row),
  // grouped per square of side kSquare_m by their centroid; each group's vertex box gives a
  // sphere. Small squares keep a low object's sphere low (a runway light stays a light).
  constexpr double kSquare_m = 10.0;
  struct Box {
    glm::dvec3 lo{std::numeric_limits<double>::infinity()}, hi{-lo};
  };
  std::vector<std::pair<std::int64_t, Box>> boxes;  // (square key, box), then sorted and merged
  const scene::SceneDescription& d = scene_->description();
  for (std::uint32_t id = 0; id < d.objects.size(); ++id) {
    const scene::ObjectDesc& o = d.objects[id];
    if (o.motion || o.trajectory) {
      dynamic_occluders_.push_back(id);
      continue;
    }
    if (other_lod(o))
      continue;  // another level of the terrain the engine holds at its own
    const bool structure = id < structures.size() && structures[id] != 0;
    const glm::dmat4 w = scene_->world_from_body(id);
    for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
      const std::uint16_t mat = o.mesh.triangle_material[t];
      const int row = mat < materials_.sigma0_row.size() ? materials_.sigma0_row[mat] : -1;
      if (!structure && row >= 0)
        continue;  // terrain: the horizon holds it
      Box b;
      for (int v = 0; v < 3; ++v) {
        const glm::dvec3 p(w *
                           glm::dvec4(glm::dvec3(o.mesh.positions_m[o.mesh.triangles[t][v]]), 1.0));
        b.lo = glm::min(b.lo, p);
        b.hi = glm::max(b.hi, p);
      }
      const glm::dvec3 c = 0.5 * (b.lo + b.hi);
      const auto ix = static_cast<std::int64_t>(std::floor(c.x / kSquare_m));
      const auto iy = static_cast<std::int64_t>(std::floor(c.y / kSquare_m));
      boxes.emplace_back((ix << 32) ^ (iy & 0xffffffff), b);
    }
  }
  std::sort(boxes.begin(), boxes.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  for (std::size_t i = 0; i < boxes.size();) {
    Box b = boxes[i].second;
    std::size_t j = i + 1;
    for (; j < boxes.size() && boxes[j].first == boxes[i].first; ++j) {
      b.lo = glm::min(b.lo, boxes[j].second.lo);
      b.hi = glm::max(b.hi, boxes[j].second.hi);
    }
    occluders_.push_back({0.5 * (b.lo + b.hi), 0.5 * glm::length(b.hi - b.lo)});
    i = j;
  }
}

void TerrainEngine::mark_layers() {
  // Facets of different objects whose horizontal boxes overlap (by more than a centimetre: not
  // neighbours sharing an edge): the one that does not lie wholly above the other is marked.
  // Candidates meet in squares of side max_facet_m (each facet in every square its box touches:
  // at most four).
  bool several = false;
  for (const TerrainFacet& f : facets_)
    several = several || f.object != facets_.front().object;
  if (!several)
    return;
  constexpr double kGap_m = 0.01;
  const double side = spec_.max_facet_m;
  auto lo_of = [](const TerrainFacet& f) { return glm::min(glm::min(f.a_m, f.b_m), f.c_m); };
  auto hi_of = [](const TerrainFacet& f) { return glm::max(glm::max(f.a_m, f.b_m), f.c_m); };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> entries;  // (square, facet)
  for (std::uint32_t i = 0; i < facets_.size(); ++i) {
    const glm::dvec3 lo = lo_of(facets_[i]), hi = hi_of(facets_[i]);
    const auto x0 = static_cast<std::int64_t>(std::floor(lo.x / side));
    const auto x1 = static_cast<std::int64_t>(std::floor(hi.x / side));
    const auto y0 = static_cast<std::int64_t>(std::floor(lo.y / side));
    const auto y1 = static_cast<std::int64_t>(std::floor(hi.y / side));
    for (std::int64_t x = x0; x <= x1; ++x)
      for (std::int64_t y = y0; y <= y1; ++y)
        entries.emplace_back(
            (static_cast<std::uint64_t>(x) << 32) ^ (static_cast<std::uint64_t>(y) & 0xffffffffull),
            i);
  }
  std::sort(entries.begin(), entries.end());
  for (std::size_t s0 = 0; s0 < entries.size();) {
    std::size_t s1 = s0 + 1;
    while (s1 < entries.size() && entries[s1].first == entries[s0].first)
      ++s1;
    for (std::size_t p = s0; p < s1; ++p) {
      TerrainFacet& a = facets_[entries[p].second];
      const glm::dvec3 alo = lo_of(a), ahi = hi_of(a);
      for (std::size_t q = p + 1; q < s1; ++q) {
        TerrainFacet& b = facets_[entries[q].second];
        if (a.object == b.object)
          continue;
        const glm::dvec3 blo = lo_of(b), bhi = hi_of(b);
        if (std::min(ahi.x, bhi.x) - std::max(alo.x, blo.x) <= kGap_m ||
            std::min(ahi.y, bhi.y) - std::max(alo.y, blo.y) <= kGap_m)
          continue;
        if (bhi.z > alo.z + kGap_m)
          a.layered = true;  // b reaches above a's lowest point: may cover it
        if (ahi.z > blo.z + kGap_m)
          b.layered = true;
      }
    }
    s0 = s1;
  }
}

std::uint32_t TerrainEngine::sigma0_flags(const TerrainFacet& f,
                                          double cos_incidence) const noexcept {
  return materials_.table.lookup_flags(f.sigma0_row, spec_.channel, cos_incidence);
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

namespace {

// The horizon's layout for a grid and a view: columns of col_step_rad from az0_rad (the grid's
// azimuths with one column of margin each side), bins of rho_step_m from rho = 0 to the grid's
// last range edge.
struct HorizonShape {
  double az0_rad = 0.0, col_step_rad = 0.0, rho_step_m = 0.0;
  std::size_t columns = 0, bins = 0;
};

HorizonShape horizon_shape(const CellGrid& grid, const TerrainView& view, double r_max) {
  HorizonShape h;
  h.col_step_rad =
      view.horizon_azimuth_rad > 0.0 ? view.horizon_azimuth_rad : 0.5 * grid.azimuth_step_rad;
  h.rho_step_m = view.horizon_rho_m > 0.0 ? view.horizon_rho_m : view.patch_min_m;
  if (!(h.col_step_rad > 0.0) || !(h.rho_step_m > 0.0) || !std::isfinite(r_max) || !(r_max > 0.0))
    return {};
  const double span = grid.azimuth_step_rad * static_cast<double>(grid.columns);
  h.columns = static_cast<std::size_t>(std::ceil(span / h.col_step_rad - 1e-9)) + 2;
  h.az0_rad = grid.azimuth_min_rad - h.col_step_rad;
  h.bins = static_cast<std::size_t>(std::ceil(r_max / h.rho_step_m)) + 1;
  return h;
}

double last_edge(const CellGrid& grid) {
  double r_max = 0.0;
  for (std::size_t c = 0; c < (grid.per_column_edges ? grid.columns : 1); ++c)
    r_max = std::max(r_max, grid.range_edges_m[c * (grid.bins + 1) + grid.bins]);
  return r_max;
}

// atan2(y, x) within kFastAtan2Error_rad: atan on [0, 1] by a degree-11 odd polynomial (the
// minimax fit of Abramowitz & Stegun, Handbook of Mathematical Functions, 1964, 4.4.49's form;
// coefficients as in Rajan et al., "Efficient approximations for the arctangent function", IEEE
// Signal Processing Magazine 23(3), 2006), folded into the octants. Its largest error on [0, 1],
// checked on 2e6 points against NumPy's arctan, is 1.7e-6 rad; the sweep only narrows its
// searches with it, widened by the bound, and decides by exact tests.
constexpr double kFastAtan2Error_rad = 1e-5;
// The octant folding of fast_atan2 and fast_atan2_estrin around `odd(a)`, an odd polynomial's
// value at a = min(|x|, |y|) / max(|x|, |y|) in [0, 1].
template <class OddPolynomial>
inline double folded_atan2(double y, double x, OddPolynomial odd) noexcept {
  const double ax = std::abs(x), ay = std::abs(y);
  const double hi = std::max(ax, ay), lo = std::min(ax, ay);
  double r = odd(hi > 0.0 ? lo / hi : 0.0);
  if (ay > ax)
    r = 0.5 * kPi - r;
  if (x < 0.0)
    r = kPi - r;
  return y < 0.0 ? -r : r;
}
inline double fast_atan2(double y, double x) noexcept {
  return folded_atan2(y, x, [](double a) {
    const double a2 = a * a;
    return a *
           (0.99997726 +
            a2 * (-0.33262347 +
                  a2 * (0.19354346 + a2 * (-0.11643287 + a2 * (0.05265332 - a2 * 0.01172120)))));
  });
}

// fast_atan2's polynomial by Estrin's scheme (Knuth, The Art of Computer Programming vol. 2,
// 3rd ed., 1997, sec. 4.6.4) instead of Horner's: three multiplications deep instead of six,
// for pass 2, where the azimuth heads each patch's chain of dependent operations. Its values
// differ from fast_atan2's by the rounding of the other order (1e-16), so it keeps the same
// bound (largest error 1.66e-6 rad against std::atan2, checked on 2e8 points of [0, 1] and
// 5e7 random (x, y)). Pass 1 keeps fast_atan2 itself: its values decide which facets pass 2
// lists, exactly.
inline double fast_atan2_estrin(double y, double x) noexcept {
  return folded_atan2(y, x, [](double a) {
    const double t = a * a;
    const double t2 = t * t;
    const double p01 = 0.99997726 + t * -0.33262347;
    const double p23 = 0.19354346 + t * -0.11643287;
    const double p45 = 0.05265332 - t * 0.01172120;
    return a * ((p01 + t2 * p23) + (t2 * t2) * p45);
  });
}

// Whether v lies farther than margin from every integer. A value computed from an azimuth within
// kFastAtan2Error_rad of the exact one, by operations monotone in the azimuth, then has the same
// floor and the same side of every integer bound as the value from the exact azimuth when the
// margin covers that azimuth error in v's units plus the rounding of the few operations between.
inline bool clear_of_integers(double v, double margin) noexcept {
  const double frac = v - std::floor(v);
  return frac > margin && frac < 1.0 - margin;
}

// The facets are visited through index lists (tiles, pass 2's list), scattered over a large array:
// their cache lines are asked for a few facets ahead.
constexpr std::uint32_t kPrefetchAhead = 8;
inline void prefetch(const TerrainFacet& f) noexcept {
  const char* p = reinterpret_cast<const char*>(&f);
  for (std::size_t line = 0; line < sizeof(TerrainFacet); line += 64)
    __builtin_prefetch(p + line);
}

// Calls fn(centre, k) for patch k of facet f cut n ways, k ascending: the same centres as
// facet_patch(f, ., n, k), row by row (row i from vertex a toward b: 2 (n - i) - 1 triangles,
// "up" ones at even positions), without the square root that finds the row of a single k.
template <class Fn>
void for_each_patch(const TerrainFacet& f, std::uint32_t n, Fn&& fn) {
  const glm::dvec3 eb = (f.b_m - f.a_m), ec = (f.c_m - f.a_m);
  std::uint32_t k = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t row = 2 * (n - i) - 1;
    for (std::uint32_t r = 0; r < row; ++r, ++k) {
      const double third = r % 2 == 0 ? 1.0 / 3.0 : 2.0 / 3.0;
      const double u = (static_cast<double>(i) + third) / n;
      const double v = (static_cast<double>(r / 2) + third) / n;
      fn(f.a_m + u * eb + v * ec, k);
    }
  }
}

}  // namespace

std::size_t TerrainEngine::horizon_scratch_size(const CellGrid& grid,
                                                const TerrainView& view) noexcept {
  const std::size_t edges_needed = (grid.per_column_edges ? grid.columns : 1) * (grid.bins + 1);
  if (grid.columns == 0 || grid.bins == 0 || grid.range_edges_m.size() < edges_needed ||
      !(grid.azimuth_step_rad > 0.0))
    return 0;
  const HorizonShape h = horizon_shape(grid, view, last_edge(grid));
  return 2 * h.columns * h.bins + 2 * h.columns;  // two maps, the centres' cosines and sines
}

TerrainStats TerrainEngine::integrate(const TerrainView& view, const CellGrid& grid,
                                      std::span<std::complex<double>> field, std::span<double> mean,
                                      std::span<double> elevation_power, std::span<double> horizon,
                                      std::span<std::uint32_t> facet_list,
                                      std::span<Sigma0Use> sigma0_use,
                                      std::span<std::uint32_t> cell_flags) const noexcept {
  TerrainStats st;
  const std::size_t cells = grid.columns * grid.bins;
  const std::size_t looks = std::max<std::size_t>(view.looks, 1);
  const std::size_t edges_needed = (grid.per_column_edges ? grid.columns : 1) * (grid.bins + 1);
  if (cells == 0 || !(grid.azimuth_step_rad > 0.0) || grid.range_edges_m.size() < edges_needed ||
      mean.size() < cells || (!field.empty() && field.size() < looks * cells) ||
      (!elevation_power.empty() && elevation_power.size() < cells) ||
      (!cell_flags.empty() && cell_flags.size() < cells) || !(view.wavelength_m > 0.0) ||
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
  const double sin_el_min = std::sin(std::max(grid.elevation_min_rad, -0.5 * kPi));
  const double sin_el_max = std::sin(std::min(grid.elevation_max_rad, 0.5 * kPi));
  // Uniform range edges (one set for every column): the bin by a division.
  const double* e0 = grid.range_edges_m.data();
  const double edge_step = (e0[grid.bins] - e0[0]) / static_cast<double>(grid.bins);
  bool uniform = !grid.per_column_edges && std::isfinite(edge_step) && edge_step > 0.0;
  for (std::size_t b = 0; uniform && b <= grid.bins; ++b)
    uniform =
        std::abs(e0[b] - (e0[0] + static_cast<double>(b) * edge_step)) <= 1e-9 * e0[grid.bins];
  const double inv_edge_step = uniform ? 1.0 / edge_step : 0.0;
  const bool spread = view.spread_range && uniform;

  // Whether a sphere (centre, radius) can meet the window [r_lo, r_hi] x [az_lo, az_hi] x
  // [el_lo, el_hi]: range, then angles; its distance from the radar in rc.
  auto sphere_meets = [&](const glm::dvec3& centre_m, double radius_m, double r_lo, double r_hi,
                          double az_lo, double az_hi, double el_lo, double el_hi, double& rc) {
    const glm::dvec3 dc = centre_m - view.position_m;
    rc = glm::length(dc);
    if (std::max(0.0, rc - radius_m) > r_hi || rc + radius_m < r_lo)
      return false;
    if (rc > radius_m) {  // angular bounds of the sphere against the window's
      const glm::dvec3 a = antenna_from_world * (dc / rc);
      const double az = std::atan2(a.y, a.x);
      const double el = std::atan2(-a.z, std::sqrt(a.x * a.x + a.y * a.y));
      const double ang = std::asin(std::min(1.0, radius_m / rc));
      if (az + ang < az_lo || az - ang > az_hi || el + ang < el_lo || el - ang > el_hi)
        return false;
    }
    return true;
  };
  auto divisions = [&](const TerrainFacet& f, double rc) {
    const double r_near = std::max(0.0, rc - f.radius_m);
    return divisions_of(f, std::max(view.patch_min_m, r_near * view.patch_angle_rad));
  };

  // ---- Pass 1 (kHorizon): the terrain's horizon and the occluders' map, per column and bin.
  HorizonShape hz;
  const bool use_horizon = view.shadowing && view.shadow_method == TerrainView::Shadow::kHorizon;
  double* terrain_hz = nullptr;  // bins x columns (bin-major): max sin(el), then running
  double* occluder_hz = nullptr;
  const double* centre_cos = nullptr;  // per column: cos and sin of its centre's azimuth
  const double* centre_sin = nullptr;
  if (use_horizon) {
    hz = horizon_shape(grid, view, r_max);
    const std::size_t maps = horizon.size() >= 2 * hz.columns ? horizon.size() - 2 * hz.columns : 0;
    if (hz.columns > 0 && maps / 2 < hz.columns * hz.bins && maps / 2 >= 2 * hz.columns) {
      // Widen the bins to fit the scratch.
      hz.bins = maps / 2 / hz.columns;
      hz.rho_step_m = r_max / static_cast<double>(hz.bins - 1);
      st.horizon_coarsened = 1;
    }
    if (hz.columns > 0 && maps / 2 >= hz.columns * hz.bins) {
      terrain_hz = horizon.data();
      occluder_hz = horizon.data() + hz.columns * hz.bins;
      std::fill(terrain_hz, terrain_hz + 2 * hz.columns * hz.bins, -2.0);
      double* cs = horizon.data() + 2 * hz.columns * hz.bins;
      for (std::size_t c = 0; c < hz.columns; ++c) {
        const double az_c = hz.az0_rad + (static_cast<double>(c) + 0.5) * hz.col_step_rad;
        cs[c] = std::cos(az_c);
        cs[hz.columns + c] = std::sin(az_c);
      }
      centre_cos = cs;
      centre_sin = cs + hz.columns;
    }
  }
  const double inv_col_step = terrain_hz ? 1.0 / hz.col_step_rad : 0.0;
  const double inv_rho_step = terrain_hz ? 1.0 / hz.rho_step_m : 0.0;
  const double hz_az_max = hz.az0_rad + hz.col_step_rad * static_cast<double>(hz.columns);
  auto hz_index = [&](double az, double rho, std::size_t& index, std::size_t& bin) {
    const double cf = (az - hz.az0_rad) * inv_col_step;
    if (!(cf >= 0.0 && cf < static_cast<double>(hz.columns)))
      return false;
    bin = std::min(hz.bins - 1, static_cast<std::size_t>(rho * inv_rho_step));
    index = bin * hz.columns + static_cast<std::size_t>(cf);
    return true;
  };
  // Pass 2's facets, found by pass 1 from the same vertex transforms (facet_list): every facet
  // with a patch that can lie in the grid's window, in pass 1's order (the tiles', as pass 2's own
  // search would visit them). Without the list (or when it is too short), pass 2 searches the
  // tiles itself.
  std::size_t listed = 0;
  bool use_list = terrain_hz != nullptr && !facet_list.empty();
  const double cos_az_min = std::cos(grid.azimuth_min_rad),
               sin_az_min = std::sin(grid.azimuth_min_rad);
  const double cos_az_max = std::cos(az_max), sin_az_max = std::sin(az_max);
  const bool narrow_window = az_max - grid.azimuth_min_rad < kPi;
  // A facet's vertices in the antenna frame and what pass 1 reads of them (below).
  struct FacetFront {
    double rc = 0.0;
    glm::dvec3 v[3]{};
    double az_lo = 0.0, az_hi = 0.0, sin_el_top = 0.0, sin_el_bottom = 0.0;
    bool around_axis = false, right_of_min = false, left_of_max = false;
  };
  constexpr std::uint32_t kFacetBatch = 32;
  std::array<FacetFront, kFacetBatch> fronts;
  if (terrain_hz) {
    for (std::size_t t = 0; t < tiles_.size(); ++t) {
      double rt = 0.0;
      if (!sphere_meets(tiles_[t].centre_m, tiles_[t].radius_m, 0.0, r_max, hz.az0_rad, hz_az_max,
                        grid.elevation_min_rad, 0.5 * kPi, rt))
        continue;
      // The tile's facets in batches: first each facet's vertices in the antenna frame and
      // their azimuths and elevations (arithmetic without branches, the facets' chains of square
      // roots and divisions overlapping), then each facet's decisions and profile in turn, in
      // the tile's order. Every value is computed by the same operations as one facet at a time.
      const std::uint32_t tile_end = tile_first_[t + 1];
      for (std::uint32_t j0 = tile_first_[t]; j0 < tile_end; j0 += kFacetBatch) {
        const std::uint32_t jn = std::min(tile_end, j0 + kFacetBatch);
        for (std::uint32_t j = j0; j < jn; ++j) {
          if (j + kPrefetchAhead < tile_end)
            prefetch(facets_[tile_facets_[j + kPrefetchAhead]]);
          FacetFront& ff = fronts[j - j0];
          const TerrainFacet& f = facets_[tile_facets_[j]];
          ff.rc = glm::length(f.centroid_m - view.position_m);
          ff.v[0] = antenna_from_world * (f.a_m - view.position_m);
          ff.v[1] = antenna_from_world * (f.b_m - view.position_m);
          ff.v[2] = antenna_from_world * (f.c_m - view.position_m);
          double az_lo = std::numeric_limits<double>::infinity(), az_hi = -az_lo;
          double sin_el_top = -1.0;  // a planar facet's highest elevation is at a vertex
          double sin_el_bottom = 1.0;
          bool around_axis = false;
          bool right_of_min = true, left_of_max = true;  // every vertex outside one azimuth edge
          for (const glm::dvec3& p : ff.v) {
            const double rho_p = std::sqrt(p.x * p.x + p.y * p.y);
            if (!(rho_p > 1e-9 * (1.0 + std::abs(p.z))))
              around_axis = true;
            const double az = fast_atan2(p.y, p.x);
            az_lo = std::min(az_lo, az);
            az_hi = std::max(az_hi, az);
            const double sin_el = -p.z / std::sqrt(rho_p * rho_p + p.z * p.z);
            sin_el_top = std::max(sin_el_top, sin_el);
            sin_el_bottom = std::min(sin_el_bottom, sin_el);
            const double slack = 1e-9 * (std::abs(p.x) + std::abs(p.y));
            right_of_min = right_of_min && cos_az_min * p.y - sin_az_min * p.x < -slack;
            left_of_max = left_of_max && cos_az_max * p.y - sin_az_max * p.x > slack;
          }
          ff.az_lo = az_lo;
          ff.az_hi = az_hi;
          ff.sin_el_top = sin_el_top;
          ff.sin_el_bottom = sin_el_bottom;
          ff.around_axis = around_axis;
          ff.right_of_min = right_of_min;
          ff.left_of_max = left_of_max;
        }
        for (std::uint32_t j = j0; j < jn; ++j) {
          const FacetFront& ff = fronts[j - j0];
          const std::uint32_t fi = tile_facets_[j];
          const TerrainFacet& f = facets_[fi];
          const double rc = ff.rc;
          if (rc - f.radius_m > r_max)
            continue;  // beyond the grid (the angles by the vertices below)
          // The facet's profile in each column's centre plane (azimuth az_c: the plane through
          // the radar holding the antenna's z axis, normal (-sin az_c, cos az_c, 0)): the segment
          // where the plane cuts the triangle. Along a straight segment the elevation seen from
          // the radar is monotone, so its two ends carry the profile's extremes; in between lies
          // this facet alone (layers apart), which cannot shadow itself unless it faces away, and
          // then its near end, written first along rho, shadows the rest.
          const glm::dvec3(&v)[3] = ff.v;
          double az_lo = ff.az_lo, az_hi = ff.az_hi;
          const double sin_el_top = ff.sin_el_top, sin_el_bottom = ff.sin_el_bottom;
          const bool around_axis = ff.around_axis;
          const bool right_of_min = ff.right_of_min, left_of_max = ff.left_of_max;
          if (std::abs(az_hi - az_lo - kPi) < 4.0 * kFastAtan2Error_rad) {
            // Near the half-turn below, decide by the exact azimuths.
            az_lo = std::numeric_limits<double>::infinity();
            az_hi = -az_lo;
            for (const glm::dvec3& p : v) {
              az_lo = std::min(az_lo, std::atan2(p.y, p.x));
              az_hi = std::max(az_hi, std::atan2(p.y, p.x));
            }
          }
          // The vertices' azimuths widened by the approximation's bound (fast_atan2).
          az_lo -= kFastAtan2Error_rad;
          az_hi += kFastAtan2Error_rad;
          if (use_list && rc + f.radius_m >= r_min) {
            // The patches' window from the vertices. Azimuth: a triangle whose vertices all lie
            // beyond the line of one azimuth edge (through the axis) lies wholly beyond it, the
            // window being narrower than pi; between the edges, a triangle clear of the axis
            // spans the azimuths of its vertices (margin 1e-9 rad for rounding). Elevation:
            // every point of the triangle lies within its longest edge L of each vertex, so its
            // direction within L / r_near of a vertex's, its sin(el) within that of the
            // vertices' (sine is 1-Lipschitz). Conservative: the patches themselves are tested.
            bool keep = !narrow_window || (!right_of_min && !left_of_max);
            if (keep && !around_axis && az_hi - az_lo <= kPi)
              keep = az_hi >= grid.azimuth_min_rad - 1e-9 && az_lo <= az_max + 1e-9;
            const double r_near = rc - f.radius_m;
            if (keep && r_near > 0.0) {
              const double margin = f.longest_edge_m / r_near;
              keep = sin_el_top + margin >= sin_el_min && sin_el_bottom - margin <= sin_el_max;
            }
            if (keep) {
              if (listed < facet_list.size())
                facet_list[listed++] = fi;
              else
                use_list = false;
            }
          }
          if (around_axis || az_hi - az_lo - 2.0 * kFastAtan2Error_rad > kPi)
            continue;  // a facet around the antenna's axis or behind it: no profile in the columns
          if (sin_el_top < sin_el_min)
            continue;  // wholly below the grid's elevations: it shadows none of its patches
          // Centre c at az0 + (c + 1/2) step: the centres in [az_lo, az_hi].
          const double c_lo = std::ceil((az_lo - hz.az0_rad) * inv_col_step - 0.5);
          const double c_hi = std::floor((az_hi - hz.az0_rad) * inv_col_step - 0.5);
          const double c_first = std::max(0.0, c_lo);
          const double c_last = std::min(static_cast<double>(hz.columns) - 1.0, c_hi);
          for (double cd = c_first; cd <= c_last; cd += 1.0) {
            const auto col = static_cast<std::size_t>(cd);
            const double sn = centre_sin[col], cs = centre_cos[col];
            double sd[3];
            for (int q = 0; q < 3; ++q)
              sd[q] = cs * v[q].y - sn * v[q].x;
            int ends = 0;
            for (int q = 0; q < 3 && ends < 2; ++q) {
              const int r = (q + 1) % 3;
              if ((sd[q] > 0.0) == (sd[r] > 0.0))
                continue;
              const double u = sd[q] / (sd[q] - sd[r]);
              const glm::dvec3 p = v[q] + u * (v[r] - v[q]);
              ++ends;
              ++st.horizon_patches;
              const double rho = std::sqrt(p.x * p.x + p.y * p.y);
              const double range = std::sqrt(rho * rho + p.z * p.z);
              if (!(range > 0.0) || cs * p.x + sn * p.y < 0.0)
                continue;  // the plane's other half, behind the axis
              const auto bin = std::min(hz.bins - 1, static_cast<std::size_t>(rho * inv_rho_step));
              double& h = terrain_hz[bin * hz.columns + col];
              h = std::max(h, -p.z / range);
            }
          }
        }
      }
    }
    // What is not terrain: each sphere's highest sin(el), from its nearest rho on, over the
    // columns its cap spans (a cap of angular radius alpha around (az, el) spans azimuths
    // az +- asin(sin alpha / cos el) while |el| + alpha < pi/2).
    auto add_occluder = [&](const glm::dvec3& centre_m, double radius_m) {
      const glm::dvec3 dc = centre_m - view.position_m;
      const double dist = glm::length(dc);
      if (dist - radius_m > r_max)
        return;
      std::size_t c0 = 0, c1 = hz.columns;
      double top = 2.0, rho_near = 0.0;
      if (dist > radius_m) {
        const glm::dvec3 a = antenna_from_world * (dc / dist);
        const double el = std::asin(std::clamp(-a.z, -1.0, 1.0));
        const double alpha = std::asin(radius_m / dist);
        if (el + alpha < grid.elevation_min_rad)
          return;  // below every patch's line of sight
        top = std::sin(std::min(el + alpha, 0.5 * kPi));
        rho_near = std::max(0.0, std::sqrt(a.x * a.x + a.y * a.y) * dist - radius_m);
        if (std::abs(el) + alpha < 0.5 * kPi - 1e-6) {
          const double az = std::atan2(a.y, a.x);
          const double half = std::asin(std::min(1.0, std::sin(alpha) / std::cos(el)));
          const double lo = (az - half - hz.az0_rad) * inv_col_step;
          const double hi = (az + half - hz.az0_rad) * inv_col_step;
          if (hi < 0.0 || lo >= static_cast<double>(hz.columns))
            return;
          c0 = static_cast<std::size_t>(std::max(0.0, lo));
          c1 = std::min(hz.columns, static_cast<std::size_t>(hi) + 1);
        }
      }
      const auto bin = std::min(hz.bins - 1, static_cast<std::size_t>(rho_near * inv_rho_step));
      for (std::size_t c = c0; c < c1; ++c)
        occluder_hz[bin * hz.columns + c] = std::max(occluder_hz[bin * hz.columns + c], top);
    };
    for (const Occluder& o : occluders_)
      add_occluder(o.centre_m, o.radius_m);
    const auto states = scene_->objects();
    for (std::uint32_t id : dynamic_occluders_) {
      const scene::ObjectState& o = states[id];
      add_occluder(0.5 * (o.bounds_min_m + o.bounds_max_m),
                   0.5 * glm::length(o.bounds_max_m - o.bounds_min_m));
    }
    // Running maxima outward: bin b then holds the horizon of bins 0..b.
    // (Bins outer, columns inner: the maps are bin-major, each bin's row one vector op.)
    for (std::size_t b = 1; b < hz.bins; ++b) {
      double* t_row = terrain_hz + b * hz.columns;
      double* o_row = occluder_hz + b * hz.columns;
      for (std::size_t c = 0; c < hz.columns; ++c) {
        t_row[c] = std::max(t_row[c], t_row[c - hz.columns]);
        o_row[c] = std::max(o_row[c], o_row[c - hz.columns]);
      }
    }
  }

  // ---- Pass 2: the patches of the grid's cells, facet by facet.
  // A patch's azimuth decides its column, its horizon column and, through the horizon's linear
  // interpolation weight, whether it is shadowed. The exact std::atan2 is the costliest step of a
  // patch; fast_atan2 is within kFastAtan2Error_rad of it (its bound, above), so its answer is
  // taken wherever these decisions come out the same for every azimuth within that bound: the
  // column and horizon positions away from the integers (half-integers for the interpolation's
  // left column) by the bound in their units, and the shadow test away from the horizon by what
  // the weight can move it. Elsewhere (about one patch in a hundred on the shipped scenarios) the
  // exact azimuth decides.
  // The margins add 1e-9 (relative to the position) for the rounding of the few operations
  // between the azimuth and the position, far above it.
  const double col_margin = kFastAtan2Error_rad / grid.azimuth_step_rad;
  // On the fast path the column by a multiplication (its rounding, 1e-16 relative, inside the
  // margin's 1e-9): only its floor and its side of the grid's bounds are used.
  const double inv_azimuth_step = 1.0 / grid.azimuth_step_rad;
  const double hz_margin = kFastAtan2Error_rad * inv_col_step;
  auto margin_of = [](double position, double margin) {
    return margin + 1e-9 * (1.0 + std::abs(position));
  };
  // The patches go through a batch: first the arithmetic that does not branch (direction, fast
  // azimuth and column, range, unit vector, antenna frame) for every patch of the batch, then each
  // patch's decisions in turn, in the same order as one at a time. Each patch's chain of
  // dependent square roots and divisions then overlaps the others' instead of waiting behind the
  // branches that end the patch before it; every value is computed by the same operations as
  // before, so the results are the same.
  struct Pending {
    glm::dvec3 centre{0.0};
    const TerrainFacet* f = nullptr;
    double patch_area_m2 = 0.0;
    double inv_n = 1.0;
    std::uint64_t key0 = 0;
    std::uint32_t k = 0;
    bool az_exact = false;
    double range = 0.0, az = 0.0, col_f = 0.0;
    glm::dvec3 u{0.0}, a{0.0};
  };
  constexpr std::size_t kBatch = 32;
  std::array<Pending, kBatch> batch;
  std::size_t pending = 0;
  auto evaluate = [&](const Pending& p) {
    const TerrainFacet& f = *p.f;
    const double range = p.range;
    if (!(range > 0.0)) {
      ++st.patches_outside;
      return;
    }
    const glm::dvec3& u = p.u;
    const glm::dvec3& a = p.a;
    double az = p.az;
    double col_f = p.col_f;
    const bool az_exact = p.az_exact;
    if (az_exact) {
      az = std::atan2(a.y, a.x);
      col_f = (az - grid.azimuth_min_rad) / grid.azimuth_step_rad;
    }
    const double sin_el = -a.z;
    if (!(col_f >= 0.0 && col_f < static_cast<double>(grid.columns)) || sin_el < sin_el_min ||
        sin_el > sin_el_max) {
      ++st.patches_outside;
      return;
    }
    const auto col = static_cast<std::size_t>(col_f);
    const double* e = e0 + (grid.per_column_edges ? col * (grid.bins + 1) : 0);
    std::size_t bin = 0;
    if (uniform) {
      const double bf = (range - e[0]) * inv_edge_step;
      if (!(bf >= 0.0 && bf < static_cast<double>(grid.bins) + 1.0)) {
        ++st.patches_outside;
        return;
      }
      bin = static_cast<std::size_t>(bf);
      // Rounding at an edge: the bin with e[bin] <= range < e[bin + 1], as upper_bound.
      if (bin > 0 && range < e[bin])
        --bin;
      else if (bin < grid.bins && range >= e[bin + 1])
        ++bin;
      if (bin >= grid.bins || range < e[bin]) {
        ++st.patches_outside;
        return;
      }
    } else {
      const double* it = std::upper_bound(e, e + grid.bins + 1, range);
      if (it == e || it == e + grid.bins + 1) {
        ++st.patches_outside;
        return;
      }
      bin = static_cast<std::size_t>(it - e - 1);
    }
    const double cos_inc = std::abs(glm::dot(f.normal, u));
    if (!(cos_inc > 1e-9)) {
      ++st.patches_grazing;
      return;
    }
    if (view.shadowing) {
      bool query = true;
      if (terrain_hz) {
        std::size_t index = 0, hb = 0;
        const double rho = range * std::sqrt(a.x * a.x + a.y * a.y);
        if (hz_index(az, rho, index, hb)) {
          if (hb > 0) {
            // The horizon at the patch's azimuth: between the profiles of the two nearest
            // column centres, linearly (one alone where the other holds no terrain).
            const double x = (az - hz.az0_rad) * inv_col_step - 0.5;
            const auto c0 = static_cast<std::size_t>(std::max(0.0, std::floor(x)));
            const std::size_t c1 = std::min(c0 + 1, hz.columns - 1);
            const double h0 = terrain_hz[(hb - 1) * hz.columns + c0];
            const double h1 = terrain_hz[(hb - 1) * hz.columns + c1];
            auto horizon_at = [&](double x_at) {
              const double w = std::clamp(x_at - static_cast<double>(c0), 0.0, 1.0);
              return h0 < -1.5 ? h1 : (h1 < -1.5 ? h0 : h0 + w * (h1 - h0));
            };
            double h = horizon_at(x);
            // The weight moves by at most the azimuth's bound in columns (clamp is
            // 1-Lipschitz), the horizon by that times |h1 - h0|, plus the rounding of the
            // interpolation (a few units of 1e-16 on values of at most 2): closer than that,
            // the exact azimuth decides.
            if (!az_exact && h0 >= -1.5 && h1 >= -1.5 &&
                !(std::abs(sin_el - h) > margin_of(x, hz_margin) * std::abs(h1 - h0) + 1e-12))
              h = horizon_at((std::atan2(a.y, a.x) - hz.az0_rad) * inv_col_step - 0.5);
            if (sin_el < h) {
              ++st.patches_shadowed;  // below the horizon of the nearer terrain
              return;
            }
          }
          // Behind something that is not terrain, or a layer under another terrain object.
          query = f.layered || sin_el < occluder_hz[index];
        }
      }
      if (query) {
        ++st.occlusion_queries;
        if (!clear(p.centre, f.normal, view.position_m)) {
          ++st.patches_shadowed;
          return;
        }
      }
    }
    // sigma0 and, when asked for, its samples' flags from one lookup (one acos): the same
    // samples and interpolation as sigma0() and sigma0_flags() (radar/clutter/terrain.cpp).
    const bool want_flags = !sigma0_use.empty() || !cell_flags.empty();
    std::uint32_t flags = 0;
    double power = (want_flags ? static_cast<double>(materials_.table.lookup(
                                     f.sigma0_row, spec_.channel, cos_inc, flags))
                               : sigma0(f, cos_inc)) *
                   p.patch_area_m2;
    if (view.one_way_loss_db_per_m > 0.0)
      power *= std::pow(10.0, -0.2 * view.one_way_loss_db_per_m * range);
    const std::size_t cell = bin * grid.columns + col;
    double half_m = 0.0;
    if (spread) {
      // The patches' edges: the facet's edges / n, the same for every patch of the facet.
      const glm::dvec3 pe1 = (f.b_m - f.a_m) * p.inv_n, pe2 = (f.c_m - f.a_m) * p.inv_n;
      const glm::dvec3 pe3 = pe2 - pe1;
      half_m = 0.5 * std::max({std::abs(glm::dot(u, pe1)), std::abs(glm::dot(u, pe2)),
                               std::abs(glm::dot(u, pe3))});
    }
    if (half_m > 1e-6 * edge_step) {
      // The box [range - h, range + h] over the bins it overlaps, clipped to the grid (what
      // falls outside is lost, as for a patch outside). Weights sum to 1 inside the grid.
      const double lo = range - half_m, hi = range + half_m, inv_len = 0.5 / half_m;
      const auto b_lo = static_cast<std::size_t>(std::clamp(
          std::floor((lo - e[0]) * inv_edge_step), 0.0, static_cast<double>(grid.bins - 1)));
      const auto b_hi = static_cast<std::size_t>(std::clamp(
          std::floor((hi - e[0]) * inv_edge_step), 0.0, static_cast<double>(grid.bins - 1)));
      for (std::size_t b = b_lo; b <= b_hi; ++b) {
        const double w = (std::min(hi, e[b + 1]) - std::max(lo, e[b])) * inv_len;
        if (!(w > 0.0))
          continue;
        const std::size_t c = b * grid.columns + col;
        mean[c] += w * power;
        if (!elevation_power.empty())
          elevation_power[c] += w * power * sin_el;
      }
    } else {
      mean[cell] += power;
      if (!elevation_power.empty())
        elevation_power[cell] += power * sin_el;
    }
    if (want_flags) {  // issue 28: flagged sigma0 values
      if (f.sigma0_row < sigma0_use.size())
        sigma0_use[f.sigma0_row].add(flags, cos_inc, power);
      if (!cell_flags.empty())
        cell_flags[cell] |= flags;
    }
    ++st.patches_lit;
    if (field.empty())
      return;
    const double path = -k2 * range;
    const TerrainPatch patch{p.centre, p.patch_area_m2, p.key0 + p.k};
    for (std::size_t l = 0; l < looks; ++l) {
      const SpeckleSample s = speckle(patch, l);
      field[l * cells + cell] += std::polar(std::sqrt(power * static_cast<double>(s.intensity)),
                                            static_cast<double>(s.phase_rad) + path);
    }
  };
  auto flush = [&] {
    for (std::size_t i = 0; i < pending; ++i) {
      Pending& p = batch[i];
      const glm::dvec3 d = p.centre - view.position_m;
      // The fast azimuth from the unnormalised direction, so that it need not wait for the
      // range's square root and division: the azimuth of d and of u = d / R differ only by the
      // rounding of u (a few 1e-16 on a unit vector), at most ~1e-15 / rho_u rad with rho_u the
      // horizontal part of u in the antenna frame, kept above 1e-6 (otherwise the exact
      // azimuth) so that this stays below 1e-9 rad, far inside kFastAtan2Error_rad beside the
      // approximation's own 1.7e-6 rad.
      const glm::dvec3 ad = antenna_from_world * d;
      p.az = fast_atan2_estrin(ad.y, ad.x);
      p.col_f = (p.az - grid.azimuth_min_rad) * inv_azimuth_step;
      // The horizon's column and the interpolation's left column: cf and cf - 1/2 clear of the
      // integers, i.e. 2 cf clear of them by twice the margin (the doubling is exact).
      const double cf2 = terrain_hz ? 2.0 * ((p.az - hz.az0_rad) * inv_col_step) : 0.5;
      p.az_exact = !(std::max(std::abs(ad.x), std::abs(ad.y)) >
                     1e-6 * std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)})) ||
                   !clear_of_integers(p.col_f, margin_of(p.col_f, col_margin)) ||
                   !clear_of_integers(cf2, 2.0 * margin_of(cf2, hz_margin));
      // A patch at the radar itself (range 0) gets no usable unit vector: evaluate() leaves it
      // out before reading one.
      p.range = glm::length(d);
      p.u = d / p.range;
      p.a = antenna_from_world * p.u;
    }
    for (std::size_t i = 0; i < pending; ++i)
      evaluate(batch[i]);
    pending = 0;
  };
  auto patches_of = [&](std::uint32_t fi, double rc) {
    const TerrainFacet& f = facets_[fi];
    ++st.facets_considered;
    const std::uint32_t n = divisions(f, rc);
    const std::uint64_t count = static_cast<std::uint64_t>(n) * n;
    if (st.patches + count > view.max_patches) {
      ++st.budget_cut;
      return;
    }
    const double patch_area_m2 = f.area_m2 / static_cast<double>(count);
    const std::uint64_t key0 = mix64((static_cast<std::uint64_t>(fi) << 20) ^ n);
    const double inv_n = 1.0 / static_cast<double>(n);  // the patches' edges (spread_range)
    st.patches += count;
    for_each_patch(f, n, [&](const glm::dvec3& centre, std::uint32_t k) {
      if (pending == kBatch)
        flush();
      Pending& p = batch[pending++];
      p.centre = centre;
      p.f = &f;
      p.patch_area_m2 = patch_area_m2;
      p.inv_n = inv_n;
      p.key0 = key0;
      p.k = k;
    });
  };
  if (use_list) {
    for (std::size_t k = 0; k < listed; ++k) {
      if (k + kPrefetchAhead < listed)
        prefetch(facets_[facet_list[k + kPrefetchAhead]]);
      const std::uint32_t fi = facet_list[k];
      patches_of(fi, glm::length(facets_[fi].centroid_m - view.position_m));
    }
    flush();
    return st;
  }
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    double rt = 0.0;
    if (!sphere_meets(tiles_[t].centre_m, tiles_[t].radius_m, r_min, r_max, grid.azimuth_min_rad,
                      az_max, grid.elevation_min_rad, grid.elevation_max_rad, rt))
      continue;
    for (std::uint32_t j = tile_first_[t]; j < tile_first_[t + 1]; ++j) {
      const std::uint32_t fi = tile_facets_[j];
      double rc = 0.0;
      if (sphere_meets(facets_[fi].centroid_m, facets_[fi].radius_m, r_min, r_max,
                       grid.azimuth_min_rad, az_max, grid.elevation_min_rad, grid.elevation_max_rad,
                       rc))
        patches_of(fi, rc);
    }
  }
  flush();
  return st;
}

}  // namespace radar_emu::radar::clutter
