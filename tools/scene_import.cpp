#include "tools/scene_import.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "common/units.hpp"
#include "config/cli_args.hpp"
#include "config/toml_reader.hpp"
#include "radar/em/surfaces.hpp"
#include "scene/gltf.hpp"

#if RADAR_EMU_HAVE_GEODATA
#include "scene/geodata/import.hpp"
#endif

namespace radar_emu::tools {
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

int run_scene_import(const SceneImportOptions& o) {
  scene::geodata::ImportSpec spec;
  spec.dem = o.dem;
  spec.surround_dem = o.surround_dem;
  spec.osm = o.osm;
  if (!o.landcover.empty()) {
    if (o.classes.empty())
      throw std::invalid_argument("--landcover: needs --classes TABLE.toml");
    spec.landcover = o.landcover;
    spec.classes = load_class_table(o.classes);
  }
  const auto [lat_deg, lon_deg] = config::parse_pair(o.anchor, "--anchor");
  if (std::abs(lat_deg) >= 89.0 || std::abs(lon_deg) > 180.0)
    throw std::invalid_argument("--anchor: latitude within +-89 deg, longitude within +-180 deg");
  spec.anchor_latitude_rad = common::radians(lat_deg);
  spec.anchor_longitude_rad = common::radians(lon_deg);
  const auto [east_m, north_m] = config::parse_pair(o.central, "--central");
  spec.central_east_m = east_m;
  spec.central_north_m = north_m;
  spec.central_cell_m = o.cell_m;
  spec.surround_side_m = o.surround_m;
  spec.surround_cell_m = o.surround_cell_m;
  spec.tile_cells = o.tile_cells;
  spec.lod_levels = o.lod_levels;
  if (!radar::is_surface_material(o.default_material))
    throw std::invalid_argument("--default-material: \"" + o.default_material +
                                "\" is not a radar terrain material");
  spec.default_material = o.default_material;
  spec.datum = o.datum == "egm96"       ? scene::geodata::DatumChoice::kEgm96
               : o.datum == "ellipsoid" ? scene::geodata::DatumChoice::kEllipsoid
                                        : scene::geodata::DatumChoice::kFromFile;
  spec.max_memory_bytes = static_cast<std::uint64_t>(o.max_memory_mib * 1048576.0);
  spec.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };

  const scene::geodata::ImportEstimate e = scene::geodata::estimate_import(spec);
  std::printf(
      "estimate: %llu central + %llu surround nodes, %llu triangles (all LOD levels), %llu "
      "vertices: %.0f MiB to import, %.0f MiB loaded (limit %.0f MiB)\n",
      static_cast<unsigned long long>(e.central_nodes),
      static_cast<unsigned long long>(e.surround_nodes),
      static_cast<unsigned long long>(e.triangles), static_cast<unsigned long long>(e.vertices),
      static_cast<double>(e.import_bytes) / 1048576.0,
      static_cast<double>(e.load_bytes) / 1048576.0, o.max_memory_mib);
  if (o.dry_run)
    return 0;
  scene::geodata::ImportReport report;
  const scene::SceneDescription d = scene::geodata::import_geodata(spec, report);
  const auto t0 = std::chrono::steady_clock::now();
  std::fprintf(stderr, "import: writing %s\n", o.out.c_str());
  scene::write_gltf(d, o.out);
  const double write_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.quiet) {
    std::printf("%s", scene::geodata::report_text(report).c_str());
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(o.out, ec);
    std::printf("%s: %zu objects, written in %.2f s (%.1f MB)\n", o.out.c_str(), d.objects.size(),
                write_s, ec ? 0.0 : static_cast<double>(bytes) / 1e6);
  }
  return 0;
}

#else

scene::geodata::ClassTable load_class_table(const std::string&) {
  throw std::runtime_error("scene import: built without GDAL and PROJ (scripts/install-deps.sh)");
}
int run_scene_import(const SceneImportOptions&) {
  throw std::runtime_error("scene import: built without GDAL and PROJ (scripts/install-deps.sh)");
}

#endif

}  // namespace radar_emu::tools
