// Ray queries against closed forms, moving objects, validation of broken descriptions.

#include "scene/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "scene/default_scene.hpp"

namespace sc = radar_emu::scene;

namespace {
sc::SceneDescription one_triangle_and_box() {
  sc::SceneDescription d;
  d.materials = {{"grass", {}}, {"metal", {}}};
  sc::ObjectDesc ground{"ground", {}, glm::dmat4(1.0), std::nullopt};
  ground.mesh.positions_m = {{-1000, -1000, 0}, {1000, -1000, 0}, {0, 1000, 0}};
  ground.mesh.triangles = {{0, 1, 2}};
  ground.mesh.triangle_material = {0};
  d.objects.push_back(ground);
  sc::ObjectDesc box{"box", {}, glm::dmat4(1.0), sc::LinearMotion{{0, 0, 0}, {10, 0, 0}}};
  // A 2 m cube centred 1 m above its origin.
  const glm::vec3 lo(-1, -1, 0), hi(1, 1, 2);
  box.mesh.positions_m = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z},
                          {lo.x, hi.y, lo.z}, {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z},
                          {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  box.mesh.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  box.mesh.triangle_material.assign(12, 1);
  d.objects.push_back(box);
  return d;
}
}  // namespace

TEST(Scene, RayHitsGroundAtTheSlantDistance) {
  sc::Scene s(one_triangle_and_box());
  for (double angle_deg : {10.0, 30.0, 60.0, 89.0}) {
    const double a = angle_deg * std::acos(-1.0) / 180.0;
    sc::Ray r;
    r.origin_m = {0.0, -500.0, 100.0};
    r.direction = {0.0, std::cos(a), -std::sin(a)};  // depressed by `angle`
    sc::Hit h;
    ASSERT_TRUE(s.intersect(r, h)) << angle_deg;
    EXPECT_NEAR(h.t_m, 100.0 / std::sin(a), 1e-9 * h.t_m) << angle_deg;
    EXPECT_NEAR(h.position_m.z, 0.0, 1e-9);
    EXPECT_NEAR(h.normal.z, 1.0, 1e-12);
    EXPECT_EQ(h.object_id, 0u);
    EXPECT_EQ(h.material_id, 0);
    EXPECT_TRUE(s.occluded(r));
  }
  sc::Ray up;
  up.origin_m = {0, -500, 100};
  up.direction = {0, 0, 1};
  sc::Hit h;
  EXPECT_FALSE(s.intersect(up, h));
  EXPECT_FALSE(s.occluded(up));
}

TEST(Scene, DoublePrecisionRefitFromTenKilometres) {
  sc::Scene s(one_triangle_and_box());
  sc::Ray r;
  r.origin_m = {0.0, -10000.0, 523.0};
  const glm::dvec3 target(3.3, 123.4567, 0.0);
  r.direction = glm::normalize(target - r.origin_m);
  sc::Hit h;
  ASSERT_TRUE(s.intersect(r, h));
  EXPECT_NEAR(h.position_m.z, 0.0, 1e-9);  // on the plane to 1e-9 m, not float's ~1 mm
  EXPECT_NEAR(glm::length(h.position_m - target), 0.0, 1e-8);
}

TEST(Scene, MovingBoxIsHitWhereItHasMoved) {
  sc::Scene s(one_triangle_and_box());
  sc::Ray r;
  r.origin_m = {-100.0, 0.0, 1.0};
  r.direction = {1.0, 0.0, 0.0};
  sc::Hit h;
  ASSERT_TRUE(s.intersect(r, h));
  EXPECT_NEAR(h.t_m, 99.0, 1e-9);  // face at x = -1
  EXPECT_EQ(h.object_id, 1u);
  EXPECT_NEAR(h.normal.x, -1.0, 1e-12);
  s.set_time(2.5);  // moved 25 m along +x
  ASSERT_TRUE(s.intersect(r, h));
  EXPECT_NEAR(h.t_m, 124.0, 1e-9);
  EXPECT_NEAR(s.objects()[1].bounds_min_m.x, 24.0, 1e-9);
  EXPECT_NEAR(s.objects()[1].bounds_max_m.x, 26.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.objects()[1].velocity_mps.x, 10.0);
  EXPECT_TRUE(s.objects()[1].moving);
  EXPECT_FALSE(s.objects()[0].moving);
}

TEST(Scene, BrokenDescriptionsFailWithContext) {
  auto expect_error = [](sc::SceneDescription d, const std::string& needle) {
    try {
      sc::Scene s(std::move(d));
      ADD_FAILURE() << "no error for " << needle;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  auto d = one_triangle_and_box();
  d.objects[1].mesh.triangles[3] = {0, 1, 99};
  expect_error(d, "object 'box': triangle 3 indexes vertex");
  d = one_triangle_and_box();
  d.objects[0].mesh.positions_m[1].x = std::nanf("");
  expect_error(d, "object 'ground': vertex 1 is not finite");
  d = one_triangle_and_box();
  d.objects[0].mesh.triangle_material[0] = 7;
  expect_error(d, "material index 7");
  d = one_triangle_and_box();
  d.objects[0].mesh.positions_m = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  expect_error(d, "only degenerate triangles");
  expect_error(sc::SceneDescription{}, "no objects");
}

TEST(DefaultScene, HasTheDocumentedObjectsAndLayout) {
  const sc::SceneDescription d = sc::default_scene();
  sc::Scene s(d);
  std::vector<std::string> names;
  for (const auto& o : s.objects())
    names.push_back(o.name);
  EXPECT_EQ(names, (std::vector<std::string>{"ground", "runway", "parked_aircraft",
                                             "parked_vehicle", "light_mast", "moving_vehicle"}));
  const auto& runway = s.objects()[1];
  EXPECT_NEAR(runway.bounds_max_m.x - runway.bounds_min_m.x, 45.0, 1e-6);
  EXPECT_NEAR(runway.bounds_max_m.y - runway.bounds_min_m.y, 3000.0, 1e-6);
  const auto& aircraft = s.objects()[2];
  EXPECT_NEAR(aircraft.bounds_max_m.x - aircraft.bounds_min_m.x, 32.0, 1e-5);  // fuselage
  EXPECT_NEAR(aircraft.bounds_max_m.y - aircraft.bounds_min_m.y, 30.0, 1e-5);  // wing span
  EXPECT_TRUE(s.objects()[5].moving);
  EXPECT_DOUBLE_EQ(s.objects()[5].velocity_mps.y, 15.0);
  // A ray straight down onto the runway centreline hits asphalt, beside it grass.
  sc::Ray r;
  r.origin_m = {0, 1500, 100};
  r.direction = {0, 0, -1};
  sc::Hit h;
  ASSERT_TRUE(s.intersect(r, h));
  EXPECT_EQ(d.materials[h.material_id].name, "asphalt");
  r.origin_m = {-40, 1500, 100};
  ASSERT_TRUE(s.intersect(r, h));
  EXPECT_EQ(d.materials[h.material_id].name, "grass");
  // Every metallic object's mesh is closed: each edge is shared by exactly two triangles.
  for (const auto& o : d.objects) {
    if (o.name == "ground" || o.name == "runway")
      continue;
    std::map<std::pair<glm::vec3, glm::vec3>, int,
             bool (*)(const std::pair<glm::vec3, glm::vec3>&,
                      const std::pair<glm::vec3, glm::vec3>&)>
        edges([](const auto& a, const auto& b) {
          auto key = [](const auto& e) {
            return std::make_tuple(e.first.x, e.first.y, e.first.z, e.second.x, e.second.y,
                                   e.second.z);
          };
          return key(a) < key(b);
        });
    for (const auto& t : o.mesh.triangles) {
      const glm::vec3 v[3] = {o.mesh.positions_m[t.x], o.mesh.positions_m[t.y],
                              o.mesh.positions_m[t.z]};
      for (int k = 0; k < 3; ++k)
        ++edges[{v[k], v[(k + 1) % 3]}];
    }
    for (const auto& [e, count] : edges) {
      // Directed edge a->b appears once and its reverse once: closed and consistently wound.
      EXPECT_EQ(count, 1) << o.name;
      const auto it = edges.find({e.second, e.first});
      EXPECT_TRUE(it != edges.end()) << o.name << " has an open edge";
    }
  }
}
