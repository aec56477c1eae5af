#include "radar/products/ev_image.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "radar/clutter/speckle.hpp"

namespace radar_emu::radar {

namespace {

void require(bool ok, const char* field, const char* expected) {
  if (!ok)
    throw std::invalid_argument(std::string("EV image: ") + field + " " + expected);
}

void validate(const EvImageConfig& c) {
  constexpr double kHalfPi = std::numbers::pi / 2.0;
  require(std::isfinite(c.azimuth_min_rad) && std::isfinite(c.azimuth_max_rad) &&
              c.azimuth_min_rad < c.azimuth_max_rad && c.azimuth_min_rad > -kHalfPi &&
              c.azimuth_max_rad < kHalfPi,
          "azimuth_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  require(std::isfinite(c.elevation_min_rad) && std::isfinite(c.elevation_max_rad) &&
              c.elevation_min_rad < c.elevation_max_rad && c.elevation_min_rad > -kHalfPi &&
              c.elevation_max_rad < kHalfPi,
          "elevation_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  require(std::isfinite(c.pixel_rad) && c.pixel_rad > 0.0 &&
              c.pixel_rad <= c.azimuth_max_rad - c.azimuth_min_rad + 1e-12 &&
              c.pixel_rad <= c.elevation_max_rad - c.elevation_min_rad + 1e-12,
          "pixel_rad", "must be > 0 and fit the field both ways");
  require(std::isfinite(c.ground_height_m), "ground_height_m", "must be finite");
  require(c.looks >= 1 && c.looks <= 10000, "looks", "must be in 1..10000");
  // 2^24 pixels at most (a 0.15 deg grid over a hemisphere is 1.4 M).
  const double cells = std::floor((c.azimuth_max_rad - c.azimuth_min_rad) / c.pixel_rad + 1e-9) *
                       std::floor((c.elevation_max_rad - c.elevation_min_rad) / c.pixel_rad + 1e-9);
  require(cells <= double(1 << 24), "pixel_rad", "gives more than 2^24 pixels");
}

}  // namespace

int ev_image_columns(const EvImageConfig& c) {
  validate(c);
  return std::max(1, static_cast<int>(
                         std::floor((c.azimuth_max_rad - c.azimuth_min_rad) / c.pixel_rad + 1e-9)));
}

int ev_image_rows(const EvImageConfig& c) {
  validate(c);
  return std::max(1, static_cast<int>(std::floor(
                         (c.elevation_max_rad - c.elevation_min_rad) / c.pixel_rad + 1e-9)));
}

double ev_column_azimuth_rad(const EvImageConfig& c, int column) noexcept {
  return c.azimuth_min_rad + (column + 0.5) * c.pixel_rad;
}

double ev_row_elevation_rad(const EvImageConfig& c, int row) noexcept {
  return c.elevation_max_rad - (row + 0.5) * c.pixel_rad;
}

EvImage form_ev_image(std::span<const Contribution> contributions, const RadarPose& pose,
                      const EvImageConfig& c) {
  EvTerrain none;
  return form_ev_image(contributions, pose, c, none);
}

EvImage form_ev_image(std::span<const Contribution> contributions, const RadarPose& pose,
                      const EvImageConfig& c, EvTerrain& terrain) {
  const bool engine = terrain.engine != nullptr;
  EvImage img;
  img.columns = ev_image_columns(c);
  img.rows = ev_image_rows(c);
  const auto cols = static_cast<std::size_t>(img.columns);
  const auto rows = static_cast<std::size_t>(img.rows);
  const std::size_t cells = cols * rows;
  constexpr double kInf = std::numeric_limits<double>::infinity();

  // Range edges per column (header: R = (z_a - z_g) / (-w_z)); edge k at el_max - k p.
  const double height_m = pose.position_m.z - c.ground_height_m;
  img.range_edges_m.assign(cols * (rows + 1), kInf);
  for (std::size_t col = 0; col < cols; ++col) {
    const double az = ev_column_azimuth_rad(c, static_cast<int>(col));
    for (std::size_t k = 0; k <= rows; ++k) {
      const double el = c.elevation_max_rad - static_cast<double>(k) * c.pixel_rad;
      const glm::dvec3 w = pose.world_from_antenna * direction_from_azel({az, el});
      if (w.z < 0.0 && height_m > 0.0)
        img.range_edges_m[col * (rows + 1) + k] = height_m / -w.z;
    }
  }

  // Each contribution's cell (or none), found once for every look.
  std::vector<std::uint32_t> cell(contributions.size(), std::numeric_limits<std::uint32_t>::max());
  for (std::size_t i = 0; i < contributions.size(); ++i) {
    const Contribution& q = contributions[i];
    if (engine && !q.coherent)
      continue;  // terrain comes from the engine
    const double x = (q.azimuth_rad - c.azimuth_min_rad) / c.pixel_rad;
    if (!(x >= 0.0 && x < static_cast<double>(cols))) {
      ++img.outside_columns;
      continue;
    }
    const auto col = static_cast<std::size_t>(x);
    const double* edges = img.range_edges_m.data() + col * (rows + 1);
    if (!std::isfinite(edges[rows])) {
      ++img.no_ground;
      continue;
    }
    if (!(q.range_m >= edges[rows])) {
      ++img.nearer_than_field;
      continue;
    }
    if (q.range_m >= edges[0]) {  // beyond the top row (the whole column sees the ground)
      ++img.farther_than_field;
      continue;
    }
    // Edges fall with k: the row is the last k with edges[k + 1] <= R, i.e. the first edge
    // k + 1 (k + 1 in 1..rows) with edges[k + 1] <= R.
    std::size_t lo = 0, hi = rows;  // edges[hi] <= R; find the smallest such index >= 1
    while (hi - lo > 1) {
      const std::size_t mid = (lo + hi) / 2;
      if (edges[mid] <= q.range_m)
        hi = mid;
      else
        lo = mid;
    }
    const std::size_t row = hi - 1;
    cell[i] = static_cast<std::uint32_t>(row * cols + col);
    ++img.contributions_used;
  }

  // The mean image: clutter powers plus the targets' coherent sum.
  std::vector<std::complex<double>> coherent(cells, {0.0, 0.0});
  std::vector<double> clutter_power(cells, 0.0);
  for (std::size_t i = 0; i < contributions.size(); ++i) {
    if (cell[i] == std::numeric_limits<std::uint32_t>::max())
      continue;
    const Contribution& q = contributions[i];
    if (q.coherent)
      coherent[cell[i]] += q.amplitude;
    else
      clutter_power[cell[i]] += std::norm(q.amplitude);
  }
  // The engine's terrain: its cells are (bin b = rows - 1 - r, column), range edges ascending.
  const std::size_t looks_engine = c.speckle ? static_cast<std::size_t>(c.looks) : 1;
  std::vector<std::complex<double>> terrain_field;
  if (engine) {
    std::vector<double> asc(cols * (rows + 1));
    for (std::size_t col = 0; col < cols; ++col)
      for (std::size_t b = 0; b <= rows; ++b)
        asc[col * (rows + 1) + b] = img.range_edges_m[col * (rows + 1) + (rows - b)];
    clutter::TerrainView v;
    v.position_m = pose.position_m;
    v.world_from_antenna = pose.world_from_antenna;
    v.wavelength_m = terrain.wavelength_m;
    v.patch_min_m = terrain.patch_min_m;
    v.patch_angle_rad = c.pixel_rad / 2.0;
    v.looks = looks_engine;
    v.one_way_loss_db_per_m = terrain.one_way_loss_db_per_m;
    // Blocks of columns in parallel, each its own grid and buffers (the result does not depend
    // on the threading: every cell is summed by one block in facet order).
    constexpr std::size_t kBlock = 8;
    const std::size_t blocks = (cols + kBlock - 1) / kBlock;
    std::vector<clutter::TerrainStats> block_stats(blocks);
    // Issue 28: what each block read from flagged sigma0 samples, merged below.
    const std::size_t rows_s0 = terrain.engine->materials().table.materials();
    std::vector<std::vector<clutter::Sigma0Use>> block_use(
        blocks, std::vector<clutter::Sigma0Use>(rows_s0));
    std::vector<std::uint64_t> block_terrain_cells(blocks, 0), block_flagged_cells(blocks, 0);
    terrain_field.assign(looks_engine * cells, {0.0, 0.0});
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t k) {
      const std::size_t c0 = k * kBlock, nc = std::min(kBlock, cols - c0), bc = nc * rows;
      clutter::CellGrid cg;
      cg.azimuth_min_rad = c.azimuth_min_rad + static_cast<double>(c0) * c.pixel_rad;
      cg.azimuth_step_rad = c.pixel_rad;
      cg.columns = nc;
      cg.elevation_min_rad = c.elevation_min_rad;
      cg.elevation_max_rad = c.elevation_max_rad;
      cg.bins = rows;
      cg.range_edges_m = std::span<const double>(asc).subspan(c0 * (rows + 1), nc * (rows + 1));
      cg.per_column_edges = true;
      std::vector<double> mean(bc, 0.0);
      std::vector<std::complex<double>> field(looks_engine * bc);
      std::vector<std::uint32_t> cell_flags(bc, 0u);
      block_stats[k] =
          terrain.engine->integrate(v, cg, field, mean, {}, {}, {}, block_use[k], cell_flags);
      for (std::size_t i = 0; i < bc; ++i) {
        block_terrain_cells[k] += static_cast<std::uint64_t>(mean[i] > 0.0);
        block_flagged_cells[k] += static_cast<std::uint64_t>(mean[i] > 0.0 && cell_flags[i] != 0u);
      }
      // Back to the image's rows (row r = bin rows - 1 - r) and columns.
      for (std::size_t b = 0; b < rows; ++b)
        for (std::size_t j = 0; j < nc; ++j) {
          const std::size_t from = b * nc + j, to = (rows - 1 - b) * cols + c0 + j;
          clutter_power[to] += mean[from];
          for (std::size_t l = 0; l < looks_engine; ++l)
            terrain_field[l * cells + to] = field[l * bc + from];
        }
    });
    if (terrain.sigma0_use.size() < rows_s0)
      terrain.sigma0_use.resize(rows_s0);
    for (std::size_t k = 0; k < blocks; ++k) {
      for (std::size_t r = 0; r < rows_s0; ++r)
        terrain.sigma0_use[r].merge(block_use[k][r]);
      terrain.terrain_cells += block_terrain_cells[k];
      terrain.flagged_cells += block_flagged_cells[k];
    }
    for (const clutter::TerrainStats& b : block_stats) {
      terrain.stats.facets_considered += b.facets_considered;
      terrain.stats.patches += b.patches;
      terrain.stats.patches_lit += b.patches_lit;
      terrain.stats.patches_shadowed += b.patches_shadowed;
      terrain.stats.occlusion_queries += b.occlusion_queries;
      terrain.stats.patches_grazing += b.patches_grazing;
      terrain.stats.patches_outside += b.patches_outside;
      terrain.stats.budget_cut += b.budget_cut;
    }
  }
  img.mean_m2.resize(cells);
  for (std::size_t p = 0; p < cells; ++p)
    img.mean_m2[p] = static_cast<float>(clutter_power[p] + std::norm(coherent[p]));
  if (engine) {
    // Looks: the targets' coherent sum plus the engine's field of that look.
    if (!c.speckle) {
      img.intensity_m2 = img.mean_m2;
      return img;
    }
    img.intensity_m2.assign(cells, 0.0f);
    for (std::size_t p = 0; p < cells; ++p) {
      double sum = 0.0;
      for (std::size_t l = 0; l < looks_engine; ++l)
        sum += std::norm(coherent[p] + terrain_field[l * cells + p]);
      img.intensity_m2[p] = static_cast<float>(sum / static_cast<double>(looks_engine));
    }
    return img;
  }
  if (!c.speckle) {
    img.intensity_m2 = img.mean_m2;
    return img;
  }

  // N looks of independent speckle, each summed coherently per cell (looks in parallel, added
  // in look order: the result does not depend on the threading).
  const auto looks = static_cast<std::size_t>(c.looks);
  const std::uint64_t n = contributions.size();
  clutter::SpeckleSpec spec;
  spec.model = clutter::SpeckleModel::kExponential;
  spec.seed = c.seed;
  std::vector<std::vector<float>> look_power(looks);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, looks), [&](const tbb::blocked_range<std::size_t>& range) {
        std::vector<std::complex<double>> field(cells);
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
          std::copy(coherent.begin(), coherent.end(), field.begin());
          for (std::size_t i = 0; i < contributions.size(); ++i) {
            const Contribution& q = contributions[i];
            if (q.coherent || cell[i] == std::numeric_limits<std::uint32_t>::max())
              continue;
            const clutter::SpeckleSample s =
                clutter::speckle_sample(spec, static_cast<std::uint64_t>(l) * n + i);
            field[cell[i]] += std::polar(std::abs(q.amplitude) * std::sqrt(double(s.intensity)),
                                         double(s.phase_rad));
          }
          std::vector<float>& out = look_power[l];
          out.resize(cells);
          for (std::size_t p = 0; p < cells; ++p)
            out[p] = static_cast<float>(std::norm(field[p]));
        }
      });
  std::vector<double> sum(cells, 0.0);
  for (const std::vector<float>& lp : look_power)
    for (std::size_t p = 0; p < cells; ++p)
      sum[p] += static_cast<double>(lp[p]);
  img.intensity_m2.resize(cells);
  for (std::size_t p = 0; p < cells; ++p)
    img.intensity_m2[p] = static_cast<float>(sum[p] / static_cast<double>(looks));
  return img;
}

}  // namespace radar_emu::radar
