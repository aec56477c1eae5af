// The one mesh topology (scene/mesh/topology.hpp): the weld rule (near-coincident vertices
// welded, farther ones not, order-independent), the edge table's counts and flags on closed,
// open, non-manifold and mis-wound meshes, parts, closure, winding and orientation.
#include "scene/mesh/topology.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "scene/targets.hpp"

namespace sc = radar_emu::scene;

namespace {

// The unit cube [0, 1]^3, 8 shared vertices, 12 triangles wound outward.
struct IndexedMesh {
  std::vector<glm::dvec3> positions;
  std::vector<glm::uvec3> triangles;
};
IndexedMesh unit_cube() {
  IndexedMesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  // Each face as two triangles, counter-clockwise seen from outside.
  const std::array<std::array<unsigned, 4>, 6> faces{{
      {0, 2, 3, 1},  // z = 0, normal -z
      {4, 5, 7, 6},  // z = 1, normal +z
      {0, 1, 5, 4},  // y = 0, normal -y
      {2, 6, 7, 3},  // y = 1, normal +y
      {0, 4, 6, 2},  // x = 0, normal -x
      {1, 3, 7, 5},  // x = 1, normal +x
  }};
  for (const auto& f : faces) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  return m;
}

std::vector<std::array<glm::dvec3, 3>> soup(const IndexedMesh& m) {
  std::vector<std::array<glm::dvec3, 3>> s;
  for (const glm::uvec3& t : m.triangles)
    s.push_back({m.positions[t.x], m.positions[t.y], m.positions[t.z]});
  return s;
}

sc::MeshTopology build(const IndexedMesh& m) {
  return sc::build_topology(std::span<const glm::dvec3>(m.positions), m.triangles);
}

TEST(MeshTopology, ClosedCubeHasTwelveFacesEighteenEdgesAndNoBoundary) {
  const IndexedMesh cube = unit_cube();
  for (const sc::MeshTopology& t : {build(cube), sc::build_topology(soup(cube))}) {
    EXPECT_EQ(t.weld.size(), 8u);
    EXPECT_EQ(t.use.size(), 12u);
    EXPECT_EQ(t.edges.size(), 18u);
    EXPECT_EQ(t.half_edges.size(), 36u);
    EXPECT_EQ(t.boundary_edges, 0u);
    EXPECT_EQ(t.non_manifold_edges, 0u);
    EXPECT_EQ(t.inconsistent_edges, 0u);
    EXPECT_TRUE(t.closed());
    ASSERT_EQ(t.parts.size(), 1u);
    EXPECT_TRUE(t.parts[0].closed());
    EXPECT_EQ(t.parts[0].triangles, 12u);
    EXPECT_NEAR(t.parts[0].volume_m3, 1.0, 1e-15);
    for (const sc::MeshEdge& e : t.edges) {
      EXPECT_LT(e.v0, e.v1);
      EXPECT_EQ(e.count, 2u);
      EXPECT_EQ(e.flags, 0u);
      // The two half-edges run the edge in opposite directions and are where the triangles say.
      const auto uses = t.uses(e);
      EXPECT_NE(uses[0].forward, uses[1].forward);
      for (const sc::HalfEdge& h : uses)
        EXPECT_EQ(&t.edges[t.triangle_edges[h.triangle][h.corner]], &e);
    }
    const std::vector<std::int8_t> w = sc::closed_part_winding(t);
    EXPECT_EQ(std::count(w.begin(), w.end(), 1), 12);
  }
  // Wound inward: closed, negative volume, winding -1.
  IndexedMesh inward = cube;
  for (glm::uvec3& tri : inward.triangles)
    std::swap(tri.y, tri.z);
  const sc::MeshTopology t = build(inward);
  EXPECT_TRUE(t.closed());
  EXPECT_NEAR(t.parts[0].volume_m3, -1.0, 1e-15);
  const std::vector<std::int8_t> w = sc::closed_part_winding(t);
  EXPECT_EQ(std::count(w.begin(), w.end(), -1), 12);
}

TEST(MeshTopology, OpenPlateCountsItsBoundaryEdges) {
  IndexedMesh plate;
  plate.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  plate.triangles = {{0, 1, 2}, {0, 2, 3}};
  const sc::MeshTopology t = build(plate);
  EXPECT_EQ(t.edges.size(), 5u);
  EXPECT_EQ(t.boundary_edges, 4u);
  EXPECT_FALSE(t.closed());
  ASSERT_EQ(t.parts.size(), 1u);
  EXPECT_EQ(t.parts[0].boundary_edges, 4u);
  EXPECT_FALSE(t.parts[0].closed());
  for (const sc::MeshEdge& e : t.edges)
    EXPECT_EQ(e.boundary(), e.count == 1);
  EXPECT_EQ(sc::closed_part_winding(t), (std::vector<std::int8_t>{0, 0}));
  // The cube with one face (two triangles) missing: the four edges around the hole.
  IndexedMesh box = unit_cube();
  box.triangles.resize(10);
  EXPECT_EQ(build(box).boundary_edges, 4u);
}

TEST(MeshTopology, NonManifoldTJunctionIsFlagged) {
  // A fin on a plate: three triangles on the edge (0, 1) (a T seen end-on).
  IndexedMesh t_junction;
  t_junction.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  t_junction.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const sc::MeshTopology t = build(t_junction);
  EXPECT_EQ(t.non_manifold_edges, 1u);
  EXPECT_EQ(t.boundary_edges, 6u);
  ASSERT_EQ(t.parts.size(), 1u);  // joined through the non-manifold edge
  EXPECT_EQ(t.parts[0].non_manifold_edges, 1u);
  EXPECT_FALSE(t.parts[0].closed());
  const auto shared = std::find_if(t.edges.begin(), t.edges.end(),
                                   [](const sc::MeshEdge& e) { return e.non_manifold(); });
  ASSERT_NE(shared, t.edges.end());
  EXPECT_EQ(shared->count, 3u);
  EXPECT_EQ(std::min(shared->v0, shared->v1), 0u);
  EXPECT_EQ(std::max(shared->v0, shared->v1), 1u);
  // Its half-edges by triangle.
  const auto uses = t.uses(*shared);
  EXPECT_EQ(uses[0].triangle, 0u);
  EXPECT_EQ(uses[1].triangle, 1u);
  EXPECT_EQ(uses[2].triangle, 2u);
}

TEST(MeshTopology, FlippedFaceIsFlaggedAndOrientationTurnsItBack) {
  IndexedMesh cube = unit_cube();
  std::swap(cube.triangles[5].y, cube.triangles[5].z);
  const sc::MeshTopology t = build(cube);
  EXPECT_EQ(t.inconsistent_edges, 3u);  // its three edges
  EXPECT_EQ(t.boundary_edges, 0u);
  for (std::uint32_t e : t.triangle_edges[5])
    EXPECT_TRUE(t.edges[e].inconsistent());
  EXPECT_FALSE(t.parts[0].closed());
  EXPECT_EQ(sc::closed_part_winding(t), std::vector<std::int8_t>(12, 0));
  const sc::Orientation o = sc::orient_parts(t);
  EXPECT_EQ(o.conflict, sc::kNoIndex);
  std::vector<std::uint8_t> expected(12, 0);
  expected[5] = 1;
  EXPECT_EQ(o.flip, expected);
  // A Moebius strip (a band of 5 quads whose ends join with a half twist) is not orientable:
  // across the band at angle a runs w = cos(a / 2) radial + sin(a / 2) z, so that at a = 2 pi
  // the inner and outer rims have swapped.
  IndexedMesh strip;
  const unsigned n = 5;
  for (unsigned i = 0; i < n; ++i) {
    const double a = 2.0 * std::acos(-1.0) * i / n;
    const glm::dvec3 c(std::cos(a), std::sin(a), 0.0);
    const glm::dvec3 w = std::cos(0.5 * a) * c + glm::dvec3(0.0, 0.0, std::sin(0.5 * a));
    strip.positions.push_back(c - 0.3 * w);  // 2 i: inner rim
    strip.positions.push_back(c + 0.3 * w);  // 2 i + 1: outer rim
  }
  for (unsigned i = 0; i < n; ++i) {
    const unsigned in0 = 2 * i, out0 = 2 * i + 1;
    const unsigned in1 = i + 1 < n ? 2 * i + 2 : 1, out1 = i + 1 < n ? 2 * i + 3 : 0;
    strip.triangles.push_back({in0, in1, out1});
    strip.triangles.push_back({in0, out1, out0});
  }
  const sc::MeshTopology ts = build(strip);
  EXPECT_EQ(ts.parts.size(), 1u);
  EXPECT_EQ(ts.boundary_edges, 2u * n);  // its one rim, twice around
  EXPECT_EQ(ts.inconsistent_edges, 1u);  // where the ends meet
  EXPECT_NE(sc::orient_parts(ts).conflict, sc::kNoIndex);
}

TEST(MeshTopology, NearCoincidentVerticesWeldFartherOnesDoNot) {
  // The cube as a soup (every corner repeated per triangle), one copy of corner (1, 1, 1) moved.
  const IndexedMesh cube = unit_cube();
  const double tol = sc::kWeldRelativeTolerance * std::sqrt(3.0);  // extent: the diagonal
  auto moved = [&](double offset) {
    std::vector<std::array<glm::dvec3, 3>> s = soup(cube);
    for (auto& tri : s) {
      for (glm::dvec3& p : tri) {
        if (p == glm::dvec3(1, 1, 1)) {
          p += offset * glm::normalize(glm::dvec3(-1, -2, -0.5));  // inward: same extent
          return sc::build_topology(s);
        }
      }
    }
    return sc::build_topology(s);
  };
  const sc::MeshTopology near = moved(0.5 * tol);
  EXPECT_DOUBLE_EQ(near.weld.tolerance_m, tol);
  EXPECT_EQ(near.weld.size(), 8u);
  EXPECT_TRUE(near.closed());
  EXPECT_EQ(sc::closed_part_winding(near), std::vector<std::int8_t>(12, 1));
  // 1e-9 apart (the kind of crack a float export leaves): welded.
  EXPECT_TRUE(moved(1e-9).closed());
  // Twice the tolerance: a vertex of its own, the corner's edges in that triangle open.
  const sc::MeshTopology far = moved(2.0 * tol);
  EXPECT_EQ(far.weld.size(), 9u);
  EXPECT_EQ(far.boundary_edges, 4u);  // two edges of the moved copy and their two partners
  EXPECT_FALSE(far.closed());
  // A distance, not a grid quantisation: just under the tolerance welds, just over does not.
  EXPECT_TRUE(moved(0.99 * tol).closed());
  EXPECT_FALSE(moved(1.01 * tol).closed());
}

TEST(MeshTopology, WeldIsTransitiveAndIndependentOfVertexOrder) {
  const unsigned seed = 20240527u;
  std::cout << "random seed " << seed << "\n";
  std::mt19937 rng(seed);
  // The cube as a soup, the k-th copy of corner (0, 0, 0) moved 0.6 k tol inward: neighbours in
  // the chain are within the tolerance, its ends are not; single linkage welds them all, in any
  // vertex order.
  const IndexedMesh cube = unit_cube();
  const double tol = sc::kWeldRelativeTolerance * std::sqrt(3.0);
  std::vector<glm::dvec3> positions;
  std::vector<glm::uvec3> triangles;
  int copies = 0;
  for (const glm::uvec3& f : cube.triangles) {
    const auto base = static_cast<unsigned>(positions.size());
    for (int c = 0; c < 3; ++c) {
      glm::dvec3 p = cube.positions[f[c]];
      if (f[c] == 0)
        p += 0.6 * tol * copies++ * glm::normalize(glm::dvec3(1, 2, 3));
      positions.push_back(p);
    }
    triangles.push_back({base, base + 1, base + 2});
  }
  ASSERT_GE(copies, 3);  // the chain's ends are over the tolerance apart
  // And an octahedron beside it, each corner copy jittered by up to tol / 4 per coordinate (any
  // two copies within tol sqrt(3) / 2).
  std::uniform_real_distribution<double> jitter(-0.25 * tol, 0.25 * tol);
  const std::vector<glm::dvec3> octa{{0.5, 0.5, 0.2}, {0.5, 0.5, 0.8}, {0.2, 0.5, 0.5},
                                     {0.8, 0.5, 0.5}, {0.5, 0.2, 0.5}, {0.5, 0.8, 0.5}};
  for (unsigned x : {2u, 3u})
    for (unsigned y : {4u, 5u})
      for (unsigned z : {0u, 1u}) {
        // Outward: (x, y, z) counter-clockwise when the three are on the same side's parity.
        const bool ccw = (x == 3) == (y == 5) ? z == 1 : z == 0;
        const glm::uvec3 f = ccw ? glm::uvec3(x, y, z) : glm::uvec3(x, z, y);
        const auto base = static_cast<unsigned>(positions.size());
        for (int c = 0; c < 3; ++c)
          positions.push_back(octa[f[c]] + glm::dvec3{jitter(rng), jitter(rng), jitter(rng)});
        triangles.push_back({base, base + 1, base + 2});
      }
  const sc::MeshTopology ref =
      sc::build_topology(std::span<const glm::dvec3>(positions), triangles);
  EXPECT_EQ(ref.weld.size(), 14u);
  EXPECT_EQ(ref.edges.size(), 18u + 12u);
  EXPECT_TRUE(ref.closed());
  ASSERT_EQ(ref.parts.size(), 2u);
  EXPECT_EQ(sc::closed_part_winding(ref), std::vector<std::int8_t>(20, 1));
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<unsigned> perm(positions.size());
    std::iota(perm.begin(), perm.end(), 0u);
    std::shuffle(perm.begin(), perm.end(), rng);
    std::vector<glm::dvec3> p2(positions.size());
    for (std::size_t i = 0; i < perm.size(); ++i)
      p2[perm[i]] = positions[i];
    std::vector<glm::uvec3> t2 = triangles;
    for (glm::uvec3& t : t2)
      t = {perm[t.x], perm[t.y], perm[t.z]};
    const sc::MeshTopology t = sc::build_topology(std::span<const glm::dvec3>(p2), t2);
    EXPECT_EQ(t.weld.size(), 14u) << "trial " << trial;
    EXPECT_TRUE(t.closed()) << "trial " << trial;
    // The same vertices weld together as in the unpermuted mesh.
    for (std::size_t i = 0; i < positions.size(); ++i)
      for (std::size_t j = 0; j < positions.size(); ++j)
        ASSERT_EQ(ref.weld.welded[i] == ref.weld.welded[j],
                  t.weld.welded[perm[i]] == t.weld.welded[perm[j]])
            << "trial " << trial << ", vertices " << i << " and " << j;
  }
  // Moved 3 tol apart one from the next: nothing welds, every edge is a boundary.
  std::vector<glm::dvec3> apart = positions;
  for (std::size_t i = 0; i < apart.size(); ++i)
    apart[i] += glm::dvec3(3.0 * tol * static_cast<double>(i), 0.0, 0.0);
  const sc::MeshTopology open = sc::build_topology(std::span<const glm::dvec3>(apart), triangles);
  EXPECT_EQ(open.weld.size(), positions.size());
  EXPECT_EQ(open.boundary_edges, 3u * triangles.size());
  EXPECT_EQ(open.parts.size(), triangles.size());
}

TEST(MeshTopology, IndexedAndSoupWeldAlikeAndKeepNumbering) {
  // The generated sphere (its seam at phi = 2 pi lands 1e-16 m off phi = 0, and its south pole
  // one point per longitude): closed under the weld rule, as a soup and re-indexed.
  const sc::Mesh sphere =
      sc::make_target({sc::TargetKind::kSphere, 1.0, 1.0, 1.0, 0.0}).objects[0].mesh;
  const sc::MeshTopology t = sc::build_topology(sphere.positions_m, sphere.triangles);
  EXPECT_TRUE(t.closed()) << t.boundary_edges << " boundary edges";
  EXPECT_EQ(t.parts.size(), 1u);
  EXPECT_EQ(t.collapsed_triangles, 0u);
  EXPECT_NEAR(t.parts[0].volume_m3, 4.0 / 3.0 * std::acos(-1.0), 0.2);
  std::vector<std::array<glm::dvec3, 3>> s;
  for (const glm::uvec3& tri : sphere.triangles)
    s.push_back({glm::dvec3(sphere.positions_m[tri.x]), glm::dvec3(sphere.positions_m[tri.y]),
                 glm::dvec3(sphere.positions_m[tri.z])});
  const sc::MeshTopology ts = sc::build_topology(s);
  EXPECT_EQ(ts.weld.size(), t.weld.size());
  EXPECT_EQ(ts.edges.size(), t.edges.size());
  EXPECT_TRUE(ts.closed());
  EXPECT_DOUBLE_EQ(ts.weld.tolerance_m, t.weld.tolerance_m);
  // Without coincident vertices the numbering is the input's.
  const IndexedMesh cube = unit_cube();
  const sc::MeshTopology tc = build(cube);
  for (std::uint32_t i = 0; i < 8; ++i) {
    EXPECT_EQ(tc.weld.welded[i], i);
    EXPECT_EQ(tc.weld.first_input[i], i);
  }
}

TEST(MeshTopology, CollapsedSkippedInvalidAndNonFiniteTriangles) {
  // A sliver whose short edge is under the tolerance collapses; its neighbours then pair up.
  IndexedMesh cube = unit_cube();
  const double tol = sc::kWeldRelativeTolerance * std::sqrt(3.0);
  // Triangle 0 (0, 2, 3) takes a copy of corner 3 moved 0.1 tol (vertex 8), and the sliver
  // (2, 3, 8) fills the crack.
  cube.positions.push_back(cube.positions[3] + glm::dvec3(-0.1 * tol, 0.0, 0.0));
  cube.triangles[0] = {0, 2, 8};
  cube.triangles.push_back({2, 3, 8});
  const sc::MeshTopology t = build(cube);
  EXPECT_EQ(t.collapsed_triangles, 1u);
  EXPECT_EQ(t.use[12], sc::TriangleUse::kCollapsed);
  EXPECT_EQ(t.triangle_part[12], sc::kNoIndex);
  EXPECT_TRUE(t.closed());
  // Skipped triangles leave their edges open; an index out of range is invalid, not a crash.
  IndexedMesh box = unit_cube();
  std::vector<std::uint8_t> skip(12, 0);
  skip[0] = 1;
  box.triangles.push_back({0, 1, 99});
  skip.push_back(0);
  const sc::MeshTopology tb =
      sc::build_topology(std::span<const glm::dvec3>(box.positions), box.triangles, skip);
  EXPECT_EQ(tb.use[0], sc::TriangleUse::kSkipped);
  EXPECT_EQ(tb.use[12], sc::TriangleUse::kInvalid);
  EXPECT_EQ(tb.boundary_edges, 3u);
  // A non-finite vertex welds to nothing and does not widen the extent (no undefined
  // behaviour: this suite runs under UBSan).
  IndexedMesh inf = unit_cube();
  inf.positions.push_back({std::numeric_limits<double>::infinity(), 0.0, 0.0});
  inf.positions.push_back({std::numeric_limits<double>::infinity(), 0.0, 0.0});
  inf.positions.push_back({std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0});
  inf.triangles.push_back({8, 9, 10});
  const sc::MeshTopology ti = build(inf);
  EXPECT_DOUBLE_EQ(ti.weld.extent_m, std::sqrt(3.0));
  EXPECT_EQ(ti.weld.size(), 11u);
  EXPECT_EQ(ti.boundary_edges, 3u);
}

}  // namespace
