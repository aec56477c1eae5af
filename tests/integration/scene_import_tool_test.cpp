// The shipped land-cover class tables load, map the published class codes, and a bad table gets
// the reader's one-line "FILE: [table] key: what"; so does a bad [scene.import] table.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "loop/scenario.hpp"
#include "loop/scene_import.hpp"
#include "scene/geodata/import.hpp"

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
