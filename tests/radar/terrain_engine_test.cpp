// The terrain engine (radar/clutter/terrain_engine.hpp) against theory:
//  - a homogeneous flat field: each range-azimuth cell's mean equals the closed-form integral of
//    sigma0 dA over the cell's annular sector (sigma0 read from the catalogue's table at each
//    ring's incidence, independently of the engine) within 0.5 dB, and the single-look
//    intensity normalised by it is exponential (Kolmogorov-Smirnov, alpha = 0.01);
//  - the SAR chain over the engine's terrain (sar_terrain -> synthesis -> backprojection onto the
//    DEM): a ridge's shadow ends where the line of sight over its crest meets the ground, and a
//    tower's wall lays over toward the radar by the displacement of equal slant range (h cot
//    theta in the far field), each within one pixel;
//  - patches longer in range than a bin, spread over the bins they cover, follow that closed form
//    per bin (put whole into one bin they leave a comb);
//  - the frame path does not allocate; bad input is a clear error; a DEM hole is flagged.
#include "radar/clutter/terrain_engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <vector>

#include "../alloc_counter.hpp"
#include "radar/constants.hpp"
#include "radar/em/surfaces.hpp"
#include "radar/products/sar.hpp"
#include "radar/products/sar_terrain.hpp"
#include "scene/scene.hpp"

namespace radar_emu::radar {
namespace {

namespace cl = clutter;
constexpr double kC = kSpeedOfLight_mps;
constexpr std::uint64_t kSeed = 20261124;

double db(double x) {
  return 10.0 * std::log10(x);
}

// A quad a b c d (counter-clockwise from above) of material `mat`.
void quad(scene::Mesh& m, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d,
          std::uint16_t mat) {
  const auto base = static_cast<std::uint32_t>(m.positions_m.size());
  for (const glm::dvec3& v : {a, b, c, d})
    m.positions_m.emplace_back(v);
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base, base + 2, base + 3});
  m.triangle_material.push_back(mat);
  m.triangle_material.push_back(mat);
}

struct Built {
  scene::Scene scene;
  SurfaceSet surfaces;
};

cl::TerrainEngine engine_of(const scene::Scene& s, const SurfaceSet& set,
                            const cl::TerrainEngineSpec& spec) {
  std::vector<int> rows;
  for (const Surface& m : set.surfaces)
    rows.push_back(m.sigma0_row);
  std::vector<std::uint8_t> structures(s.objects().size(), 0);
  return cl::TerrainEngine(s, cl::terrain_materials(rows, set.sigma0_table, s.materials()),
                           structures, spec);
}

// A level antenna at height h_m over the origin looking north (antenna x north, y east, z down:
// azimuth is the horizontal angle), at carrier_hz, patches of patch_m.
cl::TerrainView north_view(double h_m, double carrier_hz, double patch_m) {
  cl::TerrainView view;
  view.position_m = {0.0, 0.0, h_m};
  view.world_from_antenna = glm::dmat3({0, 1, 0}, {1, 0, 0}, {0, 0, -1});
  view.wavelength_m = kC / carrier_hz;
  view.patch_min_m = patch_m;
  return view;
}

// bins + 1 slant-range edges from r0_m, step_m apart.
std::vector<double> range_edges(double r0_m, double step_m, std::size_t bins) {
  std::vector<double> edges;
  for (std::size_t b = 0; b <= bins; ++b)
    edges.push_back(r0_m + step_m * static_cast<double>(b));
  return edges;
}

// Kolmogorov-Smirnov distance of samples against Exp(1).
double ks_exponential(std::vector<double> xs) {
  std::sort(xs.begin(), xs.end());
  const double n = static_cast<double>(xs.size());
  double d = 0.0;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const double f = 1.0 - std::exp(-xs[i]);
    d = std::max({d, std::abs(f - static_cast<double>(i) / n),
                  std::abs(f - static_cast<double>(i + 1) / n)});
  }
  return d;
}

// Closed form of a flat field seen from height h_m: the integral of sigma0(theta(rho)) rho drho
// over the ground ranges of the slant-range bin [r1_m, r2_m], rho = sqrt(R^2 - h^2),
// cos theta = h / R (midpoint rule, 1 mm steps), per radian of azimuth [m^2]; sigma0 is read from
// the catalogue's table (row 0, VV), independently of the engine.
double ring_integral_m2(const SurfaceSet& set, double h_m, double r1_m, double r2_m) {
  const double rho1 = std::sqrt(r1_m * r1_m - h_m * h_m);
  const double rho2 = std::sqrt(r2_m * r2_m - h_m * h_m);
  double ring = 0.0;
  const double step = 1e-3;
  for (double rho = rho1 + step / 2; rho < rho2; rho += step)
    ring += static_cast<double>(
                set.sigma0_table.lookup(0, cl::Sigma0Table::kVV, h_m / std::hypot(rho, h_m))) *
            rho * step;
  return ring;
}

TEST(TerrainEngine, HomogeneousFieldCellMeanAndExponentialIntensity) {
  constexpr double kF = 35e9, kH = 100.0;
  scene::SceneDescription d;
  d.materials = {{"grass", {}}};
  scene::ObjectDesc g;
  g.name = "field";
  quad(g.mesh, {-200, 250, 0}, {200, 250, 0}, {200, 850, 0}, {-200, 850, 0}, 0);
  d.objects.push_back(g);
  const scene::Scene s(d);
  const SurfaceSet set = resolve_surfaces(s.materials(), {kF, Polarisation::kVV, {}});
  cl::TerrainEngineSpec spec;
  spec.speckle.seed = kSeed;
  std::cout << "speckle seed " << kSeed << "\n";
  const cl::TerrainEngine eng = engine_of(s, set, spec);

  cl::TerrainView view = north_view(kH, kF, 1.0);
  view.looks = 4;
  constexpr double kDeg = kPi / 180.0;
  cl::CellGrid grid;
  grid.azimuth_min_rad = -10.0 * kDeg;
  grid.azimuth_step_rad = 2.0 * kDeg;
  grid.columns = 10;
  grid.bins = 50;
  const std::vector<double> edges = range_edges(300.0, 10.0, grid.bins);
  grid.range_edges_m = edges;
  const std::size_t cells = grid.columns * grid.bins;
  std::vector<std::complex<double>> field(view.looks * cells);
  std::vector<double> mean(cells, 0.0);
  const cl::TerrainStats st = eng.integrate(view, grid, field, mean);
  EXPECT_EQ(st.patches_shadowed, 0u);
  EXPECT_EQ(st.budget_cut, 0u);

  // Closed form per cell: dphi times the ring integral of the slant bin.
  double worst_db = 0.0;
  std::vector<double> normalised;
  for (std::size_t b = 0; b < grid.bins; ++b) {
    const double expected =
        ring_integral_m2(set, kH, edges[b], edges[b + 1]) * grid.azimuth_step_rad;
    for (std::size_t c = 0; c < grid.columns; ++c) {
      const std::size_t cell = b * grid.columns + c;
      worst_db = std::max(worst_db, std::abs(db(mean[cell] / expected)));
      for (std::size_t l = 0; l < view.looks; ++l)
        normalised.push_back(std::norm(field[l * cells + cell]) / expected);
    }
  }
  double sum = 0.0;
  for (double x : normalised)
    sum += x;
  const double speckled_db = db(sum / static_cast<double>(normalised.size()));
  const double d_ks = ks_exponential(normalised);
  const double critical = 1.63 / std::sqrt(static_cast<double>(normalised.size()));  // Massey
  std::cout << "cells " << cells << ": worst cell mean vs closed form " << worst_db
            << " dB; speckled mean " << speckled_db << " dB; KS D " << d_ks << " (critical "
            << critical << ")\n";
  EXPECT_LT(worst_db, 0.5);
  EXPECT_NEAR(speckled_db, 0.0, 0.5);
  EXPECT_LT(d_ks, critical);

  // The frame path allocates nothing.
  std::fill(mean.begin(), mean.end(), 0.0);
  test::start_counting_allocations();
  const cl::TerrainStats again = eng.integrate(view, grid, field, mean);
  EXPECT_EQ(test::stop_counting_allocations(), 0u);
  EXPECT_EQ(again.patches_lit, st.patches_lit);

  // The horizon sweep over a flat field: nothing shadowed, no query, the same cells.
  cl::TerrainView hv = view;
  hv.shadow_method = cl::TerrainView::Shadow::kHorizon;
  std::vector<double> scratch(cl::TerrainEngine::horizon_scratch_size(grid, hv));
  std::vector<double> mean_h(cells, 0.0);
  test::start_counting_allocations();
  const cl::TerrainStats sh = eng.integrate(hv, grid, {}, mean_h, {}, scratch);
  EXPECT_EQ(test::stop_counting_allocations(), 0u);
  EXPECT_EQ(sh.patches_shadowed, 0u);
  EXPECT_EQ(sh.occlusion_queries, 0u);
  EXPECT_EQ(sh.horizon_coarsened, 0u);
  EXPECT_GT(sh.horizon_patches, 0u);
  EXPECT_EQ(sh.patches_lit, st.patches_lit);
  for (std::size_t c = 0; c < cells; ++c)
    EXPECT_NEAR(mean_h[c], mean[c], 1e-9 * mean[c]);
}

// Patches longer in range than a bin (the loop's far cells: a patch sized to the azimuth cell,
// range bins of 3 m): put whole into its centroid's bin, the field's cell means are a comb
// along range (bins with no centroid stay empty, a CFAR reads the others as targets); spread
// over the bins their range extent covers (TerrainView::spread_range) they follow the closed
// form of the first test, and the total is unchanged.
TEST(TerrainEngine, PatchesLongerThanABinAreSpreadOverTheBinsTheyCover) {
  constexpr double kF = 94e9, kH = 30.0, kDeg = kPi / 180.0;
  scene::SceneDescription d;
  d.materials = {{"grass", {}}};
  scene::ObjectDesc g;
  g.name = "field";
  quad(g.mesh, {-300, 200, 0}, {300, 200, 0}, {300, 800, 0}, {-300, 800, 0}, 0);
  d.objects.push_back(g);
  const scene::Scene s(d);
  const SurfaceSet set = resolve_surfaces(s.materials(), {kF, Polarisation::kVV, {}});
  const cl::TerrainEngine eng = engine_of(s, set, {});
  const cl::TerrainView view = north_view(kH, kF, 10.0);  // patches of five 2 m bins
  cl::CellGrid grid;
  grid.azimuth_min_rad = -10.0 * kDeg;
  grid.azimuth_step_rad = 5.0 * kDeg;
  grid.columns = 4;
  grid.bins = 100;
  const std::vector<double> edges = range_edges(400.0, 2.0, grid.bins);
  grid.range_edges_m = edges;
  const std::size_t cells = grid.columns * grid.bins;
  std::vector<double> whole(cells, 0.0), spread(cells, 0.0);
  (void)eng.integrate(view, grid, {}, whole);
  cl::TerrainView sv = view;
  sv.spread_range = true;
  (void)eng.integrate(sv, grid, {}, spread);

  // Per bin, summed over the four columns (the 20 deg sector; what a patch's azimuth does at the
  // columns' edges is not under test), against the closed form of the annulus (as above).
  double worst_whole_db = 0.0, worst_spread_db = 0.0, total_whole = 0.0, total_spread = 0.0;
  for (std::size_t b = 0; b < grid.bins; ++b) {
    const double expected = ring_integral_m2(set, kH, edges[b], edges[b + 1]) * 20.0 * kDeg;
    double w = 0.0, sp = 0.0;
    for (std::size_t c = 0; c < grid.columns; ++c) {
      w += whole[b * grid.columns + c];
      sp += spread[b * grid.columns + c];
    }
    total_whole += w;
    total_spread += sp;
    // The first and last patch length of bins: the box reaches past the grid there.
    if (b < 5 || b + 5 >= grid.bins)
      continue;
    worst_whole_db = std::max(worst_whole_db, w > 0.0 ? std::abs(db(w / expected)) : 99.0);
    worst_spread_db = std::max(worst_spread_db, std::abs(db(sp / expected)));
  }
  std::cout << "patch 10 m over 2 m bins: worst bin vs closed form " << worst_whole_db
            << " dB whole, " << worst_spread_db << " dB spread; totals " << total_whole << " / "
            << total_spread << " m^2\n";
  EXPECT_GT(worst_whole_db, 3.0);  // the comb
  EXPECT_LT(worst_spread_db, 1.0);
  EXPECT_NEAR(total_spread / total_whole, 1.0, 0.02);
}

// ------------------------------------------------------------------ the horizon sweep

// A level antenna at height H over the origin looking north (x north, y east, z down), cells of
// 1 deg x 2 m from 100 to 1000 m.
struct NorthGrid {
  static constexpr double kH = 100.0, kF = 35e9, kBin_m = 2.0, kR0_m = 100.0;
  cl::TerrainView view;
  cl::CellGrid grid;
  std::vector<double> edges;
  NorthGrid() {
    view = north_view(kH, kF, 2.0);
    grid.azimuth_min_rad = -5.0 * kPi / 180.0;
    grid.azimuth_step_rad = 1.0 * kPi / 180.0;
    grid.columns = 10;
    grid.bins = 450;
    edges = range_edges(kR0_m, kBin_m, grid.bins);
    grid.range_edges_m = edges;
  }
  // Cell means with the given shadowing; the statistics in `st`.
  std::vector<double> means(const cl::TerrainEngine& eng, cl::TerrainView::Shadow how,
                            cl::TerrainStats& st) const {
    cl::TerrainView v = view;
    v.shadow_method = how;
    std::vector<double> scratch(cl::TerrainEngine::horizon_scratch_size(grid, v));
    std::vector<double> mean(grid.columns * grid.bins, 0.0);
    st = eng.integrate(v, grid, {}, mean, {}, scratch);
    return mean;
  }
  // Slant range of the near edge of the first bin of `column` after the last unlit bin beyond
  // range r_from_m (where a shadow ends); -1 when every bin is lit.
  double shadow_end_m(const std::vector<double>& mean, std::size_t column, double r_from_m) const {
    double end = -1.0;
    for (std::size_t b = 0; b < grid.bins; ++b)
      if (edges[b] > r_from_m && !(mean[b * grid.columns + column] > 0.0))
        end = edges[b + 1];
    return end;
  }
};

TEST(TerrainEngineHorizon, RidgeShadowEndsWhereTheLineOverTheCrestMeetsTheGround) {
  // A ridge along x: front foot at y = gc - 20, crest h = 20 m at gc = 600 m, back foot at
  // gc + 10 (63 deg, steeper than the line of sight); flat ground from 50 to 1000 m. Seen from
  // H = 100 m at azimuth phi, the line over the crest (ground distance gc / cos phi) meets the
  // ground at rho = (gc / cos phi) H / (H - h): slant range sqrt(rho^2 + H^2).
  const double gc = 600.0, h = 20.0, H = NorthGrid::kH;
  scene::SceneDescription d;
  d.materials = {{"grass", {}}};
  scene::ObjectDesc o;
  o.name = "ground";
  const double x0 = -100.0, x1 = 100.0;
  quad(o.mesh, {x0, 50, 0}, {x1, 50, 0}, {x1, gc - 20, 0}, {x0, gc - 20, 0}, 0);
  quad(o.mesh, {x0, gc - 20, 0}, {x1, gc - 20, 0}, {x1, gc, h}, {x0, gc, h}, 0);
  quad(o.mesh, {x0, gc, h}, {x1, gc, h}, {x1, gc + 10, 0}, {x0, gc + 10, 0}, 0);
  quad(o.mesh, {x0, gc + 10, 0}, {x1, gc + 10, 0}, {x1, 1000, 0}, {x0, 1000, 0}, 0);
  d.objects.push_back(o);
  const scene::Scene s(d);
  const SurfaceSet set = resolve_surfaces(s.materials(), {NorthGrid::kF, Polarisation::kVV, {}});
  cl::TerrainEngineSpec spec;
  spec.max_facet_m = 20.0;
  const cl::TerrainEngine eng = engine_of(s, set, spec);
  const NorthGrid ng;
  cl::TerrainStats sh, sr;
  const std::vector<double> horizon = ng.means(eng, cl::TerrainView::Shadow::kHorizon, sh);
  const std::vector<double> rays = ng.means(eng, cl::TerrainView::Shadow::kRays, sr);
  EXPECT_EQ(sh.occlusion_queries, 0u);  // terrain only: no query
  EXPECT_EQ(sh.horizon_coarsened, 0u);
  EXPECT_GT(sh.patches_shadowed, 0u);
  const double r_crest = std::hypot(gc, H - h);
  for (std::size_t c = 0; c < ng.grid.columns; ++c) {
    // The column's far azimuth edge: the shadow's last point in it.
    const auto edge = [&](std::size_t k) {
      return std::abs(ng.grid.azimuth_min_rad + ng.grid.azimuth_step_rad * static_cast<double>(k));
    };
    const double phi = std::max(edge(c), edge(c + 1));
    const double rho_end = gc / std::cos(phi) * H / (H - h);
    const double expected = std::hypot(rho_end, H);
    const double by_horizon = ng.shadow_end_m(horizon, c, r_crest);
    const double by_rays = ng.shadow_end_m(rays, c, r_crest);
    std::cout << "column " << c << ": shadow ends at " << by_horizon << " m (horizon), " << by_rays
              << " m (rays), geometry " << expected << " m\n";
    // Within one range bin plus a patch (2 m each) of the geometry and of the rays.
    EXPECT_NEAR(by_horizon, expected, 2.0 * NorthGrid::kBin_m);
    EXPECT_NEAR(by_horizon, by_rays, 2.0 * NorthGrid::kBin_m);
  }
  std::cout << "ridge: " << sh.patches_shadowed << " patches shadowed by the horizon, "
            << sr.patches_shadowed << " by rays (" << sr.occlusion_queries << " queries)\n";
  // The back face (10 m of it here) in the crest's own horizon bin is not behind a nearer bin:
  // lit by the horizon, hidden by the queries (a crest's bin: 2 m of every back face).
  EXPECT_LE(sh.patches_shadowed, sr.patches_shadowed);
  EXPECT_NEAR(static_cast<double>(sh.patches_shadowed), static_cast<double>(sr.patches_shadowed),
              0.05 * static_cast<double>(sr.patches_shadowed));
}

TEST(TerrainEngineHorizon, MetalBoxShadowsTheGroundBehindItByItsQueries) {
  // A metal box (no sigma0: not terrain) 10 m wide, 10 m deep, h = 15 m tall, its near face at
  // y = 400 m straight ahead, on flat grass: along phi = 0 the ground is hidden from its far
  // face's foot to where the line over its far top edge meets the ground, 410 H / (H - h).
  const double H = NorthGrid::kH, h = 15.0;
  scene::SceneDescription d;
  d.materials = {{"grass", {}}, {"metal", {}}};
  scene::ObjectDesc g;
  g.name = "ground";
  quad(g.mesh, {-100, 50, 0}, {100, 50, 0}, {100, 1000, 0}, {-100, 1000, 0}, 0);
  d.objects.push_back(g);
  scene::ObjectDesc b;
  b.name = "box";
  const double xa = -5, xb = 5, ya = 400, yb = 410;
  quad(b.mesh, {xa, ya, 0}, {xb, ya, 0}, {xb, ya, h}, {xa, ya, h}, 1);
  quad(b.mesh, {xa, ya, h}, {xb, ya, h}, {xb, yb, h}, {xa, yb, h}, 1);
  quad(b.mesh, {xb, yb, 0}, {xa, yb, 0}, {xa, yb, h}, {xb, yb, h}, 1);
  quad(b.mesh, {xa, ya, 0}, {xa, ya, h}, {xa, yb, h}, {xa, yb, 0}, 1);
  quad(b.mesh, {xb, ya, 0}, {xb, yb, 0}, {xb, yb, h}, {xb, ya, h}, 1);
  d.objects.push_back(b);
  const scene::Scene s(d);
  const SurfaceSet set = resolve_surfaces(s.materials(), {NorthGrid::kF, Polarisation::kVV, {}});
  cl::TerrainEngineSpec spec;
  spec.max_facet_m = 20.0;
  const cl::TerrainEngine eng = engine_of(s, set, spec);
  EXPECT_GE(eng.static_occluders(), 1u);
  const NorthGrid ng;
  cl::TerrainStats sh, sr;
  const std::vector<double> horizon = ng.means(eng, cl::TerrainView::Shadow::kHorizon, sh);
  const std::vector<double> rays = ng.means(eng, cl::TerrainView::Shadow::kRays, sr);
  // Column 5 holds azimuths [0, 1 deg): at 410-480 m the box (x in [-5, 5]) covers [0, 0.7 deg)
  // of it; its cells over the ground from 420 m to 10 m short of rho_end (482 m).
  const double rho_end = 410.0 * H / (H - h);
  std::size_t dark = 0, lit_after = 0, checked = 0;
  for (std::size_t bn = 0; bn < ng.grid.bins; ++bn) {
    const double r = 0.5 * (ng.edges[bn] + ng.edges[bn + 1]);
    const double rho = std::sqrt(r * r - H * H);
    const double m = horizon[bn * ng.grid.columns + 5];
    if (rho > 420.0 && rho < rho_end - 10.0) {
      ++checked;
      // Partly hidden (the box spans 0.7 of the column's 1 deg): under 0.6 of the open
      // ground's level at the same range (column 7, [2, 3) deg).
      dark += m < 0.6 * horizon[bn * ng.grid.columns + 7];
    }
    if (rho > rho_end + 5.0 && rho < rho_end + 100.0)
      lit_after += m > 0.0;
  }
  std::cout << "box: " << dark << " of " << checked << " cells behind it darkened; "
            << sh.occlusion_queries << " queries of " << sh.patches
            << " patches (rays: " << sr.occlusion_queries << "); shadowed " << sh.patches_shadowed
            << " vs " << sr.patches_shadowed << "\n";
  EXPECT_GT(checked, 20u);
  EXPECT_EQ(dark, checked);
  EXPECT_GT(lit_after, 40u);
  // The same patches hidden as by a query per patch, the queries only near the box's shadow.
  EXPECT_EQ(sh.patches_shadowed, sr.patches_shadowed);
  EXPECT_EQ(sh.patches_lit, sr.patches_lit);
  EXPECT_LT(sh.occlusion_queries, sh.patches / 20);
  for (std::size_t c = 0; c < horizon.size(); ++c)
    EXPECT_DOUBLE_EQ(horizon[c], rays[c]);
}

// ------------------------------------------------------------------ SAR geometry over the engine

// 35 GHz, 500 m altitude, 63 deg, B = 100 MHz; flying +x, looking right (-y).
SarParams geometry_case() {
  SarParams p;
  p.carrier_hz = 35e9;
  p.bandwidth_hz = 100e6;
  p.sample_rate_hz = 120e6;
  p.pulse_duration_s = 0.3e-6;
  p.gates = 192;
  p.incidence_rad = 63.0 * kPi / 180.0;
  p.azimuth_beamwidth_rad = 0.5 * kPi / 180.0;
  p.elevation_beamwidth_rad = 20.0 * kPi / 180.0;
  p.prf_hz = 600.0;  // 0.167 m between pulses <= lambda / (4 sin(1.29 beamwidth)) = 0.19 m
  p.velocity_mps = {100.0, 0.0, 0.0};
  const double r0 = 500.0 / std::cos(p.incidence_rad);
  p.near_range_m = r0 - 0.5 * static_cast<double>(p.gates) * kC / (2 * p.sample_rate_hz);
  const double track = 40.0;
  p.pulses = static_cast<std::size_t>(track / (100.0 / p.prf_hz)) + 1;
  p.start_position_m = {-0.5 * track, 0.0, 500.0};
  return p;
}
constexpr double kTheta = 0.004;

struct Imaged {
  SarImageGrid grid;
  SarImage img;
  SarDem dem;
};

// Terrain cells -> raw -> range compression -> backprojection on the DEM; image rows along x
// from -12 to 12 m, columns over ground range (distance from the track) [g0, g1] every 1 m.
Imaged image_scene(const scene::SceneDescription& d, double g0, double g1) {
  const SarParams p = geometry_case();
  const scene::Scene s(d);
  const SurfaceSet set = resolve_surfaces(s.materials(), {p.carrier_hz, Polarisation::kVV, {}});
  cl::TerrainEngineSpec spec;
  spec.speckle.seed = kSeed;
  spec.max_facet_m = 10.0;
  const cl::TerrainEngine eng = engine_of(s, set, spec);
  const TerrainCells cells = terrain_cells(eng, p, 0.6);
  SarRaw raw = make_raw(p);
  synthesise_points(p, cells.cells, 0, p.pulses, raw);
  const SarCompressed rc = range_compress(p, raw, SarTaper::kNone);
  Imaged out;
  out.grid.azimuth_spacing_m = 0.5;
  out.grid.ground_range_spacing_m = 1.0;
  out.grid.rows = 49;
  out.grid.cols = static_cast<std::size_t>(g1 - g0) + 1;
  out.grid.origin_m = {-12.0, -g0, 0.0};
  out.dem = sar_dem(eng, p, out.grid);
  out.grid.height_m = out.dem.height_m;
  out.img = backproject(p, rc, out.grid, {kTheta, SarTaper::kNone, 16, 0.01});
  return out;
}

// Mean intensity of each column over every row.
std::vector<double> column_means(const Imaged& im) {
  std::vector<double> m(im.grid.cols, 0.0);
  for (std::size_t r = 0; r < im.grid.rows; ++r)
    for (std::size_t c = 0; c < im.grid.cols; ++c)
      m[c] += static_cast<double>(std::norm(im.img.pixels[r * im.grid.cols + c])) /
              static_cast<double>(im.grid.rows);
  return m;
}

TEST(TerrainEngineSar, RidgeShadowEndsWhereTheLineOverTheCrestMeetsTheGround) {
  // A ridge along track: front foot at ground range gc - 20 (45 deg slope facing the radar),
  // crest h = 20 m at gc, back foot at gc + 10 (63 deg, steeper than the 27 deg grazing angle).
  const double H = 500.0, gc = H * std::tan(63.0 * kPi / 180.0), h = 20.0;
  scene::SceneDescription d;
  d.materials = {{"grass", {}}};
  scene::ObjectDesc o;
  o.name = "ground";
  const double x0 = -20.0, x1 = 20.0;
  auto y = [](double g) { return -g; };  // look right of +x: ground range along -y
  // Wound counter-clockwise seen from above/outside (y = -g flips the handedness).
  quad(o.mesh, {x0, y(gc - 70), 0}, {x0, y(gc - 20), 0}, {x1, y(gc - 20), 0}, {x1, y(gc - 70), 0},
       0);
  quad(o.mesh, {x0, y(gc - 20), 0}, {x0, y(gc), h}, {x1, y(gc), h}, {x1, y(gc - 20), 0}, 0);
  quad(o.mesh, {x0, y(gc), h}, {x0, y(gc + 10), 0}, {x1, y(gc + 10), 0}, {x1, y(gc), h}, 0);
  quad(o.mesh, {x0, y(gc + 10), 0}, {x0, y(gc + 90), 0}, {x1, y(gc + 90), 0}, {x1, y(gc + 10), 0},
       0);
  d.objects.push_back(o);
  const double g0 = gc - 60.0, g1 = gc + 80.0;
  const Imaged im = image_scene(d, g0, g1);
  const std::vector<double> m = column_means(im);
  // Field level: the flat ground well beyond the shadow.
  double field = 0.0;
  int n = 0;
  for (std::size_t c = 0; c < m.size(); ++c)
    if (g0 + static_cast<double>(c) > gc + 60.0) {
      field += m[c];
      ++n;
    }
  field /= n;
  // Geometry: the line from the platform (height H, ground range 0) over the crest (gc, h)
  // meets z = 0 at gc H / (H - h).
  const double shadow_end = gc * H / (H - h);
  // Measured: coming back from the far field toward the crest, the first column under half the
  // field's level (the crossing lies half a pixel beyond it).
  double measured = -1.0;
  for (std::size_t c = m.size() - 1; c > static_cast<std::size_t>(gc - g0); --c)
    if (m[c] < 0.5 * field) {
      measured = g0 + static_cast<double>(c) + 0.5;
      break;
    }
  std::size_t masked = 0;
  for (std::size_t c = 0; c < im.grid.cols; ++c)
    masked += (im.dem.mask[24 * im.grid.cols + c] & kSarShadow) != 0;
  std::cout << "ridge: shadow ends at " << measured - gc << " m beyond the crest (geometry "
            << shadow_end - gc << " m, flat-earth h tan theta " << h * gc / H << " m); mask "
            << masked << " shadow pixels in a row\n";
  EXPECT_NEAR(measured, shadow_end, 1.0);
  // The mask's shadow run: from the crest to the shadow's end, within a pixel.
  EXPECT_NEAR(static_cast<double>(masked), shadow_end - gc, 1.5);
}

TEST(TerrainEngineSar, TowerLaysOverTowardTheRadarByEqualRange) {
  // A concrete tower 20 m along track, 6 m deep, h = 40 m tall, its near wall at ground range
  // gw, standing on water (dark): its near wall's top images where the ground has the same
  // slant range.
  const double H = 500.0, gw = H * std::tan(63.0 * kPi / 180.0), h = 40.0;
  scene::SceneDescription d;
  d.materials = {{"water", {}}, {"concrete", {}}};
  scene::ObjectDesc o;
  o.name = "ground";
  auto y = [](double g) { return -g; };
  quad(o.mesh, {-20, y(gw - 50), 0}, {-20, y(gw + 30), 0}, {20, y(gw + 30), 0}, {20, y(gw - 50), 0},
       0);
  d.objects.push_back(o);
  scene::ObjectDesc t;
  t.name = "tower";
  const double xa = -10.0, xb = 10.0, ga = gw, gb = gw + 6.0;
  quad(t.mesh, {xa, y(ga), 0}, {xb, y(ga), 0}, {xb, y(ga), h}, {xa, y(ga), h}, 1);  // near wall
  quad(t.mesh, {xa, y(ga), h}, {xb, y(ga), h}, {xb, y(gb), h}, {xa, y(gb), h}, 1);  // roof
  quad(t.mesh, {xb, y(gb), 0}, {xa, y(gb), 0}, {xa, y(gb), h}, {xb, y(gb), h}, 1);  // far wall
  d.objects.push_back(t);
  const double g0 = gw - 40.0, g1 = gw + 20.0;
  const Imaged im = image_scene(d, g0, g1);
  // Rows over the tower's middle 12 m along track.
  std::vector<double> m(im.grid.cols, 0.0);
  for (std::size_t r = 12; r < 37; ++r)
    for (std::size_t c = 0; c < im.grid.cols; ++c)
      m[c] += static_cast<double>(std::norm(im.img.pixels[r * im.grid.cols + c]));
  // Smear level: the median of the columns between the expected top image and the wall.
  const double r_top = std::hypot(gw, H - h);
  const double g_top = std::sqrt(r_top * r_top - H * H);  // same slant range on the ground
  std::vector<double> smear;
  for (std::size_t c = 0; c < m.size(); ++c) {
    const double g = g0 + static_cast<double>(c);
    if (g > g_top + 3.0 && g < gw - 3.0)
      smear.push_back(m[c]);
  }
  std::nth_element(smear.begin(), smear.begin() + static_cast<std::ptrdiff_t>(smear.size() / 2),
                   smear.end());
  const double level = smear[smear.size() / 2];
  double measured = -1.0;
  for (std::size_t c = 0; c < m.size(); ++c)
    if (m[c] > 0.5 * level) {
      measured = g0 + static_cast<double>(c) - 0.5;
      break;
    }
  std::size_t layover = 0;
  for (std::uint8_t b : im.dem.mask)
    layover += (b & kSarLayover) != 0;
  std::cout << "tower: layover " << gw - measured << " m toward the radar (geometry " << gw - g_top
            << " m, far-field h cot theta " << h / std::tan(63.0 * kPi / 180.0) << " m)\n";
  EXPECT_NEAR(measured, g_top, 1.0);
}

// Issue 28: the flags of the catalogue's sigma0 values a product read. Water at 35 GHz (the NRL
// sea-clutter curve) is flagged near nadir and not at 60-80 deg incidence; the expected flags
// come from the catalogue itself (clutter::sigma0 by name, not the engine's table), at the
// incidences of each grid's ranges from a radar H above a flat field.
TEST(TerrainEngine, FlaggedSigma0ValuesAreCountedWhereTheCatalogueFlagsThem) {
  constexpr double kF = 35e9, kH = 100.0, kDeg = kPi / 180.0;
  scene::SceneDescription d;
  d.materials = {{"water", {}}};
  scene::ObjectDesc g;
  g.name = "lake";
  quad(g.mesh, {-200, -20, 0}, {200, -20, 0}, {200, 850, 0}, {-200, 850, 0}, 0);
  d.objects.push_back(g);
  const scene::Scene s(d);
  const SurfaceSet set = resolve_surfaces(s.materials(), {kF, Polarisation::kVV, {}});
  const cl::TerrainEngine eng = engine_of(s, set, {});
  cl::TerrainView view = north_view(kH, kF, 1.0);
  view.shadowing = false;
  auto run = [&](double r0, double r1, std::vector<cl::Sigma0Use>& use,
                 std::vector<std::uint32_t>& cell_flags, std::vector<double>& mean) {
    cl::CellGrid grid;
    grid.azimuth_min_rad = -10.0 * kDeg;
    grid.azimuth_step_rad = 4.0 * kDeg;
    grid.columns = 5;
    grid.bins = 10;
    grid.elevation_min_rad = -1.55;
    std::vector<double> edges;
    for (std::size_t b = 0; b <= grid.bins; ++b)
      edges.push_back(r0 + (r1 - r0) * static_cast<double>(b) / static_cast<double>(grid.bins));
    grid.range_edges_m = edges;
    use.assign(eng.materials().table.materials(), {});
    cell_flags.assign(grid.columns * grid.bins, 0u);
    mean.assign(grid.columns * grid.bins, 0.0);
    return eng.integrate(view, grid, {}, mean, {}, {}, {}, use, cell_flags);
  };
  auto catalogue_flags = [&](double theta_rad) {
    return cl::sigma0("water", kF, cl::Sigma0Pol::kVV, theta_rad).flags;
  };
  const double far_lo = std::acos(kH / 200.0), far_hi = std::acos(kH / 500.0);    // 60-78.5 deg
  const double near_lo = std::acos(kH / 101.0), near_hi = std::acos(kH / 110.0);  // 8-24.6 deg
  ASSERT_EQ(
      catalogue_flags(far_lo) | catalogue_flags(0.5 * (far_lo + far_hi)) | catalogue_flags(far_hi),
      0u);
  const std::uint32_t near_flags = catalogue_flags(near_lo) | catalogue_flags(near_hi);
  ASSERT_NE(near_flags, 0u);

  std::vector<cl::Sigma0Use> use;
  std::vector<std::uint32_t> cell_flags;
  std::vector<double> mean;
  // Far: every patch inside the curve's validity, nothing flagged, no line.
  cl::TerrainStats st = run(200.0, 500.0, use, cell_flags, mean);
  ASSERT_GT(st.patches_lit, 0u);
  EXPECT_EQ(use[0].patches, st.patches_lit);
  EXPECT_EQ(use[0].flagged_patches, 0u);
  EXPECT_EQ(cl::sigma0_use_flags(use), 0u);
  EXPECT_EQ(std::count_if(cell_flags.begin(), cell_flags.end(), [](auto f) { return f != 0u; }), 0);
  EXPECT_TRUE(cl::sigma0_use_lines(use, cl::sigma0_row_names(eng.materials()), kF).empty());
  EXPECT_DOUBLE_EQ(cl::sigma0_use_patch_fraction(use), 0.0);
  // Near nadir: every patch flagged with the catalogue's bits, every lit cell marked, the
  // incidence span inside the grid's.
  st = run(101.0, 110.0, use, cell_flags, mean);
  ASSERT_GT(st.patches_lit, 0u);
  EXPECT_EQ(use[0].patches, st.patches_lit);
  EXPECT_EQ(use[0].flagged_patches, st.patches_lit);
  EXPECT_EQ(use[0].flags, near_flags);
  EXPECT_GE(use[0].flagged_incidence_min_rad, near_lo - 0.1 * kDeg);
  EXPECT_LE(use[0].flagged_incidence_max_rad, near_hi + 0.1 * kDeg);
  for (std::size_t i = 0; i < mean.size(); ++i) {
    if (mean[i] > 0.0) {
      EXPECT_EQ(cell_flags[i], near_flags) << "cell " << i;
    }
  }
  EXPECT_DOUBLE_EQ(cl::sigma0_use_patch_fraction(use), 1.0);
  EXPECT_DOUBLE_EQ(cl::sigma0_use_power_fraction(use), 1.0);
  const std::vector<std::string> lines =
      cl::sigma0_use_lines(use, cl::sigma0_row_names(eng.materials()), kF);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].rfind("water at 35 GHz, ", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find(cl::describe_validity(near_flags)), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("(100.0 % of the terrain's patches, 100.0 % of its power)"),
            std::string::npos)
      << lines[0];
}

TEST(TerrainEngine, BadInputIsAClearError) {
  // A scene of metal only: no terrain.
  scene::SceneDescription d;
  d.materials = {{"metal", {}}};
  scene::ObjectDesc o;
  o.name = "plate";
  quad(o.mesh, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, 0);
  d.objects.push_back(o);
  const scene::Scene s(d);
  const SurfaceSet set = resolve_surfaces(s.materials(), {35e9, Polarisation::kVV, {}});
  try {
    (void)engine_of(s, set, {});
    FAIL() << "no terrain accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no terrain"), std::string::npos) << e.what();
  }
  // An unknown material: the resolver's error names it.
  scene::SceneDescription u = d;
  u.materials = {{"plasticine", {}}};
  const scene::Scene su(u);
  EXPECT_THROW((void)resolve_surfaces(su.materials(), {35e9, Polarisation::kVV, {}}),
               UnresolvedMaterial);
  // A DEM hole: a field with a square gap; the gap's pixels are flagged, not black-and-silent.
  scene::SceneDescription h;
  h.materials = {{"grass", {}}};
  scene::ObjectDesc g;
  g.name = "field";
  quad(g.mesh, {-50, -950, 0}, {50, -950, 0}, {50, -900, 0}, {-50, -900, 0}, 0);
  quad(g.mesh, {-50, -900, 0}, {-5, -900, 0}, {-5, -890, 0}, {-50, -890, 0}, 0);
  quad(g.mesh, {5, -900, 0}, {50, -900, 0}, {50, -890, 0}, {5, -890, 0}, 0);
  quad(g.mesh, {-50, -890, 0}, {50, -890, 0}, {50, -850, 0}, {-50, -850, 0}, 0);
  h.objects.push_back(g);
  const scene::Scene sh(h);
  const SurfaceSet hs = resolve_surfaces(sh.materials(), {35e9, Polarisation::kVV, {}});
  const cl::TerrainEngine eng = engine_of(sh, hs, {});
  SarImageGrid grid;
  grid.rows = 21;
  grid.cols = 41;
  grid.azimuth_spacing_m = 1.0;
  grid.ground_range_spacing_m = 1.0;
  grid.origin_m = {-10.0, -880.0, 0.0};
  const SarDem dem = sar_dem(eng, geometry_case(), grid);
  // The gap: x in (-5, 5), ground range in (890, 900): 9 x 9 pixel centres strictly inside.
  EXPECT_EQ(dem.holes, 81u);
  EXPECT_EQ(dem.mask[10 * grid.cols + 15] & kSarNoDem, kSarNoDem);
  EXPECT_EQ(dem.mask[0] & kSarNoDem, 0);
}

}  // namespace
}  // namespace radar_emu::radar
