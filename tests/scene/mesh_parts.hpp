#pragma once
// Mesh facts the scene tests check against closed forms: connected parts, watertightness with
// consistent winding, and the divergence-theorem volume. Test code only.

#include <cstddef>
#include <vector>

#include "scene/types.hpp"

namespace radar_emu::test {

/// Connected parts of a mesh (triangles sharing a vertex position), as triangle index lists.
[[nodiscard]] std::vector<std::vector<std::size_t>> mesh_parts(const scene::Mesh& m);

/// Every directed edge a->b of `tris` appears exactly once and its reverse b->a exactly once:
/// the triangles close a surface and are consistently wound.
[[nodiscard]] bool closed_and_consistent(const scene::Mesh& m,
                                         const std::vector<std::size_t>& tris);
/// The same over the whole mesh.
[[nodiscard]] bool closed_and_consistent(const scene::Mesh& m);

/// Signed volume by the divergence theorem, sum over triangles of a . (b x c) / 6: positive and
/// equal to the true volume only when the triangles close a surface wound outward.
[[nodiscard]] double signed_volume(const scene::Mesh& m, const std::vector<std::size_t>& tris);

}  // namespace radar_emu::test
