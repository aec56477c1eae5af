// The fidelity governor (loop/governor.hpp): it chooses the finest level predicted to fit
// the deadline, its levels cost less as they go up, the strongest target keeps the finest rays,
// measured slowness makes it coarsen, and a degraded frame is flagged in the ICD header.

#include "loop/governor.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "io/detection_icd.hpp"
#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "radar/em/sbr.hpp"
#include "radar/sensor/sensor.hpp"
#include "scene/scene.hpp"

namespace loop = radar_emu::loop;
namespace radar = radar_emu::radar;
namespace sc = radar_emu::scene;

namespace {

loop::Scenario default_scenario() {
  return loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
}

radar::RadarPose start_pose(const loop::Scenario& s) {
  return loop::scripted_pose(s);
}

// The default scenario's scene, tracer and sensor at the start pose.
struct DefaultFrame {
  loop::Scenario s = default_scenario();
  sc::Scene scene{loop::scene_description(s)};
  radar::SbrTracer tracer{scene, s.sbr};
  radar::Sensor sensor{s.sensor};
  radar::RadarPose pose = start_pose(s);
  DefaultFrame() { scene.set_time(0.0); }
};

DefaultFrame& default_frame() {
  static DefaultFrame f;
  return f;
}

// A square PEC plate of side a facing -y (the radar looks north), centred at (x, y, z).
sc::ObjectDesc plate(const char* name, double a, double x, double y, double z) {
  sc::ObjectDesc o{name, {}, glm::dmat4(1.0), std::nullopt};
  const auto h = static_cast<float>(0.5 * a);
  const auto fx = static_cast<float>(x), fy = static_cast<float>(y), fz = static_cast<float>(z);
  o.mesh.positions_m = {
      {fx - h, fy, fz - h}, {fx + h, fy, fz - h}, {fx + h, fy, fz + h}, {fx - h, fy, fz + h}};
  o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  o.mesh.triangle_material = {0, 0};
  return o;
}

}  // namespace

TEST(Governor, AnAmpleBudgetKeepsTheScenariosFidelity) {
  DefaultFrame& f = default_frame();
  loop::GovernorConfig g = f.s.governor;
  g.mode = loop::GovernorConfig::Mode::kModel;
  g.compute_fraction = 1.0;
  // 0.1 Hz: a 10 s deadline.
  loop::FidelityGovernor gov(g, f.scene, f.tracer, f.sensor, 10.0);
  const loop::GovernorDecision& d = gov.decide(f.pose);
  EXPECT_EQ(d.level, 0);
  EXPECT_FALSE(d.degraded);
  EXPECT_EQ(d.rays, d.full_rays);
  EXPECT_EQ(d.rays, f.tracer.plan(f.pose).rays()) << "level 0 is the configuration as it is";
  EXPECT_EQ(d.knobs.terrain_spacing_scale, 1.0);
  EXPECT_EQ(d.knobs.max_bounces, 0);
}

TEST(Governor, LevelsCostLessAsTheyGoUpAndTheChoiceIsTheFinestThatFits) {
  DefaultFrame& f = default_frame();
  loop::GovernorConfig g = f.s.governor;
  g.mode = loop::GovernorConfig::Mode::kModel;
  g.max_level = loop::FidelityGovernor::kMaxLevel;
  const double period_s = 1.0;  // deadlines up to 1 s
  loop::FidelityGovernor probe(g, f.scene, f.tracer, f.sensor, period_s);
  std::vector<double> predicted;
  std::size_t previous_rays = 0;
  for (int level = 0; level <= 10; ++level) {
    const loop::GovernorDecision& d = probe.decide_at(f.pose, level);
    ASSERT_EQ(d.level, level);
    if (level > 0) {
      EXPECT_LT(d.rays, previous_rays) << "level " << level;
      EXPECT_LT(d.predicted_ms, predicted.back()) << "level " << level;
    }
    EXPECT_EQ(d.knobs.terrain_spacing_scale, std::pow(2.0, 0.25 * level));
    EXPECT_EQ(d.knobs.max_bounces == 0, level < loop::FidelityGovernor::kBounceLevel);
    previous_rays = d.rays;
    predicted.push_back(d.predicted_ms);
    std::printf("level %2d: %7zu rays, predicted %.1f ms\n", level, d.rays, d.predicted_ms);
  }
  // For deadlines between the levels' predictions, the governor takes the first level below.
  for (int level = 1; level < 10; ++level) {
    const auto k = static_cast<std::size_t>(level);
    const double deadline_ms = 0.5 * (predicted[k] + predicted[k - 1]);
    g.compute_fraction = deadline_ms * 1e-3 / period_s;
    loop::FidelityGovernor gov(g, f.scene, f.tracer, f.sensor, period_s);
    const loop::GovernorDecision& d = gov.decide(f.pose);
    EXPECT_EQ(d.level, level) << "deadline " << deadline_ms << " ms";
    EXPECT_LE(d.predicted_ms, d.deadline_ms);
    EXPECT_TRUE(d.degraded);
    EXPECT_FALSE(d.over_deadline);
  }
  // A deadline nothing meets: the finest level within 5 % of the deadline of the coarsest
  // level's cost, flagged as predicted late. With a deadline of 1 ns that is the coarsest.
  g.compute_fraction = 1e-6 / period_s;
  g.max_level = 6;
  loop::FidelityGovernor late(g, f.scene, f.tracer, f.sensor, period_s);
  EXPECT_EQ(late.decide(f.pose).level, 6);
  EXPECT_TRUE(late.decide(f.pose).over_deadline);
  // A deadline below the cost of every level: where the levels stop buying 5 % of the deadline.
  g.max_level = 10;
  const double deadline_ms = 0.5 * predicted[10];
  g.compute_fraction = deadline_ms * 1e-3 / period_s;
  loop::FidelityGovernor floor(g, f.scene, f.tracer, f.sensor, period_s);
  const loop::GovernorDecision& fd = floor.decide(f.pose);
  EXPECT_TRUE(fd.over_deadline);
  std::size_t want = 10;
  while (want > 0 && predicted[want - 1] <= predicted[10] + 0.05 * deadline_ms)
    --want;
  EXPECT_EQ(fd.level, static_cast<int>(want));
  EXPECT_LT(want, 10u) << "the levels' costs flatten out (the sensor's cells)";
  // Disabled: level 0 whatever the deadline.
  g.enabled = false;
  loop::FidelityGovernor off(g, f.scene, f.tracer, f.sensor, period_s);
  EXPECT_EQ(off.decide(f.pose).level, 0);
}

TEST(Governor, WhenNoLevelCanFitItPlansOnlyTheLastLevelsAndChoosesAsIfItTriedEach) {
  // The default frame with a deadline under what no level reduces (the floor: the frame's fixed
  // trace cost, the facet pass over the bundled targets, the sensor's cells). Trying each level
  // in turn would end at the last (10 here); the governor goes there at once and steps back
  // through the levels within 5 % of the deadline of its cost. Its choice is the one the
  // levels' own predictions (decide_at) give, and its plans are level 0's (with the refresh's
  // wait: 2), then two for each level it reached: the last, those it stepped back to, and the
  // first that stopped it. Trying each level would take 2 x 11.
  DefaultFrame& f = default_frame();
  loop::GovernorConfig g = f.s.governor;
  g.mode = loop::GovernorConfig::Mode::kModel;
  g.max_level = 10;
  const double period_s = 1.0;
  loop::FidelityGovernor probe(g, f.scene, f.tracer, f.sensor, period_s);
  std::vector<double> predicted;
  for (int level = 0; level <= 10; ++level)
    predicted.push_back(probe.decide_at(f.pose, level).predicted_ms);
  const double cells =
      static_cast<double>(f.sensor.antenna().beams() * f.sensor.processor().range_bins() *
                          f.sensor.processor().velocity_bins());
  const double floor_ms =
      g.trace_ms_per_frame +
      1e-6 * (g.trace_ns_per_facet * static_cast<double>(f.tracer.plan(f.pose).target_facets)) +
      1e-6 * g.sensor_ns_per_cell * cells;
  ASSERT_GT(predicted[10], floor_ms);
  for (const double deadline_ms : {0.999 * floor_ms, 0.5 * floor_ms, 1e-6}) {
    g.compute_fraction = deadline_ms * 1e-3 / period_s;
    loop::FidelityGovernor gov(g, f.scene, f.tracer, f.sensor, period_s);
    const loop::GovernorDecision& d = gov.decide(f.pose);
    std::size_t want = 10;
    while (want > 0 && predicted[want - 1] <= predicted[10] + 0.05 * deadline_ms)
      --want;
    EXPECT_EQ(d.level, static_cast<int>(want)) << "deadline " << deadline_ms << " ms";
    EXPECT_EQ(d.predicted_ms, predicted[want]);
    EXPECT_TRUE(d.over_deadline);
    const std::size_t reached = 10 - want + 1 + (want > 0 ? 1 : 0);
    EXPECT_EQ(d.plans, 2 + 2 * reached) << "deadline " << deadline_ms << " ms";
    std::printf("deadline %.3f ms (floor %.3f ms): level %d, %zu plans\n", deadline_ms, floor_ms,
                d.level, d.plans);
  }
}

TEST(Governor, TheStrongestTargetKeepsTheFinestRays) {
  // Two equal plates, one at 500 m and one at 4000 m: the far one's expected SNR is
  // 40 log10(8) = 36.1 dB lower, rank 3 (10 dB steps).
  sc::SceneDescription d;
  d.materials = {{"metal", {}}};
  d.objects = {plate("near", 2.0, 0.0, 500.0, 0.0), plate("far", 2.0, 0.0, 4000.0, 0.0)};
  sc::Scene scene(d);
  scene.set_time(0.0);
  loop::Scenario s = default_scenario();
  s.sbr.azimuth_min_rad = -0.1;
  s.sbr.azimuth_max_rad = 0.1;
  s.sbr.elevation_min_rad = -0.1;
  s.sbr.elevation_max_rad = 0.1;
  radar::SbrTracer tracer(scene, s.sbr);
  radar::Sensor sensor(s.sensor);
  radar::RadarPose pose;
  pose.position_m = {0.0, 0.0, 0.0};
  // Antenna x (boresight) north, y east, z down.
  pose.world_from_antenna =
      glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1));
  loop::GovernorConfig g = s.governor;
  g.mode = loop::GovernorConfig::Mode::kModel;
  loop::FidelityGovernor gov(g, scene, tracer, sensor, 1.0 / s.rate_hz);
  const double base = s.sbr.target_ray_spacing_m;
  for (int level : {0, 1, 2, 4}) {
    const loop::GovernorDecision& dec = gov.decide_at(pose, level);
    ASSERT_EQ(dec.knobs.target_ray_spacing_m.size(), 2u);
    const double near = dec.knobs.target_ray_spacing_m[0], far = dec.knobs.target_ray_spacing_m[1];
    // Near: the frame's level. Far: level + min(rank 3, level).
    EXPECT_DOUBLE_EQ(near, base * std::pow(2.0, 0.5 * level)) << "level " << level;
    EXPECT_DOUBLE_EQ(far, base * std::pow(2.0, 0.5 * (level + std::min(3, level))))
        << "level " << level;
  }
}

TEST(Governor, MeasuredSlownessCoarsensAndSpeedRecoversSlowly) {
  DefaultFrame& f = default_frame();
  loop::GovernorConfig g = f.s.governor;
  g.mode = loop::GovernorConfig::Mode::kMeasured;
  g.max_level = loop::FidelityGovernor::kMaxLevel;
  g.trace_ms_per_frame = 0.0;  // the trace's model: its rays alone (model_trace_ms below)
  g.trace_ns_per_facet = 0.0;
  // Nothing is traced here: without static path reuse every level is one for all targets.
  radar::SbrConfig every_ray = f.s.sbr;
  every_ray.reuse_static_paths = false;
  const radar::SbrTracer tracer(f.scene, every_ray);
  loop::FidelityGovernor gov(g, f.scene, tracer, f.sensor, 1.0 / f.s.rate_hz);
  auto model_trace_ms = [&](std::size_t rays) {
    return g.trace_ns_per_ray * static_cast<double>(rays) * 1e-6;
  };
  constexpr std::uint64_t kCells = 300'000;
  const double sensor_ms = g.sensor_ns_per_cell * static_cast<double>(kCells) * 1e-6;
  // The first timed frame teaches nothing, however slow (it traces everything, cold): nor is it
  // the first of two slow frames, so a slow second one changes nothing either.
  const loop::GovernorDecision first = gov.decide(f.pose);
  gov.observe(10.0 * model_trace_ms(first.rays), 10.0 * sensor_ms, first.rays, 0, kCells);
  EXPECT_EQ(gov.trace_factor(), 1.0);
  EXPECT_EQ(gov.sensor_factor(), 1.0);
  (void)gov.decide(f.pose);
  gov.observe(3.0 * model_trace_ms(first.rays), 3.0 * sensor_ms, first.rays, 0, kCells);
  EXPECT_EQ(gov.trace_factor(), 1.0);
  EXPECT_EQ(gov.sensor_factor(), 1.0);
  // A frame exactly as fast as the model: the factors stay at 1.
  const loop::GovernorDecision steady = gov.decide(f.pose);
  gov.observe(model_trace_ms(steady.rays), sensor_ms, steady.rays, 0, kCells);
  EXPECT_EQ(gov.trace_factor(), 1.0);
  EXPECT_NEAR(gov.sensor_factor(), 1.0, 1e-9);
  // One frame that took three times the model's trace time: alone, it changes nothing.
  (void)gov.decide(f.pose);
  gov.observe(3.0 * model_trace_ms(steady.rays), sensor_ms, steady.rays, 0, kCells);
  EXPECT_EQ(gov.trace_factor(), 1.0);
  EXPECT_EQ(gov.decide(f.pose).level, steady.level);
  // The next one twice the model's: two slow frames in a row, the factor rises to the smaller
  // of their ratios.
  gov.observe(2.0 * model_trace_ms(steady.rays), sensor_ms, steady.rays, 0, kCells);
  EXPECT_NEAR(gov.trace_factor(), 2.0, 1e-9);
  // Two at three times: to 3 at once, and the next frame is coarser.
  (void)gov.decide_at(f.pose, steady.level);
  gov.observe(3.0 * model_trace_ms(steady.rays), sensor_ms, steady.rays, 0, kCells);
  EXPECT_NEAR(gov.trace_factor(), 2.0, 1e-9);  // min(3, 2): not above the factor
  (void)gov.decide_at(f.pose, steady.level);
  gov.observe(3.0 * model_trace_ms(steady.rays), sensor_ms, steady.rays, 0, kCells);
  EXPECT_NEAR(gov.trace_factor(), 3.0, 1e-9);
  const loop::GovernorDecision slow = gov.decide(f.pose);
  EXPECT_GT(slow.level, steady.level);
  EXPECT_LE(slow.predicted_ms, slow.deadline_ms);
  // A frame as fast as the model: the factor comes down by a tenth of the gap a frame.
  gov.observe(model_trace_ms(slow.rays), sensor_ms, slow.rays, 0, kCells);
  EXPECT_NEAR(gov.trace_factor(), 3.0 - 0.1 * (3.0 - 1.0), 1e-9);
  // Model mode never learns.
  g.mode = loop::GovernorConfig::Mode::kModel;
  loop::FidelityGovernor fixed(g, f.scene, f.tracer, f.sensor, 1.0 / f.s.rate_hz);
  (void)fixed.decide(f.pose);
  fixed.observe(100.0, 100.0, 1000, 500, 1000);
  EXPECT_EQ(fixed.trace_factor(), 1.0);
}

TEST(Governor, ModelModeCountsTheTerrainEnginesPatchesAndReturns) {
  // [radar] terrain = "engine": the engine's time (terrain_ns_per_patch x its patches) and its
  // returns (sensor_ns_per_terrain_return each, not scaled with the rays) join the prediction at
  // every level, by the closed form of the cost model (loop/governor.hpp): the patches as observed
  // at the level they were made at, times (that level's patch scale / the predicted level's)^2.
  DefaultFrame& f = default_frame();
  loop::GovernorConfig g = f.s.governor;
  g.mode = loop::GovernorConfig::Mode::kModel;
  g.terrain_ns_per_patch = 110.0;  // non-zero terms, whatever the defaults' fit
  g.sensor_ns_per_terrain_return = 120.0;
  loop::FidelityGovernor gov(g, f.scene, f.tracer, f.sensor, 1.0 / f.s.rate_hz);
  constexpr std::uint64_t kCells = 300'000, kRays = 100'000, kReturns = 20'000;
  (void)gov.decide_at(f.pose, 0);
  gov.observe(10.0, 5.0, kRays, kReturns, kCells);
  const loop::GovernorDecision rays_only = gov.decide_at(f.pose, 0);
  constexpr std::uint64_t kPatches = 150'000, kEngineReturns = 30'000;
  gov.observe(10.0, 5.0, kRays, kReturns + kEngineReturns, kCells, kPatches, kEngineReturns);
  const loop::GovernorDecision with_engine = gov.decide_at(f.pose, 0);
  const double expected_extra_ms =
      1e-6 * (g.terrain_ns_per_patch * static_cast<double>(kPatches) +
              g.sensor_ns_per_terrain_return * static_cast<double>(kEngineReturns));
  std::cout << "level 0: " << rays_only.predicted_ms << " ms with rays only, "
            << with_engine.predicted_ms << " ms with the engine's " << kPatches << " patches\n";
  EXPECT_NEAR(with_engine.predicted_ms - rays_only.predicted_ms, expected_extra_ms, 1e-9);
  // Patches counted at level 0 predict level 6 at 1 / (2^(6/4))^2 = 1/8 of them (the engine's
  // patches grow with the level as the terrain rays' spacing); the returns at half as many: at
  // scale 2^(6/4) = 2.83 the engine merges its cells two range bins a cell
  // (radar::TerrainReturns::cell_merge; the columns stay, set_terrain_cells not called).
  gov.observe(10.0, 5.0, kRays, kReturns, kCells);
  const loop::GovernorDecision coarse_rays = gov.decide_at(f.pose, 6);
  (void)gov.decide_at(f.pose, 0);
  gov.observe(10.0, 5.0, kRays, kReturns + kEngineReturns, kCells, kPatches, kEngineReturns);
  const loop::GovernorDecision coarse_engine = gov.decide_at(f.pose, 6);
  const double coarse_extra_ms =
      1e-6 * (g.terrain_ns_per_patch * static_cast<double>(kPatches) / 8.0 +
              g.sensor_ns_per_terrain_return * static_cast<double>(kEngineReturns) / 2.0);
  EXPECT_NEAR(coarse_engine.predicted_ms - coarse_rays.predicted_ms, coarse_extra_ms, 1e-9);
  // And patches counted at level 6 predict level 6 as they are, level 0 at 8 times as many (and
  // returns counted in cells merged two ways, twice as many).
  gov.observe(10.0, 5.0, kRays, kReturns + kEngineReturns, kCells, kPatches, kEngineReturns);
  const loop::GovernorDecision again_6 = gov.decide_at(f.pose, 6);
  EXPECT_NEAR(again_6.predicted_ms - coarse_rays.predicted_ms, expected_extra_ms, 1e-9);
  gov.observe(10.0, 5.0, kRays, kReturns + kEngineReturns, kCells, kPatches, kEngineReturns);
  const loop::GovernorDecision fine = gov.decide_at(f.pose, 0);
  EXPECT_NEAR(fine.predicted_ms - rays_only.predicted_ms,
              1e-6 * (g.terrain_ns_per_patch * static_cast<double>(kPatches) * 8.0 +
                      g.sensor_ns_per_terrain_return * static_cast<double>(kEngineReturns) * 2.0),
              1e-9);
}

TEST(Governor, ModelModeFollowsTheEnginesMergedCellsAndItsFacets) {
  // The closed forms of the engine's terms (loop/governor.hpp) at the levels of a heavy scene:
  // for an engine whose columns merge up to two ways (TerrainReturnsConfig::
  // coarse_azimuth_max_rad two columns wide; the loop's do not merge), level L merges k =
  // 2^floor(L/4) range bins (up to 16) and min(k, 2) columns a cell, so returns T counted at level
  // 0 predict level L at T / (k min(k, 2)); patches P counted at level 0 predict level L at P /
  // 2^(L/2), but never fewer than the F facets they were cut from (one patch a facet at least).
  DefaultFrame& f = default_frame();
  loop::GovernorConfig g = f.s.governor;
  g.mode = loop::GovernorConfig::Mode::kModel;
  g.terrain_ns_per_patch = 110.0;  // non-zero terms, whatever the defaults' fit
  g.sensor_ns_per_terrain_return = 120.0;
  loop::FidelityGovernor gov(g, f.scene, f.tracer, f.sensor, 1.0 / f.s.rate_hz);
  radar::TerrainCoarsening tc;
  tc.azimuth_merge_max = 2;
  gov.set_terrain_cells(tc);
  EXPECT_EQ(gov.terrain_cells_merged(0), 1u);
  EXPECT_EQ(gov.terrain_cells_merged(3), 1u);
  EXPECT_EQ(gov.terrain_cells_merged(4), 4u);    // 2 x 2
  EXPECT_EQ(gov.terrain_cells_merged(8), 8u);    // 4 x 2
  EXPECT_EQ(gov.terrain_cells_merged(12), 16u);  // 8 x 2
  EXPECT_EQ(gov.terrain_cells_merged(16), 32u);  // 16 x 2
  constexpr std::uint64_t kCells = 300'000, kRays = 100'000, kReturns = 20'000;
  constexpr std::uint64_t kPatches = 160'000, kFacets = 40'000, kEngineReturns = 32'000;
  // The engine's share of the prediction at `level` [ms]: the prediction after a frame at
  // `counted_at` with the engine's `patches`, kEngineReturns and `facets` counted, less the same
  // after a frame of rays alone.
  auto engine_share_ms = [&](int counted_at, int level, std::uint64_t patches,
                             std::uint64_t facets) {
    (void)gov.decide_at(f.pose, counted_at);
    gov.observe(10.0, 5.0, kRays, kReturns, kCells);
    const double rays_ms = gov.decide_at(f.pose, level).predicted_ms;
    (void)gov.decide_at(f.pose, counted_at);
    gov.observe(10.0, 5.0, kRays, kReturns + kEngineReturns, kCells, patches, kEngineReturns,
                facets);
    return gov.decide_at(f.pose, level).predicted_ms - rays_ms;
  };
  for (const int level : {0, 4, 8, 12, 16}) {
    const double k = std::pow(2.0, std::floor(level / 4.0));
    const double merged = k * std::min(k, 2.0);
    const double s2 = std::pow(2.0, 0.5 * level);  // (patch scale)^2
    // The engine's figures counted at level 0.
    const double engine_ms = engine_share_ms(0, level, kPatches, kFacets);
    const double patches = std::max(static_cast<double>(kFacets), kPatches / s2);
    const double expected_ms =
        1e-6 * (g.terrain_ns_per_patch * patches +
                g.sensor_ns_per_terrain_return * static_cast<double>(kEngineReturns) / merged);
    std::cout << "level " << level << ": engine " << patches << " patches, "
              << kEngineReturns / merged << " returns, " << engine_ms << " ms\n";
    EXPECT_NEAR(engine_ms, expected_ms, 1e-9) << "level " << level;
  }
  // Counted at level 12 (16 cells merged): level 4 (4 merged) predicts 4 times the returns.
  EXPECT_NEAR(engine_share_ms(12, 4, kFacets, kFacets),
              1e-6 * (g.terrain_ns_per_patch * static_cast<double>(kFacets) * 16.0 +
                      g.sensor_ns_per_terrain_return * static_cast<double>(kEngineReturns) * 4.0),
              1e-9);
  // A coarse level of detail with a quarter of the facets from the range merge 8 on (level 12,
  // radar::TerrainReturnsConfig::coarse_lod_merge): facets F counted at level 0 predict F / 4
  // from level 12 on, and F counted at level 12 predict 4 F below it.
  tc.lod_merge = 8;
  tc.lod_facet_ratio = 0.25;
  gov.set_terrain_cells(tc);
  EXPECT_EQ(gov.terrain_facet_ratio(11), 1.0);
  EXPECT_EQ(gov.terrain_facet_ratio(12), 0.25);
  for (const int level : {8, 12, 16}) {
    const double k = std::pow(2.0, std::floor(level / 4.0));
    const double s2 = std::pow(2.0, 0.5 * level);
    const double facets = static_cast<double>(kFacets) * (level >= 12 ? 0.25 : 1.0);
    EXPECT_NEAR(engine_share_ms(0, level, kPatches, kFacets),
                1e-6 * (g.terrain_ns_per_patch * std::max(facets, kPatches / s2) +
                        g.sensor_ns_per_terrain_return * static_cast<double>(kEngineReturns) /
                            (k * std::min(k, 2.0))),
                1e-9)
        << "level " << level;
  }
  constexpr std::uint64_t kCoarseFacets = kFacets / 4;
  // Level 8 from level 12: patch scale 4 against 8 (4 times the patches), 4 times the facets;
  // cells merged 8 against 16.
  EXPECT_NEAR(engine_share_ms(12, 8, kCoarseFacets, kCoarseFacets),
              1e-6 * (g.terrain_ns_per_patch * static_cast<double>(kCoarseFacets) * 4.0 +
                      g.sensor_ns_per_terrain_return * static_cast<double>(kEngineReturns) * 2.0),
              1e-9);
}

TEST(Governor, InvalidSettingsFailAtSetupNamingTheField) {
  DefaultFrame& f = default_frame();
  loop::GovernorConfig g;
  g.compute_fraction = 0.0;
  try {
    loop::FidelityGovernor gov(g, f.scene, f.tracer, f.sensor, 0.05);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("compute_fraction"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loop::parse_scenario("[governor]\nmode = \"fast\"\n", "t.toml"), std::runtime_error);
  EXPECT_THROW(loop::parse_scenario("[governor]\nmax_level = 40\n", "t.toml"), std::runtime_error);
  EXPECT_THROW(loop::parse_scenario("[governor]\nrays = 4\n", "t.toml"), std::runtime_error);
}

TEST(Governor, DegradedFramesAreFlaggedInTheIcdHeaderAndReported) {
  loop::Scenario s = default_scenario();
  s.frames = 6;
  s.governor.compute_fraction = 0.05;  // 2.5 ms: the default needs coarser levels
  loop::ClosedLoop loop(s, {});
  const loop::RunResult r = loop.run();
  ASSERT_EQ(r.records.size(), 6u);
  std::uint64_t degraded = 0;
  for (const loop::FrameRecord& rec : r.records) {
    EXPECT_TRUE(rec.ownship_valid);
    EXPECT_GT(rec.governor_level, 0);
    EXPECT_NE(rec.header.status & radar_emu::io::icd::status::kDegraded, 0) << rec.frame_index;
    degraded += rec.governor_level > 0 ? 1 : 0;
  }
  EXPECT_EQ(r.governor.frames_degraded, degraded);
  // The same scenario with a deadline it meets at level 0: no flag.
  s.rate_hz = 0.05;
  s.governor.compute_fraction = 1.0;
  loop::ClosedLoop easy(s, {});
  const loop::RunResult e = easy.run();
  for (const loop::FrameRecord& rec : e.records) {
    EXPECT_EQ(rec.governor_level, 0);
    EXPECT_EQ(rec.header.status & radar_emu::io::icd::status::kDegraded, 0);
  }
  EXPECT_EQ(e.governor.frames_degraded, 0u);
}

TEST(Governor, TheFirstFrameIsPredictedFromTheFramePrimedAtSetup) {
  // With static path reuse the loop traces frame 0's pose at setup and puts that frame through
  // the terrain engine and the sensor once, for the governor's first prediction. Frame 0 is then
  // predicted like frame 1 (the same paths re-evaluated a few metres on), not from the start
  // figures of the whole image synthesised and half a return a ray (18 % more on this frame).
  loop::Scenario s = default_scenario();
  s.frames = 3;
  s.governor.compute_fraction = 1.0;  // 50 ms: every frame at level 0
  ASSERT_TRUE(s.sbr.reuse_static_paths);
  loop::ClosedLoop loop(s, {});
  const loop::RunResult r = loop.run();
  ASSERT_EQ(r.records.size(), 3u);
  for (const loop::FrameRecord& rec : r.records)
    ASSERT_EQ(rec.governor_level, 0) << rec.frame_index;
  const double first = r.records[0].governor_predicted_ms,
               second = r.records[1].governor_predicted_ms;
  std::cout << "predicted: frame 0 " << first << " ms, frame 1 " << second << " ms\n";
  EXPECT_NEAR(first, second, 0.1 * second);
}

TEST(Governor, AfterADegradedFrameKeptTargetsComeBackToTheFinestLevelInSteps) {
  // Static path reuse keeps a target's paths at the spacing they were traced with, so a finer
  // level first costs that target's rays again. A frame forced to level 3 keeps every static
  // target at level 3's spacing; a deadline that holds the default frame at level 0 with its
  // paths kept but not a whole frame's rays at level 0 is then met by coming back in steps:
  // each frame keeps the lagging targets' paths, traces the strongest of them at the finer
  // spacing while the rays fit, and reports its coarsest target's level, which falls to 0.
  DefaultFrame& f = default_frame();
  ASSERT_TRUE(f.s.sbr.reuse_static_paths);
  radar::SbrTracer tracer(f.scene, f.s.sbr);
  loop::GovernorConfig g = f.s.governor;
  g.mode = loop::GovernorConfig::Mode::kModel;
  const double period_s = 1.0 / f.s.rate_hz;
  // The deadline between the two: level 0 with every static path kept, and level 0 traced.
  loop::FidelityGovernor probe(g, f.scene, tracer, f.sensor, period_s);
  std::vector<radar::Contribution> out(tracer.max_contributions());
  radar::TraceStats ts;
  auto trace = [&](const loop::GovernorDecision& d) {
    (void)tracer.trace(f.pose, out, ts, d.knobs);
  };
  const double traced_ms = probe.decide_at(f.pose, 0).predicted_ms;
  trace(probe.decide_at(f.pose, 0));
  const double kept_ms = probe.decide_at(f.pose, 0).predicted_ms;
  ASSERT_LT(kept_ms, 0.8 * traced_ms);
  const double deadline_ms = 0.5 * (kept_ms + traced_ms);
  g.compute_fraction = deadline_ms * 1e-3 / period_s;
  loop::FidelityGovernor gov(g, f.scene, tracer, f.sensor, period_s);
  trace(gov.decide_at(f.pose, 3));  // the degraded frame: every static target at level 3
  std::vector<int> levels;
  for (int frame = 0; frame < 12 && (levels.empty() || levels.back() > 0); ++frame) {
    const loop::GovernorDecision& d = gov.decide(f.pose);
    EXPECT_LE(d.predicted_ms, deadline_ms) << frame;
    levels.push_back(d.level);
    trace(d);
  }
  std::cout << "deadline " << deadline_ms << " ms (level 0 kept " << kept_ms << ", traced "
            << traced_ms << "); levels after the degraded frame:";
  for (int l : levels)
    std::cout << " " << l;
  std::cout << "\n";
  ASSERT_FALSE(levels.empty());
  EXPECT_EQ(levels.back(), 0);
  EXPECT_GE(levels.size(), 2u);  // not all at once: a whole frame's rays do not fit
  for (std::size_t i = 1; i < levels.size(); ++i)
    EXPECT_LE(levels[i], levels[i - 1]) << i;
}
