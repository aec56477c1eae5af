#include "scene/mesh/topology.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace radar_emu::scene {

namespace {

// Disjoint sets whose representative is the lowest index of the set (so that numbering sets by
// their representative follows the input order).
class LowestRootSets {
 public:
  explicit LowestRootSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0u);
  }
  std::uint32_t find(std::uint32_t x) noexcept {
    while (parent_[x] != x)
      x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void join(std::uint32_t a, std::uint32_t b) noexcept {
    a = find(a);
    b = find(b);
    if (a < b)
      parent_[b] = a;
    else
      parent_[a] = b;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

template <class T>
struct TripleHash {
  std::size_t operator()(const std::array<T, 3>& k) const noexcept {
    std::uint64_t b[3];
    std::memcpy(b, k.data(), sizeof b);
    return static_cast<std::size_t>((b[0] * 0x9E3779B97F4A7C15ull) ^
                                    (b[1] * 0xC2B2AE3D27D4EB4Full) ^
                                    (b[2] * 0x165667B19E3779F9ull));
  }
};

bool finite(const glm::dvec3& p) noexcept {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

template <class Vec>
VertexWeld weld_impl(std::span<const Vec> positions, std::span<const glm::uvec3> triangles) {
  const std::size_t n = positions.size();
  if (n >= kNoIndex)
    throw std::invalid_argument("mesh topology: too many vertices");
  VertexWeld w;
  // The extent of the finite vertices the triangles use.
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const glm::uvec3& t : triangles) {
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t i = t[c];
      if (i >= n)
        continue;
      const glm::dvec3 p(positions[i]);
      if (!finite(p))
        continue;
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  }
  w.extent_m = lo.x <= hi.x ? glm::length(hi - lo) : 0.0;
  w.tolerance_m = kWeldRelativeTolerance * w.extent_m;

  LowestRootSets sets(n);
  // Equal positions first (meshes repeat a vertex per face): a hash of the bits, -0 taken as +0.
  std::unordered_map<std::array<double, 3>, std::uint32_t, TripleHash<double>> exact;
  exact.reserve(n);
  std::vector<std::uint32_t> distinct;  // the first vertex at each finite position
  for (std::uint32_t i = 0; i < n; ++i) {
    const glm::dvec3 p = glm::dvec3(positions[i]) + glm::dvec3(0.0);
    if (!finite(p))
      continue;
    const auto [it, fresh] = exact.try_emplace({p.x, p.y, p.z}, i);
    if (fresh)
      distinct.push_back(i);
    else
      sets.join(it->second, i);
  }
  // Then the distinct positions within the tolerance of each other, on a grid of cells 8
  // tolerances wide (a cell's points chained through `next`): a point looks in its own cell and,
  // along each axis where it lies within the tolerance of a cell face (a margin covers the
  // division's rounding), in the neighbour beyond it. Mesh vertices are mostly far more than
  // the tolerance apart, so most points look in one cell only.
  if (w.tolerance_m > 0.0 && distinct.size() > 1) {
    const double cell_m = 8.0 * w.tolerance_m;
    const double near = 1.0 / 8.0 + 1e-6;  // the tolerance in cells, with a margin
    std::unordered_map<std::array<std::int64_t, 3>, std::uint32_t, TripleHash<std::int64_t>> head;
    head.reserve(distinct.size());
    std::vector<std::uint32_t> next(n, kNoIndex);
    for (const std::uint32_t i : distinct) {
      const glm::dvec3 p(positions[i]);
      const glm::dvec3 q = (p - lo) / cell_m, f = glm::floor(q);
      // A vertex 800 extents or more outside the used ones (an unused stray) keeps to exact
      // equality: within 1e9 cells the division rounds by less than the margin.
      if (!(std::abs(f.x) < 1e9 && std::abs(f.y) < 1e9 && std::abs(f.z) < 1e9))
        continue;
      const std::array<std::int64_t, 3> c{static_cast<std::int64_t>(f.x),
                                          static_cast<std::int64_t>(f.y),
                                          static_cast<std::int64_t>(f.z)};
      std::array<std::array<std::int64_t, 2>, 3> range{};  // per axis: first and last offset
      for (int k = 0; k < 3; ++k) {
        const double frac = q[k] - f[k];
        range[static_cast<std::size_t>(k)] = {frac < near ? -1 : 0, frac > 1.0 - near ? 1 : 0};
      }
      for (std::int64_t dx = range[0][0]; dx <= range[0][1]; ++dx) {
        for (std::int64_t dy = range[1][0]; dy <= range[1][1]; ++dy) {
          for (std::int64_t dz = range[2][0]; dz <= range[2][1]; ++dz) {
            const auto it = head.find({c[0] + dx, c[1] + dy, c[2] + dz});
            for (std::uint32_t j = it == head.end() ? kNoIndex : it->second; j != kNoIndex;
                 j = next[j]) {
              if (glm::length(glm::dvec3(positions[j]) - p) <= w.tolerance_m)
                sets.join(i, j);
            }
          }
        }
      }
      const auto [it, fresh] = head.try_emplace(c, i);
      if (!fresh) {
        next[i] = it->second;
        it->second = i;
      }
    }
  }
  w.welded.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t r = sets.find(i);
    if (r == i) {
      w.welded[i] = static_cast<std::uint32_t>(w.first_input.size());
      w.first_input.push_back(i);
    } else {
      w.welded[i] = w.welded[r];  // r < i: numbered already
    }
  }
  return w;
}

template <class Vec>
MeshTopology build_impl(std::span<const Vec> positions, VertexWeld weld,
                        std::span<const glm::uvec3> triangles, std::span<const std::uint8_t> skip) {
  const std::size_t n = positions.size(), nt = triangles.size();
  if (!skip.empty() && skip.size() != nt)
    throw std::invalid_argument("mesh topology: one skip flag per triangle is needed");
  if (weld.welded.size() != n)
    throw std::invalid_argument("mesh topology: the weld is of another mesh");
  if (nt >= kNoIndex)
    throw std::invalid_argument("mesh topology: too many triangles");
  MeshTopology m;
  m.weld = std::move(weld);
  constexpr std::array<std::uint32_t, 3> kNone3{kNoIndex, kNoIndex, kNoIndex};
  m.corners.assign(nt, kNone3);
  m.use.assign(nt, TriangleUse::kUsed);
  m.triangle_edges.assign(nt, kNone3);
  m.triangle_part.assign(nt, kNoIndex);

  // Half-edges keyed by their welded end points, sorted by (edge, triangle, corner).
  struct Entry {
    std::uint64_t key;
    std::uint32_t triangle;
    std::uint8_t corner;
    bool forward;
  };
  std::vector<Entry> entries;
  entries.reserve(3 * nt);
  for (std::uint32_t t = 0; t < nt; ++t) {
    const glm::uvec3 tri = triangles[t];
    if (tri.x >= n || tri.y >= n || tri.z >= n) {
      m.use[t] = TriangleUse::kInvalid;
      continue;
    }
    const std::array<std::uint32_t, 3> v{m.weld.welded[tri.x], m.weld.welded[tri.y],
                                         m.weld.welded[tri.z]};
    m.corners[t] = v;
    if (!skip.empty() && skip[t] != 0) {
      m.use[t] = TriangleUse::kSkipped;
      continue;
    }
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
      m.use[t] = TriangleUse::kCollapsed;
      ++m.collapsed_triangles;
      continue;
    }
    for (std::uint8_t c = 0; c < 3; ++c) {
      const std::uint32_t a = v[c], b = v[(c + 1u) % 3u];
      entries.push_back(
          {(static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b), t, c, a < b});
    }
  }
  // Entries arrive in (triangle, corner) order; a counting sort by the lower vertex keeps that
  // order, then each vertex's few entries are sorted by the higher one, stably.
  {
    std::vector<std::uint32_t> start(m.weld.size() + 1, 0);
    for (const Entry& e : entries)
      ++start[(e.key >> 32) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<Entry> sorted(entries.size());
    for (const Entry& e : entries)
      sorted[start[e.key >> 32]++] = e;
    entries.swap(sorted);
    // start[v] is now the end of vertex v's run (the beginning of v + 1's).
    std::uint32_t begin = 0;
    for (std::size_t v = 0; v < m.weld.size(); ++v) {
      const std::uint32_t end = start[v];
      if (end - begin > 32) {  // a high-valence vertex (a fan's centre)
        std::stable_sort(entries.begin() + begin, entries.begin() + end,
                         [](const Entry& x, const Entry& y) { return x.key < y.key; });
        begin = end;
        continue;
      }
      for (std::uint32_t a = begin + 1; a < end; ++a) {  // insertion sort: stable, no buffer
        const Entry e = entries[a];
        std::uint32_t b = a;
        for (; b > begin && entries[b - 1].key > e.key; --b)
          entries[b] = entries[b - 1];
        entries[b] = e;
      }
      begin = end;
    }
  }
  m.half_edges.resize(entries.size());
  m.edges.reserve(entries.size() / 2 + 1);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    if (i == 0 || e.key != entries[i - 1].key) {
      MeshEdge edge;
      edge.v0 = static_cast<std::uint32_t>(e.key >> 32);
      edge.v1 = static_cast<std::uint32_t>(e.key & 0xFFFFFFFFu);
      edge.first = static_cast<std::uint32_t>(i);
      m.edges.push_back(edge);
    }
    ++m.edges.back().count;
    m.half_edges[i] = {e.triangle, e.corner, e.forward};
    m.triangle_edges[e.triangle][e.corner] = static_cast<std::uint32_t>(m.edges.size() - 1);
  }

  // Parts: triangles joined across every edge, numbered by their lowest triangle.
  LowestRootSets sets(nt);
  for (const MeshEdge& e : m.edges) {
    for (std::uint32_t k = 1; k < e.count; ++k)
      sets.join(m.half_edges[e.first].triangle, m.half_edges[e.first + k].triangle);
  }
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (m.use[t] != TriangleUse::kUsed)
      continue;
    const std::uint32_t r = sets.find(t);
    if (r == t) {
      m.triangle_part[t] = static_cast<std::uint32_t>(m.parts.size());
      m.parts.emplace_back();
    } else {
      m.triangle_part[t] = m.triangle_part[r];  // r < t: numbered already
    }
    MeshPart& p = m.parts[m.triangle_part[t]];
    ++p.triangles;
    const glm::uvec3 tri = triangles[t];
    const glm::dvec3 a(positions[tri.x]), b(positions[tri.y]), c(positions[tri.z]);
    p.volume_m3 += glm::dot(a, glm::cross(b, c));
  }
  for (MeshPart& p : m.parts)
    p.volume_m3 /= 6.0;

  for (MeshEdge& e : m.edges) {
    if (e.count == 1)
      e.flags |= kEdgeBoundary;
    else if (e.count > 2)
      e.flags |= kEdgeNonManifold;
    else if (m.half_edges[e.first].forward == m.half_edges[e.first + 1].forward)
      e.flags |= kEdgeInconsistent;
    MeshPart& p = m.parts[m.triangle_part[m.half_edges[e.first].triangle]];
    p.boundary_edges += e.boundary() ? 1u : 0u;
    p.non_manifold_edges += e.non_manifold() ? 1u : 0u;
    p.inconsistent_edges += e.inconsistent() ? 1u : 0u;
    m.boundary_edges += e.boundary() ? 1u : 0u;
    m.non_manifold_edges += e.non_manifold() ? 1u : 0u;
    m.inconsistent_edges += e.inconsistent() ? 1u : 0u;
  }
  return m;
}

}  // namespace

VertexWeld weld_vertices(std::span<const glm::vec3> positions_m,
                         std::span<const glm::uvec3> triangles) {
  return weld_impl(positions_m, triangles);
}
VertexWeld weld_vertices(std::span<const glm::dvec3> positions_m,
                         std::span<const glm::uvec3> triangles) {
  return weld_impl(positions_m, triangles);
}

MeshTopology build_topology(std::span<const glm::vec3> positions_m,
                            std::span<const glm::uvec3> triangles,
                            std::span<const std::uint8_t> skip) {
  return build_impl(positions_m, weld_impl(positions_m, triangles), triangles, skip);
}
MeshTopology build_topology(std::span<const glm::dvec3> positions_m,
                            std::span<const glm::uvec3> triangles,
                            std::span<const std::uint8_t> skip) {
  return build_impl(positions_m, weld_impl(positions_m, triangles), triangles, skip);
}
MeshTopology build_topology(std::span<const glm::dvec3> positions_m, VertexWeld weld,
                            std::span<const glm::uvec3> triangles,
                            std::span<const std::uint8_t> skip) {
  return build_impl(positions_m, std::move(weld), triangles, skip);
}
MeshTopology build_topology(std::span<const std::array<glm::dvec3, 3>> triangles_m) {
  std::vector<glm::dvec3> positions(3 * triangles_m.size());
  std::vector<glm::uvec3> triangles(triangles_m.size());
  for (std::size_t t = 0; t < triangles_m.size(); ++t) {
    const auto i = static_cast<unsigned>(3 * t);
    positions[i] = triangles_m[t][0];
    positions[i + 1] = triangles_m[t][1];
    positions[i + 2] = triangles_m[t][2];
    triangles[t] = {i, i + 1, i + 2};
  }
  return build_topology(std::span<const glm::dvec3>(positions), triangles);
}

std::vector<std::int8_t> closed_part_winding(const MeshTopology& topology) {
  std::vector<std::int8_t> out(topology.triangle_part.size(), 0);
  for (std::size_t t = 0; t < out.size(); ++t) {
    const std::uint32_t p = topology.triangle_part[t];
    if (p == kNoIndex)
      continue;
    const MeshPart& part = topology.parts[p];
    if (part.closed() && part.volume_m3 != 0.0)
      out[t] = part.volume_m3 > 0.0 ? 1 : -1;
  }
  return out;
}

Orientation orient_parts(const MeshTopology& topology) {
  const std::size_t nt = topology.use.size();
  Orientation o;
  o.flip.assign(nt, 0);
  std::vector<std::uint8_t> seen(nt, 0);
  std::vector<std::uint32_t> queue;
  for (std::uint32_t seed = 0; seed < nt; ++seed) {
    if (topology.use[seed] != TriangleUse::kUsed || seen[seed])
      continue;
    seen[seed] = 1;
    queue.assign(1, seed);
    for (std::size_t qi = 0; qi < queue.size(); ++qi) {
      const std::uint32_t t = queue[qi];
      std::array<std::uint32_t, 3> es = topology.triangle_edges[t];
      std::sort(es.begin(), es.end());
      for (const std::uint32_t ei : es) {
        const MeshEdge& e = topology.edges[ei];
        if (e.count != 2)
          continue;
        const HalfEdge& h0 = topology.half_edges[e.first];
        const HalfEdge& h1 = topology.half_edges[e.first + 1];
        const HalfEdge& mine = h0.triangle == t ? h0 : h1;
        const HalfEdge& theirs = h0.triangle == t ? h1 : h0;
        // Consistent winding runs a shared edge in opposite directions.
        const bool same_direction = (mine.forward != (o.flip[t] != 0)) == theirs.forward;
        const std::uint8_t want = same_direction ? 1 : 0;
        const std::uint32_t u = theirs.triangle;
        if (!seen[u]) {
          seen[u] = 1;
          o.flip[u] = want;
          queue.push_back(u);
        } else if (o.flip[u] != want) {
          o.conflict = t;
          return o;
        }
      }
    }
  }
  return o;
}

}  // namespace radar_emu::scene
