#pragma once
// Terrain clutter of `radar-emu sar` as fixed ground cells: the scene's terrain (its objects that
// are not targets) sampled on a horizontal grid by vertical rays, each cell a point scatterer of
// amplitude sqrt(sigma0(theta) A I) e^(j phi): sigma0 of the clutter models (radar/clutter,
// model "total") of the cell's material at its local incidence toward the platform at broadside,
// A the cell's surface area, (I, phi) its speckle sample (radar/clutter/speckle.hpp: the seed's
// "exponential intensity, uniform phase stored in each polygon"). Cells shadowed from the platform
// at broadside, or facing away, are left out. Fixed cells (rather than the tracer's per-ray
// diffuse returns, whose hit points move with the radar) keep each patch's phase from pulse to
// pulse, which is what lets the aperture focus them; with several cells per resolution cell the
// sum is circular Gaussian, so single-look intensity is exponential (Oliver & Quegan 2004, ch. 4).
// Setup (allocates; threads over grid lines with TBB).

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "radar/clutter/speckle.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/sar.hpp"
#include "scene/scene.hpp"

namespace radar_emu::radar {

struct TerrainCellSpec {
  glm::dvec3 origin_m{0.0};  ///< the grid's first cell centre (horizontal), world
  double cell_m = 1.0;       ///< grid step along track and across [m]
  std::size_t along = 0, across = 0;
  Polarisation polarisation = Polarisation::kVV;
  clutter::SpeckleSpec speckle;
};

struct TerrainCells {
  std::vector<SarScatterer> cells;
  std::size_t shadowed = 0;  ///< left out: shadowed or facing away
  std::size_t empty = 0;     ///< no terrain under the cell (a target, or nothing)
};

/// `tracer` tells targets from terrain and gives each scene material's sigma0 (its resolved
/// surfaces, radar/em/surfaces.hpp; read in `spec.polarisation`'s channel). Throws
/// std::invalid_argument when the tracer's carrier is not `p.carrier_hz`.
[[nodiscard]] TerrainCells terrain_cells(const scene::Scene& scene, const SbrTracer& tracer,
                                         const SarParams& p, const TerrainCellSpec& spec);

}  // namespace radar_emu::radar
