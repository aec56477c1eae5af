// `radar-emu scene gen|info|preview|target`: scene databases and canonical targets. The target's
// option table and cross-checks are in app/cmd_scene_target.cpp; the work is tools/scene.hpp's.

#include <memory>

#include "app/cmd.hpp"
#include "config/cli_checks.hpp"
#include "tools/scene.hpp"

namespace radar_emu::app {

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
  commands.push_back({gen, [gen_options] { return tools::run_scene_gen(*gen_options); }});
  commands.push_back({info, [info_options] { return tools::run_scene_info(*info_options); }});
  commands.push_back(
      {preview, [preview_options] { return tools::run_scene_preview(*preview_options); }});
}

}  // namespace radar_emu::app
