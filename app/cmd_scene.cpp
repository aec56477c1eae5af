// `radar-emu scene gen|info|preview|target`: scene databases and canonical targets. The target's
// option table and cross-checks are in app/cmd_scene_target.cpp; the work is tools/scene.hpp's.

#include <memory>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_checks.hpp"
#include "tools/scene.hpp"
#include "tools/scene_import.hpp"

namespace radar_emu::app {

namespace {

void add_scene_import_command(CLI::App& scene, Commands& commands) {
  using config::in_range;
  using config::output_file;
  auto o = std::make_shared<tools::SceneImportOptions>();
  CLI::App* cmd = scene.add_subcommand(
      "import",
      "Build a scene database (glTF) from GIS files: a DEM (any GDAL raster), an optional "
      "land-cover raster with a class -> material table, optional OpenStreetMap features. "
      "The result is a tiled terrain with levels of detail like `scene gen terrain`: a fine "
      "central area inside a coarser surround, in ENU metres around --anchor, heights on the "
      "WGS84 ellipsoid. Load it with [scene] file = \"OUT\". The size and memory are estimated "
      "first and the import is refused past --max-memory-mib; progress goes to stderr.");
  cmd->add_option("--dem", o->dem, "DEM raster (GeoTIFF, DTED, ...; heights in m or ft)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--anchor", o->anchor,
                  "LAT,LON [deg]: origin of the scene (ENU), the centre of both areas; must "
                  "lie on the DEM")
      ->required();
  cmd->add_option("--out", o->out, "Output scene: .glb or .gltf")
      ->check(output_file({".glb", ".gltf"}));
  cmd->add_option("--central", o->central,
                  "EAST,NORTH [m]: central area extent (default 5000,7000)");
  cmd->add_option("--cell-m", o->cell_m, "Central grid cell side [m] (default 5)")
      ->check(in_range(0.0, 1000.0, "m", true, false));
  cmd->add_option("--surround-m", o->surround_m,
                  "Surround square side [m] (default 0: no surround); >= the central sides")
      ->check(in_range(0.0, 40000.0, "m", false, false));
  cmd->add_option("--surround-cell-m", o->surround_cell_m,
                  "Surround grid cell side [m] (default 30)")
      ->check(in_range(0.0, 5000.0, "m", true, false));
  cmd->add_option("--surround-dem", o->surround_dem,
                  "Coarser DEM for the surround (default: --dem)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--landcover", o->landcover, "Land-cover raster (class codes)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--classes", o->classes,
                  "Class -> material table (TOML; shipped: examples/landcover/esa_worldcover.toml, "
                  "examples/landcover/corine_clc.toml)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--osm", o->osm,
                  "OpenStreetMap file (.osm XML or .pbf): roads, runways, taxiways, aprons, "
                  "buildings (height, else building:levels x 3 m, else 6 m), water, forest, "
                  "power lines, masts")
      ->check(CLI::ExistingFile);
  cmd->add_option("--datum", o->datum,
                  "Vertical datum of the DEM heights: file (as the file states; none stated: "
                  "EGM96, as SRTM and DTED), egm96, ellipsoid (default file)")
      ->check(CLI::IsMember({"file", "egm96", "ellipsoid"}));
  cmd->add_option("--default-material", o->default_material,
                  "Material of cells without land cover or OSM area (default grass)");
  cmd->add_option("--tile-cells", o->tile_cells,
                  "Cells along a tile side (default 64; a multiple of 2^(levels-1))")
      ->check(CLI::Range(2, 1024));
  cmd->add_option("--lod-levels", o->lod_levels, "Levels of detail, 1..4 (default 3)")
      ->check(CLI::Range(1, 4));
  cmd->add_option("--max-memory-mib", o->max_memory_mib,
                  "Refuse when the estimated import or load memory exceeds this (default 8192)")
      ->check(in_range(0.0, 1e7, "MiB", true, false));
  cmd->add_flag("--dry-run", o->dry_run, "Print the estimate only");
  cmd->add_flag("-q,--quiet", o->quiet, "No report (the estimate and errors are still printed)");
  commands.push_back({cmd, [o] {
                        if (!o->dry_run && o->out.empty())
                          throw std::invalid_argument("--out: required (unless --dry-run)");
                        OfflineRun run("scene import", "rows", o->quiet);
                        o->control = run.control();
                        return run.finish(tools::run_scene_import(*o),
                                          "the tiles done are in " + o->out +
                                              ", marked incomplete (scene info shows it)");
                      }});
}

}  // namespace

void add_scene_commands(CLI::App& app, Commands& commands) {
  CLI::App* scene = app.add_subcommand("scene", "Scene databases and canonical targets");
  scene->require_subcommand(1);
  add_scene_target_command(*scene, commands);
  using config::in_range;
  using config::output_file;
  auto gen_options = std::make_shared<tools::SceneGenOptions>();
  auto info_options = std::make_shared<tools::SceneInfoOptions>();
  auto preview_options = std::make_shared<tools::ScenePreviewOptions>();
  CLI::App* gen = scene->add_subcommand(
      "gen", "Generate a scene database into glTF: terrain (scene/terrain_gen.hpp) or airport");
  gen->add_option("kind", gen_options->kind, "terrain|airport")->required();
  gen->add_option("--seed", gen_options->seed,
                  "Seed of every random choice, 0..2^64-1 (default 1): same seed, same file");
  gen->add_option("--out", gen_options->out, "Output file: .glb or .gltf")
      ->required()
      ->check(output_file({".glb", ".gltf"}));
  gen->add_flag("-q,--quiet", gen_options->quiet, "No summary (warnings are still printed)");

  CLI::App* info = scene->add_subcommand(
      "info", "Polygon counts (per material, area, LOD level), extent and objects of a glTF scene");
  info->add_option("file", info_options->file, "Scene: .glb or .gltf")->required();
  info->add_flag("--json", info_options->json, "One JSON object instead of the table");

  CLI::App* preview = scene->add_subcommand(
      "preview", "Render an optical preview PNG of a glTF scene (sun-lit material colours)");
  tools::ScenePreviewOptions& p = *preview_options;
  preview->add_option("file", p.file, "Scene: .glb or .gltf")->required();
  preview->add_option("--out", p.out, "Output PNG")->required()->check(output_file({".png"}));
  preview->add_option("--camera", p.camera,
                      "Camera position E,N,U [m] (default: oblique overview from the south-west)");
  preview->add_option("--look-at", p.look_at, "Point looked at E,N,U [m]");
  preview
      ->add_option("--fov-deg", p.fov_deg,
                   "Vertical field of view in (0, 180) deg (default: the overview camera's 40)")
      ->check(in_range(0.0, 180.0, "deg", true, true));
  preview->add_option("--width", p.width_px, "Image width [pixels] (default 1024)")
      ->check(CLI::Range(1, 16384));
  preview->add_option("--height", p.height_px, "Image height [pixels] (default 768)")
      ->check(CLI::Range(1, 16384));
  preview->add_flag("-q,--quiet", p.quiet, "No summary (warnings are still printed)");
  add_scene_import_command(*scene, commands);
  commands.push_back({gen, [gen_options] {
                        OfflineRun run("scene gen", "stages", gen_options->quiet);
                        gen_options->control = run.control();
                        return run.finish(
                            tools::run_scene_gen(*gen_options),
                            "the scene was generated whole and is written to " + gen_options->out);
                      }});
  commands.push_back({info, [info_options] { return tools::run_scene_info(*info_options); }});
  commands.push_back(
      {preview, [preview_options] { return tools::run_scene_preview(*preview_options); }});
}

}  // namespace radar_emu::app
