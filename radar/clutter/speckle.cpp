#include "radar/clutter/speckle.hpp"

#include <cmath>
#include <stdexcept>

#include "radar/constants.hpp"

namespace radar_emu::radar::clutter {

namespace {

// SplitMix64 (Steele, Lea & Flood, OOPSLA 2014): one 64-bit state, full period, passes BigCrush
// when used as here, one stream per (seed, polygon).
std::uint64_t mix64(std::uint64_t z) noexcept {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

struct Stream {
  std::uint64_t state;
  std::uint64_t next() noexcept { return mix64(state += 0x9E3779B97F4A7C15ull); }
  /// Uniform on the open interval (0, 1): 53 random bits, centred in their cell.
  double uniform() noexcept { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }
  double normal() noexcept {  // Box-Muller, one of the pair
    return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2.0 * kPi * uniform());
  }
  /// Gamma(shape a, scale 1): Marsaglia & Tsang (2000); a < 1 by Gamma(a+1) U^(1/a).
  double gamma(double a) noexcept {
    if (a < 1.0)
      return gamma(a + 1.0) * std::pow(uniform(), 1.0 / a);
    const double d = a - 1.0 / 3.0;
    const double c = 1.0 / std::sqrt(9.0 * d);
    for (;;) {
      double x = normal();
      double v = 1.0 + c * x;
      if (v <= 0.0)
        continue;
      v = v * v * v;
      const double u = uniform();
      if (std::log(u) < 0.5 * x * x + d - d * v + d * std::log(v))
        return d * v;
    }
  }
};

}  // namespace

void validate(const SpeckleSpec& spec) {
  if ((spec.model == SpeckleModel::kLooks || spec.model == SpeckleModel::kK) && spec.looks < 1)
    throw std::invalid_argument("speckle: looks must be >= 1 (got " + std::to_string(spec.looks) +
                                ")");
  if (spec.model == SpeckleModel::kK && !(spec.k_order_nu > 0.0 && std::isfinite(spec.k_order_nu)))
    throw std::invalid_argument("speckle: K-distribution order nu must be finite and > 0");
}

SpeckleSample speckle_sample(const SpeckleSpec& spec, std::uint64_t index) noexcept {
  if (spec.model == SpeckleModel::kNone)
    return {};
  Stream rng{mix64(spec.seed) ^ mix64(index ^ 0xD1B54A32D192ED03ull)};
  double intensity = 1.0;
  switch (spec.model) {
    case SpeckleModel::kExponential:
      intensity = -std::log(rng.uniform());
      break;
    case SpeckleModel::kLooks: {
      const double looks = static_cast<double>(spec.looks < 1 ? 1 : spec.looks);
      intensity = rng.gamma(looks) / looks;
      break;
    }
    case SpeckleModel::kK: {
      const double looks = static_cast<double>(spec.looks < 1 ? 1 : spec.looks);
      const double nu = spec.k_order_nu > 0.0 ? spec.k_order_nu : 1.0;
      intensity = (rng.gamma(nu) / nu) * (rng.gamma(looks) / looks);
      break;
    }
    case SpeckleModel::kNone:
      break;
  }
  const double phase = 2.0 * kPi * rng.uniform();
  return {static_cast<float>(intensity), static_cast<float>(phase)};
}

void fill_speckle_pattern(const SpeckleSpec& spec, std::uint64_t first_index,
                          std::span<SpeckleSample> out) {
  validate(spec);
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = speckle_sample(spec, first_index + i);
}

const char* to_string(SpeckleModel model) noexcept {
  switch (model) {
    case SpeckleModel::kNone:
      return "none";
    case SpeckleModel::kExponential:
      return "exponential";
    case SpeckleModel::kLooks:
      return "looks";
    case SpeckleModel::kK:
      return "k";
  }
  return "?";
}

}  // namespace radar_emu::radar::clutter
