#pragma once
// The perfectly conducting sphere, monostatic: the exact Mie series and the physical-optics
// closed form, both as complex backscatter amplitudes A [m] with sigma = |A|^2, phase referred
// to the sphere's centre, exp(+j w t) (the convention of radar/em/rcs.hpp).
// Pure computation; throw std::invalid_argument for non-positive or non-finite arguments.
// A reference solution (radar/reference/): the engines never call it; the tests and the
// tradeoff tool compare them against it.

#include <complex>

namespace radar_emu::radar {

/// Mie series (Ruck, Barrick, Stuart & Krichbaum, Radar Cross Section Handbook, 1970, vol. 1,
/// sec. 3.2; physics.md): sigma / (pi a^2) = (ka)^-2 |sum_n (-1)^n (2n+1) / (xi_n xi_n')|^2,
/// xi_n(x) = x h_n(x). Accurate to about 1e-10 relative for ka up to a few hundred.
[[nodiscard]] std::complex<double> mie_sphere_amplitude_m(double radius_m,
                                                          double wavenumber_rad_per_m);
[[nodiscard]] double mie_sphere_rcs_m2(double radius_m, double wavenumber_rad_per_m);

/// PO over the lit hemisphere in closed form: A = -j k/sqrt(pi) 2 pi a^2 [-j e^{jx}/x +
/// (e^{jx} - 1)/x^2], x = 2ka, so sigma/(pi a^2) = 1 - sin(2ka)/(ka) + sin^2(ka)/(ka)^2
/// (physics.md; Knott, Shaeffer & Tuley 2004, sec. 5.5).
[[nodiscard]] std::complex<double> po_sphere_amplitude_m(double radius_m,
                                                         double wavenumber_rad_per_m);
[[nodiscard]] double po_sphere_rcs_m2(double radius_m, double wavenumber_rad_per_m);

}  // namespace radar_emu::radar
