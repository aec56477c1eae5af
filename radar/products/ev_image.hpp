#pragma once
// The forward-looking enhanced-vision (EV) radar image of the seed paper (ONERA / OKTAL SE,
// "Realistic radar simulation package applied to multisensor scenarios", section "Enhanced
// vision in airport context", figure 5): a 94 GHz radar scanning a 30 x 10 deg field with
// 0.15 deg (azimuth) x 10 deg (elevation) beams; "the range gates are summed up in each 0.15 deg
// in elevation to obtain square pixels"; "for each resolution cell or pixel, coherent summation
// of the different contributions from clutter and targets"; "average of 10 uncorrelated images".
//
// Grid. Column c (0 = left) is the beam at antenna azimuth az_c = az_min + (c + 1/2) p, row r
// (0 = top) the elevation band [el_max - (r + 1) p, el_max - r p], p the pixel (beam) size. The
// beam is taken as ideal: a return belongs to the column its direction of arrival
// (Contribution::azimuth_rad) falls in.
//
// Range gate to elevation (the seed's "range gates summed per 0.15 deg of elevation"). The radar
// measures range, not elevation (its beam is 10 deg tall); a return at slant range R in column c
// is put in the row whose elevation band sees the reference ground plane z = z_g (world, up) at
// range R. The ray of antenna direction (az_c, el), world unit vector w(az_c, el), meets the
// plane at
//   R(az_c, el) = (z_a - z_g) / (-w_z)        (w_z < 0; no ground at w_z >= 0),
// z_a the antenna height; for a level antenna straight ahead this is R = h / sin(psi), h the
// height above the plane and psi = -el the depression angle (flat-earth geometry, Skolnik,
// Radar Handbook, 3rd ed., 2008, sec. 16.2). R falls monotonically with the depression, so each
// row is one interval of range gates [R(az_c, el_low), R(az_c, el_high)); the row whose upper
// edge is at or above the horizon takes every range beyond its lower edge. Returns nearer than
// the bottom row, or in no column, are counted and left out. On flat ground this places every
// ground point at its true direction, so the image registers with an optical view on the same
// angular grid; objects above the plane are placed at the ground's elevation at their range (the
// radar cannot tell), i.e. shifted down in the image.
//
// Pixel value. The coherent sum of the contributions of the cell (radar/em/sbr.hpp: complex
// amplitude A [m], no range term, so the image is range-compensated: |sum|^2 is the radar cross
// section of the cell [m^2]):
//   F_l(cell) = sum_targets A_i + sum_clutter |A_i| g_{l,i},   I = (1/N) sum_l |F_l|^2,
// g_{l,i} a unit-power circular complex Gaussian (exponential intensity, uniform phase: the
// seed's speckle model, radar/clutter/speckle.hpp, "exponential probability density function
// coupled with an uniform probability density function for the phase"), independent from look
// to look and contribution to contribution (speckle_sample(seed, l * n + i)). Targets keep their
// deterministic phase exp(-j k L) in every look. N looks of independent speckle average to
// Gamma(N, <I>/N) intensity over homogeneous clutter: coefficient of variation 1/sqrt(N)
// (Oliver & Quegan, Understanding SAR Images, 2004, eq. 4.8). The mean image
//   <I>(cell) = sum_clutter |A_i|^2 + |sum_targets A_i|^2
// (the expectation of I) is formed alongside. Atmospheric loss is the caller's
// (radar/propagation/path.hpp, apply_two_way_loss on the contributions first). Receiver noise
// and the antenna's elevation pattern are not applied (the display is the scene's reflectivity).
//
// Pure computation, setup/offline: allocates, throws std::invalid_argument for a bad grid.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "radar/clutter/terrain_engine.hpp"
#include "radar/em/sbr.hpp"

namespace radar_emu::radar {

struct EvImageConfig {
  double azimuth_min_rad = -0.2617993877991494;  ///< left edge of the field (antenna frame)
  double azimuth_max_rad = 0.2617993877991494;   ///< right edge
  double elevation_min_rad = -0.0872664625997165;
  double elevation_max_rad = 0.0872664625997165;
  double pixel_rad = 0.002617993877991494;  ///< square pixel: beam width = elevation band
  double ground_height_m = 0.0;             ///< z_g of the reference plane (world, up) [m]
  int looks = 10;                           ///< N >= 1 uncorrelated looks averaged
  std::uint64_t seed = 20261124;            ///< speckle of the looks
  bool speckle = true;                      ///< false: every look is the mean image (no speckle)
};

/// Columns and rows of the grid: floor(field / pixel + 1e-9), at least 1 (the grid starts at the
/// field's left and top edges). Throws std::invalid_argument naming the field that is bad.
[[nodiscard]] int ev_image_columns(const EvImageConfig& config);
[[nodiscard]] int ev_image_rows(const EvImageConfig& config);

struct EvImage {
  int columns = 0;
  int rows = 0;
  /// Row-major [row][column], row 0 at the top: the N-look intensity I [m^2].
  std::vector<float> intensity_m2;
  /// The expectation of I (no speckle) [m^2].
  std::vector<float> mean_m2;
  /// Per column, the rows + 1 range edges [m] of the rows (edge k is row k's upper edge,
  /// elevation el_max - k p; +inf where the ray does not meet the ground plane).
  std::vector<double> range_edges_m;
  std::uint64_t contributions_used = 0;
  std::uint64_t outside_columns = 0;     ///< direction of arrival outside the field's azimuths
  std::uint64_t nearer_than_field = 0;   ///< range below the bottom row's near edge
  std::uint64_t farther_than_field = 0;  ///< range beyond the top row's far edge
  std::uint64_t no_ground = 0;           ///< column whose every row edge misses the ground plane
  [[nodiscard]] float at(int row, int column) const noexcept {
    return intensity_m2[static_cast<std::size_t>(row) * static_cast<std::size_t>(columns) +
                        static_cast<std::size_t>(column)];
  }
};

/// Azimuth of column c's centre and elevation of row r's centre [rad].
[[nodiscard]] double ev_column_azimuth_rad(const EvImageConfig& config, int column) noexcept;
[[nodiscard]] double ev_row_elevation_rad(const EvImageConfig& config, int row) noexcept;

/// Forms the image (header) from one trace's contributions (atmospheric loss already applied)
/// seen from `pose`.
[[nodiscard]] EvImage form_ev_image(std::span<const Contribution> contributions,
                                    const RadarPose& pose, const EvImageConfig& config);

/// Terrain from the terrain engine (radar/clutter/terrain_engine.hpp) instead of the tracer's
/// diffuse terrain returns: every pixel (column c, the range interval of row r) is one cell of
/// the engine, which adds the patches whose range and azimuth fall in it (and whose elevation is
/// inside the field), look l's field with speckle look l (look 0: the texture stored per patch);
/// the contributions' non-coherent (diffuse) returns are then left out, their coherent ones
/// (targets, structures) added as in the header. Patches are half a pixel wide at their
/// range (at least `patch_min_m`); the one-way atmospheric loss is applied per patch.
struct EvTerrain {
  const clutter::TerrainEngine* engine = nullptr;
  double wavelength_m = 0.0;
  double patch_min_m = 0.5;
  double one_way_loss_db_per_m = 0.0;
  clutter::TerrainStats stats{};  ///< filled by form_ev_image
  /// Issue 28: per sigma0 row of the engine's table, the patches that read flagged values
  /// (clutter::Sigma0Use), and the image's cells with terrain and those with a flagged patch;
  /// form_ev_image adds to them (sizing sigma0_use to the table's rows when smaller).
  std::vector<clutter::Sigma0Use> sigma0_use;
  std::uint64_t terrain_cells = 0;
  std::uint64_t flagged_cells = 0;
};
[[nodiscard]] EvImage form_ev_image(std::span<const Contribution> contributions,
                                    const RadarPose& pose, const EvImageConfig& config,
                                    EvTerrain& terrain);

}  // namespace radar_emu::radar
