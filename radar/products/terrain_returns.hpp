#pragma once
// Terrain clutter of the closed loop from the terrain engine (radar/clutter/terrain_engine.hpp)
// instead of the frame tracer's terrain rays: one diffuse return per lit range-azimuth cell of
// the field of view, in the tracer's own return format (Contribution, coherent = false), so the
// sensor takes both alike and the tracer keeps the targets, structures and their multiple
// bounces (SbrConfig::terrain_rays = false turns its terrain grid off).
//
// Cells. Columns of azimuth_cell_rad across [azimuth_min_rad, azimuth_max_rad) (antenna frame),
// range bins of range_cell_m from range_min_m to range_max_m. The engine integrates
// sigma0(local incidence) dA over the terrain patches seen from the antenna (shadowing on,
// structures shadow the ground; the terrain's own shadows by the engine's horizon sweep) whose
// elevation lies in [elevation_min_rad, elevation_max_rad]: the discretised integral of sigma0 over
// the cell's illuminated surface (Ulaby & Long, Microwave Radar and Radiometric Remote Sensing,
// 2014, eq. 5.35). A lit cell's return:
//   |A|^2          = sum_k sigma_k over the cell's patches [m^2] (mean power: the sensor draws
//                    the speckle, as it does for a terrain ray's footprint);
//   range_m        = the cell's centre, range_spread_m its width (the sensor spreads the power
//                    uniformly over it, as over a ray footprint's extent along range);
//   azimuth_rad    = the column's centre;
//   elevation_rad  = asin(sum_k sigma_k sin el_k / sum_k sigma_k) (the power-weighted patch
//                    elevation, by its sine);
//   radial velocity = -v . u, u the unit line of sight to the cell's direction (az, el), v the
//                    antenna's velocity: static ground seen from a moving radar, positive
//                    receding (the tracer's rule at a terrain ray's first hit, path rate
//                    (0 - v) . d; the Doppler shift is the sensor's, f_D = -2 v_r / lambda).
// Patches are patch_fraction of a cell wide: the engine's patch size max(range cell, R azimuth
// cell) x patch_fraction, so that each column holds one or more. Far out a patch is longer than
// the range cell: its power is spread over the range cells its extent covers
// (TerrainView::spread_range), not put whole into one, which would leave the cells between
// patches empty (a comb along range; CFAR false alarms).
//
// Coarse cells (the fidelity governor's terrain knob, compute()'s `scale`). At scale s >= 2 the
// cells merge: k = the largest power of two <= s (at most kMaxMerge) range bins per cell, and
// min(k, azimuth_merge_max()) columns per column, azimuth_merge_max() the widest power of two
// whose column stays within coarse_azimuth_max_rad and divides the columns. The engine
// integrates the same patches into the merged grid (its horizon at half a merged cell), so
// that a merged cell's power is the sum of the cells it replaces (a patch spread over range
// bins by overlap adds to the merged bin what it added to its parts: the merged edges are
// among the fine ones), and its elevation the power-weighted one of theirs. The last merged bin
// may reach past range_max_m by less than a merged bin (the terrain there is counted too; the
// sensor keeps what lies in its swath). The engine's patches, the horizon's samples and the
// returns handed to the sensor fall as the level rises: the returns as 1 / (range merge x
// azimuth merge). The columns do not merge by default: the loop's are half a beamwidth wide,
// and merged to one beam position (1 deg) they raised the default run's false alarms from 2.0 to
// 4.5 a frame at its governor levels 4-5 (merged range bins lowered them: docs/performance.md).
// Coarse level of detail. From a range merge of coarse_lod_merge on (the governor's level 12
// by default) the cells are a few facets of the finest level wide, and the engine's work, one
// patch a facet at least, no longer falls with the patch size: a second engine holds the
// terrain's tiles at their coarser level coarse_lod_level (the scene's own LOD meshes: every
// 2nd node of the level-0 grid for level 1, a quarter of the facets; scene/terrain_gen.hpp), and
// integrates those instead. The same surface sampled more coarsely: its area and sigma0 dA
// integral about the same, its shadows those of the coarser surface (the crests between the
// coarse nodes are lost), what the level's estimated error stands for.
//
// Costs. The constructor allocates and throws (std::invalid_argument; the engine's "no terrain"
// included). compute() allocates nothing and does not throw: the columns are cut into `slices`
// slices (a number of the configuration, not of the threads), integrated in parallel (TBB), each
// into its own buffers: the output (values and order: slice, bin, column) is the same for any
// number of threads.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "radar/clutter/terrain_engine.hpp"
#include "radar/em/sbr.hpp"
#include "scene/scene.hpp"

namespace radar_emu::radar {

struct TerrainReturnsConfig {
  double azimuth_min_rad = -0.1745;  ///< field of view, antenna frame
  double azimuth_max_rad = 0.1745;
  double elevation_min_rad = -0.0873;
  double elevation_max_rad = 0.0873;
  double azimuth_cell_rad = 4.363e-3;  ///< column width (0.25 deg), > 0
  double range_min_m = 0.0;            ///< first bin's near edge, >= 0
  double range_max_m = 6000.0;         ///< last bin's far edge, > range_min_m
  double range_cell_m = 3.0;           ///< bin width, > 0
  /// Patch size as a fraction of the cell's smaller extent (range bin, R x column), (0, 1].
  double patch_fraction = 1.0;
  double carrier_hz = 94e9;  ///< the path phase of the engine's field (not used for the mean)
  bool shadowing = true;     ///< patches hidden from the radar are left out
  /// Shadows by the engine's horizon sweep per azimuth column (queries only behind what is not
  /// terrain; radar/clutter/terrain_engine.hpp); false: one occlusion query per patch.
  bool horizon = true;
  /// Patches per frame, all slices together (counted in TerrainStats::budget_cut when it cuts).
  std::uint64_t max_patches = 20'000'000;
  std::size_t max_cells = 4'000'000;  ///< setup refuses more columns x bins
  /// Slices of columns integrated in parallel (at most the columns), >= 1. The same output for
  /// any number of threads; each slice sweeps the horizon of its own columns, so more slices
  /// than cores repeat that work for nothing (2: the project's 2-core target).
  std::size_t slices = 2;
  /// Widest column the coarse cells may merge to [rad] (compute()'s scale); 0 (or less than two
  /// columns): the columns never merge, only the range bins (the closed loop's choice: header).
  double coarse_azimuth_max_rad = 0.0;
  /// From this merge along range on (compute()'s scale; 0: never) the engine integrates the
  /// terrain's coarser level of detail coarse_lod_level (header). 8: the governor's level 12.
  std::size_t coarse_lod_merge = 8;
  int coarse_lod_level = 1;  ///< >= 1 (the scene's LOD levels, scene/types.hpp)
};

/// How many fine cells a coarse cell merges, along each axis (TerrainReturns::cell_merge).
struct TerrainCellMerge {
  std::size_t range = 1;    ///< range bins per cell, a power of two
  std::size_t azimuth = 1;  ///< columns per column, a power of two
  [[nodiscard]] std::size_t cells() const noexcept { return range * azimuth; }
};

/// What coarsens with the governor's terrain knob, for its cost model (loop/governor.hpp).
struct TerrainCoarsening {
  std::size_t azimuth_merge_max = 1;  ///< TerrainReturns::azimuth_merge_max()
  /// From this range merge on the coarse level of detail (0: none), whose facets are
  /// lod_facet_ratio of the fine ones (the whole database's).
  std::size_t lod_merge = 0;
  double lod_facet_ratio = 1.0;
};

class TerrainReturns {
 public:
  /// Setup: builds the engine from the tracer's resolved materials (make_terrain_engine: the
  /// tracer's targets left to the rays) and the cell grid in config.slices slices. Throws
  /// std::invalid_argument naming the field, or the engine's error (a scene with no terrain).
  /// Keeps a reference to `scene`.
  TerrainReturns(const scene::Scene& scene, const SbrTracer& tracer,
                 const TerrainReturnsConfig& config);

  /// Coarsest merge along range (level 16's scale, 2^4).
  static constexpr std::size_t kMaxMerge = 16;
  /// The cells merged at `scale` (compute()'s; >= 1) for a grid whose columns merge at most
  /// `azimuth_merge_max` ways (a power of two): k = the largest power of two <= scale (1 below
  /// 2, not a number, or infinite; at most kMaxMerge), {k, min(k, azimuth_merge_max)}. Real-time
  /// safe. The fidelity governor predicts the returns with it.
  [[nodiscard]] static TerrainCellMerge cell_merge(double scale,
                                                   std::size_t azimuth_merge_max) noexcept;
  /// The most columns a coarse column merges (a power of two; header).
  [[nodiscard]] std::size_t azimuth_merge_max() const noexcept { return azimuth_merge_max_; }
  /// The coarse cells and level of detail, for the governor's cost model.
  [[nodiscard]] TerrainCoarsening coarsening() const noexcept;
  /// The engine at coarse_lod_level (none: the scene has no LOD group above level 0, or
  /// coarse_lod_merge is 0).
  [[nodiscard]] const clutter::TerrainEngine* coarse_engine() const noexcept {
    return coarse_engine_ ? &*coarse_engine_ : nullptr;
  }

  /// Returns per frame at most: the cells of the grid.
  [[nodiscard]] std::size_t max_returns() const noexcept { return columns_ * bins_; }
  [[nodiscard]] std::size_t columns() const noexcept { return columns_; }
  [[nodiscard]] std::size_t bins() const noexcept { return bins_; }
  [[nodiscard]] const clutter::TerrainEngine& engine() const noexcept { return engine_; }
  [[nodiscard]] const TerrainReturnsConfig& config() const noexcept { return config_; }

  /// The lit cells' returns for `pose` into `out` (header), in slice, bin, column order; returns
  /// how many. `stats` is added to. Real-time safe: no allocation, no exception; returns beyond
  /// out.size() are dropped and counted in `dropped`. `scale` (>= 1; the fidelity governor's
  /// terrain knob, TraceKnobs::terrain_spacing_scale) multiplies the patch size: the patches, and
  /// the engine's work, fall as its square (down to one a facet); and from 2 on it merges the
  /// cells (cell_merge(scale, azimuth_merge_max()); header): the returns fall, their total mean
  /// power stays (spread_range).
  [[nodiscard]] std::size_t compute(const RadarPose& pose, std::span<Contribution> out,
                                    clutter::TerrainStats& stats, std::uint64_t& dropped,
                                    double scale = 1.0) noexcept;
  /// Issue 28: per sigma0 row of the engine's table, what every compute() so far read (lit
  /// patches, those whose sample the catalogue flags; clutter::Sigma0Use). Not for a frame in
  /// flight.
  [[nodiscard]] std::span<const clutter::Sigma0Use> sigma0_use() const noexcept {
    return sigma0_use_;
  }
  /// Setup: forgets what the compute() calls so far read (sigma0_use()), e.g. after a frame
  /// computed at setup only to learn its cost.
  void forget_sigma0_use() noexcept {
    std::fill(sigma0_use_.begin(), sigma0_use_.end(), clutter::Sigma0Use{});
  }

 private:
  struct Slice {
    std::size_t first_column = 0, columns = 0;
    std::vector<double> mean, elevation_power;  ///< bins x columns of the slice
    std::vector<double> horizon;                ///< the engine's horizon scratch
    std::vector<std::uint32_t> facet_list;      ///< the engine's list of facets in the window
    clutter::TerrainStats stats;
    std::vector<clutter::Sigma0Use> sigma0_use;  ///< this frame's, per sigma0 row
  };
  /// The pose left at its default; cells merged by `m`.
  [[nodiscard]] clutter::TerrainView view(TerrainCellMerge m = {}) const noexcept;
  /// Slice `sl`'s cells merged by `m` (the range edges: merged_edges_m_ when m.range > 1).
  [[nodiscard]] clutter::CellGrid slice_grid(const Slice& sl,
                                             TerrainCellMerge m = {}) const noexcept;
  [[nodiscard]] std::size_t merged_bins(std::size_t range_merge) const noexcept {
    return (bins_ + range_merge - 1) / range_merge;
  }
  TerrainReturnsConfig config_;
  clutter::TerrainEngine engine_;
  std::optional<clutter::TerrainEngine> coarse_engine_;  ///< coarse_lod_level's facets
  std::size_t columns_ = 0, bins_ = 0;
  std::vector<double> edges_m_;         ///< bins + 1
  std::vector<double> merged_edges_m_;  ///< bins + 1 (the frame's merged bins use the first)
  std::size_t azimuth_merge_max_ = 1;
  std::vector<double> cos_az_, sin_az_;  ///< per column, of its centre
  std::vector<Slice> slices_;
  std::vector<clutter::Sigma0Use> sigma0_use_;  ///< every frame's, per sigma0 row
  std::uint32_t terrain_object_ = 0;  ///< Contribution::object_id: the object of most terrain area
};

}  // namespace radar_emu::radar
