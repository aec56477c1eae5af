// Waypoint trajectories against closed forms: straight legs, circular turns (centre, radius,
// tangent heading), arc length at constant speed, joints, loops, turn rate, bank, climb, errors.

#include "scene/trajectory.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace sc = radar_emu::scene;

namespace {

constexpr double kPi = std::numbers::pi;

std::string error_of(const sc::Trajectory& t) {
  try {
    (void)sc::TrajectoryPath(t);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

double heading(const glm::dvec3& v) {
  return std::atan2(v.y, v.x);
}

}  // namespace

TEST(SceneTrajectory, StraightLegAtConstantSpeedThenRest) {
  sc::Trajectory t;
  t.waypoints_m = {{10.0, 20.0, 1.0}, {10.0 + 300.0, 20.0 + 400.0, 1.0}};  // 500 m
  t.speed_mps = 12.5;
  const sc::TrajectoryPath p(t);
  EXPECT_DOUBLE_EQ(p.length_m(), 500.0);
  EXPECT_DOUBLE_EQ(p.duration_s(), 40.0);
  const glm::dvec3 dir(0.6, 0.8, 0.0);
  for (double ts : {0.0, 3.7, 20.0, 39.99}) {
    const sc::TrajectorySample s = p.at(ts);
    EXPECT_LT(glm::length(s.position_m - (t.waypoints_m[0] + 12.5 * ts * dir)), 1e-9) << ts;
    EXPECT_LT(glm::length(s.velocity_mps - 12.5 * dir), 1e-12) << ts;
    // Body x along the velocity, y to its left (horizontal), z up.
    EXPECT_LT(glm::length(s.world_from_body[0] - dir), 1e-12);
    EXPECT_LT(glm::length(s.world_from_body[1] - glm::dvec3(-0.8, 0.6, 0.0)), 1e-12);
    EXPECT_LT(glm::length(s.world_from_body[2] - glm::dvec3(0.0, 0.0, 1.0)), 1e-12);
    EXPECT_FALSE(s.on_arc);
  }
  // Open path: at rest at its ends outside [0, duration].
  EXPECT_EQ(p.at(-5.0).position_m, t.waypoints_m[0]);
  EXPECT_EQ(p.at(-5.0).velocity_mps, glm::dvec3(0.0));
  EXPECT_LT(glm::length(p.at(41.0).position_m - t.waypoints_m[1]), 1e-9);
  EXPECT_EQ(p.at(41.0).velocity_mps, glm::dvec3(0.0));
  EXPECT_LT(glm::length(p.at(41.0).world_from_body[0] - dir), 1e-12);  // heading kept
}

TEST(SceneTrajectory, RightAngleTurnIsAQuarterCircleOfTheRadius) {
  // East 100 m, then north 100 m; r = 20 m: tangent length r tan(45 deg) = 20 m, so the legs
  // are 80 m, the arc r pi / 2, the centre (80, 20).
  sc::Trajectory t;
  t.waypoints_m = {{0.0, 0.0, 0.0}, {100.0, 0.0, 0.0}, {100.0, 100.0, 0.0}};
  t.speed_mps = 5.0;
  t.turn_radius_m = 20.0;
  const sc::TrajectoryPath p(t);
  const double arc = 20.0 * kPi / 2.0;
  EXPECT_NEAR(p.length_m(), 160.0 + arc, 1e-12);
  ASSERT_EQ(p.segments().size(), 3u);
  EXPECT_TRUE(p.segments()[1].arc);
  EXPECT_NEAR(p.segments()[1].length_m, arc, 1e-12);
  const glm::dvec3 centre(80.0, 20.0, 0.0);
  EXPECT_LT(glm::length(p.segments()[1].centre_m - centre), 1e-12);
  // Time per piece = length / speed.
  const double t_arc0 = 80.0 / 5.0, t_arc1 = (80.0 + arc) / 5.0;
  EXPECT_LT(glm::length(p.at(t_arc0).position_m - glm::dvec3(80, 0, 0)), 1e-9);
  EXPECT_LT(glm::length(p.at(t_arc1).position_m - glm::dvec3(100, 20, 0)), 1e-9);
  for (int i = 1; i < 20; ++i) {
    const double ts = t_arc0 + (t_arc1 - t_arc0) * i / 20.0;
    const sc::TrajectorySample s = p.at(ts);
    ASSERT_TRUE(s.on_arc) << ts;
    // On the circle, at the angle swept at constant speed: phi = v (t - t0) / r from (80, 0).
    EXPECT_NEAR(glm::length(s.position_m - centre), 20.0, 1e-9) << ts;
    const double phi = 5.0 * (ts - t_arc0) / 20.0;
    EXPECT_LT(glm::length(s.position_m -
                          (centre + 20.0 * glm::dvec3(std::sin(phi), -std::cos(phi), 0.0))),
              1e-9);
    // Heading tangent to the circle, speed unchanged.
    EXPECT_NEAR(glm::dot(s.velocity_mps, s.position_m - centre), 0.0, 1e-9) << ts;
    EXPECT_NEAR(glm::length(s.velocity_mps), 5.0, 1e-12);
    EXPECT_NEAR(heading(s.world_from_body[0]), phi, 1e-12);
  }
  // Second leg: due north from (100, 20).
  const sc::TrajectorySample s = p.at(t_arc1 + 6.0);
  EXPECT_LT(glm::length(s.position_m - glm::dvec3(100.0, 50.0, 0.0)), 1e-9);
  EXPECT_LT(glm::length(s.velocity_mps - glm::dvec3(0.0, 5.0, 0.0)), 1e-12);
}

TEST(SceneTrajectory, RandomPolylinesAreContinuousWithTheClosedFormLength) {
  const std::uint32_t seed = 77;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int paths = 0;
  for (int trial = 0; trial < 200; ++trial) {
    sc::Trajectory t;
    glm::dvec3 p(0.0);
    const int n = 3 + static_cast<int>(rng() % 5);
    for (int i = 0; i < n; ++i) {
      t.waypoints_m.push_back(p);
      p += glm::dvec3{300.0 * u(rng), 300.0 * u(rng), 10.0 * u(rng)};
    }
    t.speed_mps = 5.0 + 20.0 * (u(rng) + 1.0);
    t.turn_radius_m = 5.0 + 10.0 * (u(rng) + 1.0);
    t.loop = rng() % 2 == 0;
    std::unique_ptr<sc::TrajectoryPath> path;
    try {
      path = std::make_unique<sc::TrajectoryPath>(t);
    } catch (const std::invalid_argument&) {
      continue;  // a radius too large for a short leg, or a reversal: rejected, fine
    }
    ++paths;
    // Closed-form length: legs minus both tangent lengths of each turn plus the arcs r theta.
    const std::size_t m = t.waypoints_m.size(), legs = t.loop ? m : m - 1;
    double expected = 0.0;
    for (std::size_t i = 0; i < legs; ++i)
      expected += glm::length(t.waypoints_m[(i + 1) % m] - t.waypoints_m[i]);
    for (std::size_t j = 0; j < m; ++j) {
      if (!t.loop && (j == 0 || j == m - 1))
        continue;
      const glm::dvec3 a = glm::normalize(t.waypoints_m[j] - t.waypoints_m[(j + m - 1) % m]);
      const glm::dvec3 b = glm::normalize(t.waypoints_m[(j + 1) % m] - t.waypoints_m[j]);
      const double theta = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
      expected += t.turn_radius_m * (theta - 2.0 * std::tan(theta / 2.0));
    }
    EXPECT_NEAR(path->length_m(), expected, 1e-9 * expected) << trial;
    // Arc length at constant speed: the path parameter is v t (within the lap).
    const double tm = 0.37 * path->duration_s();
    EXPECT_NEAR(path->at(tm).path_m, t.speed_mps * tm, 1e-9 * path->length_m());
    // Joints: position and heading continuous (C1) across every piece boundary.
    const double eps_s = 1e-6;
    for (const sc::TrajectorySegment& g : path->segments()) {
      if (g.start_m == 0.0)
        continue;
      const double tj = g.start_m / t.speed_mps;
      const sc::TrajectorySample before = path->at(tj - eps_s), after = path->at(tj + eps_s);
      EXPECT_LT(glm::length(after.position_m - before.position_m), 2.0 * eps_s * t.speed_mps * 1.01)
          << trial;
      // The heading turns at most v / r rad/s on arcs.
      EXPECT_LT(glm::length(after.world_from_body[0] - before.world_from_body[0]),
                2.0 * eps_s * t.speed_mps / t.turn_radius_m * 1.01 + 1e-9)
          << trial;
      EXPECT_LT(glm::length(path->at(tj).position_m - g.start_position_m), 1e-6) << trial;
    }
    if (t.loop) {
      // A lap later (and a lap earlier) it is back where it was.
      const double d = path->duration_s();
      EXPECT_LT(glm::length(path->at(tm + d).position_m - path->at(tm).position_m), 1e-6);
      EXPECT_LT(glm::length(path->at(tm - d).position_m - path->at(tm).position_m), 1e-6);
    }
  }
  EXPECT_GT(paths, 100);
}

TEST(SceneTrajectory, LoopStartsAfterTheTurnAtTheFirstWaypoint) {
  // A 100 m square with r = 10 m: four legs of 80 m and four quarter circles.
  sc::Trajectory t;
  t.waypoints_m = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}, {0, 100, 0}};
  t.speed_mps = 10.0;
  t.turn_radius_m = 10.0;
  t.loop = true;
  const sc::TrajectoryPath p(t);
  EXPECT_NEAR(p.length_m(), 320.0 + 2.0 * kPi * 10.0, 1e-12);
  EXPECT_LT(glm::length(p.at(0.0).position_m - glm::dvec3(10, 0, 0)), 1e-12);
  EXPECT_LT(glm::length(p.at(p.duration_s()).position_m - glm::dvec3(10, 0, 0)), 1e-9);
  // Half a turn's time before t = 0, it is on the arc around (10, 10) at 45 degrees.
  const sc::TrajectorySample s = p.at(-(10.0 * kPi / 4.0) / 10.0);
  EXPECT_TRUE(s.on_arc);
  const double h = 10.0 / std::sqrt(2.0);
  EXPECT_LT(glm::length(s.position_m - glm::dvec3(10.0 - h, 10.0 - h, 0.0)), 1e-9);
  EXPECT_NEAR(heading(s.velocity_mps), -kPi / 4.0, 1e-12);
}

TEST(SceneTrajectory, TurnRateSetsTheRadiusAndTheYawRate) {
  sc::Trajectory t;
  t.waypoints_m = {{0, 0, 0}, {500, 0, 0}, {500, 500, 0}};
  t.speed_mps = 20.0;
  t.turn_rate_rad_s = 0.1;  // r = v / omega = 200 m
  const sc::TrajectoryPath p(t);
  EXPECT_DOUBLE_EQ(p.turn_radius_m(), 200.0);
  const double t0 = 300.0 / 20.0;  // arc starts 500 - 200 m along the first leg
  const double dt = 1.5;
  const double yaw =
      heading(p.at(t0 + 2.0 + dt).world_from_body[0]) - heading(p.at(t0 + 2.0).world_from_body[0]);
  EXPECT_NEAR(yaw, 0.1 * dt, 1e-12);
}

TEST(SceneTrajectory, BankedTurnTiltsBodyUpTowardTheCentre) {
  // Left turn (east then north), v = 60 m/s, r = 500 m: tan(bank) = v^2 / (g r).
  sc::Trajectory t;
  t.waypoints_m = {{0, 0, 300}, {2000, 0, 300}, {2000, 2000, 300}};
  t.speed_mps = 60.0;
  t.turn_radius_m = 500.0;
  t.bank = true;
  const sc::TrajectoryPath p(t);
  const double bank = std::atan(60.0 * 60.0 / (9.80665 * 500.0));
  const sc::TrajectorySample s = p.at((1500.0 + 500.0 * kPi / 4.0) / 60.0);  // mid-turn
  ASSERT_TRUE(s.on_arc);
  const glm::dvec3 z = s.world_from_body[2];
  EXPECT_NEAR(std::acos(z.z), bank, 1e-12);
  const glm::dvec3 to_centre = glm::normalize(p.segments()[1].centre_m - s.position_m);
  EXPECT_NEAR(glm::dot(glm::normalize(glm::dvec3(z.x, z.y, 0.0)), to_centre), 1.0, 1e-12);
  // Still a rotation, x along the velocity.
  EXPECT_NEAR(glm::determinant(s.world_from_body), 1.0, 1e-12);
  EXPECT_NEAR(glm::dot(s.world_from_body[0], glm::normalize(s.velocity_mps)), 1.0, 1e-12);
  // Wings level on the legs.
  EXPECT_NEAR(p.at(10.0).world_from_body[2].z, 1.0, 1e-12);
}

TEST(SceneTrajectory, ClimbingLegPitchesTheBody) {
  sc::Trajectory t;
  t.waypoints_m = {{0, 0, 0}, {0, 400, 30}};
  t.speed_mps = 10.0;
  const sc::TrajectoryPath p(t);
  const sc::TrajectorySample s = p.at(5.0);
  EXPECT_NEAR(std::asin(s.world_from_body[0].z), std::atan2(30.0, 400.0), 1e-12);
  EXPECT_NEAR(s.world_from_body[1].z, 0.0, 1e-12);  // y stays horizontal
  EXPECT_NEAR(glm::length(s.velocity_mps), 10.0, 1e-12);
}

TEST(SceneTrajectory, BadTrajectoriesAreRejectedWithTheReason) {
  sc::Trajectory t;
  t.waypoints_m = {{0, 0, 0}};
  t.speed_mps = 1.0;
  EXPECT_EQ(error_of(t), "trajectory: needs at least 2 waypoints, got 1");
  t.waypoints_m = {{0, 0, 0}, {10, 0, 0}};
  t.speed_mps = 0.0;
  EXPECT_EQ(error_of(t), "trajectory: speed_mps must be a finite number > 0");
  t.speed_mps = 1.0;
  t.waypoints_m = {{0, 0, 0}, {10, 0, 0}, {10, 0, 0}};
  EXPECT_EQ(error_of(t), "trajectory: waypoints 1 and 2 coincide");
  t.waypoints_m = {{0, 0, 0}, {0, 0, 10}};
  EXPECT_EQ(error_of(t), "trajectory: leg 0 is vertical (no heading)");
  t.waypoints_m = {{0, 0, 0}, {10, 0, 0}, {0, 0, 0.0}, {0, 5, 0}};
  t.turn_radius_m = 1.0;
  EXPECT_NE(error_of(t).find("reverses at waypoint 1"), std::string::npos) << error_of(t);
  t.waypoints_m = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}};
  t.turn_radius_m = 11.0;  // tangent length 11 m > the 10 m legs
  EXPECT_NE(error_of(t).find("leg 0 (10.000000 m) is shorter than the tangent lengths"),
            std::string::npos)
      << error_of(t);
  t.turn_radius_m = 1.0;
  t.turn_rate_rad_s = 0.5;
  EXPECT_EQ(error_of(t), "trajectory: give turn_radius_m or turn_rate_rad_s, not both");
  t.turn_rate_rad_s = 0.0;
  t.waypoints_m[1].x = std::nan("");
  EXPECT_EQ(error_of(t), "trajectory: waypoint 1 is not finite");
}
