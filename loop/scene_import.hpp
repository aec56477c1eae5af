#pragma once
// The one path from GIS inputs (a DEM, land cover, OpenStreetMap, an anchor) to a scene database:
// `radar-emu scene import` (tools/scene_import.hpp) and a scenario's or a SAR case's
// [scene.import] table (loop/scenario.hpp, GeodataSource) both build their
// scene::geodata::ImportSpec here and import it with scene::geodata::import_geodata, so a
// scenario that names the files gets exactly the database the command would have written.
// Setup only (reads files, allocates). Without GDAL and PROJ at build time every function
// throws std::runtime_error saying so.
//
// Class tables (land-cover code -> catalogue material) are TOML files (examples/landcover/):
//
//   [classes]
//   name = "ESA WorldCover 10 m v200"   # reports
//   fallback = "grass"                  # optional: unknown codes and no-data; absent: error
//   [[class]]
//   code = 10                           # the raster's value
//   label = "Tree cover"                # documentation only
//   material = "forest"                 # a radar terrain catalogue name

#include <string>

#include "loop/scenario.hpp"
#include "scene/geodata/import.hpp"
#include "scene/types.hpp"

namespace radar_emu::loop {

/// Reads a class table (format above); material names are checked against the radar terrain
/// catalogue. Throws config::ConfigError "FILE: [table] key: what".
[[nodiscard]] scene::geodata::ClassTable load_class_table(const std::string& path);

/// The import spec of `source`: its class table read, its numbers and names checked (throws
/// std::invalid_argument naming the GeodataSource field: an anchor beyond +-89 deg latitude or
/// +-180 deg longitude, land cover without a class table, an unknown datum or default material).
/// No progress callback is set.
[[nodiscard]] scene::geodata::ImportSpec import_spec(const GeodataSource& source);

/// import_geodata(import_spec(source), report): the database a scenario's [scene.import] names.
[[nodiscard]] scene::SceneDescription import_scene(const GeodataSource& source,
                                                   scene::geodata::ImportReport& report);

}  // namespace radar_emu::loop
