#pragma once
// OpenStreetMap features through GDAL's OSM driver (XML .osm or .pbf), as plain values: what the
// geodata import (scene/geodata/import.hpp) turns into geometry. GDAL stays in osm.cpp.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace radar_emu::scene::geodata {

/// A point: WGS84 longitude, latitude [rad].
struct LonLat {
  double longitude_rad = 0.0;
  double latitude_rad = 0.0;
};

using Tags = std::map<std::string, std::string, std::less<>>;

struct OsmNode {
  std::int64_t id = 0;
  LonLat at;
  Tags tags;
};
/// An open or closed way that GDAL puts in its "lines" layer.
struct OsmWay {
  std::int64_t id = 0;
  std::vector<LonLat> points;
  Tags tags;
};
/// A closed way or multipolygon relation ("multipolygons" layer): polygons, each outer ring
/// first, then its holes; rings closed (first point repeated at the end).
struct OsmArea {
  std::int64_t id = 0;  ///< way id (closed ways) or relation id
  std::vector<std::vector<std::vector<LonLat>>> polygons;
  Tags tags;
};

struct OsmData {
  std::vector<OsmNode> nodes;  ///< tagged nodes only
  std::vector<OsmWay> ways;
  std::vector<OsmArea> areas;
  /// Ways GDAL reported as referring to nodes the file does not have: dropped whole (GDAL
  /// would keep the nodes it found, bending the way), with ways of fewer than two nodes.
  std::size_t broken_ways = 0;
  std::vector<std::int64_t> broken_way_ids;  ///< the first few, for the report
};

/// Reads every tagged node, way and area of `path`. Throws std::runtime_error "PATH: what" when
/// GDAL cannot open it as OSM. Setup only.
[[nodiscard]] OsmData read_osm(const std::filesystem::path& path);

/// Tag value or "" when absent.
[[nodiscard]] std::string tag(const Tags& tags, std::string_view key);

}  // namespace radar_emu::scene::geodata
