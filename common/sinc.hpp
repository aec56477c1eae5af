#pragma once
// The unnormalised sinc, sin(x) / x. Real-time safe.

#include <cmath>

namespace radar_emu::common {

/// sin(x) / x [x in rad], exact at 0 (1). Near 0 the series 1 - x^2/6 + x^4/120, whose
/// truncation error is under x^6/5040 < 2e-22 for |x| < 1e-3.
[[nodiscard]] inline double sinc(double x) noexcept {
  if (std::abs(x) < 1e-3) {
    const double x2 = x * x;
    return 1.0 - x2 / 6.0 + x2 * x2 / 120.0;
  }
  return std::sin(x) / x;
}

}  // namespace radar_emu::common
