#pragma once
// `radar-emu scene gen|info|preview|target`: generate a scene database (scene/terrain_gen.hpp,
// scene/airport_gen.hpp) into glTF, summarise one (scene/scene_info.hpp: text or one JSON
// object), render an optical preview PNG of one (scene/preview.hpp), write a canonical target
// mesh (scene/targets.hpp). The options are plain structs; app/cmd_scene*.cpp reads them from
// the command line. Errors are exceptions whose message is one line naming the option or file;
// main() prints them.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "common/work_control.hpp"
#include "scene/scene_info.hpp"
#include "scene/targets.hpp"

namespace radar_emu::tools {

struct SceneGenOptions {
  std::string kind;        ///< "terrain" or "airport"
  std::string seed = "1";  ///< decimal 0 .. 2^64-1 (text, so that errors name --seed)
  std::string out;         ///< .glb (binary) or .gltf
  bool quiet = false;
  /// Progress in stages (generate, write) and the stop flag, heard after the writing (each stage
  /// takes about a second): the scene generated is written whole all the same.
  common::WorkControl control;
};

struct SceneInfoOptions {
  std::string file;   ///< .glb / .gltf
  bool json = false;  ///< one JSON object on stdout instead of the table
};

struct ScenePreviewOptions {
  std::string file;               ///< .glb / .gltf
  std::string out;                ///< PNG
  std::string camera;             ///< "E,N,U" [m]; empty: scene::default_preview_camera's
  std::string look_at;            ///< "E,N,U" [m]; empty: the default camera's
  std::optional<double> fov_deg;  ///< vertical field of view [deg]; none: the default camera's
  int width_px = 1024;
  int height_px = 768;
  bool quiet = false;
};

/// Parses a seed: decimal digits only, 0 .. 18446744073709551615. Throws std::invalid_argument
/// "OPTION: 'TEXT' is not ...".
[[nodiscard]] std::uint64_t parse_seed(const std::string& text, const std::string& option);

/// Generates the database and writes it; prints counts and the time taken. Returns 0, or 128 +
/// the signal when options.control's stop flag was raised meanwhile (the database, whole, is
/// written first); throws on bad options (unknown kind, bad seed, output not
/// .glb/.gltf) and I/O failure.
int run_scene_gen(const SceneGenOptions& options);
/// Loads the file and prints its summary (table, or with `json` one JSON object). Returns 0.
int run_scene_info(const SceneInfoOptions& options);
/// Loads the file, renders it (scene/preview.hpp) and writes an RGB PNG. Returns 0.
int run_scene_preview(const ScenePreviewOptions& options);

/// The JSON form of `info` (one object; keys in scene_tool.cpp's order): polygons_total (every
/// LOD level), polygons_full_detail, polygons_by_lod_level ("none", "0", "1", ...),
/// polygons_by_area and polygons_by_material (full detail), polygons_by_area_all_levels,
/// objects, objects_by_kind, lod_groups, materials, vertices, extent_m {min, max}, anchor_deg_m.
[[nodiscard]] std::string scene_info_json(const scene::SceneInfo& info, const std::string& file,
                                          std::size_t load_warnings);
/// The table form of `info`.
[[nodiscard]] std::string scene_info_text(const scene::SceneInfo& info, const std::string& file,
                                          std::size_t load_warnings);

}  // namespace radar_emu::tools
