#pragma once
// The physical-optics radiation integral over one flat triangle, in closed form.
//
// For a triangle T with vertices v0, v1, v2 and a real phase-gradient vector g [rad/m],
//   I(g) = integral over T of exp(j g . r) dS    [m^2].
// With the barycentric map r = v0 + s (v1 - v0) + t (v2 - v0), dS = 2 A ds dt, and the
// Hermite-Genocchi formula for divided differences (de Boor, A Practical Guide to Splines, 2001,
// ch. I, eq. (I.36)), the integral is exactly
//   I = -2 A f[a0, a1, a2],  f(x) = exp(j x),  a_i = g . v_i,
// the second divided difference of exp(j x) at the vertex phases: this is the Gordon-type closed
// form (W. B. Gordon, "Far-field approximations to the Kirchhoff-Helmholtz representations of
// scattered fields", IEEE TAP 23(4), 1975) written so that its removable singularities are
// handled once, in one place:
//   - first differences f[x, y] = j exp(j (x+y)/2) sinc((x-y)/2) are evaluated through sinc with
//     its own Taylor branch, so an edge whose phase difference vanishes costs no accuracy;
//   - when the whole spread max(a) - min(a) is under kSeriesSpreadRad, the second difference is
//     summed as the Taylor series f[a0, a1, a2] = exp(j m) sum_{n>=2} j^n / n! h_{n-2}(a - m)
//     (h_k: complete homogeneous symmetric polynomials, m the mean phase), which needs no
//     division at all; above it, the recurrence (f[a1,a2] - f[a0,a1]) / (a2 - a0) is used with
//     a0, a2 the extreme phases, so the divisor is at least kSeriesSpreadRad.
// Either branch keeps about 1e-13 relative accuracy for any mix of vanishing and large edge phase
// differences (tests/radar/facet_po_test.cpp checks every regime against brute-force quadrature).
// Pure computation, real-time safe (no allocation), thread-safe.

#include <complex>
#include <glm/glm.hpp>

#include "common/sinc.hpp"

namespace radar_emu::radar {

/// Phase spread under which the series branch is used [rad].
inline constexpr double kSeriesSpreadRad = 1.0;

/// sin(x) / x, exact at 0 (common/sinc.hpp).
using common::sinc;

/// Second divided difference f[a0, a1, a2] of f(x) = exp(j x) at three real points [rad].
[[nodiscard]] std::complex<double> exp_divided_difference2(double a0, double a1,
                                                           double a2) noexcept;

/// integral over the triangle (v0, v1, v2) of exp(j g . r) dS [m^2]; vertices [m], g [rad/m].
/// Returns 0 for a degenerate triangle; never NaN for finite inputs.
[[nodiscard]] std::complex<double> triangle_phase_integral(const glm::dvec3& v0,
                                                           const glm::dvec3& v1,
                                                           const glm::dvec3& v2,
                                                           const glm::dvec3& g_rad_per_m) noexcept;

/// The same with the vertex phases per unit wavenumber already formed: b_i = w . v_i [m] with
/// the phase gradient g = k w, so I = -2 A f[k b0, k b1, k b2]. For frequency sweeps over the
/// same geometry (area_m2 = triangle area).
[[nodiscard]] std::complex<double> triangle_phase_integral(double area_m2, double b0_m, double b1_m,
                                                           double b2_m,
                                                           double wavenumber_rad_per_m) noexcept;

}  // namespace radar_emu::radar
