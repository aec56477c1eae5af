#include "scene/geodata/polygon.hpp"

#include <cstddef>
#include <list>

namespace radar_emu::scene::geodata::detail {
namespace {

double cross(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) noexcept {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

bool in_triangle(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) noexcept {
  return cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0;
}

}  // namespace

double signed_area2(const std::vector<glm::dvec2>& ring) noexcept {
  double a = 0.0;
  for (std::size_t i = 0, n = ring.size(); i < n; ++i) {
    const glm::dvec2 p = ring[i], q = ring[(i + 1) % n];
    a += p.x * q.y - q.x * p.y;
  }
  return a;
}

std::vector<glm::uvec3> triangulate(const std::vector<glm::dvec2>& ring, bool* fanned) {
  std::vector<glm::uvec3> out;
  if (fanned)
    *fanned = false;
  std::vector<std::uint32_t> idx(ring.size());
  for (std::size_t i = 0; i < idx.size(); ++i)
    idx[i] = static_cast<std::uint32_t>(i);
  while (idx.size() > 3) {
    bool clipped = false;
    const std::size_t n = idx.size();
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t ia = idx[(k + n - 1) % n], ib = idx[k], ic = idx[(k + 1) % n];
      const glm::dvec2 a = ring[ia], b = ring[ib], c = ring[ic];
      if (cross(a, b, c) <= 0.0)
        continue;  // reflex or flat: not an ear
      bool empty = true;
      for (std::uint32_t j : idx) {
        if (j != ia && j != ib && j != ic && ring[j] != a && ring[j] != b && ring[j] != c &&
            in_triangle(ring[j], a, b, c)) {
          empty = false;
          break;
        }
      }
      if (!empty)
        continue;
      out.push_back({ia, ib, ic});
      idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
      break;
    }
    if (!clipped) {
      if (fanned)
        *fanned = true;
      for (std::size_t k = 1; k + 1 < idx.size(); ++k)
        out.push_back({idx[0], idx[k], idx[k + 1]});
      return out;
    }
  }
  if (idx.size() == 3)
    out.push_back({idx[0], idx[1], idx[2]});
  return out;
}

bool inside(const std::vector<std::vector<glm::dvec2>>& rings, glm::dvec2 p) noexcept {
  bool in = false;
  for (const auto& ring : rings) {
    for (std::size_t i = 0, n = ring.size(), j = n - 1; i < n; j = i++) {
      const glm::dvec2 a = ring[i], b = ring[j];
      if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x)
        in = !in;
    }
  }
  return in;
}

}  // namespace radar_emu::scene::geodata::detail
