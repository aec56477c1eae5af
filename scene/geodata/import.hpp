#pragma once
// Real geography in: a scene database (scene/types.hpp) from standard GIS files, in the shape of
// the generated terrain (scene/terrain_gen.hpp) so that the loop, `image` and `sar` use it
// unchanged.
//
// Inputs: a DEM (any GDAL raster), optionally a coarser DEM for the surround, a land-cover raster
// with a class -> material table, and OpenStreetMap features (GDAL's OSM driver).
//
// Frame: ENU metres around the anchor (latitude, longitude chosen by the caller; its height is
// the terrain's ellipsoidal height there, so the ground at the anchor is z = 0). A grid node
// (x, y) takes the terrain height at the geodetic point under it: the node is mapped to latitude
// and longitude with EnuFrame::geodetic_from_enu at the node's height (two passes: the first at
// z = 0), the DEM is sampled there bilinearly (pixel centres, scene/geodata/raster.hpp), the
// height converted to the ellipsoid (EGM96: h = H + N through PROJ) and mapped back to ENU z.
//
// Shape (areas as scene/terrain_gen.hpp names them):
//   terrain_rRR_cCC_lodL    central   square cells of `central_cell_m` over central_east_m x
//                                     central_north_m centred on the anchor, in tiles of
//                                     tile_cells x tile_cells cells (row RR from the south,
//                                     column CC from the west), each at lod_levels levels (level
//                                     L takes every 2^L-th node, the tile's last node always);
//                                     lod_group = a running tile number
//   surround_rRR_cCC_lodL   surround  the same over the surround_side_m square at
//                                     surround_cell_m, minus the cells entirely inside the
//                                     central area (cells straddling its edge are kept: the two
//                                     grids overlap by under one surround cell there, both on the
//                                     same DEM)
//   road_K, runway_K, taxiway_K       strips draped_offset_m above the DEM's bilinear surface
//                                     (vertices every half central cell), lifted to the level-0
//                                     mesh where it lies higher (valleys): never under the ground
//   building_K              central   footprints extruded from the lowest ground under them to
//                                     `height` (m), else `building:levels` x level_height_m, else
//                                     default_levels x level_height_m (counted); walls and a flat
//                                     roof (inner courtyards are roofed over: counted)
//   pylon_K, wire_S_C                 power=line ways: a pylon at each vertex (`height` or 30 m),
//                                     three conductors per span sagging 2 % of the span
//   mast_K                            man_made=mast|tower|communications_tower nodes, `height`
//                                     or 30 m
// Cell materials: land cover at the cell centre (nearest pixel) through the class table, else
// default_material; OSM areas override them (water, forest / wood, farmland, grass / meadow,
// residential / industrial, apron): a cell whose centre lies inside the area takes its material.
// Materials are names of the radar terrain catalogue (radar/em/surfaces.hpp resolves them).
//
// Bad input (one-line std::runtime_error "FILE: what", or a counted fallback in ImportReport):
//   no georeference, no transformation to WGS84, an unsupported vertical CRS: error;
//   DEM no-data: filled from valid neighbours (ImportReport::dem_holes_filled);
//   a grid node outside the DEM (central or surround): error naming the node and the DEM;
//   the anchor outside the DEM: error;
//   a land-cover class missing from the table: error, or the table's fallback material when it
//   names one (ImportReport::unknown_class_cells); land-cover no-data: the same fallback;
//   OSM ways with missing nodes or fewer than two: dropped (ImportReport::osm_broken_ways);
//   OSM features off the terrain: dropped (ImportReport::osm_outside).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/work_control.hpp"
#include "scene/geodata/raster.hpp"
#include "scene/types.hpp"

namespace radar_emu::scene::geodata {

/// Land-cover class code -> catalogue material name.
struct ClassTable {
  std::string name;  ///< e.g. "ESA WorldCover 2021 v200" (reports)
  std::map<std::int64_t, std::string> material_by_class;
  std::optional<std::string> fallback;  ///< unknown codes and no-data; none: error
};

/// How the file's heights are taken.
enum class DatumChoice : std::uint8_t {
  kFromFile,   ///< the datum the file states; unstated: EGM96 (as SRTM, DTED; reported)
  kEgm96,      ///< EGM96 whatever the file states
  kEllipsoid,  ///< WGS84 ellipsoidal whatever the file states
};

struct ImportSpec {
  std::filesystem::path dem;           ///< central (and, without surround_dem, surround) DEM
  std::filesystem::path surround_dem;  ///< optional coarser DEM for the surround
  std::filesystem::path landcover;     ///< optional land-cover raster (class codes)
  ClassTable classes;                  ///< required with `landcover`
  std::filesystem::path osm;           ///< optional OpenStreetMap file (.osm / .pbf)
  double anchor_latitude_rad = 0.0;    ///< origin of the ENU frame
  double anchor_longitude_rad = 0.0;
  DatumChoice datum = DatumChoice::kFromFile;

  double central_east_m = 5000.0;   ///< central area width (x), centred on the anchor, > 0
  double central_north_m = 7000.0;  ///< central area height (y), > 0
  double central_cell_m = 5.0;      ///< central grid cell side, > 0
  double surround_side_m = 0.0;     ///< surround square side; 0: no surround
  double surround_cell_m = 30.0;    ///< surround grid cell side, > 0
  int tile_cells = 64;              ///< cells along a tile side, a multiple of 2^(lod_levels-1)
  int lod_levels = 3;               ///< 1 .. 4

  std::string default_material = "grass";  ///< cells without land cover or OSM area
  double draped_offset_m = 0.05;           ///< roads above the level-0 ground
  double level_height_m = 3.0;             ///< per building level
  double default_levels = 2.0;             ///< buildings with neither height nor levels
  double pylon_height_m = 30.0;            ///< pylons without `height`
  double mast_height_m = 30.0;             ///< masts without `height`

  /// Refuse (before any file is read) when the estimated memory exceeds this [bytes].
  std::uint64_t max_memory_bytes = 8ull << 30;
  /// Progress lines (stderr in the CLI); may be empty.
  std::function<void(const std::string&)> progress;
  /// Progress in rows (the height grids' node rows, then the rows of tiles) and the stop flag,
  /// polled between height rows and before the OpenStreetMap stages. A stop ends the import
  /// with what is whole: the rows of tiles whose every node has its height, no OpenStreetMap
  /// areas or features once stopped before them; SceneDescription::incomplete then says what is
  /// missing. Empty: never stops early.
  common::WorkControl control;
};

/// Size of the terrain before building it (exact for the grids; OSM features not included).
struct ImportEstimate {
  std::uint64_t central_nodes = 0;
  std::uint64_t surround_nodes = 0;
  std::uint64_t triangles = 0;  ///< every LOD level
  std::uint64_t vertices = 0;
  /// Peak memory of the import [bytes]: heights and materials of both grids, the meshes, and
  /// the DEM rasters are not included (bounded by their file size).
  std::uint64_t import_bytes = 0;
  /// Memory of the loaded scene [bytes]: meshes plus Embree BVHs (about 64 B a triangle).
  std::uint64_t load_bytes = 0;
};

struct ImportReport {
  std::string vertical;  ///< how heights were converted, e.g. "EGM96 geoid (file) -> ellipsoid"
  double anchor_height_m = 0.0;      ///< ellipsoidal height of the anchor (ground)
  double anchor_undulation_m = 0.0;  ///< EGM96 N at the anchor (0 when not used)
  double dem_spacing_m = 0.0;
  std::size_t dem_holes_filled = 0;
  std::size_t unknown_class_cells = 0;  ///< level-0 cells given the fallback (unknown / no-data)
  std::map<std::int64_t, std::size_t> cells_by_class;    ///< level-0 central + surround cells
  std::map<std::string, std::size_t> cells_by_material;  ///< level-0 cells, after OSM areas
  std::size_t osm_roads = 0, osm_runways = 0, osm_taxiways = 0, osm_areas = 0;
  std::size_t osm_buildings = 0, osm_buildings_height = 0, osm_buildings_levels = 0,
              osm_buildings_default = 0, osm_courtyards_roofed = 0;
  std::size_t osm_power_lines = 0, osm_pylons = 0, osm_masts = 0;
  std::size_t osm_broken_ways = 0;  ///< dropped (missing nodes, < 2 nodes)
  std::size_t osm_outside = 0;      ///< features dropped off the terrain
  std::size_t osm_ignored = 0;      ///< tagged features the import does not model
  ImportEstimate estimate;
  double seconds = 0.0;
};

/// Checks the spec's numbers and returns the size estimate. Throws std::invalid_argument naming
/// the field for an invalid spec, and std::runtime_error with the estimate when it is over
/// spec.max_memory_bytes. Reads no file.
[[nodiscard]] ImportEstimate estimate_import(const ImportSpec& spec);

/// Builds the database (layout at the top of this header). Throws as described there. Setup
/// only (allocates, reads files).
[[nodiscard]] SceneDescription import_geodata(const ImportSpec& spec, ImportReport& report);

/// A human-readable summary of the report (several lines).
[[nodiscard]] std::string report_text(const ImportReport& report);

}  // namespace radar_emu::scene::geodata
