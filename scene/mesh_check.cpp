#include "scene/mesh_check.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <stdexcept>
#include <unordered_map>

namespace radar_emu::scene {

bool is_degenerate(const Mesh& m, std::size_t t) noexcept {
  const glm::uvec3 tri = m.triangles[t];
  const std::size_t n = m.positions_m.size();
  if (tri.x >= n || tri.y >= n || tri.z >= n || tri.x == tri.y || tri.y == tri.z || tri.x == tri.z)
    return true;
  const glm::dvec3 a(m.positions_m[tri.x]), b(m.positions_m[tri.y]), c(m.positions_m[tri.z]);
  const double twice_area = glm::length(glm::cross(b - a, c - a));
  const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
  return !(twice_area > 2e-12 * longest * longest);
}

MeshCheck check_mesh(const Mesh& m) {
  MeshCheck r;
  r.triangles = m.triangles.size();
  // Weld by exact position (bit pattern of the three floats).
  std::unordered_map<std::string, std::uint32_t> ids;
  std::vector<std::uint32_t> welded(m.positions_m.size());
  for (std::size_t i = 0; i < m.positions_m.size(); ++i) {
    std::string key(sizeof(glm::vec3), '\0');
    std::memcpy(key.data(), &m.positions_m[i], sizeof(glm::vec3));
    welded[i] = ids.emplace(std::move(key), static_cast<std::uint32_t>(ids.size())).first->second;
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edges;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    if (is_degenerate(m, t)) {
      r.degenerate.push_back(t);
      continue;
    }
    const glm::uvec3 tri = m.triangles[t];
    const std::array<std::uint32_t, 3> v{welded[tri.x], welded[tri.y], welded[tri.z]};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = v[static_cast<std::size_t>(k)],
                          b = v[static_cast<std::size_t>((k + 1) % 3)];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  }
  for (const auto& [e, count] : edges) {
    if (count == 1)
      ++r.boundary_edges;
    else if (count > 2)
      ++r.non_manifold_edges;
  }
  return r;
}

std::vector<std::string> clean_loaded_mesh(Mesh& m, const std::string& source,
                                           std::span<const std::size_t> lines) {
  const MeshCheck c = check_mesh(m);
  std::vector<std::string> warnings;
  constexpr std::size_t kListed = 10;
  for (std::size_t i = 0; i < c.degenerate.size() && i < kListed; ++i) {
    const std::size_t t = c.degenerate[i];
    std::string w = source + ": triangle " + std::to_string(t);
    if (t < lines.size() && lines[t] != 0)
      w += " (line " + std::to_string(lines[t]) + ")";
    warnings.push_back(w + " is degenerate (zero area or repeated vertex): dropped");
  }
  if (c.degenerate.size() > kListed) {
    warnings.push_back(source + ": ... and " + std::to_string(c.degenerate.size() - kListed) +
                       " more degenerate triangles dropped");
  }
  if (c.degenerate.size() == m.triangles.size())
    throw std::runtime_error(source + ": every triangle is degenerate");
  if (!c.degenerate.empty()) {
    std::vector<std::uint8_t> drop(m.triangles.size(), 0);
    for (std::size_t t : c.degenerate)
      drop[t] = 1;
    std::size_t out = 0;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      if (drop[t])
        continue;
      m.triangles[out] = m.triangles[t];
      m.triangle_material[out] = m.triangle_material[t];
      ++out;
    }
    m.triangles.resize(out);
    m.triangle_material.resize(out);
  }
  if (c.boundary_edges > 0) {
    warnings.push_back(source + ": open mesh: " + std::to_string(c.boundary_edges) +
                       " boundary edges (shadowing and PO assume closed bodies; sheets such as "
                       "plates are fine)");
  }
  if (c.non_manifold_edges > 0) {
    warnings.push_back(source + ": " + std::to_string(c.non_manifold_edges) +
                       " non-manifold edges (shared by more than two triangles)");
  }
  return warnings;
}

}  // namespace radar_emu::scene
