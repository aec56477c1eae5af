// Targets added to a scene (scene/placement.hpp): ground heights against the plane equation,
// compass headings, the three kinds of motion, materials, mesh files and their axes, errors.

#include "scene/placement.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/units.hpp"
#include "scene/gltf.hpp"
#include "scene/scene.hpp"
#include "scene/trajectory.hpp"

namespace sc = radar_emu::scene;
namespace fs = std::filesystem;

namespace {

namespace common = radar_emu::common;

// The ground of these tests: the plane z = 0.1 x + 0.05 y + 3 over [-100, 100]^2 (two
// triangles), material "grass".
double plane_z(double x, double y) {
  return 0.1 * x + 0.05 * y + 3.0;
}
sc::ObjectDesc quad(const std::string& name, double x0, double x1, double y0, double y1,
                    bool tilted, double z = 0.0) {
  sc::ObjectDesc o;
  o.name = name;
  auto p = [&](double x, double y) {
    return glm::vec3(static_cast<float>(x), static_cast<float>(y),
                     static_cast<float>(tilted ? plane_z(x, y) : z));
  };
  o.mesh.positions_m = {p(x0, y0), p(x1, y0), p(x1, y1), p(x0, y1)};
  o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  o.mesh.triangle_material = {0, 0};
  return o;
}
sc::SceneDescription tilted_ground() {
  sc::SceneDescription d;
  d.materials = {{"grass", {0.2f, 0.6f, 0.2f}}, {"metal", {0.8f, 0.8f, 0.8f}}};
  d.objects.push_back(quad("ground", -100, 100, -100, 100, true));
  return d;
}

sc::TargetPlacement builtin(sc::TargetKind kind, double a, double b, double c) {
  sc::TargetPlacement t;
  t.name = "t";
  t.context = "test.toml: [[target]] #1";
  t.builtin = sc::TargetSpec{kind, a, b, c, 0.0};
  return t;
}

std::string error_of(sc::SceneDescription d, const sc::TargetPlacement& t) {
  try {
    sc::add_targets(d, {&t, 1});
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

fs::path tmp(const std::string& name) {
  static const fs::path dir = [] {
    const fs::path p =
        fs::temp_directory_path() / ("radar_emu_placement_test_" + std::to_string(::getpid()));
    fs::create_directories(p);
    return p;
  }();
  return dir / name;
}

glm::dvec3 apply(const glm::dmat4& x, glm::vec3 p) {
  return glm::dvec3(x * glm::dvec4(glm::dvec3(p), 1.0));
}

}  // namespace

TEST(GroundProbe, HeightOfATiltedPlaneIsItsEquation) {
  const sc::SceneDescription d = tilted_ground();
  const sc::GroundProbe g(d);
  for (const glm::dvec2 q : {glm::dvec2(10, 20), glm::dvec2(-50.5, 33.3), glm::dvec2(0, 0),
                             glm::dvec2(99.9, -99.9), glm::dvec2(-30, -30)}) {
    const auto h = g.height_m(q.x, q.y);
    ASSERT_TRUE(h.has_value());
    // float vertices of magnitude ~20 m: a few micrometres.
    EXPECT_NEAR(*h, plane_z(q.x, q.y), 1e-5) << q.x << ", " << q.y;
  }
  EXPECT_FALSE(g.height_m(150.0, 0.0).has_value());  // beyond the ground: nothing below
}

TEST(GroundProbe, HighestStaticSurfaceCountsMovingAndCoarseLevelsDoNot) {
  sc::SceneDescription d = tilted_ground();
  // A flat roof 2 m above its body origin, placed 10 m up: z = 12 over [0, 10]^2.
  sc::ObjectDesc roof = quad("roof", 0, 10, 0, 10, false, 2.0);
  roof.world_from_body[3] = glm::dvec4(0, 0, 10, 1);
  d.objects.push_back(roof);
  // A moving sheet at 50 m and a coarse level-of-detail sheet at 40 m over the same square
  // are not ground; the finest level of the same group (over another square, 30 m) is.
  sc::ObjectDesc mover = quad("mover", 0, 10, 0, 10, false, 50.0);
  mover.motion = sc::LinearMotion{{0, 0, 0}, {1, 0, 0}};
  d.objects.push_back(mover);
  sc::ObjectDesc coarse = quad("coarse", 0, 10, 0, 10, false, 40.0);
  coarse.lod_group = 3;
  coarse.lod_level = 1;
  d.objects.push_back(coarse);
  sc::ObjectDesc fine = quad("fine", 20, 30, 0, 10, false, 30.0);
  fine.lod_group = 3;
  fine.lod_level = 0;
  d.objects.push_back(fine);
  const sc::GroundProbe g(d);
  EXPECT_NEAR(*g.height_m(5.0, 5.0), 12.0, 1e-9);
  EXPECT_NEAR(*g.height_m(25.0, 5.0), 30.0, 1e-9);
  EXPECT_NEAR(*g.height_m(-5.0, 5.0), plane_z(-5.0, 5.0), 1e-5);
}

TEST(Placement, FixedTargetFacesItsCompassHeadingAndRestsOnTheGround) {
  // A 4 x 2 x 2 m box is centred on its body origin (z from -1 to 1); with on_ground its
  // lowest point sits position.z = 0.5 m above the plane: origin z = ground + 0.5 + 1.
  for (const auto& [heading_deg, nose] :
       {std::pair{90.0, glm::dvec2(1, 0)}, std::pair{0.0, glm::dvec2(0, 1)},
        std::pair{180.0, glm::dvec2(0, -1)},
        std::pair{225.0, glm::dvec2(-std::sqrt(0.5), -std::sqrt(0.5))}}) {
    sc::SceneDescription d = tilted_ground();
    sc::TargetPlacement t = builtin(sc::TargetKind::kBox, 4, 2, 2);
    t.position_m = {10, 20, 0.5};
    t.on_ground = true;
    t.heading_rad = common::radians(heading_deg);
    sc::add_targets(d, {&t, 1});
    ASSERT_EQ(d.objects.size(), 2u);
    const sc::ObjectDesc& o = d.objects[1];
    EXPECT_EQ(o.name, "t");
    EXPECT_EQ(o.area, "target");
    EXPECT_FALSE(o.motion || o.trajectory);
    const glm::dvec3 origin = apply(o.world_from_body, {0, 0, 0});
    EXPECT_NEAR(origin.z, plane_z(10, 20) + 0.5 + 1.0, 1e-5);
    // The body's +x end (x = 2) is 2 m from the origin along the compass heading.
    const glm::dvec3 front = apply(o.world_from_body, {2, 0, 0}) - origin;
    EXPECT_NEAR(front.x, 2.0 * nose.x, 1e-12) << heading_deg;
    EXPECT_NEAR(front.y, 2.0 * nose.y, 1e-12) << heading_deg;
    EXPECT_NEAR(front.z, 0.0, 1e-12);
    // Body y is left of the nose (body frame x forward, y left, z up).
    const glm::dvec3 left = apply(o.world_from_body, {0, 1, 0}) - origin;
    EXPECT_NEAR(left.x, -nose.y, 1e-12);
    EXPECT_NEAR(left.y, nose.x, 1e-12);
  }
  // Without on_ground the position is the body origin itself.
  sc::SceneDescription d = tilted_ground();
  sc::TargetPlacement t = builtin(sc::TargetKind::kBox, 4, 2, 2);
  t.position_m = {10, 20, 0.5};
  sc::add_targets(d, {&t, 1});
  EXPECT_EQ(glm::dvec3(d.objects[1].world_from_body[3]), glm::dvec3(10, 20, 0.5));
}

TEST(Placement, StraightLineMovesAlongTheCourseAndTheNoseKeepsTheHeading) {
  // A truck's nose is its +x end (x = a / 2). Course north at 10 m/s; with heading = course it
  // faces its velocity, with heading 180 it reverses (nose south while moving north).
  for (const double heading_deg : {0.0, 180.0, 270.0}) {
    sc::SceneDescription d = tilted_ground();
    sc::TargetPlacement t = builtin(sc::TargetKind::kTruck, 8, 2.5, 3.4);
    t.position_m = {-20, -30, 0};
    t.speed_mps = 10.0;
    t.course_rad = 0.0;
    t.heading_rad = common::radians(heading_deg);
    sc::add_targets(d, {&t, 1});
    const sc::ObjectDesc& o = d.objects[1];
    ASSERT_TRUE(o.motion.has_value());
    EXPECT_NEAR(o.motion->velocity_mps.x, 0.0, 1e-12);
    EXPECT_NEAR(o.motion->velocity_mps.y, 10.0, 1e-12);
    EXPECT_EQ(o.motion->velocity_mps.z, 0.0);
    EXPECT_EQ(o.motion->start_position_m, glm::dvec3(-20, -30, 0));
    // Where the scene puts the truck's original nose vertex (the mesh keeps its vertex order).
    const sc::SceneDescription plain = sc::make_target({sc::TargetKind::kTruck, 8, 2.5, 3.4, 0.0});
    std::size_t nose = 0;
    for (std::size_t i = 0; i < plain.objects[0].mesh.positions_m.size(); ++i) {
      if (plain.objects[0].mesh.positions_m[i].x > plain.objects[0].mesh.positions_m[nose].x)
        nose = i;
    }
    const sc::Scene scene(d);
    const glm::dmat4 x = scene.world_from_body(1);
    const glm::dvec3 dir =
        apply(x, o.mesh.positions_m[nose]) - glm::dvec3(x[3]);  // from the body origin
    // Body x along the compass heading h: nose (sin h, cos h), left (-cos h, sin h).
    const double h = common::radians(heading_deg);
    const glm::dvec3 v(plain.objects[0].mesh.positions_m[nose]);
    EXPECT_NEAR(v.x, 4.0, 1e-6);
    EXPECT_NEAR(dir.x, v.x * std::sin(h) - v.y * std::cos(h), 1e-4) << heading_deg;
    EXPECT_NEAR(dir.y, v.x * std::cos(h) + v.y * std::sin(h), 1e-4) << heading_deg;
    EXPECT_NEAR(dir.z, v.z, 1e-4);
  }
}

TEST(Placement, WaypointsAreDroppedOntoTheGroundEachOnItsOwn) {
  sc::SceneDescription d = tilted_ground();
  sc::TargetPlacement t = builtin(sc::TargetKind::kJeep, 4, 1.8, 1.9);  // lowest point z = 0
  t.waypoints_m = {{-50, 0, 0}, {50, 0, 0}, {50, 60, 2}};
  t.speed_mps = 8.0;
  t.turn_radius_m = 10.0;
  t.closed = false;
  t.bank = true;
  t.on_ground = true;
  sc::add_targets(d, {&t, 1});
  const sc::ObjectDesc& o = d.objects[1];
  ASSERT_TRUE(o.trajectory.has_value());
  ASSERT_EQ(o.trajectory->waypoints_m.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const glm::dvec3 w = o.trajectory->waypoints_m[i];
    EXPECT_EQ(glm::dvec2(w), glm::dvec2(t.waypoints_m[i]));
    EXPECT_NEAR(w.z, plane_z(w.x, w.y) + t.waypoints_m[i].z, 1e-5) << i;
  }
  EXPECT_EQ(o.trajectory->speed_mps, 8.0);
  EXPECT_EQ(o.trajectory->turn_radius_m, 10.0);
  EXPECT_TRUE(o.trajectory->bank);
  EXPECT_FALSE(o.trajectory->loop);
}

TEST(Placement, MaterialsMergeByNameOrAreOverridden) {
  sc::SceneDescription d = tilted_ground();  // grass (0), metal (1)
  sc::TargetPlacement a = builtin(sc::TargetKind::kSphere, 1, 1, 1);
  a.name = "a";
  sc::TargetPlacement b = builtin(sc::TargetKind::kPlate, 2, 1, 1);
  b.name = "b";
  b.material = "steel";
  const std::vector<sc::TargetPlacement> ts = {a, b};
  sc::add_targets(d, ts);
  ASSERT_EQ(d.materials.size(), 3u);  // metal reused, steel appended
  EXPECT_EQ(d.materials[2].name, "steel");
  for (std::uint16_t k : d.objects[1].mesh.triangle_material)
    EXPECT_EQ(k, 1u);
  for (std::uint16_t k : d.objects[2].mesh.triangle_material)
    EXPECT_EQ(k, 2u);
}

TEST(Placement, MeshFilesTakeTheirAxesScaleAndMaterials) {
  // OBJ: one triangle of material "concrete"; default axes x forward, z up.
  const fs::path obj = tmp("tri.obj");
  {
    std::ofstream f(obj);
    f << "v 1 0 0\nv 0 2 0\nv 0 0 3\nusemtl concrete\nf 1 2 3\n";
  }
  auto place = [&](const fs::path& file, std::optional<sc::MeshAxis> front,
                   std::optional<sc::MeshAxis> up, double scale) {
    sc::SceneDescription d = tilted_ground();
    sc::TargetPlacement t;
    t.name = "m";
    t.context = "ctx";
    t.mesh_file = file;
    t.mesh_front_axis = front;
    t.mesh_up_axis = up;
    t.mesh_scale = scale;
    sc::add_targets(d, {&t, 1});
    return d;
  };
  sc::SceneDescription d = place(obj, std::nullopt, std::nullopt, 1.0);
  const sc::Mesh& m = d.objects[1].mesh;
  ASSERT_EQ(m.positions_m.size(), 3u);
  EXPECT_EQ(m.positions_m[1], glm::vec3(0, 2, 0));
  EXPECT_EQ(d.materials[m.triangle_material[0]].name, "concrete");
  // Front +y, up +z: body x = file y, body z = file z, body y (left) = up x front = -file x.
  d = place(obj, sc::MeshAxis::kPlusY, sc::MeshAxis::kPlusZ, 2.0);
  EXPECT_EQ(d.objects[1].mesh.positions_m[0], glm::vec3(0, -2, 0));
  EXPECT_EQ(d.objects[1].mesh.positions_m[1], glm::vec3(4, 0, 0));
  EXPECT_EQ(d.objects[1].mesh.positions_m[2], glm::vec3(0, 0, 6));

  // glTF: a static node translated 10 m east holding the ENU vertex (1, 2, 3): the translation
  // is baked into the target's body. Default axes (+x forward, glTF +y up) keep ENU axes.
  sc::SceneDescription g;
  g.materials = {{"metal", {}}};
  sc::ObjectDesc o;
  o.name = "part";
  o.mesh.positions_m = {{1, 2, 3}, {2, 2, 3}, {1, 3, 3}};
  o.mesh.triangles = {{0, 1, 2}};
  o.mesh.triangle_material = {0};
  o.world_from_body[3] = glm::dvec4(10, 0, 0, 1);
  g.objects.push_back(o);
  const fs::path glb = tmp("part.glb");
  sc::write_gltf(g, glb);
  d = place(glb, std::nullopt, std::nullopt, 1.0);
  EXPECT_EQ(d.objects[1].mesh.positions_m[0], glm::vec3(11, 2, 3));
  // The glTF convention "the front faces +Z": ENU (11, 2, 3) is glTF (11, 3, -2); front +z
  // gives body x = -2, up +y gives body z = 3, left = y x z = +x gives body y = 11.
  d = place(glb, sc::MeshAxis::kPlusZ, std::nullopt, 1.0);
  EXPECT_EQ(d.objects[1].mesh.positions_m[0], glm::vec3(-2, 11, 3));

  // A moving node cannot be a target's mesh; axes must be perpendicular; formats by extension.
  g.objects[0].motion = sc::LinearMotion{{0, 0, 0}, {1, 0, 0}};
  const fs::path moving = tmp("moving.glb");
  sc::write_gltf(g, moving);
  EXPECT_THROW((void)place(moving, std::nullopt, std::nullopt, 1.0), std::runtime_error);
  try {
    (void)place(moving, std::nullopt, std::nullopt, 1.0);
  } catch (const std::runtime_error& e) {
    EXPECT_NE(
        std::string(e.what()).find("ctx: mesh_file " + moving.string() + ": node 'part' moves"),
        std::string::npos)
        << e.what();
  }
  try {
    (void)place(obj, sc::MeshAxis::kPlusZ, sc::MeshAxis::kMinusZ, 1.0);
    ADD_FAILURE() << "parallel axes accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "ctx: mesh_front_axis and mesh_up_axis must be perpendicular");
  }
}

TEST(Placement, ErrorsNameTheTargetAndTheProblem) {
  const sc::SceneDescription d = tilted_ground();
  sc::TargetPlacement t = builtin(sc::TargetKind::kBox, 1, 1, 1);
  t.name = "ground";  // the scene's own object
  EXPECT_EQ(error_of(d, t),
            "test.toml: [[target]] #1: name 'ground' is already taken by another object of the "
            "scene");
  t.name = "t";
  t.on_ground = true;
  t.position_m = {500, 0, 0};
  EXPECT_EQ(error_of(d, t),
            "test.toml: [[target]] #1: on_ground: no ground below position_enu_m (500, 0) m: "
            "outside the scene");
  t.on_ground = false;
  t.builtin->a_m = -1.0;
  EXPECT_EQ(error_of(d, t), "test.toml: [[target]] #1: target: a_m must be a positive number");
  t.builtin->a_m = 1.0;
  t.waypoints_m = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}};
  t.speed_mps = 5.0;
  t.turn_radius_m = 20.0;  // tangent length 20 m on legs of 10 m
  EXPECT_NE(error_of(d, t).find("test.toml: [[target]] #1: waypoints_enu_m: trajectory: leg 0"),
            std::string::npos)
      << error_of(d, t);
  sc::TargetPlacement m;
  m.name = "m";
  m.context = "ctx";
  m.mesh_file = tmp("x.ply");
  EXPECT_EQ(error_of(d, m), "ctx: mesh_file " + m.mesh_file.string() +
                                ": unknown format '.ply' (expected .glb, .gltf, .obj or .stl)");
  m.mesh_file = tmp("missing.obj");
  EXPECT_EQ(error_of(d, m).rfind("ctx: mesh_file: " + m.mesh_file.string(), 0), 0u)
      << error_of(d, m);
  // Nothing is added when a target fails.
  sc::SceneDescription copy = d;
  t.turn_radius_m = 0.0;
  t.material = "steel";  // would be a new material
  sc::TargetPlacement bad = builtin(sc::TargetKind::kBox, 1, 1, 1);
  bad.name = "ground";
  const std::vector<sc::TargetPlacement> two = {t, bad};
  EXPECT_THROW(sc::add_targets(copy, two), std::runtime_error);
  EXPECT_EQ(copy.objects.size(), 1u);
  EXPECT_EQ(copy.materials.size(), 2u);
}

TEST(MeshAxis, NamesRoundTrip) {
  EXPECT_EQ(sc::mesh_axis_from_name("+x"), sc::MeshAxis::kPlusX);
  EXPECT_EQ(sc::mesh_axis_from_name("-z"), sc::MeshAxis::kMinusZ);
  EXPECT_FALSE(sc::mesh_axis_from_name("x").has_value());
  EXPECT_FALSE(sc::mesh_axis_from_name("+w").has_value());
}
