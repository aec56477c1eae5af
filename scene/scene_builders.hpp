#pragma once
// Internal to scene/: mesh builders shared by the built-in scenes (scene/default_scene.cpp,
// scene/airport_gen.cpp), and the four closed-loop objects of the default scene, which the
// generated airport keeps unchanged. Not part of the public API. Setup only (allocates).

#include <cstdint>
#include <glm/glm.hpp>
#include <string>

#include "scene/types.hpp"

namespace radar_emu::scene::detail {

/// Quad a b c d (counter-clockwise seen from the side its normal points to) as two triangles.
void add_quad(Mesh& m, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, std::uint16_t mat);
/// Axis-aligned box [lo, hi], closed, normals outward (12 triangles).
void add_box(Mesh& m, glm::vec3 lo, glm::vec3 hi, std::uint16_t mat);
/// Closed prism of `sides` faces along x from x0 to x1, axis at (y, z) = centre, outward; two
/// faces point exactly sideways (+-y).
void add_prism_x(Mesh& m, float x0, float x1, glm::vec2 centre, float radius, int sides,
                 std::uint16_t mat);
/// Square trihedral corner reflector of edge a (three single-sheet square plates), corner at
/// `corner`, symmetry axis (direction of peak return) along `axis` (6 triangles).
void add_trihedral(Mesh& m, glm::dvec3 corner, glm::dvec3 axis, double a, std::uint16_t mat);
/// Pure translation.
[[nodiscard]] glm::dmat4 translation(const glm::dvec3& p);

/// Appends the default scene's four closed-loop objects (parked_aircraft, parked_vehicle,
/// light_mast, moving_vehicle: layout in scene/default_scene.hpp), meshes of material index
/// `metal`, each with its 0.5 m trihedral when `corner_reflectors`, ObjectDesc::area = `area`.
void add_closed_loop_objects(SceneDescription& d, std::uint16_t metal, bool corner_reflectors,
                             const std::string& area);

}  // namespace radar_emu::scene::detail
