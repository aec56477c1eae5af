#include "scene/scene_info.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>

namespace radar_emu::scene {

namespace {

// Adds n to the entry `key` of an insertion-ordered list.
template <typename K>
void add(std::vector<std::pair<K, std::size_t>>& list, const K& key, std::size_t n) {
  for (auto& [k, v] : list) {
    if (k == key) {
      v += n;
      return;
    }
  }
  list.emplace_back(key, n);
}

// World from body at t = 0: the placement, or for a moving object its start and heading along
// the horizontal velocity (as Scene places it).
glm::dmat4 world_from_body_at_start(const ObjectDesc& o) {
  if (!o.motion)
    return o.world_from_body;
  const glm::dvec3 v = o.motion->velocity_mps;
  const double vh = std::hypot(v.x, v.y);
  const double c = vh > 0.0 ? v.x / vh : 1.0, s = vh > 0.0 ? v.y / vh : 0.0;
  glm::dmat4 x(1.0);
  x[0] = glm::dvec4(c, s, 0.0, 0.0);
  x[1] = glm::dvec4(-s, c, 0.0, 0.0);
  x[3] = glm::dvec4(o.motion->start_position_m, 1.0);
  return x;
}

}  // namespace

std::string object_kind(const std::string& name) {
  std::string kind = name;
  for (;;) {
    const std::size_t cut = kind.rfind('_');
    if (cut == std::string::npos || cut == 0)
      return kind;
    const bool digit =
        std::any_of(kind.begin() + static_cast<std::ptrdiff_t>(cut) + 1, kind.end(),
                    [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); });
    if (!digit)
      return kind;
    kind.resize(cut);
  }
}

SceneInfo scene_info(const SceneDescription& d) {
  SceneInfo info;
  info.objects = d.objects.size();
  info.materials = d.materials.size();
  info.anchor = d.anchor;
  info.incomplete = d.incomplete;
  std::vector<std::size_t> per_material(d.materials.size(), 0);
  std::size_t unknown_material = 0;
  std::map<int, std::size_t> per_level;
  std::vector<std::int32_t> groups;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const ObjectDesc& o : d.objects) {
    const std::size_t n = o.mesh.triangles.size();
    const bool in_group = o.lod_group >= 0;
    const bool full = !in_group || o.lod_level == 0;
    const std::string area = o.area.empty() ? "none" : o.area;
    info.vertices += o.mesh.positions_m.size();
    info.triangles_total += n;
    per_level[in_group ? static_cast<int>(o.lod_level) : -1] += n;
    add(info.triangles_by_area_all_levels, area, n);
    add(info.objects_by_kind, object_kind(o.name), std::size_t{1});
    if (in_group)
      groups.push_back(o.lod_group);
    if (full) {
      info.triangles_full_detail += n;
      add(info.triangles_by_area, area, n);
      for (std::size_t t = 0; t < n && t < o.mesh.triangle_material.size(); ++t) {
        const std::uint16_t m = o.mesh.triangle_material[t];
        if (m < per_material.size())
          ++per_material[m];
        else
          ++unknown_material;
      }
      if (o.mesh.triangle_material.size() < n)
        unknown_material += n - o.mesh.triangle_material.size();
    }
    const glm::dmat4 x = world_from_body_at_start(o);
    for (const glm::vec3& p : o.mesh.positions_m) {
      const glm::dvec3 w(x * glm::dvec4(glm::dvec3(p), 1.0));
      lo = glm::min(lo, w);
      hi = glm::max(hi, w);
    }
  }
  for (std::size_t m = 0; m < d.materials.size(); ++m)
    add(info.triangles_by_material, d.materials[m].name, per_material[m]);
  if (unknown_material > 0)
    add(info.triangles_by_material, std::string("?"), unknown_material);
  info.triangles_by_lod_level.assign(per_level.begin(), per_level.end());
  std::sort(groups.begin(), groups.end());
  info.lod_groups =
      static_cast<std::size_t>(std::unique(groups.begin(), groups.end()) - groups.begin());
  if (info.vertices > 0) {
    info.extent_min_m = lo;
    info.extent_max_m = hi;
  }
  return info;
}

}  // namespace radar_emu::scene
