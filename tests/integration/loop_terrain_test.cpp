// The closed loop's terrain clutter from the terrain engine ([radar] terrain = "engine",
// radar/products/terrain_returns.hpp) against the tracer's terrain rays (terrain = "rays"), two
// independent computations of the same integral of sigma0 dA: rays sample the field of view on
// a 1 mrad grid and return sigma0 x their footprint at the first hit; the engine cuts the
// terrain facets into patches and bins them by range and azimuth. Also: the frame path with the
// engine does not allocate, and the targets are still detected.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/terrain_returns.hpp"
#include "scene/scene.hpp"
#include "tests/alloc_counter.hpp"

namespace loop = radar_emu::loop;
namespace radar = radar_emu::radar;

namespace {

loop::Scenario default_scenario() {
  return loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
}

loop::Scenario movers_scenario() {
  return loop::load_scenario(std::string(RADAR_EMU_TEST_DATA_DIR) +
                             "/../../examples/terrain_movers.toml");
}

radar::RadarPose first_pose(const loop::Scenario& s) {
  return loop::scripted_pose(s);
}

// Diffuse power per range bin [m^2]: each diffuse return's |A|^2 spread uniformly over
// [range - spread / 2, range + spread / 2] (the sensor's rule for a footprint), bins of bin_m
// from r0_m.
std::vector<double> power_per_bin(std::span<const radar::Contribution> in, double r0_m,
                                  double bin_m, std::size_t bins) {
  std::vector<double> p(bins, 0.0);
  for (const radar::Contribution& c : in) {
    if (c.coherent)
      continue;
    const double power = std::norm(c.amplitude);
    const double lo = c.range_m - 0.5 * c.range_spread_m, hi = c.range_m + 0.5 * c.range_spread_m;
    if (!(hi > lo)) {
      const double b = std::floor((c.range_m - r0_m) / bin_m);
      if (b >= 0 && b < static_cast<double>(bins))
        p[static_cast<std::size_t>(b)] += power;
      continue;
    }
    const auto b0 = static_cast<long>(std::floor((lo - r0_m) / bin_m));
    const auto b1 = static_cast<long>(std::floor((hi - r0_m) / bin_m));
    for (long b = std::max(0L, b0); b <= b1 && b < static_cast<long>(bins); ++b) {
      const double a = std::max(lo, r0_m + static_cast<double>(b) * bin_m);
      const double z = std::min(hi, r0_m + static_cast<double>(b + 1) * bin_m);
      if (z > a)
        p[static_cast<std::size_t>(b)] += power * (z - a) / (hi - lo);
    }
  }
  return p;
}

// Rays and engine on the scenario's first pose: the mean clutter power per range bin averaged
// over blocks of `block` bins, in dB engine - rays, for the blocks holding at least 1 % of the
// largest block's power (the lit part of the swath). Prints the table.
std::vector<double> block_differences_db(const loop::Scenario& s, std::size_t block) {
  const radar_emu::scene::Scene scene(loop::scene_description(s));
  const radar::RadarPose pose = first_pose(s);
  const radar::TerrainReturnsConfig tc = loop::terrain_returns_config(s);
  const double bin_m = tc.range_cell_m;  // the engine's cell: the sensor's bin x cell_range_bins
  const auto bins = static_cast<std::size_t>(std::ceil((tc.range_max_m - tc.range_min_m) / bin_m));

  radar::SbrConfig with_rays = s.sbr;
  with_rays.terrain_rays = true;
  radar::SbrTracer rays(scene, with_rays);
  std::vector<radar::Contribution> out(rays.max_contributions());
  radar::TraceStats ts;
  const std::size_t n_rays = rays.trace(pose, out, ts);
  const std::vector<double> p_rays =
      power_per_bin(std::span(out.data(), n_rays), tc.range_min_m, bin_m, bins);

  radar::SbrConfig no_rays = s.sbr;
  no_rays.terrain_rays = false;
  radar::SbrTracer tracer(scene, no_rays);
  radar::TerrainReturns engine(scene, tracer, tc);
  std::vector<radar::Contribution> cells(engine.max_returns());
  radar::clutter::TerrainStats es;
  std::uint64_t dropped = 0;
  const std::size_t n_cells = engine.compute(pose, cells, es, dropped);
  EXPECT_EQ(dropped, 0u);
  EXPECT_EQ(es.budget_cut, 0u);
  const std::vector<double> p_engine =
      power_per_bin(std::span(cells.data(), n_cells), tc.range_min_m, bin_m, bins);

  std::vector<double> sum_rays, sum_engine;
  for (std::size_t b0 = 0; b0 + block <= bins; b0 += block) {
    double a = 0.0, e = 0.0;
    for (std::size_t b = b0; b < b0 + block; ++b) {
      a += p_rays[b];
      e += p_engine[b];
    }
    sum_rays.push_back(a);
    sum_engine.push_back(e);
  }
  const double peak = *std::max_element(sum_rays.begin(), sum_rays.end());
  std::vector<double> diff;
  std::printf("%s: %zu ray returns, %zu engine cells (%llu patches lit of %llu)\n", s.name.c_str(),
              n_rays, n_cells, static_cast<unsigned long long>(es.patches_lit),
              static_cast<unsigned long long>(es.patches));
  std::printf("  range_m  rays_dBsm  engine_dBsm  diff_dB  (per range bin, mean over %zu bins)\n",
              block);
  for (std::size_t k = 0; k < sum_rays.size(); ++k) {
    if (!(sum_rays[k] >= 0.01 * peak))
      continue;
    const double r = tc.range_min_m +
                     (static_cast<double>(k * block) + 0.5 * static_cast<double>(block)) * bin_m;
    const double ra = 10.0 * std::log10(sum_rays[k] / static_cast<double>(block));
    const double en =
        10.0 * std::log10(std::max(sum_engine[k], 1e-300) / static_cast<double>(block));
    diff.push_back(en - ra);
    std::printf("  %7.0f  %9.2f  %11.2f  %7.2f\n", r, ra, en, en - ra);
  }
  return diff;
}

void expect_within_db(const std::vector<double>& diff, double tol_db) {
  ASSERT_GE(diff.size(), 10u) << "too few lit range blocks to compare";
  double mean = 0.0;
  for (double d : diff) {
    EXPECT_LE(std::abs(d), tol_db);
    mean += d;
  }
  mean /= static_cast<double>(diff.size());
  std::printf("  mean difference %.2f dB over %zu blocks\n", mean, diff.size());
  EXPECT_LE(std::abs(mean), 0.5 * tol_db);
}

}  // namespace

// The mean clutter power per range bin, averaged over 100 m of range (the rays' footprints
// spread over up to 40 m of range each at these grazing angles: a block holds several of their
// rows), agrees within 1 dB between the two, on the default approach over the runway scene.
TEST(LoopTerrain, EngineClutterPowerPerRangeBinMatchesTerrainRaysDefault) {
  expect_within_db(block_differences_db(default_scenario(), 17), 1.0);
}

// The same on examples/terrain_movers.toml (the 207k-polygon terrain database: hills, forest,
// roads, lakes; shadows behind the crests).
TEST(LoopTerrain, EngineClutterPowerPerRangeBinMatchesTerrainRaysTerrainDatabase) {
  expect_within_db(block_differences_db(movers_scenario(), 17), 1.0);
}

// The frame path with the engine allocates nothing (frames 5 to the last, the fixture's rule in
// closed_loop_test.cpp), and every target the terrain rays let the radar detect is still
// detected, in as many of its in-beam frames within 10 %, or within the binomial noise of the
// counts for a target detected in only some frames (the default approach with its trihedrals,
// the governor off: full physics both ways).
TEST(LoopTerrain, EngineFramePathDoesNotAllocateAndTargetsAreStillDetected) {
  loop::Scenario s = default_scenario();
  s.scene_corner_reflectors = true;
  s.governor.enabled = false;
  s.frames = 30;
  loop::Scenario e = s;
  s.terrain_engine = false;  // the tracer's terrain rays (the default is the engine)
  s.sbr.terrain_rays = true;
  e.terrain_engine = true;
  e.sbr.terrain_rays = false;

  loop::ClosedLoop rays_loop(s, {});
  const loop::RunResult with_rays = rays_loop.run();

  loop::RunOptions options;
  options.progress = radar_emu::test::count_allocations_from_frame(5);
  loop::ClosedLoop engine_loop(e, options);
  const loop::RunResult with_engine = engine_loop.run();
  const std::uint64_t allocations = radar_emu::test::stop_counting_allocations();
  EXPECT_EQ(allocations, 0u) << "heap allocations between frame 5 and the last frame";
  EXPECT_EQ(with_rays.terrain.patches, 0u);
  EXPECT_GT(with_engine.terrain.patches_lit, 0u);
  EXPECT_EQ(with_engine.terrain_dropped, 0u);
  EXPECT_EQ(with_engine.terrain.budget_cut, 0u);
  // Issue 28: the engine counts the flagged sigma0 values its patches read (at 94 GHz every land
  // value of the catalogue is assumed: clutter::sigma0 by name says so for each of the scene's
  // terrain materials, checked at 0, 45 and 89 deg), and the report says so.
  const loop::RunReport rep = engine_loop.report(with_engine);
  EXPECT_TRUE(rep.sigma0_tracked);
  EXPECT_NE(rep.sigma0_flags & radar::clutter::kAssumedValue, 0u);
  EXPECT_DOUBLE_EQ(rep.sigma0_patch_fraction, 1.0);
  ASSERT_FALSE(rep.sigma0_lines.empty());
  for (const std::string& line : rep.sigma0_lines) {
    std::printf("flagged: %s\n", line.c_str());
    const std::string material = line.substr(0, line.find(" at 94 GHz, "));
    ASSERT_NE(material.size(), line.size()) << line;
    for (double deg : {0.0, 45.0, 89.0})
      EXPECT_NE(radar::clutter::sigma0(material, e.sbr.carrier_hz, radar::clutter::Sigma0Pol::kVV,
                                       deg * std::acos(-1.0) / 180.0)
                        .flags &
                    radar::clutter::kAssumedValue,
                0u)
          << material << " at " << deg << " deg";
  }
  // The terrain rays count their returns alone: every one read an assumed value here.
  const loop::RunReport rays_rep = rays_loop.report(with_rays);
  EXPECT_TRUE(rays_rep.sigma0_tracked);
  EXPECT_GT(with_rays.trace.terrain_returns, 0u);
  EXPECT_EQ(with_rays.trace.terrain_returns_flagged, with_rays.trace.terrain_returns);
  EXPECT_NE(rays_rep.sigma0_flags & radar::clutter::kAssumedValue, 0u);
  EXPECT_DOUBLE_EQ(rays_rep.sigma0_patch_fraction, 1.0);
  ASSERT_EQ(rays_rep.sigma0_lines.size(), 1u);
  EXPECT_EQ(rays_rep.sigma0_lines[0].rfind("terrain rays at 94 GHz: ", 0), 0u)
      << rays_rep.sigma0_lines[0];

  const auto& a = with_rays.outcome.targets;
  const auto& b = with_engine.outcome.targets;
  ASSERT_EQ(a.size(), b.size());
  std::size_t detected = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].object_id, b[i].object_id);
    EXPECT_EQ(a[i].frames_in_beam, b[i].frames_in_beam);
    std::printf("object %u: in beam %llu, detected rays %llu, engine %llu\n", a[i].object_id,
                static_cast<unsigned long long>(a[i].frames_in_beam),
                static_cast<unsigned long long>(a[i].frames_detected),
                static_cast<unsigned long long>(b[i].frames_detected));
    if (a[i].frames_detected == 0)
      continue;
    ++detected;
    // Within 10 %, or for a target seen in only some frames within the noise: the two counts
    // are binomial over the frames (the receiver noise differs between the two runs), so the
    // engine's may fall short by three standard deviations of their difference, sqrt(2 n p
    // (1 - p)) with p the rays' detection rate, plus one (a count of 2 of 30 against 1 is not
    // a lost target; one of 30 of 30 lost would be).
    const auto n = static_cast<double>(a[i].frames_in_beam);
    const auto k = static_cast<double>(a[i].frames_detected);
    const double p = k / n;
    const double allowed = std::min(0.9 * k, k - 3.0 * std::sqrt(2.0 * n * p * (1.0 - p)) - 1.0);
    EXPECT_GE(static_cast<double>(b[i].frames_detected), allowed) << "object " << a[i].object_id;
  }
  EXPECT_GE(detected, 1u);
}

namespace {

// A scenario's scene at time 0 and the loop's tracer over it with its terrain rays off (the
// engine has the terrain), as the loop builds them for the engine.
radar_emu::scene::Scene scene_at_start(const loop::Scenario& s) {
  radar_emu::scene::Scene scene(loop::scene_description(s));
  scene.set_time(0.0);
  return scene;
}
radar::SbrConfig engine_tracer_config(const loop::Scenario& s) {
  radar::SbrConfig cfg = s.sbr;
  cfg.terrain_rays = false;
  return cfg;
}
struct EngineScene {
  explicit EngineScene(const loop::Scenario& s)
      : scene(scene_at_start(s)), tracer(scene, engine_tracer_config(s)) {}
  radar_emu::scene::Scene scene;
  const radar::SbrTracer tracer;
};

// TerrainReturns::compute at `scale` from the scenario's first pose into `out`, nothing dropped:
// the returns' total mean power [m^2] (sum |A|^2); their count in `n`, the engine's in `st`.
double compute_power(radar::TerrainReturns& t, const loop::Scenario& s, double scale,
                     std::vector<radar::Contribution>& out, radar::clutter::TerrainStats& st,
                     std::size_t& n) {
  std::uint64_t dropped = 0;
  n = t.compute(first_pose(s), out, st, dropped, scale);
  EXPECT_EQ(dropped, 0u);
  double power = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    power += std::norm(out[i].amplitude);
  return power;
}

// The loop's engine returns on the scenario's first pose with TBB held to `threads` (0: all).
std::vector<radar::Contribution> engine_returns(const loop::Scenario& s, int threads,
                                                std::size_t slices) {
  std::optional<tbb::global_control> limit;
  if (threads > 0)
    limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  const EngineScene e(s);
  const radar_emu::scene::Scene& scene = e.scene;
  const radar::SbrTracer& tracer = e.tracer;
  radar::TerrainReturnsConfig tc = loop::terrain_returns_config(s);
  tc.slices = slices;
  radar::TerrainReturns terrain(scene, tracer, tc);
  std::vector<radar::Contribution> out(terrain.max_returns());
  radar::clutter::TerrainStats stats;
  std::uint64_t dropped = 0;
  out.resize(terrain.compute(first_pose(s), out, stats, dropped));
  return out;
}

void expect_same_returns(const std::vector<radar::Contribution>& a,
                         const std::vector<radar::Contribution>& b) {
  ASSERT_EQ(a.size(), b.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].amplitude != b[i].amplitude || a[i].range_m != b[i].range_m ||
        a[i].azimuth_rad != b[i].azimuth_rad || a[i].elevation_rad != b[i].elevation_rad ||
        a[i].radial_velocity_mps != b[i].radial_velocity_mps)
      ++differing;
  EXPECT_EQ(differing, 0u) << "of " << a.size() << " returns";
}

}  // namespace

TEST(LoopTerrain, GovernorPatchScaleCutsThePatchesAndKeepsThePower) {
  // The governor's terrain knob (TraceKnobs::terrain_spacing_scale) passed as compute()'s
  // patch_scale: patches s times larger each way, about 1/s^2 as many (the facets smaller than a
  // patch stay one patch each, so somewhat more), and the clutter's total mean power the same
  // sum of sigma0 dA within 0.5 dB (the patches spread over the cells they cover).
  const loop::Scenario s = default_scenario();
  const EngineScene e(s);
  const radar_emu::scene::Scene& scene = e.scene;
  const radar::SbrTracer& tracer = e.tracer;
  radar::TerrainReturns terrain(scene, tracer, loop::terrain_returns_config(s));
  std::vector<radar::Contribution> out(terrain.max_returns());
  auto run = [&](double scale, double& power) {
    radar::clutter::TerrainStats st;
    std::size_t n = 0;
    power = compute_power(terrain, s, scale, out, st, n);
    return st.patches;
  };
  double p1 = 0.0, p2 = 0.0;
  const std::uint64_t n1 = run(1.0, p1), n2 = run(2.0, p2);
  const double ratio = static_cast<double>(n2) / static_cast<double>(n1);
  std::printf("patch scale 2: %llu -> %llu patches (x %.3f), total power %+.3f dB\n",
              static_cast<unsigned long long>(n1), static_cast<unsigned long long>(n2), ratio,
              10.0 * std::log10(p2 / p1));
  EXPECT_GT(ratio, 0.2);
  EXPECT_LT(ratio, 0.45);
  EXPECT_NEAR(10.0 * std::log10(p2 / p1), 0.0, 0.5);
}

TEST(LoopTerrain, GovernorScaleMergesTheCellsAndKeepsThePower) {
  // From scale 2 on the knob also merges the engine's cells (TerrainReturns::cell_merge): at the
  // governor's level 8 (scale 2^(8/4) = 4) four range bins a cell (the loop's columns do not
  // merge), so at most 1/4 of the returns of level 0 (about that many where the lit cells are
  // dense), and the total mean power the same sum of sigma0 dA within 0.5 dB (patches 4 times
  // larger too: their shadows and grazing differ a little).
  const loop::Scenario s = default_scenario();
  const EngineScene e(s);
  const radar_emu::scene::Scene& scene = e.scene;
  const radar::SbrTracer& tracer = e.tracer;
  radar::TerrainReturns terrain(scene, tracer, loop::terrain_returns_config(s));
  ASSERT_EQ(terrain.azimuth_merge_max(), 1u);
  const radar::TerrainCellMerge m = radar::TerrainReturns::cell_merge(4.0, 1);
  EXPECT_EQ(m.range, 4u);
  EXPECT_EQ(m.azimuth, 1u);
  EXPECT_EQ(radar::TerrainReturns::cell_merge(4.0, 2).azimuth, 2u);  // where columns may merge
  EXPECT_EQ(radar::TerrainReturns::cell_merge(8.0, 2).range, 8u);
  EXPECT_EQ(radar::TerrainReturns::cell_merge(1.99, 4).cells(), 1u);
  EXPECT_EQ(radar::TerrainReturns::cell_merge(1e9, 1).range, radar::TerrainReturns::kMaxMerge);
  std::vector<radar::Contribution> out(terrain.max_returns());
  auto run = [&](double scale, double& power) {
    radar::clutter::TerrainStats st;
    std::size_t n = 0;
    power = compute_power(terrain, s, scale, out, st, n);
    return n;
  };
  double p1 = 0.0, p4 = 0.0;
  const std::size_t n1 = run(1.0, p1), n4 = run(4.0, p4);
  const double ratio = static_cast<double>(n4) / static_cast<double>(n1);
  std::printf(
      "scale 4 (range bins merged 4 a cell): %zu -> %zu returns (x %.3f), total power "
      "%+.3f dB\n",
      n1, n4, ratio, 10.0 * std::log10(p4 / p1));
  EXPECT_LE(ratio, 1.0 / 4.0 + 0.02);  // a merged cell is lit when one of its 4 is
  EXPECT_GT(ratio, 0.18);
  EXPECT_NEAR(10.0 * std::log10(p4 / p1), 0.0, 0.5);
}

TEST(LoopTerrain, CoarseLevelOfDetailCutsTheFacetsAndKeepsThePower) {
  // examples/terrain_movers.toml's database (tiles at three levels of detail): at the governor's
  // level 12 (scale 8, range merge 8 = coarse_lod_merge) the engine integrates the tiles' level 1
  // (every second node of the level-0 grid): under a third of the database's facets (the roads,
  // outside the tiles, stay as they are), and under 0.6 of those in the field of view (the larger
  // facets' bounds take in more of them at its edges), each one patch; and the same sum of sigma0
  // dA over the field of view within 1 dB (the same surface sampled more coarsely: its facets'
  // tilts and shadows differ); compute() allocates nothing at any of these scales.
  const loop::Scenario s = movers_scenario();
  const EngineScene e(s);
  const radar_emu::scene::Scene& scene = e.scene;
  const radar::SbrTracer& tracer = e.tracer;
  radar::TerrainReturnsConfig tc = loop::terrain_returns_config(s);
  radar::TerrainReturns coarse(scene, tracer, tc);
  ASSERT_NE(coarse.coarse_engine(), nullptr);
  tc.coarse_lod_merge = 0;
  radar::TerrainReturns fine(scene, tracer, tc);
  EXPECT_EQ(fine.coarse_engine(), nullptr);
  const radar::TerrainCoarsening c = coarse.coarsening();
  std::printf("facets: %zu at level 0, %zu at level 1 (ratio %.3f)\n",
              coarse.engine().facets().size(), coarse.coarse_engine()->facets().size(),
              c.lod_facet_ratio);
  EXPECT_EQ(c.lod_merge, 8u);
  EXPECT_LT(c.lod_facet_ratio, 1.0 / 3.0);
  std::vector<radar::Contribution> out(fine.max_returns());
  auto run = [&](radar::TerrainReturns& t, double scale, radar::clutter::TerrainStats& st) {
    std::size_t n = 0;
    return compute_power(t, s, scale, out, st, n);
  };
  radar::clutter::TerrainStats s_fine, s_coarse, s_below;
  const double p_fine = run(fine, 8.0, s_fine), p_coarse = run(coarse, 8.0, s_coarse);
  std::printf(
      "level 12: %llu facets, %llu patches (level 0) -> %llu facets, %llu patches "
      "(level 1); total power %+.3f dB\n",
      static_cast<unsigned long long>(s_fine.facets_considered),
      static_cast<unsigned long long>(s_fine.patches),
      static_cast<unsigned long long>(s_coarse.facets_considered),
      static_cast<unsigned long long>(s_coarse.patches), 10.0 * std::log10(p_coarse / p_fine));
  EXPECT_LT(static_cast<double>(s_coarse.patches), 0.6 * static_cast<double>(s_fine.patches));
  EXPECT_NEAR(10.0 * std::log10(p_coarse / p_fine), 0.0, 1.0);
  // Below the coarse merge (level 11, scale 6.7, merge 4) the fine level of detail, as before.
  const double p_below = run(coarse, std::pow(2.0, 11.0 / 4.0), s_below);
  EXPECT_GT(p_below, 0.0);
  EXPECT_GT(static_cast<double>(s_below.facets_considered),
            0.9 * static_cast<double>(s_fine.facets_considered));
  // Merged cells and the coarse level of detail allocate nothing per frame (buffers sized at
  // setup for the finest grid and the larger facet list).
  radar::clutter::TerrainStats s_again;
  radar_emu::test::start_counting_allocations();
  (void)run(coarse, 8.0, s_again);
  (void)run(coarse, 2.0, s_again);
  (void)run(coarse, 1.0, s_again);
  EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u);
}

TEST(LoopTerrain, MergedCellsHoldTheSumOfTheCellsTheyMerge) {
  // The same patches on a grid and merged 4 x 4: each merged cell's power is the sum of the 16
  // cells it covers, its elevation their power-weighted one (sum p sin el / sum p), its range
  // and azimuth the merged cell's centre and its range spread the merged width. Without shadows,
  // so that the horizon's resolution (half a cell, merged or not) plays no part: the same sum of
  // sigma0 dA, to rounding. Fine: patch fraction 1 at scale 1 (patches one cell: R x 0.5 deg,
  // 6 m); merged: fraction 1/4 at scale 4, the same patch sizes, widest column 4 x 0.5 deg.
  const loop::Scenario s = default_scenario();
  const EngineScene e(s);
  const radar_emu::scene::Scene& scene = e.scene;
  const radar::SbrTracer& tracer = e.tracer;
  radar::TerrainReturnsConfig fine_cfg = loop::terrain_returns_config(s);
  fine_cfg.shadowing = false;
  radar::TerrainReturnsConfig merged_cfg = fine_cfg;
  merged_cfg.patch_fraction = 0.25;
  merged_cfg.coarse_azimuth_max_rad = 4.0 * fine_cfg.azimuth_cell_rad;
  radar::TerrainReturns fine(scene, tracer, fine_cfg), merged(scene, tracer, merged_cfg);
  ASSERT_EQ(fine.columns() % 4, 0u);
  ASSERT_EQ(merged.azimuth_merge_max(), 4u);
  const radar::RadarPose pose = first_pose(s);
  std::vector<radar::Contribution> a(fine.max_returns()), b(merged.max_returns());
  radar::clutter::TerrainStats sa, sb;
  std::uint64_t dropped = 0;
  a.resize(fine.compute(pose, a, sa, dropped, 1.0));
  b.resize(merged.compute(pose, b, sb, dropped, 4.0));
  EXPECT_EQ(dropped, 0u);
  EXPECT_GE(sb.patches_lit, sa.patches_lit);  // the same, and those past range_max_m
  const double c_m = fine_cfg.range_cell_m, c_rad = fine_cfg.azimuth_cell_rad;
  const std::size_t columns4 = fine.columns() / 4;
  // The fine cells summed by merged cell, over the merged bins that end a facet's length (50 m,
  // the engine's max_facet_m) short of the fine grid's far edge: the merged grid's last bin
  // reaches past it, and holds the patches centred there, whose power spreads back by up to half
  // their length (the fine grid leaves them out whole, as every patch centred outside it).
  const auto bins4 = static_cast<std::size_t>(
      std::floor((static_cast<double>(fine.bins()) * c_m - 50.0) / (4.0 * c_m)));
  std::vector<double> power(bins4 * columns4, 0.0), el_power(bins4 * columns4, 0.0);
  double fine_total = 0.0;
  for (const radar::Contribution& x : a) {
    const auto bin = static_cast<std::size_t>(std::floor((x.range_m - fine_cfg.range_min_m) / c_m));
    const auto col =
        static_cast<std::size_t>(std::floor((x.azimuth_rad - fine_cfg.azimuth_min_rad) / c_rad));
    ASSERT_LT(col, fine.columns());
    if (bin / 4 >= bins4)
      continue;
    const double p = std::norm(x.amplitude);
    power[(bin / 4) * columns4 + col / 4] += p;
    el_power[(bin / 4) * columns4 + col / 4] += p * std::sin(x.elevation_rad);
    fine_total += p;
  }
  std::size_t compared = 0, lit = 0;
  double merged_total = 0.0, worst = 0.0;
  for (const radar::Contribution& x : b) {
    const double bf = (x.range_m - fine_cfg.range_min_m) / (4.0 * c_m);
    const double cf = (x.azimuth_rad - fine_cfg.azimuth_min_rad) / (4.0 * c_rad);
    // Centred in its merged cell, 4 cells wide.
    EXPECT_NEAR(bf - std::floor(bf), 0.5, 1e-9);
    EXPECT_NEAR(cf - std::floor(cf), 0.5, 1e-9);
    EXPECT_NEAR(x.range_spread_m, 4.0 * c_m, 1e-9);
    const auto bin = static_cast<std::size_t>(bf), col = static_cast<std::size_t>(cf);
    if (bin >= bins4)
      continue;
    const double p = std::norm(x.amplitude), q = power[bin * columns4 + col];
    merged_total += p;
    ++compared;
    worst = std::max(worst, std::abs(p - q) / q);
    EXPECT_NEAR(std::sin(x.elevation_rad), el_power[bin * columns4 + col] / q, 1e-9);
  }
  for (double q : power)
    lit += q > 0.0 ? 1 : 0;
  std::printf(
      "%zu fine returns, %zu merged (%zu compared, %zu merged cells lit by the fine ones); "
      "total %.6g m^2 merged, %.6g m^2 summed; worst cell %.2g relative\n",
      a.size(), b.size(), compared, lit, merged_total, fine_total, worst);
  EXPECT_EQ(compared, lit);
  EXPECT_GT(compared, 100u);
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(merged_total / fine_total, 1.0, 1e-12 * static_cast<double>(compared));
}

TEST(LoopTerrain, EngineReturnsAreTheSameForAnyNumberOfThreads) {
  // The slices are the configuration's, not the threads': one thread and all of them give the
  // same returns, value for value and in the same order (the sensor draws its speckle in that
  // order).
  const loop::Scenario s = default_scenario();
  const std::vector<radar::Contribution> one = engine_returns(s, 1, 2);
  const std::vector<radar::Contribution> all = engine_returns(s, 0, 2);
  EXPECT_GT(one.size(), 1000u);
  expect_same_returns(one, all);
}

TEST(LoopTerrain, EngineCellsDoNotDependOnTheSlicing) {
  // The horizon of a slice's columns is swept from the facets themselves, so cutting the columns
  // into 1, 2 or 3 slices changes only the order of the returns: the same power in every cell.
  const loop::Scenario s = default_scenario();
  auto by_cell = [](std::vector<radar::Contribution> r) {
    std::sort(r.begin(), r.end(), [](const radar::Contribution& x, const radar::Contribution& y) {
      return x.range_m != y.range_m ? x.range_m < y.range_m : x.azimuth_rad < y.azimuth_rad;
    });
    return r;
  };
  const auto one = by_cell(engine_returns(s, 0, 1));
  expect_same_returns(one, by_cell(engine_returns(s, 0, 2)));
  expect_same_returns(one, by_cell(engine_returns(s, 0, 3)));
}
