// A scenario's [scene.import] (loop/scene_import.hpp) against `radar-emu scene import`, and the
// run's report of the import, over the shipped Olinda example (imports of 0.5 s and a two-frame
// run: not in the sanitize label).

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "scene/gltf.hpp"
#include "tools/scene_import.hpp"

namespace radar_emu::loop {
namespace {

std::string source(const std::string& rel) {
  const char* dir = std::getenv("RADAR_EMU_SOURCE_DIR");
  return (std::filesystem::path(dir ? dir : ".") / rel).string();
}

// "The same from a scenario's [scene]": the shipped Olinda scenario names the GIS files in
// [scene.import]; the database the loop builds from it equals, object by object and vertex by
// vertex, the .glb that `radar-emu scene import` writes with the options in the example's
// header comment (read back by the glTF loader, as a scenario's `file` would be).
TEST(SceneImportScenario, EqualsTheCommandsDatabase) {
  const Scenario s = load_scenario(source("examples/geodata/olinda_approach.toml"));
  ASSERT_TRUE(s.scene_import.has_value());
  const scene::SceneDescription from_scenario = scene_description(s);

  const auto glb = std::filesystem::temp_directory_path() / "radar_emu_olinda_cli.glb";
  tools::SceneImportOptions o;
  o.dem = source("examples/geodata/olinda_dem_utm25s.tif");
  o.osm = source("examples/geodata/olinda_airstrip.osm");
  o.anchor = "-8.005,-34.878";
  o.central = "4000,4000";
  o.cell_m = 10.0;
  o.surround_m = 7500.0;
  o.surround_cell_m = 45.0;
  o.out = glb.string();
  o.quiet = true;
  ASSERT_EQ(tools::run_scene_import(o), 0);
  const scene::SceneDescription from_command = scene::load_gltf(glb);

  EXPECT_NEAR(from_scenario.anchor.latitude_rad, from_command.anchor.latitude_rad, 1e-12);
  EXPECT_NEAR(from_scenario.anchor.longitude_rad, from_command.anchor.longitude_rad, 1e-12);
  EXPECT_NEAR(from_scenario.anchor.height_m, from_command.anchor.height_m, 1e-6);
  ASSERT_EQ(from_scenario.objects.size(), from_command.objects.size());
  std::size_t triangles = 0;
  for (std::size_t i = 0; i < from_command.objects.size(); ++i) {
    const scene::ObjectDesc& a = from_scenario.objects[i];
    const scene::ObjectDesc& b = from_command.objects[i];
    ASSERT_EQ(a.name, b.name);
    EXPECT_EQ(a.lod_group, b.lod_group) << a.name;
    EXPECT_EQ(a.lod_level, b.lod_level) << a.name;
    ASSERT_EQ(a.mesh.triangles.size(), b.mesh.triangles.size()) << a.name;
    ASSERT_EQ(a.mesh.positions_m.size(), b.mesh.positions_m.size()) << a.name;
    for (std::size_t v = 0; v < a.mesh.positions_m.size(); ++v)
      ASSERT_EQ(a.mesh.positions_m[v], b.mesh.positions_m[v]) << a.name << " vertex " << v;
    for (std::size_t t = 0; t < a.mesh.triangles.size(); ++t) {
      ASSERT_EQ(a.mesh.triangles[t], b.mesh.triangles[t]) << a.name << " triangle " << t;
      ASSERT_EQ(from_scenario.materials[a.mesh.triangle_material[t]].name,
                from_command.materials[b.mesh.triangle_material[t]].name)
          << a.name << " triangle " << t;
    }
    triangles += a.mesh.triangles.size();
  }
  std::printf("[scene.import] = scene import: %zu objects, %zu triangles identical\n",
              from_command.objects.size(), triangles);
  EXPECT_GT(triangles, 100000u);
}

// The loop reports how the import converted the heights (report.json "scene"."import"): the
// Olinda tile states no vertical datum, so EGM96 is assumed and said to be; the anchor's
// ellipsoidal height is the scene's own anchor height.
TEST(SceneImportScenario, TheRunReportsTheImport) {
  Scenario s = load_scenario(source("examples/geodata/olinda_approach.toml"));
  s.frames = 2;
  ClosedLoop loop(s, {});
  const RunResult r = loop.run();
  const RunReport report = loop.report(r);
  ASSERT_TRUE(report.scene.import.has_value());
  const SceneFigures::Import& im = *report.scene.import;
  std::printf("import: %s; anchor %.3f m (N %.3f m), %.2f s\n", im.vertical.c_str(),
              im.anchor_height_m, im.anchor_undulation_m, im.seconds);
  EXPECT_NE(im.vertical.find("EGM96"), std::string::npos) << im.vertical;
  EXPECT_NE(im.vertical.find("assumed"), std::string::npos) << im.vertical;
  EXPECT_NE(im.anchor_undulation_m, 0.0);
  EXPECT_EQ(im.dem_holes_filled, 0u);
  EXPECT_EQ(im.osm_broken_ways, 0u);
  EXPECT_NEAR(im.anchor_height_m, scene_description(s).anchor.height_m, 1e-9);
}

}  // namespace
}  // namespace radar_emu::loop
