#pragma once
// Mesh sanity at load: degenerate triangles (reported with file, triangle and line, then
// dropped) and open, non-manifold or inconsistently wound surfaces (a warning: the RCS engine's
// shadowing and two-sided facets assume closed bodies or deliberate sheets). Setup only.

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "scene/types.hpp"

namespace radar_emu::scene {

struct MeshCheck {
  std::size_t triangles = 0;
  std::vector<std::size_t> degenerate;  ///< indices of degenerate triangles, ascending
  /// Edges used by exactly one triangle / by more than two / by two running it the same way,
  /// among the non-degenerate triangles, vertices welded by the one rule of
  /// scene/mesh/topology.hpp (STL and many OBJ exports repeat vertices per triangle). Boundary
  /// edges that a T-junction closes (one side of a seam split finer than the other) are not
  /// counted.
  std::size_t boundary_edges = 0;
  std::size_t non_manifold_edges = 0;
  std::size_t inconsistent_edges = 0;
  [[nodiscard]] bool closed() const noexcept {
    return boundary_edges == 0 && non_manifold_edges == 0 && inconsistent_edges == 0;
  }
};

/// A triangle is degenerate when two of its indices are equal, an index is out of range, or its
/// area is under 1e-12 of its longest edge squared (collinear or coincident vertices).
[[nodiscard]] bool is_degenerate(const Mesh& mesh, std::size_t triangle) noexcept;
[[nodiscard]] MeshCheck check_mesh(const Mesh& mesh);

/// Drops the degenerate triangles of a freshly loaded mesh and returns the warnings, each
/// starting with `source` (the file, or "file: node NAME"): one per degenerate triangle (its
/// index in the file's triangle order and, when `lines` has an entry for it other than 0, its
/// line) up to 10, then "... and N more"; one for an open mesh, one for non-manifold edges and
/// one for inconsistently wound edges.
/// Throws std::runtime_error "SOURCE: every triangle is degenerate" when nothing is left.
[[nodiscard]] std::vector<std::string> clean_loaded_mesh(Mesh& mesh, const std::string& source,
                                                         std::span<const std::size_t> lines = {});
/// The same with `check`, the mesh's check_mesh() computed by the caller (the glTF loader
/// checks each node once, in parallel, and drops the wholly degenerate ones itself).
[[nodiscard]] std::vector<std::string> clean_loaded_mesh(Mesh& mesh, const MeshCheck& check,
                                                         const std::string& source,
                                                         std::span<const std::size_t> lines = {});

}  // namespace radar_emu::scene
