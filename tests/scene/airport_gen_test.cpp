// The generated airport: runway areas against the ICAO marking layout (closed form), materials
// from the catalogue, the default scene's closed-loop objects unchanged, approach lights on the
// extended centreline, no degenerate triangle, seed determinism, nothing in front of the
// closed-loop objects on the approach.

#include "scene/airport_gen.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "scene/default_scene.hpp"
#include "scene/mesh_check.hpp"
#include "scene/scene.hpp"

namespace sc = radar_emu::scene;

namespace {

const sc::ObjectDesc* find(const sc::SceneDescription& d, const std::string& name) {
  for (const auto& o : d.objects) {
    if (o.name == name)
      return &o;
  }
  return nullptr;
}

double triangle_area(const sc::Mesh& m, std::size_t t) {
  const auto& tri = m.triangles[t];
  return 0.5 * glm::length(glm::cross(glm::dvec3(m.positions_m[tri.y] - m.positions_m[tri.x]),
                                      glm::dvec3(m.positions_m[tri.z] - m.positions_m[tri.x])));
}

// World positions of every vertex used by a static object's triangles.
void world_bounds(const sc::ObjectDesc& o, glm::dvec3& lo, glm::dvec3& hi) {
  lo = glm::dvec3(1e300);
  hi = glm::dvec3(-1e300);
  for (const auto& t : o.mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 w(o.world_from_body * glm::dvec4(glm::dvec3(o.mesh.positions_m[t[k]]), 1.0));
      lo = glm::min(lo, w);
      hi = glm::max(hi, w);
    }
  }
}

}  // namespace

TEST(Airport, RunwayTilesItsAreaWithAsphaltAndTheIcaoMarkings) {
  const sc::SceneDescription d = sc::generate_airport({});
  const sc::ObjectDesc* runway = find(d, "runway");
  ASSERT_NE(runway, nullptr);
  std::map<std::string, double> area;
  glm::dvec3 lo, hi;
  world_bounds(*runway, lo, hi);
  for (std::size_t t = 0; t < runway->mesh.triangles.size(); ++t) {
    area[d.materials[runway->mesh.triangle_material[t]].name] += triangle_area(runway->mesh, t);
    const auto& tri = runway->mesh.triangles[t];
    const glm::vec3 n =
        glm::cross(runway->mesh.positions_m[tri.y] - runway->mesh.positions_m[tri.x],
                   runway->mesh.positions_m[tri.z] - runway->mesh.positions_m[tri.x]);
    ASSERT_GT(n.z, 0.0f) << "runway triangle " << t << " faces down";
  }
  // ICAO Annex 14 Vol. I, 5.2, at each of the two ends: 12 threshold stripes 1.8 x 30 m, two
  // aiming-point blocks 10 x 60 m, touchdown-zone pairs of 3 + 3 + 2 + 2 + 1 + 1 stripes
  // 1.8 x 22.5 m; 58 centreline dashes 0.9 x 30 m (60 m to 2940 m, 50 m period); two side
  // stripes 0.9 x 3000 m.
  const double threshold = 2 * 12 * 1.8 * 30.0;
  const double aiming = 2 * 2 * 10.0 * 60.0;
  const double touchdown = 2 * 2 * 12 * 1.8 * 22.5;
  const double centreline = ((2940.0 - 60.0 - 30.0) / 50.0 + 1) * 0.9 * 30.0;
  const double side = 2 * 0.9 * 3000.0;
  const double markings = threshold + aiming + touchdown + centreline + side;
  std::cout << "runway: " << runway->mesh.triangles.size() << " triangles, asphalt "
            << area["asphalt"] << " m^2, markings (concrete) " << area["concrete"] << " m^2\n";
  EXPECT_NEAR(markings, 12606.0, 1e-9);
  EXPECT_NEAR(area["concrete"], markings, 0.01);
  EXPECT_NEAR(area["asphalt"], 45.0 * 3000.0 - markings, 0.05);
  EXPECT_NEAR(area["asphalt"] + area["concrete"], 135000.0, 0.05);
  EXPECT_EQ(area.size(), 2u);
  // Same frame and place as the default scene's runway.
  const double rz =
      static_cast<double>(static_cast<float>(sc::DefaultSceneLayout::kRunwayHeight_m));
  EXPECT_EQ(lo, glm::dvec3(-22.5, 0.0, rz));
  EXPECT_EQ(hi, glm::dvec3(22.5, 3000.0, rz));
  // Rays straight down: a centreline dash at 75 m is concrete, the gap at 100 m asphalt.
  const sc::Scene s(d);
  auto material_at = [&](double x, double y) {
    sc::Ray r;
    r.origin_m = {x, y, 50.0};
    r.direction = {0.0, 0.0, -1.0};
    sc::Hit h;
    if (!s.intersect(r, h))
      return std::string("(none)");
    return s.objects()[h.object_id].name + ":" + s.materials()[h.material_id].name;
  };
  EXPECT_EQ(material_at(0.0, 75.0), "runway:concrete");
  EXPECT_EQ(material_at(0.0, 100.0), "runway:asphalt");
  EXPECT_EQ(material_at(15.0, 430.0), "runway:concrete");            // aiming point
  EXPECT_EQ(material_at(-15.0, 3000.0 - 430.0), "runway:concrete");  // far end's
  EXPECT_EQ(material_at(2.7, 20.0), "runway:concrete");              // first threshold stripe
  EXPECT_EQ(material_at(1.0, 20.0), "runway:asphalt");               // centre gap
  EXPECT_EQ(material_at(22.0, 1500.0), "runway:concrete");           // side stripe
  EXPECT_EQ(material_at(-120.0, 500.0), "taxiways:asphalt");
  EXPECT_EQ(material_at(300.0, 1200.0), "aprons:concrete");
  EXPECT_EQ(material_at(1000.0, -3000.0), "ground:grass");
}

TEST(Airport, MaterialsObjectsAndTriangleCounts) {
  const sc::SceneDescription d = sc::generate_airport({});
  // Only names of the clutter catalogue (radar/clutter/terrain.cpp) that the radar's material
  // resolver (radar/em/surfaces.cpp) also knows.
  const std::set<std::string> allowed{"asphalt", "concrete", "grass", "metal"};
  std::map<std::string, std::size_t> triangles_per_material;
  std::size_t total = 0, metal_objects = 0;
  for (const auto& o : d.objects) {
    EXPECT_EQ(o.area, "airport") << o.name;
    bool metal = false;
    for (std::uint16_t m : o.mesh.triangle_material) {
      ASSERT_LT(m, d.materials.size());
      ++triangles_per_material[d.materials[m].name];
      metal = metal || d.materials[m].name == "metal";
    }
    metal_objects += metal;
    total += o.mesh.triangles.size();
    // No degenerate triangle anywhere.
    for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t)
      ASSERT_FALSE(sc::is_degenerate(o.mesh, t)) << o.name << " triangle " << t;
  }
  for (const auto& m : d.materials)
    EXPECT_TRUE(allowed.count(m.name)) << m.name;
  for (const auto& [name, n] : triangles_per_material) {
    std::cout << name << ": " << n << " triangles\n";
    EXPECT_GT(n, 0u) << name;
  }
  EXPECT_EQ(triangles_per_material.size(), 4u);
  std::cout << "airport: " << d.objects.size() << " objects, " << total << " triangles, "
            << metal_objects << " metal objects\n";
  EXPECT_GE(total, 5000u);
  EXPECT_LE(total, 60000u);
  // 4 closed-loop objects, 30 approach-light stations, 3 aircraft, truck, jeep, helicopter.
  EXPECT_EQ(metal_objects, 40u);
  for (const char* name :
       {"ground", "runway", "taxiways", "aprons", "approach_light_030", "terminal", "hangar_1",
        "hangar_2", "hangar_3", "transport_1", "transport_2", "transport_3", "service_truck",
        "service_jeep", "helicopter"}) {
    EXPECT_NE(find(d, name), nullptr) << name;
  }
  const sc::Scene s(d);  // builds
  EXPECT_EQ(s.triangle_count(), total);
  // Pavements are rectangles (quads of 2 triangles) that touch but never overlap: the runway
  // as a whole and each taxiway and apron rectangle.
  std::vector<std::pair<glm::dvec2, glm::dvec2>> rects;
  glm::dvec3 rlo, rhi;
  world_bounds(*find(d, "runway"), rlo, rhi);
  rects.push_back({glm::dvec2(rlo), glm::dvec2(rhi)});
  for (const char* name : {"taxiways", "aprons"}) {
    const sc::Mesh& m = find(d, name)->mesh;
    ASSERT_EQ(m.triangles.size() % 2, 0u);
    for (std::size_t q = 0; q < m.triangles.size(); q += 2) {
      glm::dvec2 lo(1e300), hi(-1e300);
      for (std::size_t t = q; t < q + 2; ++t) {
        for (int k = 0; k < 3; ++k) {
          lo = glm::min(lo, glm::dvec2(m.positions_m[m.triangles[t][k]]));
          hi = glm::max(hi, glm::dvec2(m.positions_m[m.triangles[t][k]]));
        }
      }
      EXPECT_NEAR(triangle_area(m, q) + triangle_area(m, q + 1), (hi.x - lo.x) * (hi.y - lo.y),
                  1e-6 * (hi.x - lo.x) * (hi.y - lo.y));
      rects.push_back({lo, hi});
    }
  }
  EXPECT_EQ(rects.size(), 1u + 7u + 4u);
  std::size_t overlaps = 0;
  for (std::size_t i = 0; i < rects.size(); ++i) {
    for (std::size_t j = i + 1; j < rects.size(); ++j) {
      const glm::dvec2 lo = glm::max(rects[i].first, rects[j].first);
      const glm::dvec2 hi = glm::min(rects[i].second, rects[j].second);
      overlaps += hi.x > lo.x && hi.y > lo.y;
    }
  }
  // Bad spec.
  sc::AirportSpec bad;
  bad.parked_transports = 7;
  EXPECT_THROW((void)sc::generate_airport(bad), std::invalid_argument);
  EXPECT_EQ(overlaps, 0u);
}

TEST(Airport, KeepsTheDefaultScenesClosedLoopObjectsUnchanged) {
  const sc::SceneDescription def = sc::default_scene();
  for (bool reflectors : {true, false}) {
    sc::AirportSpec spec;
    spec.corner_reflectors = reflectors;
    const sc::SceneDescription d = sc::generate_airport(spec);
    for (const char* name : {"parked_aircraft", "parked_vehicle", "light_mast", "moving_vehicle"}) {
      const sc::ObjectDesc* a = find(d, name);
      const sc::ObjectDesc* b = find(def, name);
      ASSERT_NE(a, nullptr) << name;
      ASSERT_NE(b, nullptr) << name;
      EXPECT_EQ(a->world_from_body, b->world_from_body) << name;
      EXPECT_EQ(a->motion.has_value(), b->motion.has_value()) << name;
      if (a->motion && b->motion) {
        EXPECT_EQ(a->motion->start_position_m, b->motion->start_position_m);
        EXPECT_EQ(a->motion->velocity_mps, b->motion->velocity_mps);
      }
      for (std::uint16_t m : a->mesh.triangle_material)
        EXPECT_EQ(d.materials[m].name, "metal") << name;
      // With reflectors: the same mesh vertex for vertex. Without: the same mesh less the
      // reflector's 6 triangles (its last), so the body's bounds are the default scene's.
      const std::size_t drop = reflectors ? 0 : 6;
      ASSERT_EQ(a->mesh.triangles.size() + drop, b->mesh.triangles.size()) << name;
      for (std::size_t t = 0; t < a->mesh.triangles.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
          ASSERT_EQ(a->mesh.positions_m[a->mesh.triangles[t][k]],
                    b->mesh.positions_m[b->mesh.triangles[t][k]])
              << name << " triangle " << t;
        }
      }
    }
  }
  // The scenes' anchor is the same point.
  const sc::SceneDescription d = sc::generate_airport({});
  EXPECT_EQ(d.anchor.latitude_rad, def.anchor.latitude_rad);
  EXPECT_EQ(d.anchor.longitude_rad, def.anchor.longitude_rad);
  EXPECT_EQ(d.anchor.height_m, def.anchor.height_m);
  glm::dvec3 lo, hi;
  world_bounds(*find(d, "ground"), lo, hi);
  EXPECT_EQ(lo, glm::dvec3(-3000, -6000, 0));
  EXPECT_EQ(hi, glm::dvec3(3000, 4000, 0));
}

TEST(Airport, ApproachLightsStandOnTheExtendedCentreline) {
  const sc::SceneDescription d = sc::generate_airport({});
  // Every light station is an object "approach_light_DDD"; together they hold the masts: the
  // boxes standing on the ground (12 triangles each, in build order).
  sc::Mesh m;
  int stations = 0;
  for (const auto& o : d.objects) {
    if (o.name.rfind("approach_light_", 0) != 0)
      continue;
    ++stations;
    const auto base = static_cast<std::uint32_t>(m.positions_m.size());
    m.positions_m.insert(m.positions_m.end(), o.mesh.positions_m.begin(), o.mesh.positions_m.end());
    for (const auto& t : o.mesh.triangles)
      m.triangles.push_back(t + glm::uvec3(base));
  }
  EXPECT_EQ(stations, 30);
  ASSERT_EQ(m.triangles.size() % 12, 0u);
  std::map<int, int> centreline;  // distance south of the threshold [m] -> masts at x = 0
  int crossbar_masts = 0;
  for (std::size_t box = 0; box < m.triangles.size() / 12; ++box) {
    glm::dvec3 lo(1e300), hi(-1e300);
    for (std::size_t t = 12 * box; t < 12 * box + 12; ++t) {
      for (int k = 0; k < 3; ++k) {
        lo = glm::min(lo, glm::dvec3(m.positions_m[m.triangles[t][k]]));
        hi = glm::max(hi, glm::dvec3(m.positions_m[m.triangles[t][k]]));
      }
    }
    if (lo.z != 0.0)
      continue;  // a barrette or the crossbar, on top of a mast
    const glm::dvec3 c = 0.5 * (lo + hi);
    EXPECT_LT(c.y, 0.0);  // south of the threshold
    const int distance = static_cast<int>(std::lround(-c.y));
    EXPECT_NEAR(-c.y, distance, 1e-3);
    EXPECT_EQ(distance % 30, 0) << distance;
    if (std::abs(c.x) < 1e-6) {
      ++centreline[distance];
    } else {
      EXPECT_EQ(distance, 300);  // only the crossbar has masts off the centreline
      EXPECT_LE(std::abs(c.x), 15.0);
      ++crossbar_masts;
    }
  }
  EXPECT_EQ(centreline.size(), 30u);  // 30, 60, ..., 900 m
  EXPECT_EQ(centreline.begin()->first, 30);
  EXPECT_EQ(centreline.rbegin()->first, 900);
  for (const auto& [dist, n] : centreline)
    EXPECT_EQ(n, 1) << dist;
  EXPECT_EQ(crossbar_masts, 4);
  sc::ObjectDesc all_lights;  // the stations together (identity placement, as generated)
  all_lights.mesh = m;
  glm::dvec3 lo, hi;
  world_bounds(all_lights, lo, hi);
  EXPECT_NEAR(lo.x, -15.0, 1e-5);  // the 30 m crossbar
  EXPECT_NEAR(hi.x, 15.0, 1e-5);
  EXPECT_NEAR(lo.y, -900.15, 1e-3);
  EXPECT_NEAR(hi.y, -29.85, 1e-3);
}

TEST(Airport, SameSeedSameSceneOtherSeedOtherScene) {
  sc::AirportSpec spec;
  spec.seed = 20240607;
  std::cout << "seed " << spec.seed << "\n";
  const sc::SceneDescription a = sc::generate_airport(spec), b = sc::generate_airport(spec);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    EXPECT_EQ(a.objects[i].name, b.objects[i].name);
    EXPECT_EQ(a.objects[i].world_from_body, b.objects[i].world_from_body);
    ASSERT_EQ(a.objects[i].mesh.positions_m.size(), b.objects[i].mesh.positions_m.size());
    EXPECT_EQ(
        std::memcmp(a.objects[i].mesh.positions_m.data(), b.objects[i].mesh.positions_m.data(),
                    a.objects[i].mesh.positions_m.size() * sizeof(glm::vec3)),
        0)
        << a.objects[i].name;
    EXPECT_EQ(a.objects[i].mesh.triangles, b.objects[i].mesh.triangles);
  }
  spec.seed = 7;
  const sc::SceneDescription c = sc::generate_airport(spec);
  bool differs = false;
  for (const char* name : {"transport_1", "hangar_1", "service_truck", "helicopter"}) {
    const sc::ObjectDesc* x = find(a, name);
    const sc::ObjectDesc* y = find(c, name);
    ASSERT_TRUE(x && y) << name;
    glm::dvec3 lx, hx, ly, hy;
    world_bounds(*x, lx, hx);
    world_bounds(*y, ly, hy);
    differs = differs || lx != ly || hx != hy;
  }
  EXPECT_TRUE(differs);
  // Fewer aircraft, no extras: the closed-loop objects stay.
  spec.parked_transports = 0;
  spec.service_vehicles = false;
  spec.helicopter = false;
  spec.approach_lights = false;
  const sc::SceneDescription bare = sc::generate_airport(spec);
  EXPECT_EQ(find(bare, "transport_1"), nullptr);
  EXPECT_EQ(find(bare, "approach_light_030"), nullptr);
  EXPECT_NE(find(bare, "moving_vehicle"), nullptr);
}

TEST(Airport, NothingNewStandsBetweenTheApproachAndTheClosedLoopObjects) {
  // From the default scenario's radar, 4 km short of the threshold on a 3 deg slope, and from
  // 1.5 km short, the first thing a ray toward each closed-loop object meets is that object.
  const sc::SceneDescription d = sc::generate_airport({});
  sc::Scene s(d);
  for (double range : {4000.0, 1500.0}) {
    const glm::dvec3 radar(0.0, -range, range * std::tan(3.0 * std::acos(-1.0) / 180.0));
    // Points inside each body (default_scene.hpp's layout): the fuselage axis, box centres.
    const std::pair<const char*, glm::dvec3> targets[] = {{"parked_aircraft", {110, 700, 3.5}},
                                                          {"parked_vehicle", {-70, 400, 1.1}},
                                                          {"light_mast", {60, 250, 6.0}},
                                                          {"moving_vehicle", {-120, 200, 1.25}}};
    for (const auto& [name, target] : targets) {
      sc::Ray r;
      r.origin_m = radar;
      r.direction = glm::normalize(target - radar);
      sc::Hit h;
      ASSERT_TRUE(s.intersect(r, h)) << name;
      EXPECT_EQ(s.objects()[h.object_id].name, name) << "from " << range << " m";
    }
  }
}
