#pragma once
// `radar-emu scene import`: a scene database from GIS files (scene/geodata/import.hpp) into glTF,
// which scenarios then load with [scene] file = "..." (the loop, `image` and `sar` unchanged).
// The class -> material table is a TOML file (examples/landcover/*.toml; format in
// loop/scene_import.hpp, whose import path the command shares with [scene.import]).
//
// Errors are exceptions whose message is one line naming the option or file.

#include <optional>
#include <string>

#include "common/work_control.hpp"

namespace radar_emu::tools {

struct SceneImportOptions {
  std::string dem;                    ///< GDAL raster (GeoTIFF, DTED, ...)
  std::string surround_dem;           ///< optional coarser raster for the surround
  std::string landcover;              ///< optional land-cover raster
  std::string classes;                ///< class table TOML (required with landcover)
  std::string osm;                    ///< optional .osm / .pbf
  std::string anchor;                 ///< "LAT,LON" [deg]
  std::string central = "5000,7000";  ///< "EAST,NORTH" extent [m]
  double cell_m = 5.0;
  double surround_m = 0.0;  ///< 0: none
  double surround_cell_m = 30.0;
  std::string datum = "file";  ///< file | egm96 | ellipsoid
  int tile_cells = 64;
  int lod_levels = 3;
  std::string default_material = "grass";
  double max_memory_mib = 8192.0;
  std::string out;       ///< .glb / .gltf
  bool dry_run = false;  ///< estimate only
  bool quiet = false;
  /// Progress in rows (height rows, then rows of tiles), the stage lines (note) and the stop
  /// flag (app/cmd_scene.cpp draws and sets them).
  common::WorkControl control;
};

/// Estimates, refuses past the memory limit, imports (progress on stderr), writes `out` and
/// prints the report. Returns 0; throws on bad options, bad input, I/O failure. A stop request
/// (options.control) ends the import with what is whole (scene/geodata/import.hpp): the scene is
/// written all the same, marked incomplete (glTF scene extras radar_emu.incomplete, shown by
/// `scene info` and warned of when loaded), and 128 + the signal is returned.
int run_scene_import(const SceneImportOptions& options);

}  // namespace radar_emu::tools
