#pragma once
// The terrain engine: terrain clutter per radar cell, for every product (the SAR's ground cells,
// the EV image's pixels, a beam's range-azimuth cells), from the scene's terrain polygons.
//
// Model. A terrain surface is the set of its facets (the scene's triangles of every static object
// that is not a structure, split at setup until no edge is longer than max_facet_m, optionally
// clipped to a horizontal region). Each facet is cut into patches: the n^2 triangles of its
// uniform barycentric subdivision (n = ceil(longest edge / patch size)), each of area A/n^2 with
// the facet's normal, at its centroid. A patch seen from the radar position P returns
//   sigma_k = sigma0(material, pol, cos theta_k) A_k            (mean power, [m^2])
//   a_k = sqrt(sigma_k I_k) exp(j (phi_k - 4 pi R_k / lambda))    (complex amplitude, [m])
// with theta_k the local incidence between the facet normal and the line of sight (|n . u|:
// facets are two-sided, a surface seen from behind is hidden by the shadow test instead),
// sigma0 the catalogue's row of the facet's material (radar/em/surfaces.hpp resolves it;
// radar/clutter/terrain.hpp Sigma0Table::lookup reads it), (I_k, phi_k) the patch's speckle sample
// (radar/clutter/speckle.hpp: exponential intensity, uniform phase, a pure function of the seed,
// the facet, the subdivision and the patch: "stored in each polygon", seed paper, "Radar
// features"), R_k its range. A cell's mean is sum sigma_k over the patches it holds (the
// discretised integral of sigma0 dA over the cell's illuminated surface, Ulaby & Long,
// Microwave Radar and Radiometric Remote Sensing, 2014, eq. 5.35 for the distributed target),
// its single-look field sum a_k: with many patches per cell the sum is circular Gaussian, its
// intensity exponential with that mean (Oliver & Quegan, Understanding SAR Images, 2004, ch. 4).
// Shadowing, two ways (TerrainView::shadow_method). kRays: a patch counts only when the segment
// from it to the radar is clear (one occlusion query against the whole scene, structures
// included: buildings shadow the ground). kHorizon: a horizon sweep per azimuth column (below)
// for the terrain's own shadows, and an occlusion query only for the patches that lie behind
// something that is not terrain (a structure, a target, a moving object). Layover is
// what the cell mapping makes of it: every patch goes to the cell of its own range and
// direction, so patches at different heights sharing a range add in one cell.
//
// The horizon sweep (kHorizon). In the antenna frame, a plane of constant azimuth contains the
// radar and the antenna's z axis; while that axis is near the vertical (|tilt| < 90 deg minus the
// steepest terrain slope: the loop's depression and roll), the terrain cuts each such plane along
// a curve that is a graph over the distance from the z axis, rho = R cos(el), ground below it.
// A point P of that curve is hidden exactly when some point Q of the curve nearer the axis
// (rho_Q < rho_P) lies above P's line of sight (el_Q > el_P): the curve from Q to P then crosses
// the line of sight before P, or reaches P from above it (P is seen from below the ground). This
// is the horizon (or "line of sight by maximum elevation angle") rule of viewshed analysis
// (Franklin & Ray, "Higher isn't necessarily better: visibility algorithms and experiments",
// 6th Int. Symposium on Spatial Data Handling, 1994; De Floriani & Magillo, "Algorithms for
// visibility computation on terrains: a survey", Environment and Planning B 30(5), 2003). The
// engine samples it on its own subdivision: pass 1 writes, per column of horizon_azimuth_rad and
// per bin of horizon_rho_m, the largest sin(el) of the patches' vertices there (the facets' own
// vertices and points along their edges among them, where a crest of the piecewise-planar
// surface lies; every facet of the columns, nearer than the grid's first range too, above its
// elevation window too: both can shadow it);
// a running maximum outward along rho makes each bin the horizon of the nearer ones; pass 2
// takes a patch as shadowed when its sin(el) is below the horizon of the bins nearer than its
// own. Error: at most one horizon bin plus a patch along rho at a shadow's edge, and a column's
// width across. Where terrain objects overlap (a runway laid 0.1 m over the ground that goes on
// under it), the lower layer's facets are marked at setup and take the occlusion query: no
// sampling of the upper layer finds a step of centimetres. What is not terrain (objects left to the
// rays, moving objects, static triangles without a sigma0 row) is bounded by spheres (setup: static
// ones grouped in squares; per frame: the scene's world boxes of moving objects and structures): a
// second map holds, per column and bin, the largest sin(el) any of them reaches from that rho on; a
// patch below it gets the exact occlusion query (the sphere only says it may be behind one), any
// other patch is lit.
//
// Costs. Setup (the constructor) allocates and throws std::invalid_argument with context. The
// per-frame evaluation (integrate) allocates nothing and does not throw: patches come from the
// facets on the fly, their size growing with range (view's patch_angle_rad) so that each cell
// holds several at every range; a patch budget bounds the work (counted when it cuts). Facets
// are grouped at setup into horizontal tiles with bounding spheres: a tile outside the grid's
// range or angles is skipped whole (a frame over a large database visits the tiles in the beam,
// not every facet).

#include <complex>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "radar/clutter/speckle.hpp"
#include "radar/clutter/terrain.hpp"
#include "scene/scene.hpp"

namespace radar_emu::radar::clutter {

/// What the engine is built from (setup).
struct TerrainEngineSpec {
  /// Facets are split (longest edge halved) until no edge exceeds this [m], so that a facet's
  /// patch size can follow its range. > 0.
  double max_facet_m = 50.0;
  /// Keep only the terrain inside the horizontal box [region_min_m, region_max_m] (world x, y):
  /// facets are clipped to it (Sutherland & Hodgman, CACM 17(1), 1974). Off: the whole scene.
  bool clip_to_region = false;
  glm::dvec2 region_min_m{0.0};
  glm::dvec2 region_max_m{0.0};
  /// Which level of detail of each LOD group (a terrain tile held at several, scene.hpp) the
  /// engine takes: this one, or the group's coarsest where it has no such level. 0: the finest.
  /// >= 0. A coarser level holds fewer, larger facets of the same surface (with max_facet_m
  /// above their size, so that they are not split again): the engine's work, one patch a facet
  /// at least, falls with them.
  int lod_level = 0;
  SpeckleSpec speckle;                          ///< per-patch texture (kNone: every I = 1, phi = 0)
  Sigma0Table::Pol channel = Sigma0Table::kVV;  ///< receive-transmit channel read from the table
};

/// What the caller says about the scene's materials (its resolved SurfaceSet's rows).
struct TerrainMaterials {
  /// Per scene material: its row of `table`, or -1 for a material without diffuse clutter
  /// (a conductor): its triangles are structures, left to the rays.
  std::vector<int> sigma0_row;
  Sigma0Table table;               ///< sigma0 at the carrier
  std::vector<std::string> names;  ///< per scene material (messages, statistics)
};

/// One terrain triangle after setup, world frame.
struct TerrainFacet {
  glm::dvec3 a_m{0.0}, b_m{0.0}, c_m{0.0};  ///< vertices [m]
  glm::dvec3 normal{0.0, 0.0, 1.0};         ///< unit, as wound
  double area_m2 = 0.0;
  double longest_edge_m = 0.0;
  glm::dvec3 centroid_m{0.0};
  double radius_m = 0.0;  ///< bounding sphere around the centroid [m]
  std::uint32_t sigma0_row = 0;
  std::uint16_t material = 0;  ///< scene material index
  std::uint32_t object = 0;    ///< scene object id
  /// A facet of another terrain object lies over part of it (layers: pavement laid on the
  /// ground): the horizon sweep cannot tell which layer is on top, so with kHorizon its patches
  /// take the occlusion query.
  bool layered = false;
};

/// One patch (see the header): centroid, area, and its speckle key.
struct TerrainPatch {
  glm::dvec3 centre_m{0.0};
  double area_m2 = 0.0;
  std::uint64_t key = 0;  ///< speckle index of look 0 (look l: key + l * kLookStride)
};
inline constexpr std::uint64_t kLookStride = 0x9E3779B97F4A7C15ull;

/// Subdivision of a facet for a patch size [m]: n >= 1 (n^2 patches). Real-time safe.
[[nodiscard]] std::uint32_t patch_divisions(const TerrainFacet& f, double patch_m) noexcept;
/// Patch k (0 <= k < n^2) of facet number `facet` (its index in TerrainEngine::facets()) cut n
/// ways. Real-time safe.
[[nodiscard]] TerrainPatch facet_patch(const TerrainFacet& f, std::uint32_t facet, std::uint32_t n,
                                       std::uint32_t k) noexcept;

/// Range-azimuth cells in the antenna frame (x boresight, y right, z down; azimuth atan2(y, x),
/// elevation atan2(-z, hypot(x, y)) as radar::azel_from_direction): column c holds azimuths
/// [azimuth_min_rad + c step, + (c + 1) step); bin b of a column ranges [edge b, edge b + 1).
/// Cell index = bin * columns + column.
struct CellGrid {
  double azimuth_min_rad = 0.0;
  double azimuth_step_rad = 0.0;  ///< > 0
  std::size_t columns = 0;
  double elevation_min_rad = -1.5;  ///< patches outside [min, max] are left out (the beam)
  double elevation_max_rad = 1.5;
  std::size_t bins = 0;
  /// Ascending range edges [m]: bins + 1 values for every column, or columns x (bins + 1) when
  /// per_column_edges (edge +inf allowed at the end).
  std::span<const double> range_edges_m{};
  bool per_column_edges = false;
};

/// The radar for one evaluation.
struct TerrainView {
  glm::dvec3 position_m{0.0};          ///< antenna phase centre, world [m]
  glm::dmat3 world_from_antenna{1.0};  ///< antenna frame as in CellGrid
  double wavelength_m = 0.0;           ///< > 0: the path phase 4 pi R / lambda
  double patch_min_m = 0.5;            ///< patch size near the radar [m], > 0
  /// Patch size at range R: max(patch_min_m, R patch_angle_rad) (a fraction of the angular cell).
  double patch_angle_rad = 0.0;
  bool shadowing = true;  ///< patches hidden from the radar are left out (shadow_method)
  enum class Shadow : std::uint8_t {
    kRays,     ///< one occlusion query per patch
    kHorizon,  ///< the horizon sweep, queries only behind what is not terrain (header)
  };
  /// kHorizon needs the caller's scratch (integrate's `horizon`); without it, kRays.
  Shadow shadow_method = Shadow::kRays;
  double horizon_azimuth_rad = 0.0;  ///< horizon column width; 0: half the grid's column
  double horizon_rho_m = 0.0;        ///< horizon bin along rho = R cos(el); 0: patch_min_m
  /// Each patch's mean power (mean, elevation_power) spread over the range bins its own range
  /// extent covers, in proportion to the overlap of a box of that extent centred on the patch
  /// (uniform range edges only), instead of all of it into its centroid's bin. For patches longer
  /// in range than a bin: near grazing a patch sized to the azimuth cell (patch_angle_rad) spans
  /// several range bins, and put whole into one it leaves its neighbours empty, a comb along
  /// range that a CFAR reads as targets. The patch's extent along the line of sight u is
  /// max |u . e| over its three edges e (the facet's edges / n). The speckle field stays at the
  /// centroid's bin.
  bool spread_range = false;
  /// Atmospheric loss, one way [dB/m] >= 0: each patch's power times 10^(-2 L R / 10)
  /// (radar/propagation/path.hpp's two-way loss, applied per patch at its own range).
  double one_way_loss_db_per_m = 0.0;
  std::size_t looks = 1;                   ///< independent speckle looks, field holds looks x cells
  std::uint64_t max_patches = 50'000'000;  ///< budget per evaluation (counted when it cuts)
};

struct TerrainStats {
  std::uint64_t facets_considered = 0;  ///< facets whose bounds meet the grid
  std::uint64_t patches = 0;            ///< patches evaluated in a cell
  std::uint64_t patches_lit = 0;        ///< of those, visible and added
  std::uint64_t patches_shadowed = 0;   ///< occluded on the line of sight
  std::uint64_t patches_grazing = 0;    ///< line of sight in the facet's plane
  std::uint64_t patches_outside = 0;    ///< in no cell
  std::uint64_t budget_cut = 0;         ///< facets skipped when max_patches ran out
  std::uint64_t horizon_patches = 0;    ///< kHorizon: points of pass 1 (the horizon's samples)
  std::uint64_t occlusion_queries = 0;  ///< Embree occlusion queries made
  std::uint64_t horizon_coarsened = 0;  ///< kHorizon: scratch too small, bins widened
};

/// The engine's setup error for a scene with no terrain (no static non-structure triangle of a
/// material with a sigma0), apart from its other errors: a caller may fall back on it (the closed
/// loop's default engine over a scene of metal alone: no terrain clutter, with a warning).
class NoTerrain : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class TerrainEngine {
 public:
  /// Collects the terrain facets of `scene`: every static object (no motion, no trajectory),
  /// level spec.lod_level of each LOD group (above), not listed in `structures` (per object id: 1 =
  /// a structure or target left to the rays), its triangles whose material has a sigma0 row. Throws
  /// std::invalid_argument: materials that do not match the scene's, a spec out of range, no
  /// terrain at all ("the scene has no terrain ..."; the caller decides on a fallback), or more
  /// than 2e7 facets. Keeps a reference to `scene` (occlusion queries): it must outlive the
  /// engine.
  TerrainEngine(const scene::Scene& scene, TerrainMaterials materials,
                std::span<const std::uint8_t> structures, const TerrainEngineSpec& spec);

  [[nodiscard]] std::span<const TerrainFacet> facets() const noexcept { return facets_; }
  [[nodiscard]] const TerrainEngineSpec& spec() const noexcept { return spec_; }
  [[nodiscard]] const TerrainMaterials& materials() const noexcept { return materials_; }
  [[nodiscard]] const scene::Scene& scene() const noexcept { return *scene_; }
  /// Total terrain area [m^2] (of the facets, after clipping).
  [[nodiscard]] double area_m2() const noexcept { return area_m2_; }

  /// Linear sigma0 of facet `f` at incidence cos theta (the engine's channel). Real-time safe.
  [[nodiscard]] double sigma0(const TerrainFacet& f, double cos_incidence) const noexcept;
  /// The speckle sample of a patch in look `look`. Real-time safe.
  [[nodiscard]] SpeckleSample speckle(const TerrainPatch& p, std::uint64_t look) const noexcept;
  /// Whether the segment from `from_m` (on a facet of normal n, offset off it toward `to_m`) to
  /// `to_m` is clear. Real-time safe.
  [[nodiscard]] bool clear(const glm::dvec3& from_m, const glm::dvec3& normal,
                           const glm::dvec3& to_m) const noexcept;

  /// Adds the terrain of every cell of `grid` seen from `view`: mean[cell] += sum sigma_k,
  /// field[l * cells + cell] += sum a_k (look l's speckle), cells = grid.columns * grid.bins.
  /// `mean` must hold cells values, `field` looks * cells (or be empty: mean only).
  /// `elevation_power`, when not empty (cells values), gets elevation_power[cell] +=
  /// sigma_k sin(el_k) [m^2] (el_k the patch's elevation in the antenna frame): divided by mean,
  /// the sine of the cell's power-weighted elevation. `horizon`: the scratch of the horizon
  /// sweep (view.shadow_method kHorizon), horizon_scratch_size(grid, view) values or more (fewer:
  /// its bins are widened to fit, counted in horizon_coarsened). `facet_list` (with the horizon
  /// sweep): scratch for the facets the sweep finds with patches in the grid's window (their
  /// vertices tested in the sweep's own transforms), so that the patch pass visits only those
  /// instead of searching the tiles again; facets().size() values always suffice (too few: the
  /// patch pass searches the tiles; the result is the same either way). `sigma0_use`, when not
  /// empty (materials().table.materials() values or more), gets each lit patch added to its
  /// sigma0 row's Sigma0Use (the validity flags of the table's samples it read: issue 28);
  /// `cell_flags`, when not empty (cells values), the OR of those flags per cell. Real-time safe:
  /// no allocation, no exception; an unusable grid or view adds nothing and returns all-zero
  /// statistics.
  [[nodiscard]] TerrainStats integrate(const TerrainView& view, const CellGrid& grid,
                                       std::span<std::complex<double>> field,
                                       std::span<double> mean,
                                       std::span<double> elevation_power = {},
                                       std::span<double> horizon = {},
                                       std::span<std::uint32_t> facet_list = {},
                                       std::span<Sigma0Use> sigma0_use = {},
                                       std::span<std::uint32_t> cell_flags = {}) const noexcept;
  /// The validity flags (surface.hpp) of the table's samples sigma0() reads for facet `f` at
  /// incidence cos theta. Real-time safe.
  [[nodiscard]] std::uint32_t sigma0_flags(const TerrainFacet& f,
                                           double cos_incidence) const noexcept;
  /// Scratch values integrate() needs for the horizon sweep of `grid` from `view` (its columns
  /// and its bins out to the grid's last range edge). Real-time safe.
  [[nodiscard]] static std::size_t horizon_scratch_size(const CellGrid& grid,
                                                        const TerrainView& view) noexcept;
  /// The static occluders that are not terrain (bounding spheres, world). Diagnostics.
  [[nodiscard]] std::size_t static_occluders() const noexcept { return occluders_.size(); }

 private:
  const scene::Scene* scene_;
  TerrainMaterials materials_;
  TerrainEngineSpec spec_;
  std::vector<TerrainFacet> facets_;
  double area_m2_ = 0.0;
  /// Tiles: the facets grouped by their centroid's square of the horizontal plane (side
  /// 4 max_facet_m), each with a bounding sphere of its facets, so that integrate() culls a tile
  /// before its facets (tile t's facets: tile_facets_[tile_first_[t] .. tile_first_[t + 1]), in
  /// ascending index; empty tiles are left out).
  struct Tile {
    glm::dvec3 centre_m{0.0};
    double radius_m = 0.0;
  };
  std::vector<Tile> tiles_;
  std::vector<std::uint32_t> tile_first_;
  std::vector<std::uint32_t> tile_facets_;
  void build_tiles();
  /// What is not terrain but can shadow it (kHorizon): static triangles outside the engine,
  /// grouped per square of the horizontal plane, as bounding spheres; and the objects whose world
  /// box is read per frame (moving objects, structures).
  struct Occluder {
    glm::dvec3 centre_m{0.0};
    double radius_m = 0.0;
  };
  std::vector<Occluder> occluders_;
  std::vector<std::uint32_t> dynamic_occluders_;  ///< object ids
  void collect_occluders(std::span<const std::uint8_t> structures);
  /// Per LOD group: the level the engine takes (spec.lod_level, or the group's coarsest).
  std::vector<int> lod_taken_;
  [[nodiscard]] bool other_lod(const scene::ObjectDesc& o) const noexcept {
    return o.lod_group >= 0 && static_cast<std::size_t>(o.lod_group) < lod_taken_.size() &&
           o.lod_level != lod_taken_[static_cast<std::size_t>(o.lod_group)];
  }
  void mark_layers();
};

/// A name for each sigma0 row of `m.table`: the names of the scene materials that read it,
/// joined by "/" ("row N" for a row no material reads). For messages (issue 28).
[[nodiscard]] std::vector<std::string> sigma0_row_names(const TerrainMaterials& m);

/// The materials of a resolved SurfaceSet-like description: per scene material its sigma0 row
/// (-1 none). Convenience for callers holding radar::SurfaceSet (radar/em/surfaces.hpp).
[[nodiscard]] TerrainMaterials terrain_materials(std::span<const int> sigma0_rows,
                                                 const Sigma0Table& table,
                                                 std::span<const scene::Material> materials);

}  // namespace radar_emu::radar::clutter
