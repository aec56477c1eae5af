#include "radar/em/facet_po.hpp"

#include <algorithm>
#include <cmath>

namespace radar_emu::radar {

namespace {

// f[x, y] for f = exp(j x): (e^{jx} - e^{jy}) / (x - y) = j e^{j(x+y)/2} sinc((x-y)/2).
std::complex<double> first_difference(double x, double y) noexcept {
  const double m = 0.5 * (x + y);
  const double s = sinc(0.5 * (x - y));
  return {-std::sin(m) * s, std::cos(m) * s};
}

}  // namespace

std::complex<double> exp_divided_difference2(double a0, double a1, double a2) noexcept {
  // Divided differences are symmetric in their arguments: order them.
  if (a0 > a1)
    std::swap(a0, a1);
  if (a1 > a2)
    std::swap(a1, a2);
  if (a0 > a1)
    std::swap(a0, a1);
  const double spread = a2 - a0;
  if (spread >= kSeriesSpreadRad)
    return (first_difference(a1, a2) - first_difference(a0, a1)) / spread;
  // Series about the mean m: exp(j x) = e^{jm} sum_n (j y)^n / n!, y = x - m, and the second
  // divided difference of y^n at (y0, y1, y2) is h_{n-2}(y0, y1, y2) (de Boor 2001, ch. I).
  // h_k follows from the elementary symmetric polynomials e1, e2, e3 by Newton's identity
  // h_k = e1 h_{k-1} - e2 h_{k-2} + e3 h_{k-3} (Macdonald, Symmetric Functions, 1995, I.2.6').
  const double m = (a0 + a1 + a2) / 3.0;
  const double y0 = a0 - m, y1 = a1 - m, y2 = a2 - m;
  const double e1 = y0 + y1 + y2;  // ~0 by construction, kept for exactness
  const double e2 = y0 * y1 + y0 * y2 + y1 * y2;
  const double e3 = y0 * y1 * y2;
  double h_km3 = 0.0, h_km2 = 0.0, h_km1 = 1.0;  // h_{-2}, h_{-1}, h_0
  // Term n: j^n / n! h_{n-2}. |y| <= 2/3 of the spread < 1, and |h_k| <= C(k+2, 2) |y|^k, so the
  // terms fall faster than 1/n!: 24 terms reach below 1e-20.
  std::complex<double> sum{0.0, 0.0};
  double inv_factorial = 0.5;  // 1/2!
  const std::complex<double> j_powers[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  for (int n = 2; n < 26; ++n) {
    const double h = n == 2 ? 1.0 : e1 * h_km1 - e2 * h_km2 + e3 * h_km3;
    if (n > 2) {
      h_km3 = h_km2;
      h_km2 = h_km1;
      h_km1 = h;
    }
    sum += j_powers[n % 4] * (inv_factorial * h);
    inv_factorial /= static_cast<double>(n + 1);
  }
  return std::complex<double>(std::cos(m), std::sin(m)) * sum;
}

std::complex<double> triangle_phase_integral(double area_m2, double b0_m, double b1_m, double b2_m,
                                             double k) noexcept {
  return -2.0 * area_m2 * exp_divided_difference2(k * b0_m, k * b1_m, k * b2_m);
}

std::complex<double> triangle_phase_integral(const glm::dvec3& v0, const glm::dvec3& v1,
                                             const glm::dvec3& v2, const glm::dvec3& g) noexcept {
  const double area = 0.5 * glm::length(glm::cross(v1 - v0, v2 - v0));
  if (!(area > 0.0))
    return {0.0, 0.0};
  // Phases relative to v0 keep the differences exact when g . v0 is large; e^{j g.v0} in front.
  const double p0 = glm::dot(g, v0);
  const std::complex<double> base(std::cos(p0), std::sin(p0));
  return base * triangle_phase_integral(area, 0.0, glm::dot(g, v1 - v0), glm::dot(g, v2 - v0), 1.0);
}

}  // namespace radar_emu::radar
