#include "scene/mesh_check.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

#include "scene/mesh/topology.hpp"

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
  std::vector<std::uint8_t> skip(m.triangles.size(), 0);
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    if (is_degenerate(m, t)) {
      r.degenerate.push_back(t);
      skip[t] = 1;
    }
  }
  // Vertices welded and edges counted by the one rule (scene/mesh/topology.hpp).
  const MeshTopology topo = build_topology(m.positions_m, m.triangles, skip);
  r.non_manifold_edges = topo.non_manifold_edges;
  r.inconsistent_edges = topo.inconsistent_edges;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;
  for (const MeshEdge& e : topo.edges) {
    if (e.boundary())
      boundary.emplace_back(e.v0, e.v1);
  }
  r.boundary_edges = boundary.size();
  // T-junctions: a surface tessellated differently on two sides of a seam is closed even though
  // its edges do not pair up (the long edge of one side is split by the vertices of the other).
  // Split every boundary edge at the boundary vertices lying on it and pair the pieces; only
  // pieces left alone are real boundary. Quadratic in the boundary: skipped beyond 5000 edges.
  if (!boundary.empty() && boundary.size() <= 5000) {
    std::vector<glm::dvec3> pos(topo.weld.size());
    for (std::size_t v = 0; v < pos.size(); ++v)
      pos[v] = glm::dvec3(m.positions_m[topo.weld.first_input[v]]);
    const double tolerance_m = topo.weld.tolerance_m;
    std::vector<std::uint32_t> candidates;
    for (const auto& [a, b] : boundary) {
      candidates.push_back(a);
      candidates.push_back(b);
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> pieces;
    std::vector<std::pair<double, std::uint32_t>> on_edge;
    for (const auto& [a, b] : boundary) {
      const glm::dvec3 pa = pos[a], ab = pos[b] - pos[a];
      const double len2 = glm::dot(ab, ab);
      on_edge.clear();
      for (std::uint32_t v : candidates) {
        if (v == a || v == b)
          continue;
        const double t = glm::dot(pos[v] - pa, ab) / len2;
        if (t <= 1e-9 || t >= 1.0 - 1e-9)
          continue;
        const glm::dvec3 off = pos[v] - (pa + t * ab);
        if (glm::dot(off, off) <= 16.0 * tolerance_m * tolerance_m)  // on the edge, to the weld
          on_edge.emplace_back(t, v);
      }
      std::sort(on_edge.begin(), on_edge.end());
      std::uint32_t prev = a;
      for (const auto& [t, v] : on_edge) {
        ++pieces[{std::min(prev, v), std::max(prev, v)}];
        prev = v;
      }
      ++pieces[{std::min(prev, b), std::max(prev, b)}];
    }
    r.boundary_edges = 0;
    for (const auto& [e, count] : pieces)
      r.boundary_edges += count == 1;
  }
  return r;
}

std::vector<std::string> clean_loaded_mesh(Mesh& m, const std::string& source,
                                           std::span<const std::size_t> lines) {
  return clean_loaded_mesh(m, check_mesh(m), source, lines);
}

std::vector<std::string> clean_loaded_mesh(Mesh& m, const MeshCheck& c, const std::string& source,
                                           std::span<const std::size_t> lines) {
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
  if (c.inconsistent_edges > 0) {
    warnings.push_back(source + ": " + std::to_string(c.inconsistent_edges) +
                       " edges between triangles wound inconsistently (a part with one is taken "
                       "as open)");
  }
  return warnings;
}

}  // namespace radar_emu::scene
