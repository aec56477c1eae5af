#pragma once
// Summary figures of a scene database (what `radar-emu scene info` prints): polygon counts per
// material, area and level of detail, extent, objects. Plain structs; the JSON form lives in
// tools/ (tools/scene.cpp).

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <utility>
#include <vector>

#include "scene/types.hpp"

namespace radar_emu::scene {

struct SceneInfo {
  std::size_t objects = 0;
  std::size_t materials = 0;
  std::size_t vertices = 0;
  /// Every triangle of the description, all levels of detail together.
  std::size_t triangles_total = 0;
  /// The scene at its finest: objects outside LOD groups plus LOD level 0 of every group (what
  /// polygon budgets such as the seed paper's "200,000 polygons" count).
  std::size_t triangles_full_detail = 0;
  /// Distinct LOD groups (ObjectDesc::lod_group >= 0).
  std::size_t lod_groups = 0;
  /// Full-detail triangles per material name, in material order (unused materials listed, 0).
  std::vector<std::pair<std::string, std::size_t>> triangles_by_material;
  /// Full-detail triangles per ObjectDesc::area ("" listed as "none"), first-seen order.
  std::vector<std::pair<std::string, std::size_t>> triangles_by_area;
  /// Triangles per area over all levels of detail.
  std::vector<std::pair<std::string, std::size_t>> triangles_by_area_all_levels;
  /// Triangles per LOD level over all objects, ascending; level -1 = outside any LOD group.
  std::vector<std::pair<int, std::size_t>> triangles_by_lod_level;
  /// Objects per kind: the name less its trailing "_" parts that hold a digit ("tree_12" ->
  /// "tree", "terrain_r03_c07_lod0" -> "terrain", "wire_3_1" -> "wire"), first-seen order.
  std::vector<std::pair<std::string, std::size_t>> objects_by_kind;
  /// World (ENU) bounds of every vertex, all levels, moving objects at t = 0 [m]; both 0 for an
  /// empty scene.
  glm::dvec3 extent_min_m{0.0};
  glm::dvec3 extent_max_m{0.0};
  GeoAnchor anchor{};
  std::string incomplete;  ///< SceneDescription::incomplete (empty: whole)
};

/// The kind of an object from its name (rule in SceneInfo::objects_by_kind).
[[nodiscard]] std::string object_kind(const std::string& name);

/// Counts and bounds of `description`. Triangles whose material index is out of range count
/// under "?". Setup only (allocates).
[[nodiscard]] SceneInfo scene_info(const SceneDescription& description);

}  // namespace radar_emu::scene
