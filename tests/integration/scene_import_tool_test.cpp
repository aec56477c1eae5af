// The shipped land-cover class tables load, map the published class codes, and a bad table gets
// the reader's one-line "FILE: [table] key: what".

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "loop/scene_import.hpp"
#include "scene/geodata/import.hpp"
#include "scene/gltf.hpp"
#include "tools/scene_import.hpp"

namespace radar_emu::loop {
namespace {

std::string source(const std::string& rel) {
  const char* dir = std::getenv("RADAR_EMU_SOURCE_DIR");
  return (std::filesystem::path(dir ? dir : ".") / rel).string();
}

TEST(SceneImportTool, ShippedClassTablesLoad) {
  // ESA WorldCover v200 legend: 11 classes (10 .. 100).
  const auto wc = load_class_table(source("examples/landcover/esa_worldcover.toml"));
  EXPECT_EQ(wc.material_by_class.size(), 11u);
  EXPECT_EQ(wc.material_by_class.at(10), "forest");
  EXPECT_EQ(wc.material_by_class.at(40), "crops");
  EXPECT_EQ(wc.material_by_class.at(80), "water");
  EXPECT_EQ(wc.fallback.value_or(""), "grass");
  // CORINE Land Cover level 3: 44 classes (111 .. 523).
  const auto clc = load_class_table(source("examples/landcover/corine_clc.toml"));
  EXPECT_EQ(clc.material_by_class.size(), 44u);
  EXPECT_EQ(clc.material_by_class.at(124), "concrete");
  EXPECT_EQ(clc.material_by_class.at(311), "forest");
  EXPECT_EQ(clc.material_by_class.at(523), "water");
}

TEST(SceneImportTool, BadClassTableIsOneLine) {
  const auto path = std::filesystem::temp_directory_path() / "radar_emu_bad_classes.toml";
  std::ofstream(path) << "[classes]\nname = \"x\"\n[[class]]\ncode = 1\nmaterial = \"lava\"\n";
  try {
    (void)load_class_table(path.string());
    ADD_FAILURE() << "accepted an unknown material";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("material"), std::string::npos) << what;
    EXPECT_NE(what.find("lava"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

// "The same from a scenario's [scene]": the shipped Olinda scenario names the GIS files in
// [scene.import]; the database the loop builds from it equals, object by object and vertex by
// vertex, the .glb that `radar-emu scene import` writes with the options in the example's
// header comment (read back by the glTF loader, as a scenario's `file` would be).
TEST(SceneImportTool, ScenarioImportEqualsTheCommandsDatabase) {
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
TEST(SceneImportTool, TheRunReportsTheImport) {
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

// [scene.import] refused with the reader's one line: with another source, without its required
// keys, land cover without a class table, an unknown key.
TEST(SceneImportTool, ScenarioImportTableErrorsAreOneLine) {
  const std::string base = "[scene.import]\ndem = \"d.tif\"\nanchor_deg = [43.0, 1.0]\n";
  const std::pair<std::string, std::string> cases[] = {
      {"[scene]\nbuiltin = \"terrain\"\n" + base, "builtin"},
      {"[scene]\nfile = \"x.glb\"\n" + base, "file"},
      {"[scene.import]\nanchor_deg = [43.0, 1.0]\n", "dem"},
      {"[scene.import]\ndem = \"d.tif\"\n", "anchor_deg"},
      {base + "anchor_deg_typo = 1\n", "anchor_deg_typo"},
      {base + "landcover = \"lc.tif\"\n", "classes"},
      {"[scene.import]\ndem = \"d.tif\"\nanchor_deg = [89.5, 1.0]\n", "latitude"},
      {base + "datum = \"navd88\"\n", "navd88"},
  };
  for (const auto& [text, needle] : cases) {
    try {
      (void)parse_scenario(text, "s.toml");
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const std::exception& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("s.toml"), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace radar_emu::loop
