#pragma once
// Speckle: the multiplicative fluctuation of clutter power and phase from one resolution cell
// (or polygon) to the next, stored per polygon as a reproducible pattern (seed paper, "Radar
// features": "exponential probability density function coupled with an uniform probability
// density function for the phase of backscattered field ... stored in each polygon as a
// texture pattern").
//
// Statistics (Oliver & Quegan, Understanding SAR Images, 2004, ch. 4 and 11; Ward, Tough &
// Watts, Sea Clutter, 2006, ch. 4), all with unit mean intensity:
//   single look   I ~ Exp(1): mean of 10 log10 I = -10 gamma_E / ln 10 = -2.507 dB, standard
//                 deviation of 10 log10 I = (10 / ln 10) pi / sqrt 6 = 5.57 dB;
//   L looks       I ~ Gamma(L, 1/L): coefficient of variation 1 / sqrt(L);
//   K             I = tau * x, texture tau ~ Gamma(nu, 1/nu), x ~ Gamma(L, 1/L):
//                 <I^2> / <I>^2 = (1 + 1/L)(1 + 1/nu).
// The phase is uniform on [0, 2 pi).
//
// Reproducibility: the sample for polygon i depends only on (seed, i), through a counter-based
// generator (SplitMix64 of Steele, Lea & Flood 2014 feeding the variates below), not on the order
// of evaluation or on the C++ library: std::*_distribution is implementation-defined, so the
// variates are written out here (exponential by inversion, normal by Box-Muller, gamma by
// Marsaglia & Tsang 2000, ACM TOMS 26(3), with the U^(1/a) boost for a < 1).

#include <cstdint>
#include <span>
#include <string>

namespace radar_emu::radar::clutter {

enum class SpeckleModel : std::uint8_t {
  kNone,         ///< every factor 1 (mean clutter)
  kExponential,  ///< single-look: intensity exponential, phase uniform
  kLooks,        ///< L-look average: Gamma(L, 1/L)
  kK             ///< K-distributed: Gamma texture of order nu times L-look speckle
};

struct SpeckleSpec {
  SpeckleModel model = SpeckleModel::kExponential;
  int looks = 1;            ///< L >= 1 (kLooks, kK)
  double k_order_nu = 1.0;  ///< K-distribution order nu > 0 (kK); small nu: spiky clutter
  std::uint64_t seed = 20261122;
};

/// Throws std::invalid_argument with a one-line reason when the spec is unusable (setup).
void validate(const SpeckleSpec& spec);

struct SpeckleSample {
  float intensity = 1.0f;  ///< multiplies sigma0 (unit mean)
  float phase_rad = 0.0f;  ///< uniform on [0, 2 pi)
};

/// The speckle sample of polygon `index`: a pure function of (spec, index), noexcept, no
/// allocation (fit for the frame path as well as for setup).
[[nodiscard]] SpeckleSample speckle_sample(const SpeckleSpec& spec, std::uint64_t index) noexcept;

/// Fills `out[i]` with speckle_sample(spec, first_index + i) (the per-polygon texture).
void fill_speckle_pattern(const SpeckleSpec& spec, std::uint64_t first_index,
                          std::span<SpeckleSample> out);

[[nodiscard]] const char* to_string(SpeckleModel model) noexcept;

}  // namespace radar_emu::radar::clutter
