#pragma once
// Corner reflectors for the frame tracer's tests (sbr_test.cpp, sbr_reuse_test.cpp), all metal
// (material 0), facing a radar on the -y axis.

#include <cmath>
#include <glm/glm.hpp>
#include <optional>

#include "scene/types.hpp"

namespace radar_emu::test {

// Right dihedral: fold along z through `at`, height a (along the fold), faces of width b, opening
// toward -y: broadside double bounce.
inline scene::ObjectDesc dihedral(double a, double b, glm::dvec3 at = glm::dvec3(0.0)) {
  scene::ObjectDesc o{"dihedral", {}, glm::dmat4(1.0), std::nullopt};
  const auto h = static_cast<float>(a / 2);
  const auto w = static_cast<float>(b / std::sqrt(2.0));
  o.mesh.positions_m = {{0, 0, -h}, {-w, -w, -h}, {-w, -w, h}, {0, 0, h},
                        {0, 0, -h}, {w, -w, -h},  {w, -w, h},  {0, 0, h}};
  o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  o.mesh.triangle_material = {0, 0, 0, 0};
  o.world_from_body[3] = glm::dvec4(at, 1.0);
  return o;
}

// Square trihedral of edge a with its symmetry axis toward -y.
inline scene::ObjectDesc trihedral(double a) {
  scene::ObjectDesc o{"trihedral", {}, glm::dmat4(1.0), std::nullopt};
  // Local octant x, y, z >= 0 rotated so that (1,1,1)/sqrt(3) points to -y.
  const glm::dvec3 from = glm::normalize(glm::dvec3(1.0)), to(0, -1, 0);
  const glm::dvec3 k = glm::cross(from, to);
  const double s = glm::length(k), c = glm::dot(from, to);
  const glm::dvec3 u = k / s;
  const glm::dmat3 kx(glm::dvec3(0, u.z, -u.y), glm::dvec3(-u.z, 0, u.x), glm::dvec3(u.y, -u.x, 0));
  const glm::dmat3 r = glm::dmat3(1.0) + s * kx + (1.0 - c) * kx * kx;
  auto p = [&](double x, double y, double z) { return glm::vec3(r * glm::dvec3(x, y, z)); };
  o.mesh.positions_m = {p(0, 0, 0), p(a, 0, 0), p(a, a, 0), p(0, a, 0), p(0, 0, 0), p(0, 0, a),
                        p(a, 0, a), p(a, 0, 0), p(0, 0, 0), p(0, a, 0), p(0, a, a), p(0, 0, a)};
  o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}, {8, 9, 10}, {8, 10, 11}};
  o.mesh.triangle_material.assign(6, 0);
  return o;
}

}  // namespace radar_emu::test
