#include "loop/scene_import.hpp"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "common/units.hpp"
#include "config/toml_reader.hpp"
#include "radar/em/surfaces.hpp"

namespace radar_emu::loop {
#if RADAR_EMU_HAVE_GEODATA

scene::geodata::ClassTable load_class_table(const std::string& path) {
  const config::TomlFile file = config::TomlFile::load(path);
  const config::Table root = file.root();
  root.refuse_unknown({"classes", "class"});
  const config::Table head = root.table("classes");
  head.refuse_unknown({"name", "fallback"});
  scene::geodata::ClassTable t;
  t.name = std::filesystem::path(path).filename().string();
  head.string("name", t.name);
  std::string fallback;
  if (head.string("fallback", fallback)) {
    if (!radar::is_surface_material(fallback))
      head.fail("fallback", "\"" + fallback + "\" is not a radar terrain material");
    t.fallback = fallback;
  }
  const auto classes = root.tables("class");
  if (classes.empty())
    root.fail("class", "needs at least one [[class]] table");
  for (const config::Table& c : classes) {
    c.refuse_unknown({"code", "label", "material"});
    c.require("code");
    c.require("material");
    std::int64_t code = 0;
    c.integer("code", code, -2147483648LL, 2147483647LL);
    std::string material, label;
    c.string("material", material);
    c.string("label", label);
    if (!radar::is_surface_material(material))
      c.fail("material", "\"" + material + "\" is not a radar terrain material");
    if (!t.material_by_class.emplace(code, material).second)
      c.fail("code", std::to_string(code) + " appears twice");
  }
  return t;
}

scene::geodata::ImportSpec import_spec(const GeodataSource& g) {
  namespace gd = scene::geodata;
  if (!(std::abs(common::degrees(g.anchor_latitude_rad)) < 89.0) ||
      !(std::abs(common::degrees(g.anchor_longitude_rad)) <= 180.0))
    throw std::invalid_argument("anchor: latitude within +-89 deg, longitude within +-180 deg");
  gd::ImportSpec spec;
  spec.dem = g.dem;
  spec.surround_dem = g.surround_dem;
  spec.osm = g.osm;
  if (!g.landcover.empty()) {
    if (g.classes.empty())
      throw std::invalid_argument("landcover: needs a class table (classes)");
    spec.landcover = g.landcover;
    spec.classes = load_class_table(g.classes.string());
  }
  spec.anchor_latitude_rad = g.anchor_latitude_rad;
  spec.anchor_longitude_rad = g.anchor_longitude_rad;
  spec.central_east_m = g.central_east_m;
  spec.central_north_m = g.central_north_m;
  spec.central_cell_m = g.cell_m;
  spec.surround_side_m = g.surround_m;
  spec.surround_cell_m = g.surround_cell_m;
  spec.tile_cells = g.tile_cells;
  spec.lod_levels = g.lod_levels;
  if (!radar::is_surface_material(g.default_material))
    throw std::invalid_argument("default_material: \"" + g.default_material +
                                "\" is not a radar terrain material");
  spec.default_material = g.default_material;
  if (g.datum == "file")
    spec.datum = gd::DatumChoice::kFromFile;
  else if (g.datum == "egm96")
    spec.datum = gd::DatumChoice::kEgm96;
  else if (g.datum == "ellipsoid")
    spec.datum = gd::DatumChoice::kEllipsoid;
  else
    throw std::invalid_argument("datum: \"" + g.datum + "\" (known: file, egm96, ellipsoid)");
  spec.max_memory_bytes = g.max_memory_bytes;
  return spec;
}

scene::SceneDescription import_scene(const GeodataSource& source,
                                     scene::geodata::ImportReport& report) {
  return scene::geodata::import_geodata(import_spec(source), report);
}

#else

namespace {
[[noreturn]] void no_geodata() {
  throw std::runtime_error("scene import: built without GDAL and PROJ (scripts/install-deps.sh)");
}
}  // namespace
scene::geodata::ClassTable load_class_table(const std::string&) {
  no_geodata();
}
scene::geodata::ImportSpec import_spec(const GeodataSource&) {
  no_geodata();
}
scene::SceneDescription import_scene(const GeodataSource&, scene::geodata::ImportReport&) {
  no_geodata();
}

#endif
}  // namespace radar_emu::loop
