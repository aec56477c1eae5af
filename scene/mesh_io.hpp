#pragma once
// Wavefront OBJ and STL (binary and ASCII) meshes for targets: read with a unit scale, write in
// metres. OBJ material groups ("usemtl NAME") become radar material names; STL has none, so every
// triangle gets `default_material`.

#include <filesystem>
#include <string>
#include <vector>

#include "scene/types.hpp"

namespace radar_emu::scene {

struct MeshFileOptions {
  double scale = 1.0;                      ///< file units to metres (0.001 for mm, 0.0254 for in)
  std::string default_material = "metal";  ///< for STL, and OBJ faces before any usemtl
};

/// Reads an OBJ or STL file (by extension) into a one-object scene description (object named
/// after the file stem). Polygons are fan-triangulated; OBJ indices may be negative (relative).
/// Throws std::runtime_error "FILE:LINE: reason" (OBJ, ASCII STL) or "FILE: reason" (binary STL)
/// for anything malformed: bad numbers, indices out of range, truncated files, no triangles,
/// only degenerate triangles. Degenerate triangles are dropped and, like an open or
/// non-manifold surface, reported in `warnings` (scene/mesh_check.hpp) when it is given.
[[nodiscard]] SceneDescription load_mesh_file(const std::filesystem::path& path,
                                              const MeshFileOptions& options = {},
                                              std::vector<std::string>* warnings = nullptr);

/// Writes one object's mesh (in its body frame) as OBJ (with usemtl groups) or binary STL, by
/// extension. Throws std::runtime_error naming the path on failure.
void write_mesh_file(const Mesh& mesh, const std::vector<Material>& materials,
                     const std::filesystem::path& path);

}  // namespace radar_emu::scene
