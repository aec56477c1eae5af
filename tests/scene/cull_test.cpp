// Culling and level of detail (Scene::set_view): rays inside the beam see exactly what they see in
// a scene built with only the finest level and no culling; the level follows the documented range
// rule; the view switches levels without rebuilding or allocating.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <random>
#include <string>

#include "common/units.hpp"
#include "scene/scene.hpp"
#include "scene/scene_builders.hpp"
#include "tests/alloc_counter.hpp"

namespace sc = radar_emu::scene;

namespace {

namespace common = radar_emu::common;
constexpr int kTiles = 8;                            // 8 x 8 tiles
constexpr double kTile_m = 400.0;                    // tile side
constexpr double kSpacing_m = 20.0;                  // level 0 grid; level L: 20 * 2^L
constexpr double kFacet_m[3] = {30.0, 60.0, 120.0};  // lod_facet_m per level (declared)

double height_m(double x, double y) {
  return 15.0 * std::sin(x / 170.0) * std::cos(y / 230.0) + 0.01 * x;
}

// One level of one tile: a height field sampled every 20 * 2^level m, in the tile's body frame
// (origin at its south-west corner), placed by a translation.
sc::ObjectDesc tile(int ix, int iy, int level) {
  sc::ObjectDesc o;
  o.name = "tile_" + std::to_string(ix) + "_" + std::to_string(iy) + "_" + std::to_string(level);
  o.area = "terrain";
  o.lod_group = iy * kTiles + ix;
  o.lod_level = static_cast<std::uint8_t>(level);
  o.lod_facet_m = kFacet_m[level];
  const double x0 = ix * kTile_m, y0 = iy * kTile_m;
  o.world_from_body[3] = glm::dvec4(x0, y0, 0.0, 1.0);
  const double step = kSpacing_m * std::pow(2.0, level);
  const int n = static_cast<int>(kTile_m / step);
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = i * step, y = j * step;
      o.mesh.positions_m.emplace_back(x, y, height_m(x0 + x, y0 + y));
    }
  }
  const auto v = [&](int i, int j) { return static_cast<unsigned>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      o.mesh.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});  // CCW from above
      o.mesh.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
      o.mesh.triangle_material.insert(o.mesh.triangle_material.end(), {0, 0});
    }
  }
  return o;
}

// The terrain at levels 0..max_level, plus boxes standing on it and a box driving a loop.
sc::SceneDescription database(int max_level) {
  sc::SceneDescription d;
  d.materials = {{"grass", {}}, {"metal", {}}};
  for (int iy = 0; iy < kTiles; ++iy) {
    for (int ix = 0; ix < kTiles; ++ix) {
      for (int level = 0; level <= max_level; ++level)
        d.objects.push_back(tile(ix, iy, level));
    }
  }
  for (int k = 0; k < 12; ++k) {
    sc::ObjectDesc b;
    b.name = "building_" + std::to_string(k);
    const double x = 150.0 + 230.0 * k, y = 300.0 + 170.0 * (k % 5);
    sc::detail::add_box(b.mesh, {-10, -8, -5}, {10, 8, 25}, 0);
    b.world_from_body[3] = glm::dvec4(x, y, height_m(x, y), 1.0);
    d.objects.push_back(b);
  }
  sc::ObjectDesc truck;
  truck.name = "truck";
  sc::detail::add_box(truck.mesh, {-4, -1.5f, 0}, {4, 1.5f, 3.5f}, 0);
  truck.trajectory = sc::Trajectory{
      {{600, 600, 40}, {1400, 600, 40}, {1400, 1300, 40}}, 15.0, 80.0, 0.0, true, false};
  d.objects.push_back(truck);
  return d;
}

// Antenna looking along azimuth `yaw` (from east, counter-clockwise), depressed by `depression`,
// rolled by `roll` (rotation about boresight): x boresight, y right, z down.
glm::dmat3 antenna(double yaw, double depression, double roll) {
  const glm::dvec3 x(std::cos(yaw) * std::cos(depression), std::sin(yaw) * std::cos(depression),
                     -std::sin(depression));
  const glm::dvec3 y0(std::sin(yaw), -std::cos(yaw), 0.0);
  const glm::dvec3 z0 = glm::cross(x, y0);
  const double c = std::cos(roll), s = std::sin(roll);
  return {x, c * y0 + s * z0, -s * y0 + c * z0};
}

sc::ViewVolume view(glm::dvec3 position, const glm::dmat3& r) {
  sc::ViewVolume v;
  v.position_m = position;
  v.world_from_antenna = r;
  v.azimuth_min_rad = common::radians(-12.0);
  v.azimuth_max_rad = common::radians(10.0);
  v.elevation_min_rad = common::radians(-6.0);
  v.elevation_max_rad = common::radians(4.0);
  v.max_range_m = 2500.0;
  v.range_cell_m = 1e-3;  // forces level 0 everywhere
  return v;
}

// A ray from the radar at antenna azimuth/elevation (radar::direction_from_azel's convention).
sc::Ray beam_ray(const sc::ViewVolume& v, double az, double el) {
  sc::Ray r;
  r.origin_m = v.position_m;
  r.direction = v.world_from_antenna *
                glm::dvec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el));
  r.t_far_m = v.max_range_m;
  return r;
}

struct Scenes {
  sc::Scene lod{database(2)};
  sc::Scene full{database(0)};  // level 0 of every tile only, never culled
  std::map<std::string, std::uint32_t> full_id;
  Scenes() {
    for (std::uint32_t i = 0; i < full.objects().size(); ++i)
      full_id[full.objects()[i].name] = i;
  }
  [[nodiscard]] std::string name(const sc::Scene& s, std::uint32_t id) const {
    return s.objects()[id].name;
  }
};

// Built once per process (each test runs in its own process under CTest).
Scenes& scenes() {
  static Scenes s;
  return s;
}

}  // namespace

TEST(SceneCull, RaysInsideTheBeamHitExactlyWhatTheFullSceneHits) {
  Scenes& s = scenes();
  const std::uint32_t seed = 2024;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uint64_t rays = 0, hits = 0, culled_tiles = 0;
  for (int view_index = 0; view_index < 6; ++view_index) {
    // One draw per statement: the order in which a call's arguments are evaluated is
    // unspecified (GCC and clang differ), and the views must not depend on the compiler.
    const double x_m = -500.0 + 600.0 * u(rng);
    const double y_m = -500.0 + 600.0 * u(rng);
    const double z_m = 120.0 + 300.0 * u(rng);
    const double yaw_deg = 25.0 + 40.0 * u(rng);
    const double depression_deg = 2.0 + 6.0 * u(rng);
    const double roll_deg = -30.0 + 60.0 * u(rng);
    const sc::ViewVolume v =
        view({x_m, y_m, z_m}, antenna(common::radians(yaw_deg), common::radians(depression_deg),
                                      common::radians(roll_deg)));
    const double t_s = 50.0 * u(rng);
    s.lod.set_time(t_s);
    s.full.set_time(t_s);
    s.lod.set_view(v);
    const sc::ViewStats& st = s.lod.view_stats();
    EXPECT_EQ(st.lod_groups, 64u);
    EXPECT_EQ(st.lod_groups_culled + st.lod_groups_in_view, 64u);
    EXPECT_EQ(st.lod_groups_at_level[0], st.lod_groups_in_view);  // tiny range cell: level 0
    culled_tiles += st.lod_groups_culled;
    for (int k = 0; k < 2500; ++k) {
      double az = v.azimuth_min_rad + (v.azimuth_max_rad - v.azimuth_min_rad) * u(rng);
      double el = v.elevation_min_rad + (v.elevation_max_rad - v.elevation_min_rad) * u(rng);
      // One ray in five on an edge of the field of view (corners included), where a culling
      // test that is not conservative would fail first.
      if (k % 5 == 0)
        az = u(rng) < 0.5 ? v.azimuth_min_rad : v.azimuth_max_rad;
      if (k % 5 == 0 && k % 2 == 0)
        el = u(rng) < 0.5 ? v.elevation_min_rad : v.elevation_max_rad;
      if (k % 5 == 1)
        el = u(rng) < 0.5 ? v.elevation_min_rad : v.elevation_max_rad;
      const sc::Ray r = beam_ray(v, az, el);
      sc::Hit a, b;
      const bool ha = s.lod.intersect(r, a), hb = s.full.intersect(r, b);
      ++rays;
      ASSERT_EQ(ha, hb) << "view " << view_index << " ray " << k;
      EXPECT_EQ(s.lod.occluded(r), ha) << "view " << view_index << " ray " << k;
      if (!ha)
        continue;
      ++hits;
      ASSERT_EQ(s.name(s.lod, a.object_id), s.name(s.full, b.object_id)) << view_index << " " << k;
      EXPECT_EQ(a.primitive_id, b.primitive_id) << view_index << " " << k;
      EXPECT_EQ(a.t_m, b.t_m) << view_index << " " << k;
      EXPECT_EQ(a.position_m, b.position_m);
    }
  }
  std::cout << rays << " rays in the beam, " << hits << " hits, all identical; " << culled_tiles
            << " tiles culled over 6 views\n";
  // Not vacuous: agreeing on misses alone would prove little (the views drawn here put 45 % of
  // the rays on the ground; a quarter is the floor).
  EXPECT_GT(hits, rays / 4);
  EXPECT_GT(culled_tiles, 0u);
  s.lod.clear_view();
}

TEST(SceneCull, RaysOutsideTheBeamMissCulledTiles) {
  Scenes& s = scenes();
  // Looking north-east from the south-west corner: the south-east and north-west tiles are out
  // of the 22-degree beam. A ray straight down onto a culled tile finds nothing in the culled
  // scene, the terrain in the full one.
  const sc::ViewVolume v =
      view({-300.0, -300.0, 300.0}, antenna(common::radians(45.0), common::radians(5.0), 0.0));
  s.lod.set_view(v);
  EXPECT_EQ(s.lod.active_lod_level(7), -1);  // tile (7, 0): south-east corner
  sc::Ray down;
  down.origin_m = {7.5 * kTile_m, 0.5 * kTile_m, 500.0};
  down.direction = {0.0, 0.0, -1.0};
  sc::Hit a, b;
  EXPECT_FALSE(s.lod.intersect(down, a));
  EXPECT_FALSE(s.lod.occluded(down));
  ASSERT_TRUE(s.full.intersect(down, b));
  EXPECT_EQ(s.name(s.full, b.object_id), "tile_7_0_0");
  // Tile (2, 2), on the boresight, is in the beam: level 0 there.
  EXPECT_EQ(s.lod.active_lod_level(18), 0);
  down.origin_m = {2.5 * kTile_m, 2.5 * kTile_m, 500.0};
  ASSERT_TRUE(s.lod.intersect(down, a));
  EXPECT_EQ(s.name(s.lod, a.object_id), "tile_2_2_0");
  // Without culling every tile keeps a level.
  sc::ViewVolume keep = v;
  keep.cull_outside = false;
  s.lod.set_view(keep);
  EXPECT_EQ(s.lod.view_stats().lod_groups_culled, 0u);
  EXPECT_EQ(s.lod.active_lod_level(7), 0);
  s.lod.clear_view();
}

TEST(SceneCull, CoarserLevelsAtLongRangeFollowTheRule) {
  Scenes& s = scenes();
  sc::ViewVolume v =
      view({-400.0, -400.0, 250.0}, antenna(common::radians(45.0), common::radians(4.0), 0.0));
  v.cull_outside = false;
  v.range_cell_m = 1.0;
  v.angular_cell_rad = 0.05;  // allowed facet max(1 m, 0.05 R): level 1 from 1200 m, 2 from 2400 m
  s.lod.set_view(v);
  // Expected level from each tile's box (computed here from the description's vertices).
  const sc::SceneDescription& d = s.lod.description();
  std::map<int, std::pair<glm::dvec3, glm::dvec3>> box;
  for (const sc::ObjectDesc& o : d.objects) {
    if (o.lod_group < 0)
      continue;
    auto [it, fresh] = box.try_emplace(o.lod_group, glm::dvec3(1e300), glm::dvec3(-1e300));
    for (const glm::vec3& p : o.mesh.positions_m) {
      const glm::dvec3 w(o.world_from_body * glm::dvec4(glm::dvec3(p), 1.0));
      it->second.first = glm::min(it->second.first, w);
      it->second.second = glm::max(it->second.second, w);
    }
  }
  std::array<int, 3> seen{};
  std::vector<std::pair<double, int>> range_level;
  for (const auto& [group, b] : box) {
    const double range = glm::length(glm::clamp(v.position_m, b.first, b.second) - v.position_m);
    const double allowed = std::max(v.range_cell_m, range * v.angular_cell_rad);
    int expected = 0;
    for (int level = 0; level < 3; ++level) {
      if (kFacet_m[level] <= allowed)
        expected = level;
    }
    EXPECT_EQ(s.lod.active_lod_level(group), expected) << "tile " << group << " at " << range;
    ++seen[static_cast<std::size_t>(expected)];
    range_level.emplace_back(range, s.lod.active_lod_level(group));
  }
  std::cout << "tiles at level 0/1/2: " << seen[0] << " " << seen[1] << " " << seen[2] << "\n";
  EXPECT_GT(seen[0], 0);
  EXPECT_GT(seen[1], 0);
  EXPECT_GT(seen[2], 0);
  // Level never decreases with range.
  std::sort(range_level.begin(), range_level.end());
  for (std::size_t i = 1; i < range_level.size(); ++i)
    EXPECT_GE(range_level[i].second, range_level[i - 1].second);
  const sc::ViewStats& st = s.lod.view_stats();
  EXPECT_EQ(st.lod_groups_at_level[0] + st.lod_groups_at_level[1] + st.lod_groups_at_level[2], 64u);
  // Active triangles: the selected level of each tile plus every other object.
  std::uint64_t expected_active = 0;
  for (std::uint32_t i = 0; i < s.lod.objects().size(); ++i) {
    const sc::ObjectDesc& o = d.objects[i];
    if (o.lod_group < 0 || s.lod.active_lod_level(o.lod_group) == o.lod_level)
      expected_active += o.mesh.triangles.size();
    EXPECT_EQ(s.lod.objects()[i].active,
              o.lod_group < 0 || s.lod.active_lod_level(o.lod_group) == o.lod_level);
  }
  EXPECT_EQ(st.triangles_active, expected_active);
  EXPECT_EQ(st.triangles_total, s.lod.triangle_count());
  EXPECT_LT(st.triangles_active, st.triangles_total);
  // A ray straight down onto the far corner tile (7, 7) meets its level-2 mesh.
  sc::Ray down;
  down.origin_m = {7.5 * kTile_m, 7.5 * kTile_m, 500.0};
  down.direction = {0.0, 0.0, -1.0};
  sc::Hit h;
  ASSERT_TRUE(s.lod.intersect(down, h));
  EXPECT_EQ(s.name(s.lod, h.object_id), "tile_7_7_2");
  // Back to the default view: level 0 everywhere, nothing culled.
  s.lod.clear_view();
  ASSERT_TRUE(s.lod.intersect(down, h));
  EXPECT_EQ(s.name(s.lod, h.object_id), "tile_7_7_0");
  // Built once: the non-LOD objects, levels 0, 1, 2 and the truck; set_view rebuilt nothing.
  EXPECT_EQ(s.lod.embree_commit_count(), 5u);
  EXPECT_EQ(s.lod.static_build_count(), 1u);
}

TEST(SceneCull, DefaultViewIsTheFullSceneForEveryRay) {
  Scenes& s = scenes();
  s.lod.clear_view();
  s.lod.set_time(3.0);
  s.full.set_time(3.0);
  const std::uint32_t seed = 99;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 3000; ++k) {
    sc::Ray r;
    r.origin_m = {1600.0 + 2500.0 * u(rng), 1600.0 + 2500.0 * u(rng), 200.0 + 150.0 * u(rng)};
    r.direction = glm::normalize(glm::dvec3{u(rng), u(rng), -0.2 + 0.5 * u(rng)});
    sc::Hit a, b;
    const bool ha = s.lod.intersect(r, a), hb = s.full.intersect(r, b);
    ASSERT_EQ(ha, hb) << k;
    if (ha) {
      EXPECT_EQ(s.name(s.lod, a.object_id), s.name(s.full, b.object_id)) << k;
      EXPECT_EQ(a.t_m, b.t_m) << k;
    }
  }
}

TEST(SceneCull, InvalidViewsFallBackToTheDefault) {
  sc::Scene s(database(1));
  sc::ViewVolume v =
      view({-300.0, -300.0, 300.0}, antenna(common::radians(45.0), common::radians(5.0), 0.0));
  s.set_view(v);
  EXPECT_EQ(s.view_stats().views_set, 1u);
  EXPECT_EQ(s.active_lod_level(7), -1);
  for (auto broken : {+[](sc::ViewVolume& w) { w.max_range_m = 0.0; },
                      +[](sc::ViewVolume& w) { w.range_cell_m = -1.0; },
                      +[](sc::ViewVolume& w) { w.azimuth_min_rad = 0.3; },
                      +[](sc::ViewVolume& w) { w.elevation_max_rad = 1.6; },
                      +[](sc::ViewVolume& w) { w.position_m.z = std::nan(""); },
                      +[](sc::ViewVolume& w) { w.world_from_antenna[0] *= 2.0; }}) {
    sc::ViewVolume w = v;
    broken(w);
    s.set_view(w);
    EXPECT_EQ(s.active_lod_level(7), 0);  // default: finest level, nothing culled
  }
  EXPECT_EQ(s.view_stats().invalid_views, 6u);
  EXPECT_EQ(s.view_stats().views_set, 1u);
  EXPECT_EQ(s.active_lod_level(12345), -1);  // no such tile
}

TEST(SceneCull, LongestEdgeIsTheFacetSizeWhenNotGiven) {
  // Flat tiles without lod_facet_m: the scene measures the longest edge (the cell diagonal).
  sc::SceneDescription d;
  d.materials = {{"grass", {}}};
  for (int level = 0; level < 2; ++level) {
    sc::ObjectDesc o = tile(0, 0, level);
    o.lod_facet_m = 0.0;
    for (glm::vec3& p : o.mesh.positions_m)
      p.z = 0.0f;
    d.objects.push_back(o);
  }
  sc::Scene s(d);
  sc::ViewVolume v = view({-100.0, 200.0, 100.0}, antenna(0.0, common::radians(10.0), 0.0));
  v.range_cell_m = 40.0 * std::sqrt(2.0) + 1e-9;  // the level-1 diagonal
  s.set_view(v);
  EXPECT_EQ(s.active_lod_level(0), 1);
  v.range_cell_m = 40.0 * std::sqrt(2.0) - 1e-6;
  s.set_view(v);
  EXPECT_EQ(s.active_lod_level(0), 0);
}

TEST(SceneCull, SetViewAndSetTimeDoNotAllocate) {
  sc::Scene s(database(2));
  sc::ViewVolume v =
      view({-300.0, -300.0, 300.0}, antenna(common::radians(45.0), common::radians(5.0), 0.0));
  v.angular_cell_rad = 0.05;
  sc::Hit hit;
  s.set_view(v);
  s.set_time(1.0);
  (void)s.intersect(beam_ray(v, 0.0, common::radians(-3.0)), hit);
  radar_emu::test::start_counting_allocations();
  int hits = 0;
  for (int i = 0; i < 500; ++i) {
    s.set_time(0.1 * i);
    v.position_m.x += 1.0;
    v.world_from_antenna = antenna(common::radians(45.0 + 0.01 * i), common::radians(5.0), 0.0);
    s.set_view(v);
    hits += s.intersect(beam_ray(v, 0.0, common::radians(-3.0)), hit) ? 1 : 0;
    hits += s.occluded(beam_ray(v, 0.0, common::radians(-3.0))) ? 1 : 0;
  }
  s.clear_view();
  EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u)
      << "operator new called in set_view / set_time";
  EXPECT_EQ(hits, 1000);
  EXPECT_EQ(s.view_stats().views_set, 501u);
}
