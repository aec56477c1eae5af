#include "scene/mesh_check.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <stdexcept>

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
  // Weld vertices that coincide to 1e-7 of the mesh's extent (exporters and generators reach
  // the same corner by different float arithmetic; a point straddling a cell boundary of this
  // quantisation stays unwelded, which can only over-report boundary edges).
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const glm::vec3& p : m.positions_m) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  const double quantum = std::max(1e-7 * glm::length(hi - lo), 1e-30);
  std::map<std::array<long long, 3>, std::uint32_t> ids;
  std::vector<std::uint32_t> welded(m.positions_m.size());
  for (std::size_t i = 0; i < m.positions_m.size(); ++i) {
    const glm::dvec3 q = glm::round((glm::dvec3(m.positions_m[i]) - lo) / quantum);
    // q is within 0 .. 1e7 for finite positions; a non-finite one (a loader's bug) must not
    // reach the integer conversion (undefined behaviour): it gets a key of its own.
    const auto to_key = [](double x) {
      return x >= 0.0 && x <= 1e15 ? static_cast<long long>(x) : -1;
    };
    const std::array<long long, 3> key{to_key(q.x), to_key(q.y), to_key(q.z)};
    welded[i] = ids.emplace(key, static_cast<std::uint32_t>(ids.size())).first->second;
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
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;
  for (const auto& [e, count] : edges) {
    if (count == 1)
      boundary.push_back(e);
    else if (count > 2)
      ++r.non_manifold_edges;
  }
  r.boundary_edges = boundary.size();
  // T-junctions: a surface tessellated differently on two sides of a seam is closed even though
  // its edges do not pair up (the long edge of one side is split by the vertices of the other).
  // Split every boundary edge at the boundary vertices lying on it and pair the pieces; only
  // pieces left alone are real boundary. Quadratic in the boundary: skipped beyond 5000 edges.
  if (!boundary.empty() && boundary.size() <= 5000) {
    std::vector<glm::dvec3> pos(ids.size());
    for (std::size_t i = 0; i < m.positions_m.size(); ++i)
      pos[welded[i]] = glm::dvec3(m.positions_m[i]);
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
        if (glm::dot(off, off) <= 16.0 * quantum * quantum)  // on the edge to float precision
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
