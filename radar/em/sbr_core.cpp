#include "radar/em/sbr_core.hpp"

#include <algorithm>
#include <cmath>

#include "radar/constants.hpp"
#include "radar/em/facet_po.hpp"

namespace radar_emu::radar {

using cplx = std::complex<double>;

namespace {

// Complex division and square root in plain real arithmetic, for finite operands of moderate
// size (permittivities, cosines: no overflow or underflow to guard against, which is what
// libgcc's __divdc3 and glibc's csqrt spend their time on; the C99 Annex G semantics that
// -fcx-limited-range drops). Equal to the library's results to a few ulps.
inline cplx divide(cplx a, cplx b) noexcept {
  const double inv = 1.0 / (b.real() * b.real() + b.imag() * b.imag());
  return {(a.real() * b.real() + a.imag() * b.imag()) * inv,
          (a.imag() * b.real() - a.real() * b.imag()) * inv};
}

// Principal square root (Re >= 0; the sign of Im follows Im z, -0 included, as std::sqrt's):
// with r = |z|, sqrt(z) = t + j y / (2 t), t = sqrt((r + x) / 2) for x >= 0, and
// |y| / (2 t) + j sign(y) t, t = sqrt((r - x) / 2) otherwise (Press et al., Numerical Recipes,
// 3rd ed., 2007, sec. 5.5, complex arithmetic), cancellation-free both ways.
inline cplx principal_sqrt(cplx z) noexcept {
  const double x = z.real(), y = z.imag();
  const double r = std::sqrt(x * x + y * y);
  if (r == 0.0)
    return {0.0, y};
  if (x >= 0.0) {
    const double t = std::sqrt(0.5 * (r + x));
    return {t, y / (2.0 * t)};
  }
  const double t = std::sqrt(0.5 * (r - x));
  return {std::abs(y) / (2.0 * t), std::copysign(t, y)};
}

// The product of two finite complex numbers: the real products and sums std::complex's
// multiplication forms, without its NaN recovery (libgcc's __muldc3).
inline cplx times(cplx x, cplx y) noexcept {
  return {x.real() * y.real() - x.imag() * y.imag(), x.real() * y.imag() + x.imag() * y.real()};
}

}  // namespace

ReflectionCoefficients reflection_coefficients(const SurfaceModel& surface, double cos_incidence,
                                               double k) noexcept {
  if (surface.kind == SurfaceModel::Kind::kPec)
    return {};
  const double c = std::clamp(cos_incidence, 0.0, 1.0);
  const double sin2 = 1.0 - c * c;
  const cplx eps = surface.relative_permittivity;
  const cplx root = principal_sqrt(eps - sin2);  // principal branch: Im <= 0 for lossy eps
  ReflectionCoefficients r;
  r.perp = divide(c - root, c + root);
  r.par = divide(eps * c - root, eps * c + root);
  if (surface.kind == SurfaceModel::Kind::kCoatedPec) {
    const cplx beta = k * root;
    const cplx delay = std::exp(cplx(0.0, -2.0) * beta * surface.thickness_m);
    r.perp = divide(r.perp - delay, 1.0 - r.perp * delay);  // r12 = -1
    r.par = divide(r.par + delay, 1.0 + r.par * delay);     // r12 = +1
  }
  return r;
}

CVec reflect_field_general(const CVec& e, const glm::dvec3& d, const glm::dvec3& d_r,
                           const glm::dvec3& n, const ReflectionCoefficients& r) noexcept {
  glm::dvec3 e_perp = glm::cross(d, n);
  double len = glm::length(e_perp);
  if (len < 1e-12) {  // normal incidence: any tangential direction (take one from the field)
    e_perp = e.re - glm::dot(e.re, d) * d;
    if (glm::length(e_perp) < 1e-12 * (norm(e) + 1e-300))
      e_perp = e.im - glm::dot(e.im, d) * d;
    len = glm::length(e_perp);
    if (len == 0.0)
      return {};
  }
  e_perp *= 1.0 / len;  // one division (the field's basis: a unit vector to rounding)
  const glm::dvec3 e_par_i = glm::cross(e_perp, d), e_par_r = glm::cross(e_perp, d_r);
  return scale(times(r.perp, dot(e_perp, e)), e_perp) +
         scale(times(r.par, dot(e_par_i, e)), e_par_r);
}

CVec po_source_general(const CVec& e, const glm::dvec3& d, const glm::dvec3& n, const glm::dvec3& s,
                       const ReflectionCoefficients& r) noexcept {
  const glm::dvec3 d_r = mirror(d, n);
  const CVec e_r = reflect_field_general(e, d, d_r, n, r);
  const CVec eta_j = cross(n, cross(d, e) + cross(d_r, e_r));
  const CVec m = cross(e + e_r, n);
  return eta_j - cross(s, m);
}

std::array<glm::dvec3, kFacetSamples> facet_samples(const glm::dvec3& v0, const glm::dvec3& v1,
                                                    const glm::dvec3& v2,
                                                    const glm::dvec3& lit_normal,
                                                    double offset_m) noexcept {
  const glm::dvec3 c = (v0 + v1 + v2) / 3.0, lift = offset_m * lit_normal;
  auto inset = [&](const glm::dvec3& p) { return p + kFacetSampleInset * (c - p) + lift; };
  return {c + lift,
          inset(v0),
          inset(v1),
          inset(v2),
          inset(0.5 * (v0 + v1)),
          inset(0.5 * (v1 + v2)),
          inset(0.5 * (v2 + v0))};
}

int facet_subdivisions(double longest_edge_m, double resolution_m) noexcept {
  const double m = std::ceil(longest_edge_m / resolution_m);
  if (!(m < kMaxFacetSubdivisions))  // also NaN
    return kMaxFacetSubdivisions;
  return std::max(1, static_cast<int>(m));
}

bool facet_in_far_field(double rho_m, double range_m, double k) noexcept {
  return k * rho_m * rho_m <= 0.125 * kPi * range_m;
}

}  // namespace radar_emu::radar
