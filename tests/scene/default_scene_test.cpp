// The default airport scene: named objects, materials, layout, closed outward-wound meshes.

#include "scene/default_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <tuple>

#include "common/units.hpp"
#include "scene/scene.hpp"
#include "tests/scene/mesh_parts.hpp"

namespace sc = radar_emu::scene;
using L = sc::DefaultSceneLayout;

namespace {

namespace common = radar_emu::common;

const sc::ObjectDesc& object(const sc::SceneDescription& d, const std::string& name) {
  for (const auto& o : d.objects) {
    if (o.name == name)
      return o;
  }
  throw std::runtime_error("no object " + name);
}

std::uint32_t id_of(const sc::Scene& s, const std::string& name) {
  for (std::uint32_t i = 0; i < s.objects().size(); ++i) {
    if (s.objects()[i].name == name)
      return i;
  }
  return ~0u;
}

using radar_emu::test::closed_and_consistent;
using radar_emu::test::mesh_parts;
using radar_emu::test::signed_volume;

// An open part that is a square trihedral corner reflector: 6 triangles on 3 mutually
// perpendicular planes.
bool is_trihedral(const sc::Mesh& m, const std::vector<std::size_t>& tris) {
  if (tris.size() != 6)
    return false;
  std::vector<glm::dvec3> normals;
  for (std::size_t i : tris) {
    const auto& t = m.triangles[i];
    const glm::dvec3 a(m.positions_m[t.x]), b(m.positions_m[t.y]), c(m.positions_m[t.z]);
    const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
    bool known = false;
    for (const auto& q : normals)
      known = known || glm::dot(q, n) > 1.0 - 1e-5;
    if (!known)
      normals.push_back(n);
  }
  if (normals.size() != 3)
    return false;
  return std::abs(glm::dot(normals[0], normals[1])) < 1e-5 &&
         std::abs(glm::dot(normals[0], normals[2])) < 1e-5 &&
         std::abs(glm::dot(normals[1], normals[2])) < 1e-5;
}

// World bounds of the closed parts of an object (its body, without attached open reflectors).
void body_bounds(const sc::ObjectDesc& o, const glm::dmat4& world_from_body, glm::dvec3& lo,
                 glm::dvec3& hi) {
  lo = glm::dvec3(1e300);
  hi = glm::dvec3(-1e300);
  for (const auto& part : mesh_parts(o.mesh)) {
    if (!closed_and_consistent(o.mesh, part))
      continue;
    for (std::size_t i : part) {
      for (int k = 0; k < 3; ++k) {
        const glm::dvec3 w(world_from_body *
                           glm::dvec4(glm::dvec3(o.mesh.positions_m[o.mesh.triangles[i][k]]), 1.0));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
      }
    }
  }
}

sc::Ray down_at(double x, double y) {
  sc::Ray r;
  r.origin_m = {x, y, 100.0};
  r.direction = {0.0, 0.0, -1.0};
  return r;
}

}  // namespace

TEST(DefaultScene, HasTheNamedObjectsWithTheirMaterials) {
  const sc::SceneDescription d = sc::default_scene();
  std::vector<std::string> names;
  for (const auto& o : d.objects)
    names.push_back(o.name);
  EXPECT_EQ(names, (std::vector<std::string>{"ground", "runway", "parked_aircraft",
                                             "parked_vehicle", "light_mast", "moving_vehicle"}));
  ASSERT_EQ(d.materials.size(), 3u);
  auto material_of = [&](const std::string& name) {
    const auto& o = object(d, name);
    std::string m = d.materials[o.mesh.triangle_material.at(0)].name;
    for (auto i : o.mesh.triangle_material) {
      if (d.materials[i].name != m)
        return std::string("(mixed)");
    }
    return m;
  };
  EXPECT_EQ(material_of("ground"), "grass");
  EXPECT_EQ(material_of("runway"), "asphalt");
  for (const char* n : {"parked_aircraft", "parked_vehicle", "light_mast", "moving_vehicle"})
    EXPECT_EQ(material_of(n), "metal") << n;
  for (const auto& m : d.materials) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(m.base_color[k], 0.0f);
      EXPECT_LE(m.base_color[k], 1.0f);
    }
  }
  EXPECT_TRUE(object(d, "moving_vehicle").motion.has_value());
  EXPECT_EQ(object(d, "moving_vehicle").motion->velocity_mps, glm::dvec3(0.0, 15.0, 0.0));
  EXPECT_EQ(object(d, "moving_vehicle").motion->start_position_m, glm::dvec3(-120, 200, 0));
  EXPECT_NEAR(d.anchor.latitude_rad, common::radians(43.6), 1e-15);
  EXPECT_NEAR(d.anchor.longitude_rad, common::radians(1.4), 1e-15);
  EXPECT_EQ(d.anchor.height_m, 150.0);
}

TEST(DefaultScene, BoundsMatchTheLayout) {
  const sc::SceneDescription d = sc::default_scene();
  sc::Scene s(d);
  auto check = [&](const char* name, glm::dvec3 lo, glm::dvec3 hi, double tol = 1e-4) {
    const std::uint32_t id = id_of(s, name);
    ASSERT_LT(id, s.objects().size()) << name;
    // The body (closed parts) sits exactly where the layout says ...
    glm::dvec3 blo, bhi;
    body_bounds(d.objects[id], s.world_from_body(id), blo, bhi);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(blo[k], lo[k], tol) << name << " axis " << k;
      EXPECT_NEAR(bhi[k], hi[k], tol) << name << " axis " << k;
    }
    // ... and the object's world box holds it, plus at most a roof-mounted 0.5 m reflector.
    const sc::ObjectState& st = s.objects()[id];
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(st.bounds_min_m[k], blo[k] + 1e-9) << name;
      EXPECT_GE(st.bounds_max_m[k], bhi[k] - 1e-9) << name;
      EXPECT_GE(st.bounds_min_m[k], blo[k] - 1.0) << name;
      EXPECT_LE(st.bounds_max_m[k], bhi[k] + 1.0) << name;
    }
  };
  const sc::ObjectState& ground = s.objects()[id_of(s, "ground")];
  EXPECT_EQ(ground.bounds_min_m, glm::dvec3(-3000, -6000, 0));
  EXPECT_EQ(ground.bounds_max_m, glm::dvec3(3000, 4000, 0));
  const sc::ObjectState& runway = s.objects()[id_of(s, "runway")];
  const double rz = static_cast<double>(static_cast<float>(L::kRunwayHeight_m));
  EXPECT_EQ(runway.bounds_min_m, glm::dvec3(-22.5, 0, rz));
  EXPECT_EQ(runway.bounds_max_m, glm::dvec3(22.5, 3000, rz));
  // Fuselage 32 m east-west, wings 30 m north-south, fin tip at 11.3 m, fuselage bottom at
  // 3.5 - 2 sin 75 deg (the 12-gon has flat faces at top and bottom).
  const double bottom = 3.5 - 2.0 * std::sin(common::radians(75.0));
  check("parked_aircraft", {110 - 16, 700 - 15, bottom}, {110 + 16, 700 + 15, 11.3});
  check("parked_vehicle", {-72.5, 398.9, 0}, {-67.5, 401.1, 2.2});
  check("light_mast", {58, 249.5, 0}, {62, 250.5, 13});
  // The moving vehicle heads north: its 6 m body x lies along y.
  check("moving_vehicle", {-121.25, 197, 0}, {-118.75, 203, 2.5});
  const glm::dvec3 lo0 = s.objects()[5].bounds_min_m, hi0 = s.objects()[5].bounds_max_m;
  s.set_time(10.0);
  check("moving_vehicle", {-121.25, 347, 0}, {-118.75, 353, 2.5});
  EXPECT_NEAR(s.objects()[5].bounds_min_m.y - lo0.y, 150.0, 1e-9);
  EXPECT_NEAR(s.objects()[5].bounds_max_m.y - hi0.y, 150.0, 1e-9);
}

TEST(DefaultScene, MetallicMeshesAreClosedAndWoundOutward) {
  const sc::SceneDescription d = sc::default_scene();
  // Volumes of the bodies (each part is its own closed mesh): 12-gon area (n/2) r^2 sin(2 pi/n).
  const double fuselage = 6.0 * 4.0 * std::sin(2.0 * std::numbers::pi / 12.0) * 32.0;
  const std::map<std::string, std::pair<double, int>> body = {
      // name: volume [m^3], closed parts
      {"parked_aircraft", {fuselage + 30.0 * 4.0 * 0.4 + 0.4 * 4.0 * 6.0, 3}},
      {"parked_vehicle", {5.0 * 2.2 * 2.2, 1}},
      {"light_mast", {1.0 * 1.0 * 12.0 + 4.0 * 1.0 * 1.0, 2}},
      {"moving_vehicle", {6.0 * 2.5 * 2.5, 1}}};
  for (const auto& [name, expected] : body) {
    const sc::Mesh& m = object(d, name).mesh;
    double volume = 0.0;
    int n_closed = 0;
    for (const auto& part : mesh_parts(m)) {
      if (closed_and_consistent(m, part)) {
        // Outward: each closed part encloses a positive volume.
        const double v = signed_volume(m, part);
        EXPECT_GT(v, 0.0) << name;
        volume += v;
        ++n_closed;
      } else {
        // The only open parts allowed are corner reflectors (single-sheet plates).
        EXPECT_TRUE(is_trihedral(m, part)) << name << ": an open part that is not a trihedral";
      }
    }
    EXPECT_EQ(n_closed, expected.second) << name;
    EXPECT_NEAR(volume, expected.first, 1e-4 * expected.first) << name;
  }
  // Ground and runway face up.
  for (const char* name : {"ground", "runway"}) {
    const sc::Mesh& m = object(d, name).mesh;
    for (const auto& t : m.triangles) {
      const glm::vec3 n = glm::cross(m.positions_m[t.y] - m.positions_m[t.x],
                                     m.positions_m[t.z] - m.positions_m[t.x]);
      EXPECT_GT(n.z, 0.0f) << name;
    }
  }
}

TEST(DefaultScene, RaysFindEachObjectWhereTheLayoutPutsIt) {
  const sc::SceneDescription d = sc::default_scene();
  const sc::Scene s(d);
  sc::Hit hit;
  struct Case {
    const char* name;
    sc::Ray ray;
    double t_m;
    glm::dvec3 normal;
  };
  const double fuselage_top = 3.5 + 2.0 * std::sin(common::radians(75.0));  // flat top face
  auto horizontal = [](glm::dvec3 o, glm::dvec3 dir) {
    sc::Ray r;
    r.origin_m = o;
    r.direction = dir;
    return r;
  };
  const Case cases[] = {
      // From above, clear of the roof-mounted reflectors (within 0.9 m of the centres).
      {"light_mast", down_at(60 + 1.5, 250), 100.0 - 13.0, {0, 0, 1}},
      {"parked_vehicle", down_at(-70 - 2.0, 400), 100.0 - 2.2, {0, 0, 1}},
      {"parked_aircraft", down_at(110, 700), 100.0 - fuselage_top, {0, 0, 1}},
      {"moving_vehicle", down_at(-120, 200 + 2.0), 100.0 - 2.5, {0, 0, 1}},
      // From the east along the fuselage axis: its end cap, 16 m east of the centre.
      {"parked_aircraft", horizontal({300, 700, 3.5}, {-1, 0, 0}), 300 - 126, {1, 0, 0}},
      // From the north at wing height: the wing tip, 15 m north of the centre.
      {"parked_aircraft", horizontal({110, 800, 3.5}, {0, -1, 0}), 800 - 715, {0, 1, 0}},
      // From the south along the taxiway: the moving vehicle's rear, 3 m south of its origin.
      {"moving_vehicle", horizontal({-120, 0, 1}, {0, 1, 0}), 197, {0, -1, 0}},
      // From the west at lamp height: the lamp head sticks out 2 m west of the mast.
      {"light_mast", horizontal({0, 250, 12.5}, {1, 0, 0}), 58, {-1, 0, 0}},
  };
  for (const Case& c : cases) {
    ASSERT_TRUE(s.intersect(c.ray, hit)) << c.name;
    EXPECT_EQ(s.objects()[hit.object_id].name, c.name);
    EXPECT_EQ(d.materials[hit.material_id].name, "metal") << c.name;
    EXPECT_NEAR(hit.t_m, c.t_m, 1e-5) << c.name;
    EXPECT_NEAR(glm::dot(hit.normal, c.normal), 1.0, 1e-6) << c.name;
  }
}
