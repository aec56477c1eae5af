#pragma once
// Plane polygon helpers of the geodata import (internal to scene/): ear-clipping triangulation
// and the even-odd point-in-polygon test, in ENU metres (x east, y north).

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace radar_emu::scene::geodata::detail {

/// Twice the signed area of a ring (positive: counter-clockwise seen from above).
[[nodiscard]] double signed_area2(const std::vector<glm::dvec2>& ring) noexcept;
/// Triangulates a simple counter-clockwise ring (not closed: the first point is not repeated) by
/// ear clipping: n - 2 triangles of indices into `ring`, each counter-clockwise. A ring that is
/// not simple may leave no ear: the rest is then fanned from its first vertex (`fanned` set).
[[nodiscard]] std::vector<glm::uvec3> triangulate(const std::vector<glm::dvec2>& ring,
                                                  bool* fanned = nullptr);
/// Even-odd test against every ring (outer and holes together).
[[nodiscard]] bool inside(const std::vector<std::vector<glm::dvec2>>& rings, glm::dvec2 p) noexcept;

}  // namespace radar_emu::scene::geodata::detail
