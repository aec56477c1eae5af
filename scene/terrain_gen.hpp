#pragma once
// Procedural terrain database after the seed paper (ONERA / OKTAL SE, "Realistic radar simulation
// package applied to multisensor scenarios", section "Geometrical realistic database"): "a 5 km x
// 7 km central area ... plane surfaces (crop fields, meadows, forests, lake), linear elements
// (roads, river) and punctual items (trees, man-made constructions, bridge, pylons with
// electrical wires) ... described by 200,000 polygons", enclosed by "a 20 km x 20 km surrounding
// domain ... made up of fields, a lake and a river ... 7,000 polygons".
//
// Frame: ENU metres, origin at the centre of the central area, heights relative to the anchor.
// Anchor (TerrainLayout::kAnchor*): a made-up rural site south-west of Toulouse, France,
// 43.45 deg N, 1.30 deg E, 200 m above the WGS84 ellipsoid.
//
// Layout:
//   central area  x (east) in [-2500, 2500], y (north) in [-3500, 3500]
//   surround      x, y in [-10000, 10000] minus the central area
// Ground: a gently undulating height field (six seeded sinusoids, 2.5 to 6 km wavelengths down to
// 400 m, about +-18 m, slopes under 5 %), a valley along the river, the river bed and lake basins
// cut into it. Forest parcels are the same surface raised by their canopy (kCanopy_m), with their
// edges as slopes one grid cell wide.
//
// Objects (ObjectDesc::name, area, radar materials = radar/clutter/terrain.hpp catalogue names):
//   terrain_rRR_cCC_lodL  central    the height field in 500 m x 500 m tiles (row RR from the
//                                    south, column CC from the west; lod_group = RR * 10 + CC),
//                                    each at three levels of detail: level 0 a 24 x 24 cell grid
//                                    (20.83 m), levels 1 and 2 every 2nd / 4th node of it (the
//                                    same heights). crops, grass (meadows, river banks, forest
//                                    clearings), forest, soil_dry (ploughed fields), soil_wet
//                                    (river and lake beds), urban (yards around buildings)
//   road_0 .. road_2     central    asphalt strips draped on the level-0 ground (road_0 west-east,
//                                    crossing the river on the bridge; road_1 south-north; road_2
//                                    a branch of road_1); gravel embankment walls where a road
//                                    ramps up to the bridge
//   track_0              central    a gravel farm track (when it finds room beside the river)
//   river                central    water strip 20 m wide, flat across, its level never rising
//                                    downstream (south to north)
//   lake                 central    water, a flat elliptical sheet (96-gon)
//   bridge               central    concrete deck and piers, metal railings, where road_0 crosses
//                                    the river valley
//   building_K           central    houses (concrete walls and tiled gable roof, as concrete) and
//                                    farm sheds (concrete walls, metal roof), in hamlets and
//                                    farms along the roads
//   pylon_K              central    metal lattice towers (a tapered open frustum and a cross
//                                    arm, 20 triangles) every ~300 m on a straight power line
//   wire_S_C             central    conductor C (0, 1: arm ends; 2: earth wire on top) of span S,
//                                    a metal 3-sided tube of 1.5 cm radius sagging 4 m mid-span
//   tree_K               central    isolated trees (forest material: 8-sided cone crown on a
//                                    4-sided trunk, 24 triangles), in rows along roads and
//                                    scattered over fields; their number fills the polygon budget
//   surround_terrain     surround   coarse grid (~375 m cells) whose ring next to the central area
//                                    takes the central level-0 boundary nodes (no crack there at
//                                    level 0): crops, grass, soil_dry, soil_wet
//   surround_lake        surround   water, a flat 64-gon
//   surround_river       surround   the same river outside the central area, 25 m wide
// Meshes are wound counter-clockwise seen from above / outside. Terrain tiles and the surround
// keep world coordinates (shared tile-edge vertices are bit-identical at level 0); small objects
// keep body coordinates and a translation (rotation for pylons and buildings) in
// ObjectDesc::world_from_body. LOD levels of a tile are not stitched to neighbours at other
// levels (small cracks where levels differ); draped objects sit on the level-0 surface.

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <string_view>

#include "scene/types.hpp"

namespace radar_emu::scene {

/// Fixed geometry of the generated terrain (ENU metres).
struct TerrainLayout {
  static constexpr double kAnchorLatitude_deg = 43.45;  ///< WGS84 anchor: centre of the area
  static constexpr double kAnchorLongitude_deg = 1.30;
  static constexpr double kAnchorHeight_m = 200.0;  ///< above the ellipsoid

  static constexpr double kCentralEast_m = 5000.0;    ///< central area x in [-2500, 2500]
  static constexpr double kCentralNorth_m = 7000.0;   ///< central area y in [-3500, 3500]
  static constexpr double kSurroundSide_m = 20000.0;  ///< surround x, y in [-10000, 10000]
  static constexpr double kTile_m = 500.0;            ///< tile side
  static constexpr int kTileColumns = 10;             ///< tiles west to east
  static constexpr int kTileRows = 14;                ///< tiles south to north
  static constexpr int kTileCells = 24;               ///< level-0 grid cells along a tile side
  static constexpr int kLodLevels = 3;                ///< 0 (finest), 1, 2: grid step x2 each
  static constexpr double kCanopy_m = 12.0;           ///< forest canopy above the ground
  static constexpr double kRiverWidth_m = 20.0;       ///< central river width
  /// Central area projected area [m^2] (what the level-0 tiles cover exactly).
  static constexpr double kCentralArea_m2 = kCentralEast_m * kCentralNorth_m;
  /// Surround projected area [m^2] (the 20 km square minus the central area).
  static constexpr double kSurroundArea_m2 = kSurroundSide_m * kSurroundSide_m - kCentralArea_m2;
};

struct TerrainSpec {
  /// Seed of every random choice (std::mt19937_64): same seed and spec, byte-identical database.
  std::uint64_t seed = 1;
  /// Triangles of the central area at full detail (level-0 tiles + every other central object);
  /// isolated trees fill what the rest leaves, so the count lands within 24 of it. The paper's
  /// figure is 200,000. Must leave room for at least 50 trees (about 178,000 and up).
  std::size_t central_triangles = 200'000;
  /// Sum of the amplitudes of the undulation's sinusoids [m] (peak deviation from the mean);
  /// 0 gives flat ground apart from the valley, river bed and lake basins. At most 100.
  double relief_m = 18.0;
};

/// Generates the terrain database (layout above). Deterministic: a function of `spec` only (no
/// clock, no threads, no std distributions). Throws std::invalid_argument naming the field when
/// central_triangles or relief_m is out of range. Setup only (allocates; 0.3 to 0.6 s on one core).
[[nodiscard]] SceneDescription generate_terrain(const TerrainSpec& spec);

/// Preview colour (linear RGB) of a terrain catalogue material by name, as the generated database
/// colours it (plus "snow", which the generator does not place); mid grey for any other name.
/// One table for every scene builder (the generator, GIS import).
[[nodiscard]] glm::vec3 terrain_preview_colour(std::string_view material) noexcept;

}  // namespace radar_emu::scene
