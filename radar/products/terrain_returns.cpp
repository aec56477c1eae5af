#include "radar/products/terrain_returns.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"
#include "radar/products/sar_terrain.hpp"

namespace radar_emu::radar {

namespace {

void require_field(bool ok, const char* field, const char* rule) {
  if (!ok)
    throw std::invalid_argument(std::string("terrain returns: ") + field + " " + rule);
}

const TerrainReturnsConfig& validated(const TerrainReturnsConfig& c) {
  require_field(std::isfinite(c.azimuth_min_rad) && std::isfinite(c.azimuth_max_rad) &&
                    c.azimuth_min_rad < c.azimuth_max_rad,
                "azimuth_min_rad/azimuth_max_rad", "must be finite, min < max");
  require_field(std::isfinite(c.elevation_min_rad) && std::isfinite(c.elevation_max_rad) &&
                    c.elevation_min_rad < c.elevation_max_rad,
                "elevation_min_rad/elevation_max_rad", "must be finite, min < max");
  require_field(std::isfinite(c.azimuth_cell_rad) && c.azimuth_cell_rad > 0.0, "azimuth_cell_rad",
                "must be > 0");
  require_field(std::isfinite(c.range_cell_m) && c.range_cell_m > 0.0, "range_cell_m",
                "must be > 0");
  require_field(std::isfinite(c.range_min_m) && std::isfinite(c.range_max_m) &&
                    c.range_min_m >= 0.0 && c.range_max_m > c.range_min_m,
                "range_min_m/range_max_m", "must be finite, 0 <= min < max");
  require_field(c.patch_fraction > 0.0 && c.patch_fraction <= 1.0, "patch_fraction",
                "must be in (0, 1]");
  require_field(std::isfinite(c.carrier_hz) && c.carrier_hz > 0.0, "carrier_hz", "must be > 0");
  require_field(c.slices >= 1, "slices", "must be >= 1");
  require_field(std::isfinite(c.coarse_azimuth_max_rad) && c.coarse_azimuth_max_rad >= 0.0,
                "coarse_azimuth_max_rad", "must be finite, >= 0");
  require_field(c.coarse_lod_merge == 0 || c.coarse_lod_level >= 1, "coarse_lod_level",
                "must be >= 1 (with coarse_lod_merge > 0)");
  return c;
}

std::size_t cells_along(double span, double step) {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(span / step - 1e-9)));
}

}  // namespace

TerrainReturns::TerrainReturns(const scene::Scene& scene, const SbrTracer& tracer,
                               const TerrainReturnsConfig& config)
    : config_(validated(config)), engine_(make_terrain_engine(scene, tracer, {})) {
  const TerrainReturnsConfig& c = config_;
  // The coarse level of detail's engine, where the scene has LOD levels above 0: facets as large
  // as the level's (20.8 m x 2^level cells on the generated terrain; max_facet_m 50 m x 2^level,
  // so that they are not split again).
  if (c.coarse_lod_merge > 0 &&
      std::any_of(scene.description().objects.begin(), scene.description().objects.end(),
                  [](const scene::ObjectDesc& o) { return o.lod_group >= 0 && o.lod_level > 0; })) {
    clutter::TerrainEngineSpec spec;
    spec.lod_level = c.coarse_lod_level;
    spec.max_facet_m *= std::ldexp(1.0, std::min(c.coarse_lod_level, 8));
    coarse_engine_.emplace(make_terrain_engine(scene, tracer, spec));
  }
  columns_ = cells_along(c.azimuth_max_rad - c.azimuth_min_rad, c.azimuth_cell_rad);
  bins_ = cells_along(c.range_max_m - c.range_min_m, c.range_cell_m);
  require_field(columns_ * bins_ <= c.max_cells, "cells",
                ("(" + std::to_string(columns_) + " columns x " + std::to_string(bins_) +
                 " bins) exceed max_cells: make the cells larger")
                    .c_str());
  edges_m_.resize(bins_ + 1);
  for (std::size_t b = 0; b <= bins_; ++b)
    edges_m_[b] = c.range_min_m + static_cast<double>(b) * c.range_cell_m;
  merged_edges_m_.assign(bins_ + 1, 0.0);
  for (std::size_t col = 0; col < columns_; ++col) {
    const double az = c.azimuth_min_rad + (static_cast<double>(col) + 0.5) * c.azimuth_cell_rad;
    cos_az_.push_back(std::cos(az));
    sin_az_.push_back(std::sin(az));
  }
  // The widest merge of columns (a power of two dividing the columns, within the widest column
  // allowed): the slices are cut at its multiples, so every merge at most as wide (a power of
  // two too) keeps each merged column within one slice.
  while (2 * azimuth_merge_max_ <= kMaxMerge && columns_ % (2 * azimuth_merge_max_) == 0 &&
         static_cast<double>(2 * azimuth_merge_max_) * c.azimuth_cell_rad <=
             c.coarse_azimuth_max_rad * (1.0 + 1e-9))
    azimuth_merge_max_ *= 2;
  const std::size_t units = columns_ / azimuth_merge_max_;
  // config.slices slices of columns (at least one unit of columns each), whatever the threads.
  const std::size_t n_slices = std::min(c.slices, units);
  slices_.resize(n_slices);
  sigma0_use_.resize(engine_.materials().table.materials());
  std::size_t first = 0;
  for (std::size_t s = 0; s < n_slices; ++s) {
    Slice& sl = slices_[s];
    sl.first_column = first;
    sl.columns = azimuth_merge_max_ * (units / n_slices + (s < units % n_slices ? 1 : 0));
    first += sl.columns;
    sl.mean.assign(sl.columns * bins_, 0.0);
    sl.elevation_power.assign(sl.columns * bins_, 0.0);
    sl.sigma0_use.resize(engine_.materials().table.materials());
    if (c.shadowing && c.horizon) {
      sl.horizon.assign(clutter::TerrainEngine::horizon_scratch_size(slice_grid(sl), view()), 0.0);
      sl.facet_list.assign(
          std::max(engine_.facets().size(), coarse_engine_ ? coarse_engine_->facets().size() : 0),
          0);
    }
  }
  // The object holding most of the terrain area labels the returns (Contribution::object_id).
  std::vector<double> area(scene.objects().size(), 0.0);
  for (const clutter::TerrainFacet& f : engine_.facets())
    area[f.object] += f.area_m2;
  terrain_object_ =
      static_cast<std::uint32_t>(std::max_element(area.begin(), area.end()) - area.begin());
}

TerrainCellMerge TerrainReturns::cell_merge(double scale, std::size_t azimuth_merge_max) noexcept {
  std::size_t k = 1;
  if (std::isfinite(scale))
    while (2 * k <= kMaxMerge && static_cast<double>(2 * k) <= scale * (1.0 + 1e-12))
      k *= 2;
  return {k, std::clamp<std::size_t>(azimuth_merge_max, 1, k)};
}

TerrainCoarsening TerrainReturns::coarsening() const noexcept {
  TerrainCoarsening t;
  t.azimuth_merge_max = azimuth_merge_max_;
  if (coarse_engine_) {
    t.lod_merge = config_.coarse_lod_merge;
    t.lod_facet_ratio = static_cast<double>(coarse_engine_->facets().size()) /
                        static_cast<double>(std::max<std::size_t>(1, engine_.facets().size()));
  }
  return t;
}

clutter::TerrainView TerrainReturns::view(TerrainCellMerge m) const noexcept {
  const TerrainReturnsConfig& c = config_;
  clutter::TerrainView v;
  v.wavelength_m = kSpeedOfLight_mps / c.carrier_hz;
  v.patch_min_m = c.range_cell_m * c.patch_fraction;
  v.patch_angle_rad = c.azimuth_cell_rad * c.patch_fraction;
  v.shadowing = c.shadowing;
  // Far out a patch (R x azimuth cell wide) spans several range cells: its power goes to each
  // of them by overlap, not whole to one (TerrainView::spread_range).
  v.spread_range = true;
  v.shadow_method =
      c.horizon ? clutter::TerrainView::Shadow::kHorizon : clutter::TerrainView::Shadow::kRays;
  // The horizon: columns of half a (merged) cell, bins of half a (merged) range cell along rho.
  v.horizon_azimuth_rad = 0.5 * c.azimuth_cell_rad * static_cast<double>(m.azimuth);
  v.horizon_rho_m = 0.5 * c.range_cell_m * static_cast<double>(m.range);
  v.max_patches =
      std::max<std::uint64_t>(1, c.max_patches / std::max<std::size_t>(1, slices_.size()));
  return v;
}

clutter::CellGrid TerrainReturns::slice_grid(const Slice& sl, TerrainCellMerge m) const noexcept {
  const TerrainReturnsConfig& c = config_;
  clutter::CellGrid grid;
  grid.azimuth_step_rad = c.azimuth_cell_rad * static_cast<double>(m.azimuth);
  grid.azimuth_min_rad =
      c.azimuth_min_rad + static_cast<double>(sl.first_column) * c.azimuth_cell_rad;
  grid.columns = sl.columns / m.azimuth;
  grid.elevation_min_rad = c.elevation_min_rad;
  grid.elevation_max_rad = c.elevation_max_rad;
  grid.bins = merged_bins(m.range);
  grid.range_edges_m = m.range > 1 ? std::span<const double>(merged_edges_m_).first(grid.bins + 1)
                                   : std::span<const double>(edges_m_);
  return grid;
}

std::size_t TerrainReturns::compute(const RadarPose& pose, std::span<Contribution> out,
                                    clutter::TerrainStats& stats, std::uint64_t& dropped,
                                    double scale) noexcept {
  const TerrainReturnsConfig& c = config_;
  const TerrainCellMerge m = cell_merge(scale, azimuth_merge_max_);
  clutter::TerrainView v = view(m);
  v.position_m = pose.position_m;
  v.world_from_antenna = pose.world_from_antenna;
  if (scale > 1.0 && std::isfinite(scale)) {  // else the configured size
    v.patch_min_m *= scale;
    v.patch_angle_rad *= scale;
  }
  const std::size_t bins = merged_bins(m.range);
  if (m.range > 1)  // every m.range-th fine edge, the last past range_max_m (the same formula)
    for (std::size_t b = 0; b <= bins; ++b)
      merged_edges_m_[b] = c.range_min_m + static_cast<double>(b * m.range) * c.range_cell_m;
  const clutter::TerrainEngine& engine =
      coarse_engine_ && m.range >= c.coarse_lod_merge ? *coarse_engine_ : engine_;
  tbb::parallel_for(std::size_t{0}, slices_.size(), [&](std::size_t s) {
    Slice& sl = slices_[s];
    const std::size_t cells = bins * (sl.columns / m.azimuth);
    std::fill_n(sl.mean.begin(), cells, 0.0);
    std::fill_n(sl.elevation_power.begin(), cells, 0.0);
    std::fill(sl.sigma0_use.begin(), sl.sigma0_use.end(), clutter::Sigma0Use{});
    sl.stats = engine.integrate(v, slice_grid(sl, m), {}, std::span(sl.mean).first(cells),
                                std::span(sl.elevation_power).first(cells), sl.horizon,
                                sl.facet_list, sl.sigma0_use);
  });
  const std::span<const double> edges =
      m.range > 1 ? std::span<const double>(merged_edges_m_) : std::span<const double>(edges_m_);
  const double column_rad = c.azimuth_cell_rad * static_cast<double>(m.azimuth);
  for (const Slice& sl : slices_)
    for (std::size_t r = 0; r < sl.sigma0_use.size() && r < sigma0_use_.size(); ++r)
      sigma0_use_[r].merge(sl.sigma0_use[r]);
  const glm::dmat3& r = pose.world_from_antenna;
  std::size_t n = 0;
  for (const Slice& sl : slices_) {
    stats.facets_considered += sl.stats.facets_considered;
    stats.patches += sl.stats.patches;
    stats.patches_lit += sl.stats.patches_lit;
    stats.patches_shadowed += sl.stats.patches_shadowed;
    stats.patches_grazing += sl.stats.patches_grazing;
    stats.patches_outside += sl.stats.patches_outside;
    stats.budget_cut += sl.stats.budget_cut;
    stats.horizon_patches += sl.stats.horizon_patches;
    stats.occlusion_queries += sl.stats.occlusion_queries;
    stats.horizon_coarsened += sl.stats.horizon_coarsened;
    const std::size_t columns = sl.columns / m.azimuth;
    for (std::size_t b = 0; b < bins; ++b) {
      for (std::size_t col = 0; col < columns; ++col) {
        const std::size_t cell = b * columns + col;
        const double power = sl.mean[cell];
        if (!(power > 0.0))
          continue;
        if (n >= out.size()) {
          ++dropped;
          continue;
        }
        const std::size_t column = sl.first_column + col;  // fine columns: the table's
        const double sin_el = std::clamp(sl.elevation_power[cell] / power, -1.0, 1.0);
        const double cos_el = std::sqrt(1.0 - sin_el * sin_el);
        // The (merged) column's centre.
        const double az = c.azimuth_min_rad +
                          static_cast<double>(sl.first_column) * c.azimuth_cell_rad +
                          (static_cast<double>(col) + 0.5) * column_rad;
        const double cos_az = m.azimuth == 1 ? cos_az_[column] : std::cos(az);
        const double sin_az = m.azimuth == 1 ? sin_az_[column] : std::sin(az);
        // direction_from_azel (radar/em/sbr.hpp) from the column's sine and cosine, in the world.
        const glm::dvec3 u = r * glm::dvec3(cos_el * cos_az, cos_el * sin_az, -sin_el);
        Contribution& x = out[n++];
        x = Contribution{};
        x.amplitude = {std::sqrt(power), 0.0};
        x.range_m = 0.5 * (edges[b] + edges[b + 1]);
        x.range_spread_m = edges[b + 1] - edges[b];
        x.radial_velocity_mps = -glm::dot(pose.velocity_mps, u);
        x.azimuth_rad = m.azimuth == 1 ? c.azimuth_min_rad + (static_cast<double>(column) + 0.5) *
                                                                 c.azimuth_cell_rad
                                       : az;
        x.elevation_rad = std::asin(sin_el);
        x.object_id = terrain_object_;
        x.bounces = 1;
        x.coherent = false;
      }
    }
  }
  return n;
}

}  // namespace radar_emu::radar
