// Ray queries against closed forms, the double-precision refit, moving objects, validation.

#include "scene/scene.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>
#include <numbers>
#include <random>
#include <stdexcept>
#include <thread>

#include "common/units.hpp"
#include "scene/default_scene.hpp"

namespace sc = radar_emu::scene;

namespace {

namespace common = radar_emu::common;

// Axis-aligned box [lo, hi] in the body frame, 12 triangles wound counter-clockwise seen from
// outside. Triangles 2k and 2k+1 are face k: -z, +z, -y, +y, -x, +x.
void add_box(sc::Mesh& m, glm::vec3 lo, glm::vec3 hi, std::uint16_t material) {
  const auto b = static_cast<unsigned>(m.positions_m.size());
  m.positions_m.insert(m.positions_m.end(), {{lo.x, lo.y, lo.z},
                                             {hi.x, lo.y, lo.z},
                                             {hi.x, hi.y, lo.z},
                                             {lo.x, hi.y, lo.z},
                                             {lo.x, lo.y, hi.z},
                                             {hi.x, lo.y, hi.z},
                                             {hi.x, hi.y, hi.z},
                                             {lo.x, hi.y, hi.z}});
  const std::array<glm::uvec3, 12> t = {{{0, 2, 1},
                                         {0, 3, 2},
                                         {4, 5, 6},
                                         {4, 6, 7},
                                         {0, 1, 5},
                                         {0, 5, 4},
                                         {3, 7, 6},
                                         {3, 6, 2},
                                         {0, 4, 7},
                                         {0, 7, 3},
                                         {1, 2, 6},
                                         {1, 6, 5}}};
  for (const glm::uvec3& x : t) {
    m.triangles.push_back(x + glm::uvec3(b));
    m.triangle_material.push_back(material);
  }
}

sc::ObjectDesc ground_triangle() {
  sc::ObjectDesc ground{"ground", {}, glm::dmat4(1.0), std::nullopt};
  ground.mesh.positions_m = {{-1000, -1000, 0}, {1000, -1000, 0}, {0, 1000, 0}};
  ground.mesh.triangles = {{0, 1, 2}};
  ground.mesh.triangle_material = {0};
  return ground;
}

// Ground triangle (object 0, "grass") and a 2 m cube (object 1, "metal") whose body origin is
// its bottom centre, moving along +x at 10 m/s from the origin.
sc::SceneDescription triangle_and_moving_box() {
  sc::SceneDescription d;
  d.materials = {{"grass", {}}, {"metal", {}}};
  d.objects.push_back(ground_triangle());
  sc::ObjectDesc box{"box", {}, glm::dmat4(1.0), sc::LinearMotion{{0, 0, 0}, {10, 0, 0}}};
  add_box(box.mesh, {-1, -1, 0}, {1, 1, 2}, 1);
  d.objects.push_back(box);
  return d;
}

sc::Ray ray(glm::dvec3 origin, glm::dvec3 direction, double t_near = 0.0, double t_far = 1e30) {
  sc::Ray r;
  r.origin_m = origin;
  r.direction = glm::normalize(direction);
  r.t_near_m = t_near;
  r.t_far_m = t_far;
  return r;
}

// Closest entry distance of a ray into an axis-aligned box (slab method, in double), or -1.
double slab_entry(glm::dvec3 o, glm::dvec3 d, glm::dvec3 lo, glm::dvec3 hi) {
  double t0 = 0.0, t1 = 1e300;
  for (int k = 0; k < 3; ++k) {
    const double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
    t0 = std::max(t0, std::min(a, b));
    t1 = std::min(t1, std::max(a, b));
  }
  return t0 <= t1 ? t0 : -1.0;
}

}  // namespace

TEST(SceneRays, TriangleHitAtTheSlantRangeOfEachAngle) {
  const sc::Scene s(triangle_and_moving_box());
  const double h = 100.0;
  for (double incidence_deg : {0.0, 10.0, 30.0, 45.0, 60.0, 80.0}) {
    const double a = common::radians(incidence_deg);  // from the vertical
    const sc::Ray r = ray({0.0, -500.0, h}, {0.0, std::sin(a), -std::cos(a)});
    sc::Hit hit;
    ASSERT_TRUE(s.intersect(r, hit)) << incidence_deg;
    EXPECT_NEAR(hit.t_m, h / std::cos(a), 1e-12 * hit.t_m) << incidence_deg;
    EXPECT_NEAR(hit.position_m.y, -500.0 + h * std::tan(a), 1e-9) << incidence_deg;
    EXPECT_NEAR(hit.position_m.z, 0.0, 1e-12);
    EXPECT_DOUBLE_EQ(hit.normal.z, 1.0);
    EXPECT_EQ(hit.object_id, 0u);
    EXPECT_EQ(hit.primitive_id, 0u);
    EXPECT_EQ(hit.material_id, 0);
    EXPECT_TRUE(s.occluded(r));
    // Only up to t_far: just short of the ground is a miss for both queries.
    const sc::Ray short_ray = ray(r.origin_m, r.direction, 0.0, 0.999 * h / std::cos(a));
    EXPECT_FALSE(s.intersect(short_ray, hit));
    EXPECT_FALSE(s.occluded(short_ray));
  }
}

TEST(SceneRays, NormalIsAsWoundNotFlippedTowardTheRay) {
  const sc::Scene s(triangle_and_moving_box());
  sc::Hit hit;
  // From below, the ground's normal still points up (+z, as wound).
  ASSERT_TRUE(s.intersect(ray({10.0, 10.0, -50.0}, {0.0, 0.0, 1.0}), hit));
  EXPECT_NEAR(hit.t_m, 50.0, 1e-12);
  EXPECT_DOUBLE_EQ(hit.normal.z, 1.0);
}

TEST(SceneRays, RaysThatMustMiss) {
  const sc::Scene s(triangle_and_moving_box());
  sc::Hit hit;
  const sc::Ray misses[] = {
      ray({0, -500, 100}, {0, 0, 1}),                  // up, away from everything
      ray({990, 900, 100}, {0, 0, -1}),                // beside the triangle's slanted edge
      ray({0, -1001, 100}, {0, 0, -1}),                // just south of the triangle's base
      ray({0, -500, 100}, {1, 0, 0}),                  // parallel to the ground, above the box
      ray({0, -500, 100}, {0, 0.5, -1}, 200.0, 1e30),  // t_near beyond the ground
  };
  for (const sc::Ray& r : misses) {
    EXPECT_FALSE(s.intersect(r, hit)) << r.origin_m.x << " " << r.origin_m.y;
    EXPECT_FALSE(s.occluded(r)) << r.origin_m.x << " " << r.origin_m.y;
  }
  // Invalid rays are misses, not crashes.
  EXPECT_FALSE(s.intersect(ray({0, 0, 100}, {0, 0, -1}, 10.0, 5.0), hit));
  sc::Ray nan = ray({0, 0, 100}, {0, 0, -1});
  nan.origin_m.x = std::nan("");
  EXPECT_FALSE(s.intersect(nan, hit));
  EXPECT_FALSE(s.occluded(nan));
}

TEST(SceneRays, DefaultGroundAndRunwayAtTheSlantRange) {
  using L = sc::DefaultSceneLayout;
  const sc::SceneDescription d = sc::default_scene();
  const sc::Scene s(d);
  const double h = 300.0;
  for (double incidence_deg : {0.0, 20.0, 50.0, 75.0}) {
    const double a = common::radians(incidence_deg);
    sc::Hit hit;
    // Grass east of the runway, looking east.
    ASSERT_TRUE(s.intersect(ray({500.0, 2000.0, h}, {std::sin(a), 0.0, -std::cos(a)}), hit));
    EXPECT_NEAR(hit.t_m, h / std::cos(a), 1e-12 * hit.t_m);
    EXPECT_EQ(s.objects()[hit.object_id].name, "ground");
    EXPECT_EQ(d.materials[hit.material_id].name, "grass");
    EXPECT_DOUBLE_EQ(hit.normal.z, 1.0);
    // The runway, 5 cm above the grass, looking north along the centreline.
    ASSERT_TRUE(s.intersect(ray({0.0, 1000.0, h}, {0.0, std::sin(a), -std::cos(a)}), hit));
    // (The runway's height is stored as a float vertex coordinate: 0.05f.)
    const double runway_z = static_cast<double>(static_cast<float>(L::kRunwayHeight_m));
    EXPECT_NEAR(hit.t_m, (h - runway_z) / std::cos(a), 1e-12 * hit.t_m);
    EXPECT_EQ(s.objects()[hit.object_id].name, "runway");
    EXPECT_EQ(d.materials[hit.material_id].name, "asphalt");
  }
  // Beyond the ground's edge: nothing.
  sc::Hit hit;
  EXPECT_FALSE(s.intersect(ray({3100.0, 0.0, h}, {0, 0, -1}), hit));
}

TEST(SceneRays, RotatedBoxEntryDistanceIsTheSlabSolution) {
  // A static 4 x 2 x 3 m box yawed by 30 deg and placed at (200, 50, 10).
  sc::SceneDescription d;
  d.materials = {{"metal", {}}};
  const double yaw = common::radians(30.0);
  glm::dmat4 world_from_body(1.0);
  world_from_body[0] = {std::cos(yaw), std::sin(yaw), 0, 0};
  world_from_body[1] = {-std::sin(yaw), std::cos(yaw), 0, 0};
  world_from_body[3] = {200, 50, 10, 1};
  sc::ObjectDesc box{"box", {}, world_from_body, std::nullopt};
  const glm::dvec3 lo(-2, -1, 0), hi(2, 1, 3);
  add_box(box.mesh, glm::vec3(lo), glm::vec3(hi), 0);
  d.objects.push_back(box);
  const sc::Scene s(d);
  const glm::dmat4 body_from_world = glm::inverse(world_from_body);
  std::mt19937 rng(2024);
  std::cout << "seed 2024\n";
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int i = 0; i < 500; ++i) {
    const glm::dvec3 o{200 + 300 * u(rng), 50 + 300 * u(rng), 10 + 100 * u(rng)};
    const glm::dvec3 target{200 + 2 * u(rng), 50 + 2 * u(rng), 11.5 + 1.5 * u(rng)};
    const sc::Ray r = ray(o, target - o);
    const glm::dvec3 ob(body_from_world * glm::dvec4(o, 1.0));
    const glm::dvec3 db(body_from_world * glm::dvec4(r.direction, 0.0));
    const double t_exact = slab_entry(ob, db, lo, hi);
    sc::Hit hit;
    const bool got = s.intersect(r, hit);
    if (t_exact < 0.0 || !got) {
      // Rays aimed near the box but missing it (target outside the yawed footprint).
      EXPECT_EQ(got, t_exact >= 0.0) << i;
      continue;
    }
    ++hits;
    EXPECT_NEAR(hit.t_m, t_exact, 1e-9 * t_exact) << i;
    // The normal is the outward normal of the face entered: it opposes the ray.
    EXPECT_LT(glm::dot(hit.normal, r.direction), 0.0) << i;
    const glm::dvec3 nb(body_from_world * glm::dvec4(hit.normal, 0.0));
    EXPECT_NEAR(std::max({std::abs(nb.x), std::abs(nb.y), std::abs(nb.z)}), 1.0, 1e-12) << i;
  }
  EXPECT_GT(hits, 300);
}

TEST(SceneRefit, HitsFromTenKilometresLieOnTheTrianglePlane) {
  // A tilted triangle (normal not along an axis, vertices not on a nice grid).
  sc::SceneDescription d;
  d.materials = {{"metal", {}}};
  sc::ObjectDesc tri{"tilted", {}, glm::dmat4(1.0), std::nullopt};
  tri.mesh.positions_m = {{-37.3f, -41.9f, 3.1f}, {52.7f, -12.3f, 17.9f}, {-8.1f, 61.3f, 29.3f}};
  tri.mesh.triangles = {{0, 1, 2}};
  tri.mesh.triangle_material = {0};
  d.objects.push_back(tri);
  // The same triangle as a moving object, far from the origin, seen through an instance.
  sc::ObjectDesc mover = tri;
  mover.name = "tilted_mover";
  mover.motion = sc::LinearMotion{{3000.0, -2000.0, 0.0}, {31.7, 23.3, 0.0}};
  d.objects.push_back(mover);
  sc::Scene s(d);
  s.set_time(7.123);
  const std::uint32_t seed = 77;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (std::uint32_t object = 0; object < 2; ++object) {
    const glm::dmat4 x = s.world_from_body(object);
    const auto& p = d.objects[object].mesh.positions_m;
    const glm::dvec3 a(x * glm::dvec4(glm::dvec3(p[0]), 1.0));
    const glm::dvec3 b(x * glm::dvec4(glm::dvec3(p[1]), 1.0));
    const glm::dvec3 c(x * glm::dvec4(glm::dvec3(p[2]), 1.0));
    const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
    for (int i = 0; i < 200; ++i) {
      // A point well inside the triangle, seen from 10 km away in a random upper direction.
      double w1 = 0.1 + 0.8 * u(rng), w2 = 0.1 + 0.8 * u(rng);
      if (const double sum = w1 + w2; sum > 0.9) {
        w1 *= 0.9 / sum;
        w2 *= 0.9 / sum;
      }
      const glm::dvec3 target = a + w1 * (b - a) + w2 * (c - a);
      const double az = 2.0 * std::numbers::pi * u(rng), el = common::radians(10.0 + 70.0 * u(rng));
      const glm::dvec3 from = target + 1e4 * glm::dvec3(std::cos(el) * std::cos(az),
                                                        std::cos(el) * std::sin(az), std::sin(el));
      const sc::Ray r = ray(from, target - from);
      sc::Hit hit;
      ASSERT_TRUE(s.intersect(r, hit)) << object << " " << i;
      ASSERT_EQ(hit.object_id, object);
      const double off_plane = std::abs(glm::dot(hit.position_m - a, n));
      worst = std::max(worst, off_plane / hit.t_m);
      EXPECT_LT(off_plane, 1e-9 * hit.t_m) << object << " " << i;
      // And t is the exact range to the aimed point (float traversal alone is ~1e-7 off).
      EXPECT_NEAR(hit.t_m, glm::length(target - from), 1e-9 * hit.t_m) << object << " " << i;
      EXPECT_NEAR(std::abs(glm::dot(hit.normal, n)), 1.0, 1e-12);
    }
  }
  std::cout << "worst off-plane distance / range " << worst << "\n";
}

TEST(SceneMotion, SetTimeMovesTheInstanceNotTheStaticGeometry) {
  sc::Scene s(triangle_and_moving_box());
  EXPECT_EQ(s.static_build_count(), 1u);
  EXPECT_EQ(s.embree_commit_count(), 2u);  // the static BVH and the box's body-frame BVH
  const sc::Ray r = ray({-100.0, 0.0, 1.0}, {1.0, 0.0, 0.0});
  sc::Hit hit;
  ASSERT_TRUE(s.intersect(r, hit));
  EXPECT_NEAR(hit.t_m, 99.0, 1e-12);  // face at x = -1
  EXPECT_EQ(hit.object_id, 1u);
  EXPECT_EQ(hit.material_id, 1);
  EXPECT_DOUBLE_EQ(hit.normal.x, -1.0);
  const glm::dvec3 lo0 = s.objects()[1].bounds_min_m, hi0 = s.objects()[1].bounds_max_m;
  for (double t : {2.5, 0.1, 13.0, 0.0}) {
    s.set_time(t);
    EXPECT_DOUBLE_EQ(s.time_s(), t);
    ASSERT_TRUE(s.intersect(r, hit)) << t;
    EXPECT_NEAR(hit.t_m, 99.0 + 10.0 * t, 1e-12 * hit.t_m) << t;
    EXPECT_NEAR(hit.position_m.x, -1.0 + 10.0 * t, 1e-9) << t;
    EXPECT_EQ(hit.object_id, 1u);
    EXPECT_TRUE(s.occluded(ray({-100.0, 0.0, 1.0}, {1.0, 0.0, 0.0}, 0.0, 100.0 + 10.0 * t)));
    EXPECT_FALSE(s.occluded(ray({-100.0, 0.0, 1.0}, {1.0, 0.0, 0.0}, 0.0, 98.0 + 10.0 * t)));
    const sc::ObjectState& st = s.objects()[1];
    EXPECT_NEAR(st.bounds_min_m.x, lo0.x + 10.0 * t, 1e-12);
    EXPECT_NEAR(st.bounds_max_m.x, hi0.x + 10.0 * t, 1e-12);
    EXPECT_EQ(st.bounds_min_m.y, lo0.y);
    EXPECT_EQ(st.bounds_max_m.z, hi0.z);
  }
  // Four set_time() calls later nothing has been rebuilt or recommitted.
  EXPECT_EQ(s.static_build_count(), 1u);
  EXPECT_EQ(s.embree_commit_count(), 2u);
  EXPECT_EQ(s.embree_error_count(), 0u);
  // The static ground did not move.
  ASSERT_TRUE(s.intersect(ray({50.0, 50.0, 10.0}, {0, 0, -1}), hit));
  EXPECT_EQ(hit.object_id, 0u);
  EXPECT_NEAR(hit.t_m, 10.0, 1e-12);
  EXPECT_TRUE(s.objects()[1].moving);
  EXPECT_FALSE(s.objects()[0].moving);
  EXPECT_DOUBLE_EQ(s.objects()[1].velocity_mps.x, 10.0);
  EXPECT_EQ(s.objects()[0].velocity_mps, glm::dvec3(0.0));
}

TEST(SceneMotion, BodyXPointsAlongTheHorizontalVelocity) {
  // A 6 m (body x) x 2 m box moving north-east: its long axis lies along the diagonal.
  sc::SceneDescription d;
  d.materials = {{"metal", {}}};
  const glm::dvec3 v(10.0, 10.0, 0.0);
  sc::ObjectDesc box{"box", {}, glm::dmat4(1.0), sc::LinearMotion{{100.0, 100.0, 0.0}, v}};
  add_box(box.mesh, {-3, -1, 0}, {3, 1, 2}, 0);
  d.objects.push_back(box);
  sc::Scene s(d);
  s.set_time(1.0);
  const glm::dvec3 centre(110.0, 110.0, 1.0);
  const glm::dvec3 along = glm::normalize(v), across(-along.y, along.x, 0.0);
  sc::Hit hit;
  // From behind along body -x: hits the rear face 3 m from the centre.
  ASSERT_TRUE(s.intersect(ray(centre - 50.0 * along, along), hit));
  EXPECT_NEAR(hit.t_m, 47.0, 1e-9);
  EXPECT_NEAR(glm::dot(hit.normal, -along), 1.0, 1e-12);
  // From the side along body y: the side face 1 m from the centre.
  ASSERT_TRUE(s.intersect(ray(centre + 50.0 * across, -across), hit));
  EXPECT_NEAR(hit.t_m, 49.0, 1e-9);
  EXPECT_NEAR(glm::dot(hit.normal, across), 1.0, 1e-12);
  // Bounds of the yawed box: half extents (3 + 1) / sqrt(2) in x and y.
  const double half = 4.0 / std::sqrt(2.0);
  EXPECT_NEAR(s.objects()[0].bounds_min_m.x, 110.0 - half, 1e-5);
  EXPECT_NEAR(s.objects()[0].bounds_max_m.y, 110.0 + half, 1e-5);
}

TEST(SceneMotion, TrajectoryPlacesTheBoxAndItsVelocityWithoutRebuilding) {
  // A 6 m x 2 m x 2 m box (body origin at its bottom centre) on an L-shaped path: east 200 m,
  // a 50 m turn to the north, north 200 m, at 10 m/s. Centre of the turn (150, 50).
  sc::SceneDescription d;
  d.materials = {{"grass", {}}, {"metal", {}}};
  d.objects.push_back(ground_triangle());
  sc::ObjectDesc box{"box", {}, glm::dmat4(1.0), std::nullopt};
  add_box(box.mesh, {-3, -1, 0}, {3, 1, 2}, 1);
  box.trajectory = sc::Trajectory{{{0, 0, 0}, {200, 0, 0}, {200, 200, 0}}, 10.0, 50.0};
  d.objects.push_back(box);
  sc::Scene s(d);
  EXPECT_EQ(s.embree_commit_count(), 2u);
  EXPECT_TRUE(s.objects()[1].moving);
  const double quarter = 50.0 * std::numbers::pi / 2.0;
  sc::Hit hit;
  // On the first leg at t = 7 s the box's centre is at (70, 0, 1): a ray from the west along
  // the leg meets its rear face 3 m behind the centre.
  s.set_time(7.0);
  ASSERT_TRUE(s.intersect(ray({0.0, 0.0, 1.0}, {1, 0, 0}), hit));
  EXPECT_NEAR(hit.t_m, 67.0, 1e-9);
  EXPECT_EQ(hit.object_id, 1u);
  EXPECT_LT(glm::length(s.objects()[1].velocity_mps - glm::dvec3(10, 0, 0)), 1e-12);
  // Mid-turn: body origin at 45 degrees on the circle, heading north-east, body +y (left)
  // toward the turn centre; a ray from the centre toward it meets that side 1 m from the body
  // origin, at r - 1.
  s.set_time((150.0 + quarter / 2.0) / 10.0);
  const glm::dvec3 c(150.0, 50.0, 1.0);
  const glm::dvec3 out = glm::normalize(glm::dvec3(1.0, -1.0, 0.0));
  ASSERT_TRUE(s.intersect(ray(c, out), hit));
  EXPECT_NEAR(hit.t_m, 49.0, 1e-6);
  EXPECT_NEAR(glm::dot(hit.normal, -out), 1.0, 1e-9);  // the inner (left) face, facing the centre
  const glm::dvec3 v = s.objects()[1].velocity_mps;
  EXPECT_NEAR(glm::length(v), 10.0, 1e-12);
  EXPECT_NEAR(glm::dot(v, out), 0.0, 1e-9);  // tangent to the circle
  // The world box contains the rotated box (corners within 3.17 m of the centre).
  const glm::dvec3 centre = c + 50.0 * out;
  EXPECT_LE(s.objects()[1].bounds_min_m.x, centre.x - 4.0 / std::sqrt(2.0) + 1e-9);
  EXPECT_GE(s.objects()[1].bounds_max_m.y, centre.y + 4.0 / std::sqrt(2.0) - 1e-9);
  // Second leg, due north.
  s.set_time((150.0 + quarter + 100.0) / 10.0);
  ASSERT_TRUE(s.intersect(ray({200.0, 0.0, 1.0}, {0, 1, 0}), hit));
  EXPECT_NEAR(hit.t_m, 50.0 + 100.0 - 3.0, 1e-9);
  EXPECT_EQ(s.static_build_count(), 1u);
  EXPECT_EQ(s.embree_commit_count(), 2u);
}

TEST(SceneThreads, ConcurrentQueriesMatchSerialOnes) {
  const sc::Scene s(sc::default_scene());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<sc::Ray> rays;
  for (int i = 0; i < 4000; ++i) {
    const glm::dvec3 origin{300 * u(rng), 400 + 400 * u(rng), 200.0};
    const glm::dvec3 direction{0.3 * u(rng), 0.3 * u(rng), -1.0};
    rays.push_back(ray(origin, direction));
  }
  std::vector<sc::Hit> serial(rays.size());
  std::vector<char> serial_hit(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i)
    serial_hit[i] = s.intersect(rays[i], serial[i]) ? 1 : 0;
  std::vector<std::thread> threads;
  std::vector<int> mismatches(4, 0);
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([&, k] {
      for (std::size_t i = static_cast<std::size_t>(k); i < rays.size(); i += 4) {
        sc::Hit h;
        const bool got = s.intersect(rays[i], h);
        if (got != (serial_hit[i] != 0) ||
            (got && (h.t_m != serial[i].t_m || h.object_id != serial[i].object_id))) {
          ++mismatches[static_cast<std::size_t>(k)];
        }
        if (s.occluded(rays[i]) != got)
          ++mismatches[static_cast<std::size_t>(k)];
      }
    });
  }
  for (auto& t : threads)
    t.join();
  for (int m : mismatches)
    EXPECT_EQ(m, 0);
}

// The batched queries (Embree ray streams) answer as the single ones, ray by ray: parallel rays
// from a grid (the RCS engine's tubes and lighting samples), scattered ones, rays that reach a
// moving object (the part after the static BVH), rays with a finite t_far, invalid rays, and a
// span longer than one stream chunk. Seed 11.
TEST(SceneBatch, BatchedQueriesAnswerAsSingleOnes) {
  sc::SceneDescription d = sc::default_scene();
  for (sc::ObjectDesc& o : triangle_and_moving_box().objects) {
    if (o.motion)
      d.objects.push_back(o);
  }
  const sc::Scene s(d);
  std::mt19937 rng(11);
  std::cout << "seed 11\n";
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<sc::Ray> rays;
  for (int i = 0; i < 40; ++i) {  // a grid of parallel rays
    for (int j = 0; j < 25; ++j)
      rays.push_back(ray({-20.0 + i, -12.0 + j, 150.0}, {0.1, 0.05, -1.0}));
  }
  for (int i = 0; i < 1500; ++i) {  // scattered
    const glm::dvec3 origin{300 * u(rng), 400 + 400 * u(rng), 50.0 + 150.0 * (u(rng) + 1.0)};
    rays.push_back(
        ray(origin, {0.5 * u(rng), 0.5 * u(rng), -1.0}, 0.0, 100.0 + 300.0 * (u(rng) + 1.0)));
  }
  for (int i = 0; i < 300; ++i)  // toward the moving box at the origin
    rays.push_back(ray({1.5 * u(rng), 1.5 * u(rng), 40.0}, {-0.01 * u(rng), 0.01 * u(rng), -1.0}));
  rays[17].origin_m.x = std::numeric_limits<double>::quiet_NaN();  // invalid: no hit, not blocked
  rays[1203].t_far_m = -1.0;
  std::vector<sc::Hit> hits(rays.size());
  std::vector<std::uint8_t> found(rays.size(), 7), blocked(rays.size(), 7);
  s.intersect(rays, hits, found);
  s.occluded(rays, blocked);
  int mismatches = 0, hit_count = 0, mover_hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    sc::Hit h;
    const bool got = s.intersect(rays[i], h);
    hit_count += got ? 1 : 0;
    mover_hits += got && h.object_id + 1 == d.objects.size() ? 1 : 0;
    if (got != (found[i] != 0) ||
        (got && (h.t_m != hits[i].t_m || h.object_id != hits[i].object_id ||
                 h.primitive_id != hits[i].primitive_id || h.normal != hits[i].normal))) {
      ++mismatches;
    }
    if (s.occluded(rays[i]) != (blocked[i] != 0))
      ++mismatches;
  }
  EXPECT_EQ(found[17], 0);
  EXPECT_EQ(blocked[17], 0);
  EXPECT_EQ(found[1203], 0);
  EXPECT_GT(hit_count, 1000);
  EXPECT_GT(mover_hits, 50);
  EXPECT_EQ(mismatches, 0);
}

// The batched occlusion asks each moving object's BVH as a stream too (the rays not blocked yet
// that cross its box, in its body frame): the same answers as the single query, ray by ray, for
// the rays the tracer's facet pass batches (samples just off each mover's triangles toward a
// radar, some blocked by the mover's own other part) and for rays from behind the movers. Two
// movers are yawed (a linear motion off the x axis, a trajectory heading north), a third
// straight; all have moved (t = 2 s), so a ray left in the world frame would miss them.
TEST(SceneBatch, MoversAskedAsStreamsAnswerAsSingleQueries) {
  sc::SceneDescription d;
  d.materials = {{"grass", {}}, {"metal", {}}};
  d.objects.push_back(ground_triangle());
  sc::ObjectDesc a{"yawed", {}, glm::dmat4(1.0), sc::LinearMotion{{0, 0, 0}, {10, 5, 0}}};
  add_box(a.mesh, {-3, -1.5, 0}, {3, 1.5, 1.5}, 1);  // hull
  add_box(a.mesh, {-1, -1, 1.5}, {1, 1, 2.5}, 1);    // turret: shades part of the hull's top
  d.objects.push_back(a);
  sc::ObjectDesc b{"north", {}, glm::dmat4(1.0), std::nullopt};
  b.trajectory = sc::Trajectory{{{30, -20, 0}, {30, 100, 0}}, 5.0};
  add_box(b.mesh, {-3, -1, 0}, {3, 1, 2}, 1);
  d.objects.push_back(b);
  sc::ObjectDesc c{"straight", {}, glm::dmat4(1.0), sc::LinearMotion{{-20, 10, 0}, {4, 0, 0}}};
  add_box(c.mesh, {-2, -1, 0}, {2, 1, 2}, 1);
  d.objects.push_back(c);
  sc::Scene s(d);
  s.set_time(2.0);
  const glm::dvec3 radar(-200.0, -300.0, 80.0);
  auto toward_radar = [&](const glm::dvec3& p) {
    return ray(p, radar - p, 0.0, glm::length(radar - p));
  };
  std::vector<sc::Ray> rays;
  for (std::uint32_t id = 1; id < d.objects.size(); ++id) {
    const glm::dmat4 x = s.world_from_body(id);
    const sc::Mesh& mesh = d.objects[id].mesh;
    for (const glm::uvec3& t : mesh.triangles) {
      const glm::dvec3 v0(x * glm::dvec4(glm::dvec3(mesh.positions_m[t.x]), 1.0));
      const glm::dvec3 v1(x * glm::dvec4(glm::dvec3(mesh.positions_m[t.y]), 1.0));
      const glm::dvec3 v2(x * glm::dvec4(glm::dvec3(mesh.positions_m[t.z]), 1.0));
      const glm::dvec3 n = glm::normalize(glm::cross(v1 - v0, v2 - v0));
      // Seven points over the triangle, 1 mm off it on its outer side.
      for (int k = 0; k < 7; ++k) {
        const double u = 0.05 + 0.13 * k, v = 0.9 - u;
        rays.push_back(toward_radar(v0 + u * (v1 - v0) + 0.5 * v * (v2 - v0) + 1e-3 * n));
      }
    }
  }
  const std::size_t from_surfaces = rays.size();
  for (int i = 0; i < 60; ++i) {  // from behind each mover, at its height
    for (std::uint32_t id = 1; id < d.objects.size(); ++id) {
      const glm::dvec3 centre = 0.5 * (s.objects()[id].bounds_min_m + s.objects()[id].bounds_max_m);
      const glm::dvec3 away = glm::normalize(centre - radar);
      const glm::dvec3 side = glm::normalize(glm::cross(away, glm::dvec3(0, 0, 1)));
      rays.push_back(toward_radar(centre + 8.0 * away + (0.1 * i - 3.0) * side +
                                  glm::dvec3(0, 0, 0.03 * i - 0.8)));
    }
  }
  std::vector<std::uint8_t> blocked(rays.size(), 7);
  s.occluded(rays, blocked);
  int mismatches = 0, blocked_surface = 0, clear_surface = 0, blocked_behind = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const bool single = s.occluded(rays[i]);
    mismatches += single != (blocked[i] != 0) ? 1 : 0;
    if (i < from_surfaces) {
      blocked_surface += single ? 1 : 0;
      clear_surface += single ? 0 : 1;
    } else {
      blocked_behind += single ? 1 : 0;
    }
  }
  // Both answers occur among the surface samples and behind the movers (nothing but a mover
  // can block these rays: they climb from above the ground toward the radar).
  EXPECT_GT(blocked_surface, 100);
  EXPECT_GT(clear_surface, 100);
  EXPECT_GT(blocked_behind, 50);
  EXPECT_LT(blocked_behind, 180);
  EXPECT_EQ(mismatches, 0);

  // Split by the mover whose surface a ray leaves (the rays behind the movers: split by the
  // mover they are behind): the rest of the scene's answer OR the mover's own is the whole
  // answer; kNoMover asks the whole scene (kRest) or nothing (kOwn). Each part occurs.
  std::vector<std::uint32_t> mover(rays.size());
  std::size_t r = 0;
  for (std::uint32_t id = 1; id < d.objects.size(); ++id)
    for (std::size_t t = 0; t < d.objects[id].mesh.triangles.size() * 7; ++t)
      mover[r++] = id;
  for (int i = 0; i < 60; ++i)
    for (std::uint32_t id = 1; id < d.objects.size(); ++id)
      mover[r++] = id;
  ASSERT_EQ(r, rays.size());
  std::vector<std::uint8_t> rest(rays.size(), 7), own(rays.size(), 7), none_rest(rays.size(), 7),
      none_own(rays.size(), 7);
  s.occluded(rays, mover, sc::MoverSplit::kRest, rest);
  s.occluded(rays, mover, sc::MoverSplit::kOwn, own);
  const std::vector<std::uint32_t> nobody(rays.size(), sc::kNoMover);
  s.occluded(rays, nobody, sc::MoverSplit::kRest, none_rest);
  s.occluded(rays, nobody, sc::MoverSplit::kOwn, none_own);
  int split_mismatches = 0, by_own = 0, by_rest = 0, none_mismatches = 0, none_own_blocked = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    split_mismatches += ((rest[i] | own[i]) != 0) != (blocked[i] != 0) ? 1 : 0;
    by_own += own[i] != 0 ? 1 : 0;
    by_rest += rest[i] != 0 ? 1 : 0;
    none_mismatches += (none_rest[i] != 0) != (blocked[i] != 0) ? 1 : 0;
    none_own_blocked += none_own[i] != 0 ? 1 : 0;
  }
  std::printf("split: %d blocked by the ray's own mover, %d by the rest of the scene\n", by_own,
              by_rest);
  EXPECT_EQ(split_mismatches, 0);
  EXPECT_GT(by_own, 100);  // the turret over the hull, a box's far faces
  EXPECT_GT(by_rest, 0);   // another mover
  EXPECT_EQ(none_mismatches, 0);
  EXPECT_EQ(none_own_blocked, 0);
}

TEST(SceneValidation, BrokenDescriptionsFailWithContext) {
  auto error_of = [](sc::SceneDescription d) -> std::string {
    try {
      const sc::Scene s(std::move(d));
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "(no error)";
  };
  auto d = triangle_and_moving_box();
  d.objects[1].mesh.triangles[3] = {0, 1, 99};
  EXPECT_EQ(error_of(d),
            "scene: object 'box': triangle 3 indexes vertex 99, beyond the 8 vertices");
  d = triangle_and_moving_box();
  d.objects[0].mesh.positions_m[1].x = std::nanf("");
  EXPECT_EQ(error_of(d), "scene: object 'ground': vertex 1 is not finite");
  d = triangle_and_moving_box();
  d.objects[0].mesh.positions_m[2].z = INFINITY;
  EXPECT_EQ(error_of(d), "scene: object 'ground': vertex 2 is not finite");
  d = triangle_and_moving_box();
  d.objects[1].mesh.triangle_material[5] = 7;
  EXPECT_EQ(error_of(d),
            "scene: object 'box': triangle 5 has material index 7 but there are only 2 materials");
  d = triangle_and_moving_box();
  d.objects[0].mesh.positions_m = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};  // collinear
  EXPECT_EQ(error_of(d), "scene: object 'ground' has only degenerate (zero-area) triangles");
  d = triangle_and_moving_box();
  d.objects[1].mesh.triangle_material.pop_back();
  EXPECT_EQ(error_of(d), "scene: object 'box': 11 material indices for 12 triangles");
  d = triangle_and_moving_box();
  d.objects[1].motion->velocity_mps.y = std::nan("");
  EXPECT_EQ(error_of(d),
            "scene: object 'box': the motion's start position or velocity is not finite");
  d = triangle_and_moving_box();
  d.objects[1].trajectory = sc::Trajectory{{{0, 0, 0}, {10, 0, 0}}, 1.0};
  EXPECT_EQ(error_of(d), "scene: object 'box' has both a linear motion and a trajectory");
  d.objects[1].motion.reset();
  d.objects[1].trajectory->speed_mps = -1.0;
  EXPECT_EQ(error_of(d), "scene: object 'box': trajectory: speed_mps must be a finite number > 0");
  d = triangle_and_moving_box();
  d.objects[1].lod_group = 2;
  EXPECT_EQ(error_of(d), "scene: object 'box': a LOD tile (lod_group 2) cannot move");
  d = triangle_and_moving_box();
  d.objects[0].lod_group = -4;
  EXPECT_EQ(error_of(d), "scene: object 'ground': lod_group -4 (expected -1 or >= 0)");
  d = triangle_and_moving_box();
  d.objects[0].lod_facet_m = -1.0;
  EXPECT_EQ(error_of(d), "scene: object 'ground': lod_facet_m must be a finite number >= 0");
  d = triangle_and_moving_box();
  d.objects.push_back(d.objects[0]);
  d.objects.back().name = "ground2";
  d.objects[0].lod_group = d.objects.back().lod_group = 7;
  d.objects[0].lod_level = d.objects.back().lod_level = 1;
  EXPECT_EQ(error_of(d),
            "scene: object 'ground2': LOD group 7 already has a mesh at level 1 ('ground')");
  d = triangle_and_moving_box();
  d.objects[0].mesh.triangles.clear();
  d.objects[0].mesh.triangle_material.clear();
  EXPECT_EQ(error_of(d), "scene: object 'ground' has no triangles");
  d = triangle_and_moving_box();
  d.materials.clear();
  EXPECT_EQ(error_of(d), "scene: the scene has no materials");
  EXPECT_EQ(error_of(sc::SceneDescription{}), "scene: the scene has no objects");
}

TEST(SceneValidation, DegenerateTrianglesBesideGoodOnesAreAccepted) {
  auto d = triangle_and_moving_box();
  d.objects[0].mesh.positions_m.push_back({5, 5, 5});
  d.objects[0].mesh.triangles.push_back({3, 3, 3});
  d.objects[0].mesh.triangle_material.push_back(0);
  const sc::Scene s(std::move(d));
  EXPECT_EQ(s.triangle_count(), 14u);
}

TEST(SceneMove, AMovedSceneStillAnswers) {
  sc::Scene a(triangle_and_moving_box());
  sc::Scene b(std::move(a));
  sc::Hit hit;
  ASSERT_TRUE(b.intersect(ray({0, 0, 10}, {0, 0, -1}), hit));
  EXPECT_EQ(hit.object_id, 1u);  // the box's top at z = 2
  EXPECT_NEAR(hit.t_m, 8.0, 1e-12);
  EXPECT_EQ(b.description().objects.size(), 2u);
  EXPECT_EQ(b.materials()[1].name, "metal");
}
