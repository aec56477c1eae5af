// [[target]] tables through the whole loop: targets a scenario adds to a built-in scene are
// traced, detected at the range this test computes on its own (the scripted ownship's straight
// line, the sphere's centre minus its radius: the specular point of a sphere is its nearest
// point), and reported under their names in detections.json and truth.json.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "common/units.hpp"
#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "tests/alloc_counter.hpp"

namespace loop = radar_emu::loop;
namespace fs = std::filesystem;

namespace {

constexpr double kC_mps = 299792458.0;
namespace common = radar_emu::common;

// Two metal spheres of 1.5 m radius (finely faceted, 5 cm facets, so that a facet faces the
// radar from any direction) on the default scene's flat grass (z = 0), about 2.5 km ahead of the
// default approach's start, inside the beam (2 deg below boresight): one on a straight line, one
// on waypoints, both driving south toward the radar (5 and 6 m/s), so that their Doppler is clear
// of the ground's (a 7 m^2 sphere standing still at 94 GHz has its range-Doppler cell's grass
// clutter to beat; these have about 30 dB of SNR).
constexpr const char* kScenario = R"(
name = "targets from the scenario"
[run]
frames = 10
[scene]
builtin = "default"
# At the scenario's own ray density (the governor would coarsen the spheres' bundles to hold
# the frame budget; its own tests are in governor_test.cpp).
[governor]
enabled = false

[[target]]
name = "ball_straight"
builtin = "sphere"
size_m = 1.5
facet_m = 0.05
position_enu_m = [30.0, -1500.0, 0.0]
on_ground = true
speed_mps = 5.0
heading_deg = 180.0

[[target]]
name = "ball_waypoints"
builtin = "sphere"
size_m = 1.5
facet_m = 0.05
waypoints_enu_m = [[-60.0, -1400.0, 0.0], [-60.0, -1500.0, 0.0], [-100.0, -1600.0, 0.0]]
speed_mps = 6.0
on_ground = true
)";

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace

TEST(TargetsInTheLoop, SpheresFromTheScenarioAreDetectedWhereTheyAreUnderTheirNames) {
  const loop::Scenario s = loop::parse_scenario(kScenario, "targets.toml");
  ASSERT_EQ(s.targets.size(), 2u);
  const fs::path out =
      fs::temp_directory_path() / ("radar_emu_targets_" + std::to_string(::getpid()));
  {
    // Targets move by transforms only: the frame path still allocates nothing (from frame 3).
    loop::RunOptions options;
    options.out_dir = out;
    options.progress = [](std::uint64_t done, std::uint64_t total) {
      if (done == 3)
        radar_emu::test::start_counting_allocations();
      if (done == total)
        (void)radar_emu::test::stop_counting_allocations();
    };
    loop::ClosedLoop loop(s, options);
    const loop::RunResult r = loop.run();
    EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u) << "the frame path allocated";
    loop.write_outputs(r);
  }
  const nlohmann::json dets = read_json(out / "detections.json");
  const nlohmann::json truth = read_json(out / "truth.json");
  fs::remove_all(out);

  // Both are targets (metal): truth.json lists them by name.
  std::size_t listed = 0;
  for (const auto& o : truth.at("objects"))
    listed += o.at("object") == "ball_straight" || o.at("object") == "ball_waypoints" ? 1u : 0u;
  EXPECT_EQ(listed, 2u);

  const auto& w = s.sensor.processing.waveform;
  const double range_cell_m = kC_mps / (2.0 * w.bandwidth_hz);
  // Unambiguous radial velocity lambda PRF / 4 and the Doppler cell 2 v_ua / pulses: measured
  // radial velocities are folded into [-v_ua, v_ua).
  const double v_ua_mps = kC_mps / w.carrier_hz * s.prf_hz / 4.0;
  const double doppler_cell_mps = 2.0 * v_ua_mps / w.pulses;
  const auto fold = [&](double v) {
    return v - 2.0 * v_ua_mps * std::floor((v + v_ua_mps) / (2.0 * v_ua_mps));
  };
  const double radius_m = 1.5;
  // Wings level, heading north: boresight north, elevated by pitch - depression.
  const double el0 = s.ownship_pitch_rad - s.antenna_depression_rad;
  const glm::dvec3 boresight(0.0, std::cos(el0), std::sin(el0));
  const glm::dvec3 right(1.0, 0.0, 0.0);
  struct Ball {
    const char* name;
    glm::dvec3 centre_m;  // at t = 0: on the grass (z = 0), centre one radius up
    glm::dvec3 velocity_mps;
    int detected = 0, in_truth = 0;
  };
  // Over the run's 0.5 s both are on their first leg, due south.
  Ball balls[] = {{"ball_straight", {30.0, -1500.0, radius_m}, {0.0, -5.0, 0.0}},
                  {"ball_waypoints", {-60.0, -1400.0, radius_m}, {0.0, -6.0, 0.0}}};
  const auto& frames = dets.at("frames");
  ASSERT_EQ(frames.size(), s.frames);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const double t = frames[k].at("time_s").get<double>();
    const glm::dvec3 radar = s.ownship_start_enu_m + s.ownship_velocity_enu_mps * t;
    for (Ball& b : balls) {
      const glm::dvec3 c = b.centre_m + b.velocity_mps * t;
      const glm::dvec3 u = glm::normalize(c - radar);
      const double range_m = glm::length(c - radar) - radius_m;  // the specular point
      const double az = std::atan2(glm::dot(u, right), glm::dot(u, boresight));
      const double vr = glm::dot(b.velocity_mps - s.ownship_velocity_enu_mps, u);  // + receding
      bool found = false;
      for (const auto& d : frames[k].at("detections")) {
        if (d.at("object") != b.name)
          continue;
        EXPECT_NEAR(d.at("range_m").get<double>(), range_m, range_cell_m) << b.name << " t " << t;
        EXPECT_NEAR(common::radians(d.at("azimuth_deg").get<double>()), az, s.beam_spacing_rad)
            << b.name;
        EXPECT_NEAR(d.at("radial_velocity_mps").get<double>(), fold(vr), doppler_cell_mps)
            << b.name;
        found = true;
      }
      b.detected += found ? 1 : 0;
      for (const auto& o : truth.at("frames")[k].at("objects"))
        b.in_truth += o.at("object") == b.name ? 1 : 0;
    }
  }
  for (const Ball& b : balls) {
    std::printf("%s: detected in %d of %zu frames, in truth.json in %d\n", b.name, b.detected,
                frames.size(), b.in_truth);
    // About 30 dB of SNR: every frame, allowing one for receiver noise.
    EXPECT_GE(b.detected, static_cast<int>(frames.size()) - 1) << b.name;
    EXPECT_EQ(b.in_truth, static_cast<int>(frames.size())) << b.name;
  }
}
