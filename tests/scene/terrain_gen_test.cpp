// The generated terrain database against the seed paper's figures (200,000 polygons in the 5 x
// 7 km central area, 7,000 in the 20 x 20 km surround), closed-form areas, grid continuity, and
// ray casts through the Embree scene (roads, water, buildings and trees on top of the ground, wire
// clearance, the bridge over the river). Heavy (about 200,000 triangles a database): not in the
// sanitize label.

#include "scene/terrain_gen.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>

#include "radar/clutter/terrain.hpp"
#include "scene/mesh_check.hpp"
#include "scene/scene.hpp"
#include "scene/scene_info.hpp"

namespace sc = radar_emu::scene;
using Layout = sc::TerrainLayout;

namespace {

// The seed under test: 7, or RADAR_EMU_TERRAIN_SEED to soak other seeds by hand.
std::uint64_t seed() {
  const char* env = std::getenv("RADAR_EMU_TERRAIN_SEED");
  return env ? std::strtoull(env, nullptr, 10) : 7;
}

const sc::SceneDescription& terrain() {
  static const sc::SceneDescription d = [] {
    sc::TerrainSpec spec;
    spec.seed = seed();
    std::printf("terrain seed %llu\n", static_cast<unsigned long long>(spec.seed));
    return sc::generate_terrain(spec);
  }();
  return d;
}

bool starts_with(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

glm::dvec3 world(const sc::ObjectDesc& o, glm::vec3 p) {
  return glm::dvec3(o.world_from_body * glm::dvec4(glm::dvec3(p), 1.0));
}

std::string material_of(const sc::SceneDescription& d, const sc::ObjectDesc& o, std::size_t t) {
  return d.materials[o.mesh.triangle_material[t]].name;
}

// Materials an object uses.
std::set<std::string> materials(const sc::SceneDescription& d, const sc::ObjectDesc& o) {
  std::set<std::string> s;
  for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t)
    s.insert(material_of(d, o, t));
  return s;
}

// The full-detail description (level 0 of every tile, everything outside LOD groups).
sc::SceneDescription full_detail(const sc::SceneDescription& d) {
  sc::SceneDescription f;
  f.materials = d.materials;
  f.anchor = d.anchor;
  for (const auto& o : d.objects) {
    if (o.lod_group < 0 || o.lod_level == 0)
      f.objects.push_back(o);
  }
  return f;
}

}  // namespace

TEST(TerrainGen, PolygonCountsMatchThePaper) {
  const sc::SceneInfo info = sc::scene_info(terrain());
  std::map<std::string, std::size_t> area(info.triangles_by_area.begin(),
                                          info.triangles_by_area.end());
  // "described by 200,000 polygons" (central, full detail) and "7,000 polygons" (surround).
  EXPECT_GE(area["central"], 190'000u);
  EXPECT_LE(area["central"], 210'000u);
  EXPECT_LE(200'000 - area["central"], 24u);  // trees fill the budget to within one tree
  EXPECT_GE(area["surround"], 6'000u);
  EXPECT_LE(area["surround"], 8'000u);
  // Level 0: 140 tiles of 24 x 24 cells, two triangles each; level L has 4^-L of it.
  std::map<int, std::size_t> level(info.triangles_by_lod_level.begin(),
                                   info.triangles_by_lod_level.end());
  EXPECT_EQ(level[0], 140u * 24u * 24u * 2u);
  EXPECT_EQ(level[1], level[0] / 4);
  EXPECT_EQ(level[2], level[0] / 16);
  EXPECT_EQ(info.lod_groups, 140u);
  EXPECT_EQ(info.triangles_full_detail, area["central"] + area["surround"]);
  EXPECT_EQ(info.triangles_total, info.triangles_full_detail + level[1] + level[2]);
  // Extent: the 20 km square (the river strip may reach a few metres beyond its ends).
  EXPECT_NEAR(info.extent_min_m.x, -10'000.0, 20.0);
  EXPECT_NEAR(info.extent_max_m.y, 10'000.0, 20.0);
  EXPECT_GT(info.extent_max_m.z - info.extent_min_m.z, 15.0);  // undulating, not flat
  EXPECT_LT(info.extent_max_m.z - info.extent_min_m.z, 120.0);
  // Anchor near Toulouse.
  EXPECT_NEAR(info.anchor.latitude_rad * 180.0 / std::numbers::pi, 43.45, 1e-9);
  EXPECT_NEAR(info.anchor.longitude_rad * 180.0 / std::numbers::pi, 1.30, 1e-9);
}

TEST(TerrainGen, EveryFeatureClassIsThereWithItsMaterials) {
  const auto& d = terrain();
  std::map<std::string, int> kinds;
  std::map<std::string, std::set<std::string>> mats;
  for (const auto& o : d.objects) {
    const std::string kind = sc::object_kind(o.name);
    ++kinds[kind];
    for (const auto& m : materials(d, o))
      mats[kind].insert(m);
    EXPECT_EQ(o.area, starts_with(o.name, "surround") ? "surround" : "central") << o.name;
  }
  EXPECT_EQ(kinds["terrain"], 140 * 3);
  EXPECT_GE(kinds["road"], 3);
  EXPECT_EQ(kinds["river"], 1);
  EXPECT_EQ(kinds["lake"], 1);
  EXPECT_EQ(kinds["bridge"], 1);
  EXPECT_GE(kinds["building"], 20);
  EXPECT_GE(kinds["pylon"], 8);
  EXPECT_EQ(kinds["wire"], 3 * (kinds["pylon"] - 1));
  EXPECT_GE(kinds["tree"], 500);
  EXPECT_EQ(kinds["surround_terrain"], 1);
  EXPECT_EQ(kinds["surround_lake"], 1);
  EXPECT_EQ(kinds["surround_river"], 1);
  using S = std::set<std::string>;
  EXPECT_TRUE(mats["road"].count("asphalt"));
  mats["road"].erase("gravel");  // embankment walls where a road ramps up to the bridge
  EXPECT_EQ(mats["road"], S{"asphalt"});
  if (kinds["track"] > 0) {
    EXPECT_EQ(mats["track"], S{"gravel"});
  }
  EXPECT_EQ(mats["river"], S{"water"});
  EXPECT_EQ(mats["lake"], S{"water"});
  EXPECT_EQ(mats["surround_lake"], S{"water"});
  EXPECT_EQ(mats["surround_river"], S{"water"});
  EXPECT_EQ(mats["bridge"], (S{"concrete", "metal"}));
  EXPECT_EQ(mats["building"], (S{"concrete", "metal"}));
  EXPECT_EQ(mats["pylon"], S{"metal"});
  EXPECT_EQ(mats["wire"], S{"metal"});
  EXPECT_EQ(mats["tree"], S{"forest"});
  // Plane surfaces: crop fields, meadows, forests, ploughed land, wet beds, yards.
  for (const char* m : {"crops", "grass", "forest", "soil_dry", "soil_wet", "urban"})
    EXPECT_TRUE(mats["terrain"].count(m)) << m;
  for (const char* m : {"crops", "grass", "soil_dry", "soil_wet"})
    EXPECT_TRUE(mats["surround_terrain"].count(m)) << m;
  // Every material is a radar catalogue material with an optical colour.
  for (const auto& m : d.materials) {
    EXPECT_NE(radar_emu::radar::clutter::find_terrain_material(m.name), nullptr) << m.name;
    for (int c = 0; c < 3; ++c) {
      EXPECT_GE(m.base_color[c], 0.0f);
      EXPECT_LE(m.base_color[c], 1.0f);
    }
  }
}

TEST(TerrainGen, SameSeedSameDatabaseOtherSeedAnother) {
  sc::TerrainSpec spec;
  spec.seed = seed();
  const sc::SceneDescription again = sc::generate_terrain(spec);
  const auto& d = terrain();
  ASSERT_EQ(again.objects.size(), d.objects.size());
  ASSERT_EQ(again.materials.size(), d.materials.size());
  for (std::size_t k = 0; k < d.materials.size(); ++k) {
    EXPECT_EQ(again.materials[k].name, d.materials[k].name);
    EXPECT_EQ(again.materials[k].base_color, d.materials[k].base_color);
  }
  for (std::size_t i = 0; i < d.objects.size(); ++i) {
    const auto &a = again.objects[i], &b = d.objects[i];
    ASSERT_EQ(a.name, b.name);
    ASSERT_EQ(a.mesh.positions_m, b.mesh.positions_m) << a.name;
    ASSERT_EQ(a.mesh.triangles, b.mesh.triangles) << a.name;
    ASSERT_EQ(a.mesh.triangle_material, b.mesh.triangle_material) << a.name;
    ASSERT_EQ(a.world_from_body, b.world_from_body) << a.name;
    ASSERT_EQ(std::tie(a.area, a.lod_group, a.lod_level, a.lod_facet_m),
              std::tie(b.area, b.lod_group, b.lod_level, b.lod_facet_m));
  }
  spec.seed = seed() + 1;
  const sc::SceneDescription other = sc::generate_terrain(spec);
  // Another seed: other heights on the same grid, other features.
  ASSERT_EQ(other.objects[0].name, d.objects[0].name);
  EXPECT_NE(other.objects[0].mesh.positions_m, d.objects[0].mesh.positions_m);
  const sc::SceneInfo a = sc::scene_info(d), b = sc::scene_info(other);
  EXPECT_NE(a.triangles_by_material, b.triangles_by_material);
}

TEST(TerrainGen, TrianglesAreFiniteAndNotDegenerate) {
  const auto& d = terrain();
  std::size_t triangles = 0;
  for (const auto& o : d.objects) {
    ASSERT_EQ(o.mesh.triangle_material.size(), o.mesh.triangles.size()) << o.name;
    for (const auto& p : o.mesh.positions_m)
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << o.name;
    for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
      ASSERT_FALSE(sc::is_degenerate(o.mesh, t)) << o.name << " triangle " << t;
      const auto tri = o.mesh.triangles[t];
      const glm::dvec3 a(o.mesh.positions_m[tri.x]), b(o.mesh.positions_m[tri.y]),
          c(o.mesh.positions_m[tri.z]);
      // Well-shaped enough for the float BVH: area over the longest edge squared >= 1e-4 (the
      // thinnest facets are the 2.6 cm x 19 m wire faces: 7e-4).
      const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
      ASSERT_GT(0.5 * glm::length(glm::cross(b - a, c - a)), 1e-4 * longest * longest)
          << o.name << " triangle " << t;
      ASSERT_LT(o.mesh.triangle_material[t], d.materials.size());
      ++triangles;
    }
    if (o.lod_group >= 0) {  // the LOD facet size is the mesh's longest edge
      double longest = 0.0;
      for (const auto& t : o.mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
          longest = std::max(longest, glm::length(glm::dvec3(o.mesh.positions_m[t[k]]) -
                                                  glm::dvec3(o.mesh.positions_m[t[(k + 1) % 3]])));
        }
      }
      EXPECT_DOUBLE_EQ(o.lod_facet_m, longest) << o.name;
      // Grid step 500 / 24 m doubling per level; the diagonal plus relief.
      const double diagonal = std::sqrt(2.0) * 500.0 / 24.0 * (1 << o.lod_level);
      EXPECT_GE(o.lod_facet_m, diagonal - 1e-3) << o.name;
      EXPECT_LT(o.lod_facet_m, 1.6 * diagonal) << o.name;
    }
  }
  EXPECT_GT(triangles, 250'000u);
}

TEST(TerrainGen, ProjectedAreasAreTheAreasOfTheDomain) {
  // Sum of plan-view (signed) triangle areas: a height field that covers its domain once, wound
  // counter-clockwise seen from above, adds up to the domain's area; every triangle positive.
  const auto& d = terrain();
  std::map<int, double> central;  // per LOD level
  double surround = 0.0;
  for (const auto& o : d.objects) {
    const bool tile = starts_with(o.name, "terrain_");
    if (!tile && o.name != "surround_terrain")
      continue;
    double sum = 0.0;
    for (const auto& t : o.mesh.triangles) {
      const glm::dvec3 a = world(o, o.mesh.positions_m[t.x]), b = world(o, o.mesh.positions_m[t.y]),
                       c = world(o, o.mesh.positions_m[t.z]);
      const double plan = 0.5 * glm::cross(b - a, c - a).z;
      ASSERT_GT(plan, 0.0) << o.name;
      sum += plan;
    }
    if (tile) {
      EXPECT_NEAR(sum, Layout::kTile_m * Layout::kTile_m, 1e-3) << o.name;
      central[o.lod_level] += sum;
    } else {
      surround += sum;
    }
  }
  for (int level = 0; level < Layout::kLodLevels; ++level)
    EXPECT_NEAR(central[level], 35e6, 1.0) << "level " << level;  // 5 km x 7 km
  EXPECT_NEAR(surround, 400e6 - 35e6, 50.0);                      // 20 km square less it
}

TEST(TerrainGen, GroundIsContinuousAcrossTileAndAreaBorders) {
  // Level 0: every vertex on a tile's edge is bit-identical to the neighbouring tile's vertex at
  // the same plan position; the surround's inner ring takes every central boundary vertex.
  // Coarser levels are subsets of level 0's nodes (same heights).
  const auto& d = terrain();
  std::map<std::pair<float, float>, std::set<float>> level0;  // plan position -> heights
  std::set<std::pair<float, float>> surround;
  for (const auto& o : d.objects) {
    if (starts_with(o.name, "terrain_") && o.lod_level == 0) {
      ASSERT_EQ(o.world_from_body, glm::dmat4(1.0));
      for (const auto& p : o.mesh.positions_m)
        level0[{p.x, p.y}].insert(p.z);
    } else if (o.name == "surround_terrain") {
      for (const auto& p : o.mesh.positions_m)
        surround.insert({p.x, p.y});
    }
  }
  ASSERT_EQ(level0.size(), 241u * 337u);  // shared edge vertices merge into one grid
  for (const auto& [xy, heights] : level0)
    ASSERT_EQ(heights.size(), 1u) << "two heights at " << xy.first << ", " << xy.second;
  std::size_t boundary = 0;
  for (const auto& [xy, heights] : level0) {
    if (std::abs(xy.first) == 2500.0f || std::abs(xy.second) == 3500.0f) {
      ++boundary;
      EXPECT_TRUE(surround.count(xy)) << xy.first << ", " << xy.second;
    }
  }
  EXPECT_EQ(boundary, 2u * (240u + 336u));
  // Surround vertices on the central boundary carry the same heights.
  for (const auto& o : d.objects) {
    if (o.name != "surround_terrain")
      continue;
    for (const auto& p : o.mesh.positions_m) {
      const auto it = level0.find({p.x, p.y});
      if (it != level0.end()) {
        EXPECT_EQ(*it->second.begin(), p.z);
      }
    }
  }
  for (const auto& o : d.objects) {
    if (!starts_with(o.name, "terrain_") || o.lod_level == 0)
      continue;
    for (const auto& p : o.mesh.positions_m) {
      const auto it = level0.find({p.x, p.y});
      ASSERT_NE(it, level0.end()) << o.name;
      ASSERT_EQ(*it->second.begin(), p.z) << o.name;
    }
  }
}

TEST(TerrainGen, WaterIsFlatAndFlowsDownhill) {
  const auto& d = terrain();
  for (const auto& o : d.objects) {
    if (o.name == "lake" || o.name == "surround_lake") {
      for (const auto& p : o.mesh.positions_m)
        EXPECT_EQ(p.z, o.mesh.positions_m[0].z) << o.name;
    }
    if (o.name == "river") {
      // Quads south to north, flat across: the level never rises downstream.
      double previous = 1e9, previous_y = -1e9;
      for (std::size_t t = 0; t < o.mesh.triangles.size(); t += 2) {
        glm::dvec3 lo(1e9), hi(-1e9);
        for (std::size_t k = t; k < t + 2; ++k) {
          for (int v = 0; v < 3; ++v) {
            lo = glm::min(lo, world(o, o.mesh.positions_m[o.mesh.triangles[k][v]]));
            hi = glm::max(hi, world(o, o.mesh.positions_m[o.mesh.triangles[k][v]]));
          }
        }
        ASSERT_GT(lo.y, previous_y - 20.0);
        ASSERT_LE(hi.z, previous + 1e-3);
        previous = lo.z;
        previous_y = lo.y;
      }
    }
  }
}

TEST(TerrainGen, FeaturesSitOnTheGroundAsRaysSeeThem) {
  // Cast vertical rays through the full-detail scene (Embree): draped features must not be
  // buried under the ground, water must be the first thing seen over the lake and the river,
  // wires must clear the ground, and the bridge must span the river with clearance.
  const sc::Scene scene(full_detail(terrain()));
  const auto& desc = scene.description();
  auto down = [&](glm::dvec2 p, sc::Hit& hit) {
    sc::Ray r;
    r.origin_m = {p.x, p.y, 1000.0};
    r.direction = {0, 0, -1};
    return scene.intersect(r, hit);
  };
  auto hit_name = [&](const sc::Hit& h) { return desc.objects[h.object_id].name; };
  auto hit_material = [&](const sc::Hit& h) { return desc.materials[h.material_id].name; };
  std::size_t roads = 0, river = 0, under_bridge = 0, buildings = 0, trees = 0, lake = 0;
  for (const auto& o : desc.objects) {
    const std::string kind = sc::object_kind(o.name);
    if (kind == "road" || kind == "track" || o.name == "river") {
      for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
        if (material_of(desc, o, t) == "gravel" && kind == "road")
          continue;  // embankment walls
        glm::dvec3 c(0.0);
        for (int k = 0; k < 3; ++k)
          c += world(o, o.mesh.positions_m[o.mesh.triangles[t][k]]) / 3.0;
        sc::Hit h;
        ASSERT_TRUE(down(c, h));
        const std::string m = hit_material(h), n = sc::object_kind(hit_name(h));
        if (o.name == "river") {
          ++river;
          ASSERT_TRUE(n == "river" || n == "bridge" || n == "wire") << "river covered by " << n;
          if (n == "bridge") {
            ++under_bridge;
            sc::Ray up;  // from the water up to the deck: the clearance
            up.origin_m = {c.x, c.y, h.position_m.z - 1.0};
            up.origin_m.z = c.z + 0.01;
            up.direction = {0, 0, 1};
            sc::Hit u;
            ASSERT_TRUE(scene.intersect(up, u));
            EXPECT_EQ(hit_name(u), "bridge");
            EXPECT_GT(u.t_m, 4.0);
          }
        } else {
          ++roads;
          ASSERT_TRUE(m == "asphalt" || m == "gravel" || n == "bridge" || n == "wire")
              << o.name << " covered by " << hit_name(h) << " (" << m << ") at " << c.x << ", "
              << c.y;
        }
      }
    } else if (kind == "building" || kind == "tree") {
      const glm::dvec3 base(o.world_from_body[3]);
      sc::Hit h;
      ASSERT_TRUE(down(glm::dvec2(base), h));
      ASSERT_EQ(hit_name(h), o.name) << "buried or covered: " << o.name;
      ++(kind == "tree" ? trees : buildings);
    } else if (kind == "wire") {
      // Lowest point of the conductor away from its pylons, then straight down to the ground.
      const glm::dvec3 start = world(o, o.mesh.positions_m.front());
      const glm::dvec3 end = world(o, o.mesh.positions_m.back());
      glm::dvec3 low(0, 0, 1e9);
      for (const auto& p : o.mesh.positions_m) {
        const glm::dvec3 w = world(o, p);
        if (glm::length(glm::dvec2(w - start)) > 30.0 && glm::length(glm::dvec2(w - end)) > 30.0 &&
            w.z < low.z)
          low = w;
      }
      ASSERT_LT(low.z, 1e9) << o.name;
      sc::Ray r;
      r.origin_m = low - glm::dvec3(0, 0, 0.1);
      r.direction = {0, 0, -1};
      sc::Hit h;
      ASSERT_TRUE(scene.intersect(r, h))
          << o.name << " at " << low.x << ", " << low.y << ", " << low.z;
      EXPECT_GT(h.t_m, 10.0) << o.name << " sags to " << h.t_m << " m over " << hit_name(h);
    } else if (o.name == "lake") {
      // Well inside the shore (70 % of the way out), the water is what the radar sees.
      const glm::dvec3 centre(o.world_from_body[3]);
      for (std::size_t v = 1; v < o.mesh.positions_m.size(); ++v) {
        const glm::dvec3 w = world(o, o.mesh.positions_m[v]);
        sc::Hit h;
        ASSERT_TRUE(down(glm::dvec2(centre + 0.7 * (w - centre)), h));
        EXPECT_EQ(hit_name(h), "lake");
        ++lake;
      }
    }
  }
  EXPECT_GT(roads, 1000u);
  EXPECT_GT(river, 1000u);
  EXPECT_GT(under_bridge, 0u);
  EXPECT_GT(buildings, 20u);
  EXPECT_GT(trees, 500u);
  EXPECT_EQ(lake, 96u);
}

TEST(TerrainGen, RejectsOutOfRangeSpecs) {
  sc::TerrainSpec spec;
  spec.central_triangles = 100'000;  // less than the ground alone
  EXPECT_THROW((void)sc::generate_terrain(spec), std::invalid_argument);
  spec = {};
  spec.relief_m = -1.0;
  EXPECT_THROW((void)sc::generate_terrain(spec), std::invalid_argument);
  spec.relief_m = std::nan("");
  EXPECT_THROW((void)sc::generate_terrain(spec), std::invalid_argument);
}
