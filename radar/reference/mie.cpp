#include "radar/reference/mie.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {

void check(double radius_m, double k) {
  if (!std::isfinite(radius_m) || radius_m <= 0.0 || !std::isfinite(k) || k <= 0.0)
    throw std::invalid_argument("sphere: radius and wavenumber must be positive and finite");
}

}  // namespace

std::complex<double> mie_sphere_amplitude_m(double radius_m, double k) {
  check(radius_m, k);
  const double x = k * radius_m;
  // Terms to n_max = x + 4 x^(1/3) + 2 (Wiscombe, Applied Optics 19(9), 1980, eq. (1)), plus a
  // margin: the terms fall off super-exponentially beyond it.
  const int n_max = static_cast<int>(x + 4.0 * std::cbrt(x) + 2.0) + 10;
  // Riccati-Bessel functions psi_n = x j_n(x) by downward recurrence (Miller's algorithm,
  // normalised by psi_0 = sin x; stable for n > x, where the upward one is not) and
  // chi_n = x y_n(x) by upward recurrence (stable): z_{n-1} + z_{n+1} = (2n+1)/x z_n
  // (Abramowitz & Stegun 10.1.19).
  const int start = n_max + 20 + static_cast<int>(std::sqrt(40.0 * (n_max + 1)));
  std::vector<double> psi(static_cast<std::size_t>(n_max) + 2, 0.0);
  double up = 0.0, cur = 1e-300;
  for (int n = start; n >= 0; --n) {
    const double down = (2.0 * n + 1.0) / x * cur - up;  // psi_{n-1}
    up = cur;
    cur = down;
    if (n - 1 <= n_max + 1 && n - 1 >= 0)
      psi[static_cast<std::size_t>(n - 1)] = cur;
    if (std::abs(cur) > 1e250) {  // rescale to avoid overflow
      for (double& p : psi)
        p *= 1e-250;
      up *= 1e-250;
      cur *= 1e-250;
    }
  }
  const double scale = std::sin(x) / psi[0];
  for (double& p : psi)
    p *= scale;
  std::vector<double> chi(static_cast<std::size_t>(n_max) + 2);
  chi[0] = -std::cos(x);
  chi[1] = -std::cos(x) / x - std::sin(x);
  for (int n = 1; n <= n_max; ++n) {
    chi[static_cast<std::size_t>(n) + 1] = (2.0 * n + 1.0) / x * chi[static_cast<std::size_t>(n)] -
                                           chi[static_cast<std::size_t>(n) - 1];
  }
  // xi_n = psi_n - j chi_n = x h_n^(2)(x), outgoing for exp(+j w t); xi_n' = xi_{n-1} - n xi_n / x.
  std::complex<double> sum{0.0, 0.0};
  for (int n = 1; n <= n_max; ++n) {
    const auto i = static_cast<std::size_t>(n);
    const std::complex<double> xi(psi[i], -chi[i]), xi_prev(psi[i - 1], -chi[i - 1]);
    const std::complex<double> dxi = xi_prev - static_cast<double>(n) / x * xi;
    sum += (n % 2 == 0 ? 1.0 : -1.0) * (2.0 * n + 1.0) / (xi * dxi);
  }
  // sigma = pi a^2 |sum|^2 / x^2. The sign makes the phase that of rcs.hpp's convention: at
  // large ka the amplitude tends to the PO specular term -sqrt(pi) a e^{j 2ka}
  // (tests/radar/mie_test.cpp checks the phase against po_sphere_amplitude_m).
  return -std::sqrt(kPi) * radius_m / x * sum;
}

double mie_sphere_rcs_m2(double radius_m, double k) {
  return std::norm(mie_sphere_amplitude_m(radius_m, k));
}

std::complex<double> po_sphere_amplitude_m(double radius_m, double k) {
  check(radius_m, k);
  const double x = 2.0 * k * radius_m;
  const std::complex<double> e = std::polar(1.0, x), j(0.0, 1.0);
  return -j * k / std::sqrt(kPi) * 2.0 * kPi * radius_m * radius_m *
         (-j * e / x + (e - 1.0) / (x * x));
}

double po_sphere_rcs_m2(double radius_m, double k) {
  return std::norm(po_sphere_amplitude_m(radius_m, k));
}

}  // namespace radar_emu::radar
