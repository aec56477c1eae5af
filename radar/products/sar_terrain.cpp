#include "radar/products/sar_terrain.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>

#include "radar/em/surfaces.hpp"

namespace radar_emu::radar {

clutter::TerrainEngine make_terrain_engine(const scene::Scene& scene, const SbrTracer& tracer,
                                           clutter::TerrainEngineSpec spec) {
  const SurfaceSet& s = tracer.surfaces();
  std::vector<int> rows;
  for (const Surface& m : s.surfaces)
    rows.push_back(m.sigma0_row);
  std::vector<std::uint8_t> structures(scene.objects().size(), 0);
  for (std::uint32_t id = 0; id < structures.size(); ++id)
    structures[id] = tracer.is_target(id) ? 1 : 0;
  spec.channel = s.channel;
  return clutter::TerrainEngine(
      scene, clutter::terrain_materials(rows, s.sigma0_table, scene.materials()), structures, spec);
}

TerrainCells terrain_cells(const clutter::TerrainEngine& engine, const SarParams& p,
                           double patch_m) {
  validate(p);
  if (!(patch_m > 0.0) || !std::isfinite(patch_m))
    throw std::invalid_argument("sar terrain: patch size must be > 0");
  const auto facets = engine.facets();
  // Patches per facet, and where each facet's start in the output.
  std::vector<std::size_t> first(facets.size() + 1, 0);
  for (std::size_t i = 0; i < facets.size(); ++i) {
    const std::uint64_t n = clutter::patch_divisions(facets[i], patch_m);
    first[i + 1] = first[i] + n * n;
  }
  if (first.back() > 200'000'000ull)
    throw std::invalid_argument("sar terrain: more than 2e8 patches; make the patches larger");
  const glm::dvec3 track = sar_track_dir(p);
  std::vector<SarScatterer> all(first.back());
  std::vector<std::uint8_t> lit(first.back(), 0);
  // Issue 28: each thread's Sigma0Use per sigma0 row, merged after.
  const std::size_t rows_s0 = engine.materials().table.materials();
  tbb::enumerable_thread_specific<std::vector<clutter::Sigma0Use>> use(
      [rows_s0] { return std::vector<clutter::Sigma0Use>(rows_s0); });
  tbb::parallel_for(std::size_t{0}, facets.size(), [&](std::size_t i) {
    std::vector<clutter::Sigma0Use>& my_use = use.local();
    const clutter::TerrainFacet& f = facets[i];
    const std::uint32_t n = clutter::patch_divisions(f, patch_m);
    for (std::uint32_t k = 0; k < n * n; ++k) {
      const clutter::TerrainPatch pt = clutter::facet_patch(f, static_cast<std::uint32_t>(i), n, k);
      // The platform at broadside of the patch.
      const glm::dvec3 radar =
          p.start_position_m + glm::dot(pt.centre_m - p.start_position_m, track) * track;
      const glm::dvec3 to = radar - pt.centre_m;
      const double dist = glm::length(to);
      const double cos_inc = std::abs(glm::dot(f.normal, to / dist));
      if (!(cos_inc > 1e-9) || !engine.clear(pt.centre_m, f.normal, radar))
        continue;
      const double power = engine.sigma0(f, cos_inc) * pt.area_m2;
      if (f.sigma0_row < my_use.size())
        my_use[f.sigma0_row].add(engine.sigma0_flags(f, cos_inc), cos_inc, power);
      const clutter::SpeckleSample s = engine.speckle(pt, 0);
      all[first[i] + k] = {pt.centre_m,
                           std::polar(std::sqrt(power * double(s.intensity)), double(s.phase_rad))};
      lit[first[i] + k] = 1;
    }
  });
  TerrainCells out;
  out.sigma0_use.resize(rows_s0);
  for (const std::vector<clutter::Sigma0Use>& u : use)
    for (std::size_t r = 0; r < rows_s0; ++r)
      out.sigma0_use[r].merge(u[r]);
  out.patches = all.size();
  out.area_m2 = engine.area_m2();
  std::size_t n_lit = 0;
  for (std::uint8_t l : lit)
    n_lit += l;
  out.cells.reserve(n_lit);
  for (std::size_t i = 0; i < all.size(); ++i)
    if (lit[i] != 0)
      out.cells.push_back(all[i]);
  out.shadowed = all.size() - n_lit;
  return out;
}

SarDem sar_dem(const clutter::TerrainEngine& engine, const SarParams& p, const SarImageGrid& grid) {
  validate(p);
  if (grid.rows == 0 || grid.cols == 0 || !(grid.azimuth_spacing_m > 0.0) ||
      !(grid.ground_range_spacing_m > 0.0))
    throw std::invalid_argument("sar DEM: the image grid is empty");
  const glm::dvec3 track = sar_track_dir(p), look = sar_look_dir(p);
  const std::size_t n = grid.rows * grid.cols;
  constexpr float kNone = -std::numeric_limits<float>::infinity();
  SarDem dem;
  dem.height_m.assign(n, kNone);
  dem.mask.assign(n, 0);
  dem.facet.assign(n, -1);
  dem.sigma0_flags.assign(n, 0u);
  // Rasterise each facet's horizontal projection at the pixel centres (grid coordinates: row
  // along track, column along the look direction); the highest surface wins.
  const auto facets = engine.facets();
  for (std::size_t fi = 0; fi < facets.size(); ++fi) {
    const clutter::TerrainFacet& f = facets[fi];
    glm::dvec2 q[3];
    const glm::dvec3 v[3] = {f.a_m, f.b_m, f.c_m};
    for (int i = 0; i < 3; ++i) {
      const glm::dvec3 rel = v[i] - grid.origin_m;
      q[i] = {glm::dot(rel, track) / grid.azimuth_spacing_m,
              glm::dot(rel, look) / grid.ground_range_spacing_m};
    }
    const double det =
        (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
    if (std::abs(det) < 1e-12)
      continue;  // vertical facet: no area seen from above
    const double r0 = std::max(0.0, std::ceil(std::min({q[0].x, q[1].x, q[2].x})));
    const double r1 =
        std::min(double(grid.rows) - 1, std::floor(std::max({q[0].x, q[1].x, q[2].x})));
    const double c0 = std::max(0.0, std::ceil(std::min({q[0].y, q[1].y, q[2].y})));
    const double c1 =
        std::min(double(grid.cols) - 1, std::floor(std::max({q[0].y, q[1].y, q[2].y})));
    for (double r = r0; r <= r1; r += 1.0)
      for (double c = c0; c <= c1; c += 1.0) {
        const double l1 =
            ((r - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (c - q[0].y)) / det;
        const double l2 =
            ((q[1].x - q[0].x) * (c - q[0].y) - (r - q[0].x) * (q[1].y - q[0].y)) / det;
        const double tol = -1e-9;
        if (l1 < tol || l2 < tol || 1.0 - l1 - l2 < tol)
          continue;
        const double z = f.a_m.z + l1 * (f.b_m.z - f.a_m.z) + l2 * (f.c_m.z - f.a_m.z);
        const std::size_t i = static_cast<std::size_t>(r) * grid.cols + static_cast<std::size_t>(c);
        if (static_cast<float>(z) > dem.height_m[i]) {
          dem.height_m[i] = static_cast<float>(z);
          dem.facet[i] = static_cast<std::int32_t>(fi);
        }
      }
  }
  // Holes: the nearest covered pixel of the row, else the mean height (flagged).
  double sum = 0.0;
  std::size_t covered = 0;
  for (float h : dem.height_m)
    if (h != kNone) {
      sum += static_cast<double>(h);
      ++covered;
    }
  const float mean = covered > 0 ? static_cast<float>(sum / double(covered)) : 0.0f;
  for (std::size_t r = 0; r < grid.rows; ++r) {
    float* row = dem.height_m.data() + r * grid.cols;
    std::uint8_t* m = dem.mask.data() + r * grid.cols;
    for (std::size_t c = 0; c < grid.cols; ++c) {
      if (row[c] != kNone)
        continue;
      m[c] |= kSarNoDem;
      ++dem.holes;
    }
    for (std::size_t c = 0; c < grid.cols; ++c) {
      if ((m[c] & kSarNoDem) == 0)
        continue;
      float best = mean;
      std::size_t best_d = std::numeric_limits<std::size_t>::max();
      for (std::size_t k = 0; k < grid.cols; ++k)
        if ((m[k] & kSarNoDem) == 0) {
          const std::size_t d = k > c ? k - c : c - k;
          if (d < best_d) {
            best_d = d;
            best = row[k];
          }
        }
      row[c] = best;
    }
  }
  // Mask.
  tbb::parallel_for(std::size_t{0}, grid.rows, [&](std::size_t r) {
    for (std::size_t c = 0; c < grid.cols; ++c) {
      const std::size_t i = r * grid.cols + c;
      const double z = static_cast<double>(dem.height_m[i]);
      const glm::dvec3 x = grid.origin_m + double(r) * grid.azimuth_spacing_m * track +
                           double(c) * grid.ground_range_spacing_m * look;
      const glm::dvec3 pt{x.x, x.y, z};
      const glm::dvec3 radar =
          p.start_position_m + glm::dot(pt - p.start_position_m, track) * track;
      const std::size_t ca = c > 0 ? c - 1 : c, cb = c + 1 < grid.cols ? c + 1 : c;
      const double s = cb > ca ? (double(dem.height_m[r * grid.cols + cb]) -
                                  double(dem.height_m[r * grid.cols + ca])) /
                                     (double(cb - ca) * grid.ground_range_spacing_m)
                               : 0.0;
      const glm::dvec3 hz = pt - radar;
      const double g = std::hypot(hz.x, hz.y), below = radar.z - z;
      std::uint8_t bits = 0;
      if (below > 0.0 && s * below > g)
        bits |= kSarLayover;
      else if (below > 0.0 && s * below > 0.2 * g)
        bits |= kSarForeshortening;
      if (!engine.clear(pt, {0.0, 0.0, 1.0}, radar))
        bits |= kSarShadow;
      dem.mask[i] |= bits;
      if (dem.facet[i] >= 0) {  // the sigma0 sample the pixel's terrain reads (issue 28)
        const clutter::TerrainFacet& f = facets[static_cast<std::size_t>(dem.facet[i])];
        const glm::dvec3 to = radar - pt;
        const double dist = glm::length(to);
        if (dist > 0.0)
          dem.sigma0_flags[i] = engine.sigma0_flags(f, std::abs(glm::dot(f.normal, to / dist)));
      }
    }
  });
  for (std::uint8_t m : dem.mask) {
    dem.shadow += (m & kSarShadow) != 0;
    dem.layover += (m & kSarLayover) != 0;
    dem.foreshortening += (m & kSarForeshortening) != 0;
  }
  for (std::size_t i = 0; i < n; ++i) {
    dem.sigma0_pixels += static_cast<std::size_t>(dem.facet[i] >= 0);
    dem.sigma0_flagged += static_cast<std::size_t>(dem.facet[i] >= 0 && dem.sigma0_flags[i] != 0u);
  }
  return dem;
}

}  // namespace radar_emu::radar
