#pragma once
// One mesh topology for every user of a mesh's connectivity: the SBR core's closed parts (the
// frame tracer and the RCS engine), the edge finder's wedges (radar/em/edges.hpp), the method of
// moments' RWG functions (radar/em/mom.hpp) and the mesh check at load (scene/mesh_check.hpp).
// One weld rule, an edge table of half-edges with boundary / non-manifold / winding flags, and
// the connected parts with their closure and signed volume. Setup only (allocates); no Embree.
//
// The weld rule. Two vertices are one when they lie within
//   tolerance_m = kWeldRelativeTolerance * extent_m        (kWeldRelativeTolerance = 1e-7)
// of each other (Euclidean distance, in double), extent_m the diagonal of the bounding box of the
// finite vertices the triangles use; the relation is closed transitively (single linkage), so the
// result does not depend on the order of the vertices, and an indexed mesh and the same triangles
// as a soup (three positions per triangle) weld alike. A non-finite vertex is welded to nothing.
// Why one tolerance serves all four users:
//  - Meshes are float (scene::Mesh; style.md item 5): a vertex carries 2^-24 ~ 6e-8 of its
//    coordinates. An exporter or generator that reaches one corner by two computations lands it a
//    few float steps apart, and a latitude-longitude sphere's seam at phi = 2 pi lands 1e-16 m off
//    its phi = 0 twin (sin(2 pi) != 0 in floating point). An exact-position weld leaves such
//    cracks open: the method of moments can put no current across them, the edge finder takes
//    each side for an open sheet's boundary (a half-plane that diffracts on a smooth surface), and
//    the tracer calls a closed body open. The mesh check and the method of moments welded to
//    1e-7 of the extent already; the tracer and the edge finder welded exact positions only, so
//    the check could call a mesh closed that the tracer took for open (the generated sphere:
//    closed for the check, all 960 triangles open for the tracer, 94 half-plane edges).
//  - 1e-7 of the extent is far below anything the physics resolves or a ray can pass: the
//    wavelength at 94 GHz is 3.2 mm where 1e-7 of a 10 m target is 1 um; the ray offsets of both
//    engines are 1e-5 of the extent (100 times more), and Embree traverses in float. So the
//    tracer's "the inside of a closed part is never lit" holds for a part closed under this weld.
//  - Closure itself is exact: a part is closed only when every one of its edges (between welded
//    vertices) is used by exactly two triangles running it in opposite directions. There is no
//    tolerance on edges and no leniency for T-junctions (the mesh check reports those apart).

#include <array>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

namespace radar_emu::scene {

/// Welding distance as a fraction of the mesh's extent (the rule in the header).
inline constexpr double kWeldRelativeTolerance = 1e-7;
/// "No such element" in the topology's index fields.
inline constexpr std::uint32_t kNoIndex = 0xFFFFFFFFu;

/// The vertices of a mesh, welded by the rule in the header.
struct VertexWeld {
  /// The welded vertex of each input vertex. Welded vertices are numbered in the order of their
  /// lowest input vertex, so a mesh without coincident vertices keeps its numbering.
  std::vector<std::uint32_t> welded;
  /// The lowest input vertex of each welded vertex: its position is the welded vertex's.
  std::vector<std::uint32_t> first_input;
  double extent_m = 0.0;     ///< bounding-box diagonal of the finite used vertices [m]
  double tolerance_m = 0.0;  ///< kWeldRelativeTolerance * extent_m [m]
  [[nodiscard]] std::size_t size() const noexcept { return first_input.size(); }
};

/// Welds `positions_m` [m]; the extent is that of the vertices `triangles` use (an index out of
/// range is ignored). Every vertex is welded, used or not (one 800 extents or more outside the
/// used ones by exact position only). Throws std::invalid_argument beyond 2^32 - 1 vertices.
[[nodiscard]] VertexWeld weld_vertices(std::span<const glm::vec3> positions_m,
                                       std::span<const glm::uvec3> triangles);
[[nodiscard]] VertexWeld weld_vertices(std::span<const glm::dvec3> positions_m,
                                       std::span<const glm::uvec3> triangles);

/// One triangle's use of an edge (a half-edge): the triangle runs from its corner `corner` to
/// corner (corner + 1) % 3 along the edge.
struct HalfEdge {
  std::uint32_t triangle = 0;
  std::uint8_t corner = 0;
  bool forward = false;  ///< runs from the edge's v0 to its v1 (lower welded vertex to higher)
};

/// Bits of MeshEdge::flags.
enum EdgeFlag : std::uint8_t {
  kEdgeBoundary = 1u << 0,     ///< used by one triangle: the boundary of an open surface
  kEdgeNonManifold = 1u << 1,  ///< used by more than two triangles
  kEdgeInconsistent = 1u << 2  ///< used by two triangles running it the same way (winding flips)
};

/// An edge between two welded vertices and the half-edges on it.
struct MeshEdge {
  std::uint32_t v0 = 0, v1 = 0;  ///< welded vertices, v0 < v1
  /// Its half-edges are MeshTopology::half_edges[first, first + count), ordered by triangle, then
  /// corner.
  std::uint32_t first = 0, count = 0;
  std::uint8_t flags = 0;  ///< EdgeFlag bits; 0: two triangles, opposite directions (closed)
  [[nodiscard]] bool boundary() const noexcept { return (flags & kEdgeBoundary) != 0; }
  [[nodiscard]] bool non_manifold() const noexcept { return (flags & kEdgeNonManifold) != 0; }
  [[nodiscard]] bool inconsistent() const noexcept { return (flags & kEdgeInconsistent) != 0; }
};

/// A connected part: the triangles joined by shared edges (any number of uses).
struct MeshPart {
  std::uint32_t triangles = 0;
  std::uint32_t boundary_edges = 0, non_manifold_edges = 0, inconsistent_edges = 0;
  /// Signed volume by the divergence theorem, sum of a . (b x c) / 6 over its triangles as wound
  /// (input positions, triangle order) [m^3]: positive for a closed part wound outward
  /// (counter-clockwise seen from outside), negative inward, about 0 for a closed sheet.
  double volume_m3 = 0.0;
  /// Every edge used by exactly two triangles in opposite directions: a closed, consistently
  /// wound surface.
  [[nodiscard]] bool closed() const noexcept {
    return boundary_edges == 0 && non_manifold_edges == 0 && inconsistent_edges == 0;
  }
};

/// What became of an input triangle.
enum class TriangleUse : std::uint8_t {
  kUsed,       ///< in the topology
  kSkipped,    ///< left out by the caller (build_topology's `skip`)
  kCollapsed,  ///< two of its corners weld to one vertex: no edges, no part
  kInvalid,    ///< a vertex index out of range: no edges, no part
};

struct MeshTopology {
  VertexWeld weld;
  /// Per input triangle: its corners' welded vertices (as wound), its use, and the edge from
  /// corner i to corner (i + 1) % 3 (kNoIndex unless used).
  std::vector<std::array<std::uint32_t, 3>> corners;
  std::vector<TriangleUse> use;
  std::vector<std::array<std::uint32_t, 3>> triangle_edges;
  std::vector<HalfEdge> half_edges;
  std::vector<MeshEdge> edges;  ///< ordered by (v0, v1)
  /// Per input triangle: its part (kNoIndex unless used). Parts are numbered in the order of
  /// their lowest triangle.
  std::vector<std::uint32_t> triangle_part;
  std::vector<MeshPart> parts;
  std::size_t boundary_edges = 0, non_manifold_edges = 0, inconsistent_edges = 0;
  std::size_t collapsed_triangles = 0;

  [[nodiscard]] std::span<const HalfEdge> uses(const MeshEdge& e) const noexcept {
    return std::span<const HalfEdge>(half_edges).subspan(e.first, e.count);
  }
  /// No boundary, non-manifold or inconsistently wound edge anywhere.
  [[nodiscard]] bool closed() const noexcept {
    return boundary_edges == 0 && non_manifold_edges == 0 && inconsistent_edges == 0;
  }
};

/// The topology of `triangles` (indices into `positions_m` [m]), vertices welded by the header's
/// rule; triangles with skip[i] != 0 (`skip` empty or one entry per triangle) are left out.
[[nodiscard]] MeshTopology build_topology(std::span<const glm::vec3> positions_m,
                                          std::span<const glm::uvec3> triangles,
                                          std::span<const std::uint8_t> skip = {});
[[nodiscard]] MeshTopology build_topology(std::span<const glm::dvec3> positions_m,
                                          std::span<const glm::uvec3> triangles,
                                          std::span<const std::uint8_t> skip = {});
/// The same with the vertices already welded (`weld` = weld_vertices(positions_m, triangles)),
/// for a caller that judges its triangles on the welded vertices first.
[[nodiscard]] MeshTopology build_topology(std::span<const glm::dvec3> positions_m, VertexWeld weld,
                                          std::span<const glm::uvec3> triangles,
                                          std::span<const std::uint8_t> skip = {});
/// A triangle soup (three corners per triangle [m]): input vertex 3 i + c is corner c of
/// triangle i, so welded vertices are numbered in the order the triangles first reach them.
[[nodiscard]] MeshTopology build_topology(std::span<const std::array<glm::dvec3, 3>> triangles_m);

/// Per triangle: +1 on a closed part wound outward (positive volume), -1 on one wound inward,
/// 0 on an open part, one that encloses no volume, or a triangle not used.
[[nodiscard]] std::vector<std::int8_t> closed_part_winding(const MeshTopology& topology);

/// Flips that wind every part consistently: breadth first from the part's lowest triangle (kept
/// as wound) across its two-triangle edges, neighbours in edge order; non-manifold edges are not
/// crossed. `conflict` is the triangle at which a part was found not orientable (a Moebius-like
/// strip; the search stops there), kNoIndex if none.
struct Orientation {
  std::vector<std::uint8_t> flip;  ///< per input triangle: 1 to reverse its winding
  std::uint32_t conflict = kNoIndex;
};
[[nodiscard]] Orientation orient_parts(const MeshTopology& topology);

}  // namespace radar_emu::scene
