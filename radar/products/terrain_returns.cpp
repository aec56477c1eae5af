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
  columns_ = cells_along(c.azimuth_max_rad - c.azimuth_min_rad, c.azimuth_cell_rad);
  bins_ = cells_along(c.range_max_m - c.range_min_m, c.range_cell_m);
  require_field(columns_ * bins_ <= c.max_cells, "cells",
                ("(" + std::to_string(columns_) + " columns x " + std::to_string(bins_) +
                 " bins) exceed max_cells: make the cells larger")
                    .c_str());
  edges_m_.resize(bins_ + 1);
  for (std::size_t b = 0; b <= bins_; ++b)
    edges_m_[b] = c.range_min_m + static_cast<double>(b) * c.range_cell_m;
  for (std::size_t col = 0; col < columns_; ++col) {
    const double az = c.azimuth_min_rad + (static_cast<double>(col) + 0.5) * c.azimuth_cell_rad;
    cos_az_.push_back(std::cos(az));
    sin_az_.push_back(std::sin(az));
  }
  // config.slices slices of columns (at least one column each), whatever the threads.
  const std::size_t n_slices = std::min(c.slices, columns_);
  slices_.resize(n_slices);
  sigma0_use_.resize(engine_.materials().table.materials());
  std::size_t first = 0;
  for (std::size_t s = 0; s < n_slices; ++s) {
    Slice& sl = slices_[s];
    sl.first_column = first;
    sl.columns = columns_ / n_slices + (s < columns_ % n_slices ? 1 : 0);
    first += sl.columns;
    sl.mean.assign(sl.columns * bins_, 0.0);
    sl.elevation_power.assign(sl.columns * bins_, 0.0);
    sl.sigma0_use.resize(engine_.materials().table.materials());
    if (c.shadowing && c.horizon) {
      sl.horizon.assign(clutter::TerrainEngine::horizon_scratch_size(slice_grid(sl), view()), 0.0);
      sl.facet_list.assign(engine_.facets().size(), 0);
    }
  }
  // The object holding most of the terrain area labels the returns (Contribution::object_id).
  std::vector<double> area(scene.objects().size(), 0.0);
  for (const clutter::TerrainFacet& f : engine_.facets())
    area[f.object] += f.area_m2;
  terrain_object_ =
      static_cast<std::uint32_t>(std::max_element(area.begin(), area.end()) - area.begin());
}

clutter::TerrainView TerrainReturns::view() const noexcept {
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
  // The horizon: columns of half a cell, bins of half a range cell along rho.
  v.horizon_azimuth_rad = 0.5 * c.azimuth_cell_rad;
  v.horizon_rho_m = 0.5 * c.range_cell_m;
  v.max_patches =
      std::max<std::uint64_t>(1, c.max_patches / std::max<std::size_t>(1, slices_.size()));
  return v;
}

clutter::CellGrid TerrainReturns::slice_grid(const Slice& sl) const noexcept {
  const TerrainReturnsConfig& c = config_;
  clutter::CellGrid grid;
  grid.azimuth_step_rad = c.azimuth_cell_rad;
  grid.azimuth_min_rad =
      c.azimuth_min_rad + static_cast<double>(sl.first_column) * c.azimuth_cell_rad;
  grid.columns = sl.columns;
  grid.elevation_min_rad = c.elevation_min_rad;
  grid.elevation_max_rad = c.elevation_max_rad;
  grid.bins = bins_;
  grid.range_edges_m = edges_m_;
  return grid;
}

std::size_t TerrainReturns::compute(const RadarPose& pose, std::span<Contribution> out,
                                    clutter::TerrainStats& stats, std::uint64_t& dropped,
                                    double patch_scale) noexcept {
  const TerrainReturnsConfig& c = config_;
  clutter::TerrainView v = view();
  v.position_m = pose.position_m;
  v.world_from_antenna = pose.world_from_antenna;
  if (patch_scale > 1.0 && std::isfinite(patch_scale)) {  // else the configured size
    v.patch_min_m *= patch_scale;
    v.patch_angle_rad *= patch_scale;
  }
  tbb::parallel_for(std::size_t{0}, slices_.size(), [&](std::size_t s) {
    Slice& sl = slices_[s];
    std::fill(sl.mean.begin(), sl.mean.end(), 0.0);
    std::fill(sl.elevation_power.begin(), sl.elevation_power.end(), 0.0);
    std::fill(sl.sigma0_use.begin(), sl.sigma0_use.end(), clutter::Sigma0Use{});
    sl.stats = engine_.integrate(v, slice_grid(sl), {}, sl.mean, sl.elevation_power, sl.horizon,
                                 sl.facet_list, sl.sigma0_use);
  });
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
    for (std::size_t b = 0; b < bins_; ++b) {
      for (std::size_t col = 0; col < sl.columns; ++col) {
        const std::size_t cell = b * sl.columns + col;
        const double power = sl.mean[cell];
        if (!(power > 0.0))
          continue;
        if (n >= out.size()) {
          ++dropped;
          continue;
        }
        const std::size_t column = sl.first_column + col;
        const double sin_el = std::clamp(sl.elevation_power[cell] / power, -1.0, 1.0);
        const double cos_el = std::sqrt(1.0 - sin_el * sin_el);
        // direction_from_azel (radar/em/sbr.hpp) from the column's sine and cosine, in the world.
        const glm::dvec3 u =
            r * glm::dvec3(cos_el * cos_az_[column], cos_el * sin_az_[column], -sin_el);
        Contribution& x = out[n++];
        x = Contribution{};
        x.amplitude = {std::sqrt(power), 0.0};
        x.range_m = 0.5 * (edges_m_[b] + edges_m_[b + 1]);
        x.range_spread_m = edges_m_[b + 1] - edges_m_[b];
        x.radial_velocity_mps = -glm::dot(pose.velocity_mps, u);
        x.azimuth_rad =
            c.azimuth_min_rad + (static_cast<double>(column) + 0.5) * c.azimuth_cell_rad;
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
