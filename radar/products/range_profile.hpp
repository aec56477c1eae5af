#pragma once
// Range profiles and ISAR images from stepped-frequency complex scattering amplitudes (FFTW3).
//
// Model. Monostatic samples of point scatterers p at frequencies f_n = start + n step are
//   A(f_n) = sum_p a_p exp(-j 2 k_n R_p),  k_n = 2 pi f_n / c,
// R_p the scatterer's down-range distance from the phase reference (the target origin), positive
// away from the radar (exp(+j w t); radar/em/rcs.hpp gives exactly this). The profile is the
// windowed inverse transform
//   p(R) = sum_n w_n A(f_n) exp(+j 2 k_n R) / sum_n w_n,
// so a point scatterer gives a peak of |a_p| at R_p (Mensa, High Resolution Radar Cross-Section
// Imaging, 1991, ch. 3; Wehner, High-Resolution Radar, 2nd ed., 1995, ch. 5). The carrier phase
// exp(+j 2 k_0 R) is kept, so the complex output is p(R) itself, not just its magnitude.
// Resolution c / (2 B) with B = count * step; samples every c / (2 B oversample) over the
// unambiguous window c / (2 step), centred on 0.
//
// ISAR (small-angle, small-bandwidth, polar format ignored): for angles offset by
// dtheta_m = (m - (M-1)/2) angle_step from the centre of the sweep,
//   A(m, n) = sum_p a_p exp(-j 2 k_n R_p) exp(+j 2 k_n dtheta_m y_p),
// y_p the cross-range coordinate along d(r_hat)/d(theta) (the way the radar moves as the angle
// grows). The image is the separable windowed 2-D inverse transform with k_c (the centre
// wavenumber) on the cross-range axis: cross-range resolution lambda_c / (2 Theta), Theta =
// M angle_step. Valid while a scatterer's range migration |y| Theta and its cross-range
// migration |R| B / f_c stay under one resolution cell; beyond, images blur (Wehner 1995,
// sec. 7.4): keep Theta and B / f_c small or reformat in polar coordinates first.
//
// Setup/offline functions: they allocate and create FFTW plans (not thread-safe, FFTW's rule);
// not for the real-time frame path. Throw std::invalid_argument for bad input.

#include <complex>
#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "radar/sensor/window.hpp"

namespace radar_emu::radar {

/// The profile and ISAR tapers are the sensor's (radar/sensor/window.hpp); Taylor here is the
/// -35 dB, nbar = 4 design.
using Window = WindowKind;

struct FrequencyGrid {
  double start_hz = 0.0;
  double step_hz = 0.0;
  std::size_t count = 0;  ///< f_n = start + n step, n < count
};

struct RangeProfile {
  std::vector<double> range_m;                    ///< ascending, [-R_u/2, R_u/2)
  std::vector<std::complex<double>> amplitude_m;  ///< p(R) [m]: |p|^2 in m^2
  double resolution_m = 0.0;                      ///< c / (2 B), B = count * step
  double bin_m = 0.0;                             ///< sample spacing (resolution / oversample)
  double unambiguous_m = 0.0;                     ///< R_u = c / (2 step)
};

/// `samples_m.size()` == grid.count >= 2, step > 0, start > 0, oversample in 1..64.
[[nodiscard]] RangeProfile range_profile(std::span<const std::complex<double>> samples_m,
                                         const FrequencyGrid& grid, Window window,
                                         std::size_t oversample = 4);

struct IsarImage {
  std::vector<double> range_m;                 ///< columns, as RangeProfile::range_m
  std::vector<double> cross_range_m;           ///< rows, ascending
  std::vector<std::complex<double>> pixels_m;  ///< row-major [cross_range][range]
  double range_resolution_m = 0.0;             ///< c / (2 B)
  double cross_range_resolution_m = 0.0;       ///< lambda_c / (2 Theta)
};

/// `samples_m` row-major [angle][frequency] in ascending angle, angle_count >= 2,
/// angle_step_rad > 0.
[[nodiscard]] IsarImage isar_image(std::span<const std::complex<double>> samples_m,
                                   const FrequencyGrid& grid, double angle_step_rad,
                                   std::size_t angle_count, Window window,
                                   std::size_t oversample = 4);

}  // namespace radar_emu::radar
