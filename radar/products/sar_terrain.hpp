#pragma once
// Terrain of `radar-emu sar` from the terrain engine (radar/clutter/terrain_engine.hpp), and the
// digital elevation model (DEM) and geometry mask of the image grid.
//
// Scatterers. Every patch of the engine's facets (patch edge <= patch_m) is a point scatterer of
// amplitude sqrt(sigma0(theta) A I) e^(j phi) fixed in the world: sigma0 of its material at its
// local incidence theta toward the platform at broadside of it (the zero-Doppler position, where
// the aperture is centred), A its area, (I, phi) its speckle sample (look 0: "stored in each
// polygon", seed paper). Patches whose line of sight to that position is blocked are left out
// (shadow). Fixed scatterers keep their phase from pulse to pulse, which is what lets the aperture
// focus them; several per resolution cell make the single-look intensity exponential (Oliver &
// Quegan 2004, ch. 4). Layover follows from the synthesis: patches at one range share a cell.
//
// DEM. Per image pixel, the height of the highest terrain facet above it (the facets' horizontal
// projections rasterised on the grid), the surface backprojection focuses onto. A pixel that no
// facet covers (a hole in the DEM) takes the height of the nearest covered pixel of its row (else
// the mean height) and carries kSarNoDem in the mask: documented, flagged, never silently dark.
//
// Mask (bits of one byte per pixel), from the DEM and the platform at broadside, theta the
// incidence from the vertical, s the DEM's slope along ground range (away from the track):
//   kSarShadow          the line of sight from the pixel's surface point to the platform is
//                       blocked (terrain or structures);
//   kSarLayover         s > tan theta: the range falls going away from the track, so the slope's
//                       top images before its foot (the range derivative g - (H - z) s < 0,
//                       g the ground range, H - z the height below the platform);
//   kSarForeshortening  0.2 tan theta < s <= tan theta: a slope facing the radar, its slant range
//                       per metre of ground compressed by more than 20 % against flat ground;
//   kSarNoDem           the DEM had a hole here (above).
// Setup and offline (allocates; TBB threads; throws std::invalid_argument for bad input).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "radar/clutter/terrain_engine.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/sar.hpp"
#include "scene/scene.hpp"

namespace radar_emu::radar {

/// The terrain engine of a scene as the tracer resolved it: its sigma0 rows (the tracer's
/// SurfaceSet, in its polarisation channel) and its targets (objects with a conducting triangle)
/// left to the rays. Throws as the engine does (no terrain: std::invalid_argument).
[[nodiscard]] clutter::TerrainEngine make_terrain_engine(const scene::Scene& scene,
                                                         const SbrTracer& tracer,
                                                         clutter::TerrainEngineSpec spec);

struct TerrainCells {
  std::vector<SarScatterer> cells;
  std::size_t patches = 0;   ///< patches evaluated
  std::size_t shadowed = 0;  ///< left out: line of sight blocked
  double area_m2 = 0.0;      ///< terrain area of the engine's facets
  /// Issue 28: per sigma0 row of the engine's table, the lit patches and those whose sigma0
  /// sample the catalogue flags (outside a model's validity, extrapolated, assumed).
  std::vector<clutter::Sigma0Use> sigma0_use;
};

/// The engine's patches (edge <= patch_m) as fixed SAR scatterers (header). Throws
/// std::invalid_argument for patch_m <= 0 or over 2e8 patches.
[[nodiscard]] TerrainCells terrain_cells(const clutter::TerrainEngine& engine, const SarParams& p,
                                         double patch_m);

enum SarMaskBit : std::uint8_t {
  kSarShadow = 1,
  kSarLayover = 2,
  kSarForeshortening = 4,
  kSarNoDem = 8,
  /// The pixel's terrain reads a flagged sigma0 value (issue 28; SarDem::sigma0_flags): not in
  /// SarDem::mask (whose bits mark geometry), set in the image's mask band only.
  kSarSigma0Flagged = 16,
};

struct SarDem {
  std::vector<float> height_m;     ///< per pixel, row-major (SarImageGrid::height_m)
  std::vector<std::uint8_t> mask;  ///< SarMaskBit per pixel
  /// Per pixel, the engine's facet whose surface the DEM took (its material is the pixel's land
  /// cover), -1 in a hole.
  std::vector<std::int32_t> facet;
  std::size_t holes = 0, shadow = 0, layover = 0, foreshortening = 0;  ///< pixel counts
  /// Per pixel, the validity flags (radar/clutter/surface.hpp) of the sigma0 sample its facet
  /// reads at the pixel's broadside incidence (0: none, or no facet); issue 28.
  std::vector<std::uint32_t> sigma0_flags;
  std::size_t sigma0_flagged = 0;  ///< pixels with a facet whose sample is flagged
  std::size_t sigma0_pixels = 0;   ///< pixels with a facet
};

/// DEM and mask of `grid` (its origin's z ignored) over the engine's facets (header).
[[nodiscard]] SarDem sar_dem(const clutter::TerrainEngine& engine, const SarParams& p,
                             const SarImageGrid& grid);

}  // namespace radar_emu::radar
