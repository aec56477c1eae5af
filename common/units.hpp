#pragma once
// Units: the one pi, the speed of light, the one degree constant and the degree / dB conversions
// (style.md item 4: SI inside, degrees and dB only at the edges). Real-time safe, no allocation.

#include <cmath>

namespace radar_emu::common {

inline constexpr double kPi = 3.14159265358979323846;
/// Speed of light in vacuum [m/s] (exact, SI).
inline constexpr double kC = 299792458.0;
/// Radians per degree, pi / 180: the only degree constant of the tree.
inline constexpr double kRadPerDeg = kPi / 180.0;

/// Degrees to radians: deg * (pi / 180).
[[nodiscard]] constexpr double radians(double deg) noexcept {
  return deg * kRadPerDeg;
}

/// Radians to degrees: rad * (180 / pi). (A site that divides by kRadPerDeg instead differs from
/// this in the last bit; such sites keep `rad / kRadPerDeg`.)
[[nodiscard]] constexpr double degrees(double rad) noexcept {
  return rad * (180.0 / kPi);
}

/// Power ratio to decibels, 10 log10(p) [dB]; p > 0 (0 gives -inf, < 0 NaN).
[[nodiscard]] inline double db_from_power(double p) noexcept {
  return 10.0 * std::log10(p);
}

/// Decibels to power ratio, 10^(db / 10).
[[nodiscard]] inline double power_from_db(double db) noexcept {
  return std::pow(10.0, db / 10.0);
}

}  // namespace radar_emu::common
