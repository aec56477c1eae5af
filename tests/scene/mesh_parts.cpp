#include "tests/scene/mesh_parts.hpp"

#include <map>
#include <numeric>
#include <tuple>
#include <utility>

namespace radar_emu::test {

namespace {
using Point = std::tuple<float, float, float>;
Point key(glm::vec3 p) {
  return {p.x, p.y, p.z};
}
}  // namespace

std::vector<std::vector<std::size_t>> mesh_parts(const scene::Mesh& m) {
  std::vector<std::size_t> parent(m.triangles.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto find = [&](std::size_t i) {
    while (parent[i] != i)
      i = parent[i] = parent[parent[i]];
    return i;
  };
  std::map<Point, std::size_t> first_triangle_at;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const auto [it, inserted] =
          first_triangle_at.emplace(key(m.positions_m[m.triangles[i][k]]), i);
      if (!inserted)
        parent[find(i)] = find(it->second);
    }
  }
  std::map<std::size_t, std::vector<std::size_t>> by_root;
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    by_root[find(i)].push_back(i);
  std::vector<std::vector<std::size_t>> out;
  for (auto& [root, tris] : by_root)
    out.push_back(std::move(tris));
  return out;
}

bool closed_and_consistent(const scene::Mesh& m, const std::vector<std::size_t>& tris) {
  std::map<std::pair<Point, Point>, int> edges;
  for (std::size_t i : tris) {
    const auto& t = m.triangles[i];
    for (int k = 0; k < 3; ++k)
      ++edges[{key(m.positions_m[t[k]]), key(m.positions_m[t[(k + 1) % 3]])}];
  }
  for (const auto& [e, count] : edges) {
    const auto reverse = edges.find({e.second, e.first});
    if (count != 1 || reverse == edges.end() || reverse->second != 1)
      return false;
  }
  return true;
}

bool closed_and_consistent(const scene::Mesh& m) {
  std::vector<std::size_t> all(m.triangles.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  return closed_and_consistent(m, all);
}

double signed_volume(const scene::Mesh& m, const std::vector<std::size_t>& tris) {
  double v = 0.0;
  for (std::size_t i : tris) {
    const auto& t = m.triangles[i];
    const glm::dvec3 a(m.positions_m[t.x]), b(m.positions_m[t.y]), c(m.positions_m[t.z]);
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

}  // namespace radar_emu::test
