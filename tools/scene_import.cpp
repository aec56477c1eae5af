#include "tools/scene_import.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "common/units.hpp"
#include "config/cli_args.hpp"
#include "loop/scene_import.hpp"
#include "radar/em/surfaces.hpp"
#include "scene/gltf.hpp"

#if RADAR_EMU_HAVE_GEODATA
#include "scene/geodata/import.hpp"
#endif

namespace radar_emu::tools {
#if RADAR_EMU_HAVE_GEODATA

int run_scene_import(const SceneImportOptions& o) {
  // The command's options as a [scene.import] table would give them: one import path
  // (loop/scene_import.hpp) for the command and the scenarios.
  loop::GeodataSource g;
  g.dem = o.dem;
  g.surround_dem = o.surround_dem;
  g.osm = o.osm;
  if (!o.landcover.empty() && o.classes.empty())
    throw std::invalid_argument("--landcover: needs --classes TABLE.toml");
  g.landcover = o.landcover;
  g.classes = o.classes;
  const auto [lat_deg, lon_deg] = config::parse_pair(o.anchor, "--anchor");
  if (std::abs(lat_deg) >= 89.0 || std::abs(lon_deg) > 180.0)
    throw std::invalid_argument("--anchor: latitude within +-89 deg, longitude within +-180 deg");
  g.anchor_latitude_rad = common::radians(lat_deg);
  g.anchor_longitude_rad = common::radians(lon_deg);
  const auto [east_m, north_m] = config::parse_pair(o.central, "--central");
  g.central_east_m = east_m;
  g.central_north_m = north_m;
  g.cell_m = o.cell_m;
  g.surround_m = o.surround_m;
  g.surround_cell_m = o.surround_cell_m;
  g.tile_cells = o.tile_cells;
  g.lod_levels = o.lod_levels;
  if (!radar::is_surface_material(o.default_material))
    throw std::invalid_argument("--default-material: \"" + o.default_material +
                                "\" is not a radar terrain material");
  g.default_material = o.default_material;
  g.datum = o.datum;
  g.max_memory_bytes = static_cast<std::uint64_t>(o.max_memory_mib * 1048576.0);
  scene::geodata::ImportSpec spec = loop::import_spec(g);
  spec.progress = [&o](const std::string& line) {
    if (o.control.note)
      o.control.note(line + "\n");  // above the progress line
    else
      std::fprintf(stderr, "%s\n", line.c_str());
  };
  spec.control = o.control;

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
  spec.progress("import: writing " + o.out + (d.incomplete.empty() ? "" : " (incomplete)"));
  scene::write_gltf(d, o.out);
  const double write_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.quiet) {
    std::printf("%s", scene::geodata::report_text(report).c_str());
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(o.out, ec);
    std::printf("%s: %zu objects, written in %.2f s (%.1f MB)%s%s\n", o.out.c_str(),
                d.objects.size(), write_s, ec ? 0.0 : static_cast<double>(bytes) / 1e6,
                d.incomplete.empty() ? "" : "; INCOMPLETE: ", d.incomplete.c_str());
  }
  return d.incomplete.empty() ? 0 : 128 + o.control.stop_signal();
}

#else

int run_scene_import(const SceneImportOptions&) {
  throw std::runtime_error("scene import: built without GDAL and PROJ (scripts/install-deps.sh)");
}

#endif

}  // namespace radar_emu::tools
