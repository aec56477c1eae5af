#pragma once
// Point-target impulse-response analysis of a complex SAR image, with the usual definitions
// (those of isce3's point_target_info, NISAR calibration; implemented here from the
// definitions, no code taken):
//   - a chip of n x n pixels around the expected peak, its linear phase ramps removed (the mean
//     phase step between neighbours along each axis), oversampled by `oversample` by zero-padding
//     its 2-D spectrum (FFTW3);
//   - cuts through the oversampled peak along rows (range) and columns (azimuth);
//   - resolution: the width between the -3 dB points, each interpolated linearly in power
//     between the samples that straddle it;
//   - the main lobe runs between the first nulls (the first local minima of the power each side
//     of the peak); PSLR = highest sidelobe power / peak power; ISLR = power summed over the
//     sidelobe windows / power summed over the main lobe, the sidelobe windows reaching
//     `sidelobe_widths` main-lobe half-widths (peak to first null) beyond each null.
// Offline (allocates, plans FFTs); throws std::invalid_argument for bad input.

#include <complex>
#include <cstddef>
#include <span>
#include <vector>

namespace radar_emu::radar {

struct IrfCut {
  double resolution_px = 0.0;  ///< -3 dB width [input pixels]
  double pslr_db = 0.0;
  double islr_db = 0.0;
  std::vector<double> power_db;  ///< the cut, relative to the peak, every 1/oversample pixel
};

struct IrfResult {
  double peak_row = 0.0, peak_col = 0.0;  ///< fractional image coordinates of the peak
  double peak_power = 0.0;                ///< |peak|^2 (oversampled)
  double chip_energy = 0.0;               ///< sum of |pixel|^2 over the input chip
  IrfCut range;                           ///< along a row (columns)
  IrfCut azimuth;                         ///< along a column (rows)
};

struct IrfOptions {
  std::size_t chip = 64;        ///< even, 8..1024
  std::size_t oversample = 8;   ///< 1..64
  double sidelobe_widths = 10;  ///< > 0
  /// Known quadratic phase of the image about a point target [rad per pixel^2], down the rows
  /// (row index) and along the columns, removed before the linear ramps. 0 for images whose
  /// impulse response has a linear phase (isce3's assumption); a backprojected stripmap image
  /// whose pixels each integrate the aperture centred on themselves carries -k dx^2 / R down
  /// the azimuth axis (sar.hpp, sar_azimuth_quadratic_phase): not band-limited to the pixel
  /// grid, it would spoil the oversampling.
  double quadratic_phase_row_rad = 0.0, quadratic_phase_col_rad = 0.0;
};

/// `image` row-major rows x cols; (row, col): the expected peak (the chip is centred there; the
/// peak is searched inside it). Pixels outside the image count as 0.
[[nodiscard]] IrfResult analyse_point_target(std::span<const std::complex<float>> image,
                                             std::size_t rows, std::size_t cols, std::size_t row,
                                             std::size_t col, const IrfOptions& options = {});

/// Resolution, PSLR and ISLR of one power cut (linear power, peak anywhere, samples every
/// 1/oversample pixel), with the definitions above.
[[nodiscard]] IrfCut analyse_cut(std::span<const double> power, double oversample,
                                 double sidelobe_widths);

}  // namespace radar_emu::radar
