#include "radar/clutter/surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/glm.hpp>
#include <stdexcept>

#include "common/units.hpp"
#include "radar/constants.hpp"

namespace radar_emu::radar::clutter {

namespace {

using cplx = std::complex<double>;
using glm::dvec3;

constexpr double kGrazingLimit_rad = common::radians(70.0);
constexpr int kMaxSeriesTerms = 2000;
// IEM -> geometrical optics beyond ks = 5 (the IEM's own domain ends at ks = 3). Decided by ks
// alone, not by ks cos, so that one surface is one model at every angle: an angle-dependent
// switch put a step of tens of dB into a sigma0(theta) curve.
constexpr double kIemGeometricalOpticsKs = 5.0;

double wavenumber(double carrier_hz) {
  return 2.0 * kPi * carrier_hz / kSpeedOfLight_mps;
}

/// Unit vectors of the incident and scattered waves and their h/v polarisations (Fung 1994,
/// sec. 2: k_i = (sin t, 0, -cos t), k_s = (sin t_s cos p_s, sin t_s sin p_s, cos t_s),
/// h = z x k / |z x k|, v = h x k).
struct Frame {
  dvec3 ki, ks, hi, vi, hs, vs;
  double ci = 1.0, si = 0.0, cs = 1.0, ss = 0.0;
};

Frame make_frame(const Geometry& g) {
  Frame f;
  f.ci = std::cos(g.theta_i_rad);
  f.si = std::sin(g.theta_i_rad);
  f.cs = std::cos(g.theta_s_rad);
  f.ss = std::sin(g.theta_s_rad);
  const double cp = std::cos(g.phi_s_rad), sp = std::sin(g.phi_s_rad);
  f.ki = {f.si, 0.0, -f.ci};
  f.ks = {f.ss * cp, f.ss * sp, f.cs};
  f.hi = {0.0, 1.0, 0.0};
  f.vi = glm::cross(f.hi, f.ki);
  f.hs = {-sp, cp, 0.0};
  f.vs = glm::cross(f.hs, f.ks);
  return f;
}

struct Fresnel {
  cplx h, v;
};
/// Fresnel reflection coefficients of a half-space (Balanis 2012, sec. 5.3):
/// R_h = (cos t - sqrt(eps - sin^2 t)) / (cos t + sqrt(eps - sin^2 t)),
/// R_v = (eps cos t - sqrt(eps - sin^2 t)) / (eps cos t + sqrt(eps - sin^2 t)).
Fresnel fresnel(cplx eps, double cos_t) {
  const double c = std::clamp(cos_t, 0.0, 1.0);
  const cplx root = std::sqrt(eps - (1.0 - c * c));
  return {(c - root) / (c + root), (eps * c - root) / (eps * c + root)};
}

struct Pol {
  cplx hh, vv, hv, vh;
};

/// Tangent-plane (Kirchhoff) reflection of the incident polarisations by a facet whose normal
/// bisects k_i and k_s (the stationary-phase facet), projected on the receive polarisations:
/// beta_qp = q_s . [R_h (p_i . e_perp) e_perp + R_v (p_i . e_par_i) e_par_s] with
/// e_perp = k_i x n / |k_i x n|, e_par = e_perp x k (Barrick 1968, IEEE TAP 16(4), eq. 5, in
/// vector form; Ulaby, Moore & Fung 1982, vol. II, sec. 12-3). In backscatter k_i is normal to
/// the facet and e_perp is the incident h.
Pol kirchhoff_beta(const Frame& f, cplx rh, cplx rv) {
  const dvec3 q = f.ks - f.ki;
  const dvec3 n = q / glm::length(q);
  dvec3 e_perp = glm::cross(f.ki, n);
  const double len = glm::length(e_perp);
  e_perp = len > 1e-12 ? e_perp / len : f.hi;
  const dvec3 par_i = glm::cross(e_perp, f.ki);
  const dvec3 par_s = glm::cross(e_perp, f.ks);
  auto reflect = [&](const dvec3& p, const dvec3& rx) {
    return rh * glm::dot(p, e_perp) * glm::dot(rx, e_perp) +
           rv * glm::dot(p, par_i) * glm::dot(rx, par_s);
  };
  return {reflect(f.hi, f.hs), reflect(f.vi, f.vs), reflect(f.vi, f.hs), reflect(f.hi, f.vs)};
}

/// a^n / n! e^(-e), by logarithms (the spectrum series of IEM and KA would overflow otherwise).
double poisson_term(int n, double a, double e) {
  if (a <= 0.0)
    return 0.0;
  const double dn = static_cast<double>(n);
  return std::exp(dn * std::log(a) - std::lgamma(dn + 1.0) - e);
}

int series_terms(double lambda, std::uint32_t* invalid) {
  const double want = std::ceil(lambda + 10.0 * std::sqrt(lambda) + 20.0);
  if (want > kMaxSeriesTerms) {
    *invalid |= kSeriesTruncated;
    return kMaxSeriesTerms;
  }
  return static_cast<int>(want);
}

/// First-order SPM polarisation amplitudes alpha_qp (Rice 1951; bistatic form of Tsang, Kong &
/// Shin 1985, Theory of Microwave Remote Sensing, ch. 5, sec. 3; Ulaby, Moore & Fung 1982,
/// vol. II, sec. 12-6), written in this file's h/v basis (the sign of alpha_vv and alpha_hh is
/// the one that makes the IEM's n = 1 term equal SPM, which radar tests check):
///   alpha_hh = -(eps - 1) cos p_s / ((cos t_s + r_s)(cos t + r_i))
///   alpha_vv = -(eps - 1)(eps sin t sin t_s - cos p_s r_i r_s) / ((eps cos t_s + r_s)(eps cos t +
///   r_i)) alpha_hv =  (eps - 1) r_i sin p_s / ((cos t_s + r_s)(eps cos t + r_i)) alpha_vh =  (eps
///   - 1) r_s sin p_s / ((eps cos t_s + r_s)(cos t + r_i))
/// with r = sqrt(eps - sin^2). Backscatter: |alpha_hh| = |eps - 1| / |cos t + r|^2,
/// |alpha_vv| = |(eps - 1)(sin^2 t - eps (1 + sin^2 t))| / |eps cos t + r|^2 (Ulaby & Long
/// 2014, sec. 10-4: the SPM backscatter amplitudes).
Pol spm_alpha(cplx eps, const Frame& f, double cos_phi, double sin_phi) {
  const cplx ri = std::sqrt(eps - f.si * f.si);
  const cplx rs = std::sqrt(eps - f.ss * f.ss);
  const cplx e1 = eps - 1.0;
  Pol a;
  a.hh = -e1 * cos_phi / ((f.cs + rs) * (f.ci + ri));
  a.vv = -e1 * (eps * f.si * f.ss - cos_phi * ri * rs) / ((eps * f.cs + rs) * (eps * f.ci + ri));
  a.hv = e1 * ri * sin_phi / ((f.cs + rs) * (eps * f.ci + ri));
  a.vh = e1 * rs * sin_phi / ((eps * f.cs + rs) * (f.ci + ri));
  return a;
}

double horizontal_transfer(const Frame& f, double k) {  // |k_s,xy - k_i,xy| [rad/m]
  const double dx = f.ks.x - f.ki.x, dy = f.ks.y - f.ki.y;
  return k * std::sqrt(dx * dx + dy * dy);
}

std::uint32_t grazing_flags(const Geometry& g) {
  return (g.theta_i_rad > kGrazingLimit_rad || g.theta_s_rad > kGrazingLimit_rad) ? kGrazing
                                                                                  : kValid;
}

double rms_slope_sq(const Roughness& r) {
  // Slope variance per axis = -s^2 rho''(0): Gaussian 2 s^2/l^2, x-power 2 x s^2/l^2; the
  // exponential function has none (rho'(0) != 0), the Gaussian value stands in (flagged).
  const double s_l = r.rms_height_m / r.corr_length_m;
  return r.correlation == Correlation::kXPower ? 2.0 * r.x_power * s_l * s_l : 2.0 * s_l * s_l;
}

/// Wu, Chen & Fung (2001), IEEE TGRS 39(9), "A transition model for the reflection coefficient
/// in surface scattering" (as used by I2EM, Ulaby & Long 2014, sec. 10-5): the Fresnel
/// coefficient moves from R(theta) (small roughness, where the IEM must become SPM) to R(0)
/// (large roughness) with weight gamma = 1 - S / S0, where S is the share of the complementary
/// term in the backscattered power computed with R(0),
///   S = |F|^2 sum_n a_n W^(n) / sum_n a_n |F + 2^(n+2) R0 exp(-(ks cos)^2) / cos|^2 W^(n),
///   a_n = (ks cos)^(2n) / n!,  F = 8 R0^2 sin^2 (cos + r) / (cos r),  r = sqrt(eps - sin^2),
/// and S0 = 1 / |1 + 8 R0 / (F cos)|^2 is its limit for ks -> 0. Computed here with every
/// sum scaled by exp(-2 (ks cos)^2) (Poisson weights) so that no term overflows.
double transition_weight(cplx eps, const Roughness& r, double k, double cos_t, double sin_t,
                         bool book_code, std::uint32_t* invalid) {
  if (sin_t < 1e-9)
    return 0.0;  // normal incidence: R(theta) = R(0)
  const cplx sq_eps = std::sqrt(eps);
  const cplx r0 = (sq_eps - 1.0) / (sq_eps + 1.0);
  const cplx root = std::sqrt(eps - sin_t * sin_t);
  // sin^2 as in Wu, Chen & Fung (2001) and Fung & Chen (2009, p. 164); the distributed I2EM
  // code has sin (book_code).
  const double sin_power = book_code ? sin_t : sin_t * sin_t;
  const cplx big_f = 8.0 * r0 * r0 * sin_power * (cos_t + root) / (cos_t * root);
  const double q = std::pow(k * r.rms_height_m * cos_t, 2);
  const double ff = std::norm(big_f);
  const double cross = 8.0 * std::real(std::conj(big_f) * r0 / cos_t);
  const double rr = 16.0 * std::norm(r0 / cos_t);
  const double wavenumber_x = 2.0 * k * sin_t;
  double num = 0.0, den_kirchhoff = 0.0, den_cross = 0.0;
  const int terms = series_terms(4.0 * q, invalid);
  for (int n = 1; n <= terms; ++n) {
    const double w = roughness_spectrum(r, n, wavenumber_x);
    num += poisson_term(n, q, 2.0 * q) * w;  // a_n e^(-2q)
    den_cross += poisson_term(n, 2.0 * q, 3.0 * q) * w;
    den_kirchhoff += poisson_term(n, 4.0 * q, 4.0 * q) * w;
  }
  // Scaled by e^(-2q): num = |F|^2 sum P(q) e^-q W; den adds the cross and Kirchhoff parts.
  const double s_num = ff * num;
  const double s_den = s_num + cross * den_cross + rr * den_kirchhoff;
  if (!(s_den > 0.0))
    return 0.0;
  const double s = s_num / s_den;
  const double s0 = 1.0 / std::norm(1.0 + 8.0 * r0 / (cos_t * big_f));
  // gamma is a weight between R(theta) and R(0): kept in [0, 1]. The distributed I2EM code does
  // not clamp it (at small angles and ks 0.5-1.5 it goes to -1, moving R beyond R(theta)).
  return book_code ? 1.0 - s / s0 : std::clamp(1.0 - s / s0, 0.0, 1.0);
}

struct CoPol {
  cplx hh, vv;
};
struct CoPolPower {
  double hh = 0.0, vv = 0.0;
};

/// Kirchhoff-field coefficients of the IEM (Fung 1994, sec. 4; Fung, Li & Chen 1992):
///   f_vv =  2 R_v [sin t sin t_s - (1 + cos t cos t_s) cos p_s] / (cos t + cos t_s),
///   f_hh = -2 R_h [same bracket] / (cos t + cos t_s);
/// backscatter: f_vv = 2 R_v / cos t, f_hh = -2 R_h / cos t.
CoPol iem_kirchhoff_coefficients(const Frame& f, double cos_phi, cplx rh, cplx rv) {
  const double bracket = (f.si * f.ss - (1.0 + f.ci * f.cs) * cos_phi) / (f.ci + f.cs);
  return {-2.0 * rh * bracket, 2.0 * rv * bracket};
}

/// Complementary-field coefficients F_qp^(up/down) of the improved IEM (Fung, Liu, Chen & Tsay
/// 2002, J. Electromagn. Waves Appl. 16(5), "An improved IEM model for bistatic scattering
/// from rough surfaces"; as written in Ulaby & Long 2014, sec. 10-3.9, Code 10.3), for the
/// incident wave in the x-z plane (phi = 0). `upward` selects the upward (+) or downward (-)
/// propagating spectral component, `scattered_side` the expansion about the scattered (rather
/// than the incident) wave number. Each coefficient comes as a pair (c_1, c_2): c_1 for the
/// field in air, c_2 for the field in the lower medium (its vertical wave number k_t).
CoPol iem_complementary(bool upward, bool scattered_side, cplx eps, double k, const Frame& f,
                        double cos_phi, double sin_phi, const Fresnel& ri) {
  const double ud = upward ? 1.0 : -1.0;
  const double kz = k * f.ci, ksz = k * f.cs;
  const double dx = f.ss * cos_phi - f.si;  // (k_sx - k_x) / k
  const double sp2 = sin_phi * sin_phi;
  const double k2 = k * k;
  cplx c1, c2a, c2b, c3a, c3b, c4, c5a, c5b;
  if (!scattered_side) {
    const double qa = ud * kz;                              // vertical wave number in air
    const cplx qb = ud * k * std::sqrt(eps - f.si * f.si);  // and in the lower medium
    c1 = k * cos_phi * (ksz - qa);
    auto c2 = [&](cplx gq) {
      return f.ci * (cos_phi * (k2 * f.si * dx + gq * (ksz - qa)) + k2 * f.si * f.ss * sp2);
    };
    c2a = c2(qa);
    c2b = c2(qb);
    c3a = k * f.si * (f.si * cos_phi * (ksz - qa) - qa * (cos_phi * dx + f.ss * sp2));
    c3b = k * f.si * (f.si * cos_phi * (ksz - qa) - qb * (cos_phi * dx - f.ss * sp2));
    c4 = k * f.ci * (cos_phi * f.cs * (ksz - qa) + k * f.ss * dx);
    auto c5 = [&](cplx gq) { return gq * (cos_phi * f.cs * (qa - ksz) - k * f.ss * dx); };
    c5a = c5(qa);
    c5b = c5(qb);
  } else {
    const double qa = ud * ksz;
    const cplx qb = ud * k * std::sqrt(eps - f.ss * f.ss);
    c1 = k * cos_phi * (kz + qa);
    const double inner = cos_phi * (f.ci * (kz + qa) - k * f.si * dx) - k * f.si * f.ss * sp2;
    c2a = qa * inner;
    c2b = qb * inner;
    c3a = c3b = k * f.ss * (k * f.ci * dx + f.si * (kz + qa));
    c4 = k * f.cs * inner;
    c5a = -f.cs * (k2 * f.ss * dx + qa * cos_phi * (kz + qa));
    c5b = -f.cs * (k2 * f.ss * dx + qb * cos_phi * (kz + qa));
  }
  const double q = kz;
  const cplx qt = k * std::sqrt(eps - f.si * f.si);
  const cplx rv = ri.v, rh = ri.h;
  const cplx vv = (1.0 + rv) * (-(1.0 - rv) * c1 / q + (1.0 + rv) * c1 / qt) +
                  (1.0 - rv) * ((1.0 - rv) * c2a / q - (1.0 + rv) * c2b / qt) +
                  (1.0 + rv) * ((1.0 - rv) * c3a / q - (1.0 + rv) * c3b / (eps * qt)) +
                  (1.0 - rv) * ((1.0 + rv) * c4 / q - eps * (1.0 - rv) * c4 / qt) +
                  (1.0 + rv) * ((1.0 + rv) * c5a / q - (1.0 - rv) * c5b / qt);
  const cplx hh = (1.0 + rh) * ((1.0 - rh) * c1 / q - eps * (1.0 + rh) * c1 / qt) -
                  (1.0 - rh) * ((1.0 - rh) * c2a / q - (1.0 + rh) * c2b / qt) -
                  (1.0 + rh) * ((1.0 - rh) * c3a / q - (1.0 + rh) * c3b / qt) -
                  (1.0 - rh) * ((1.0 + rh) * c4 / q - (1.0 - rh) * c4 / qt) -
                  (1.0 + rh) * ((1.0 + rh) * c5a / q - (1.0 - rh) * c5b / qt);
  return {hh, vv};
}

/// b^m, for m >= 0, as sign and log magnitude (0^0 = 1).
struct SignedLog {
  double sign = 1.0, log_mag = 0.0;
};
SignedLog signed_power(double base, int m) {
  if (m == 0)
    return {1.0, 0.0};
  if (base == 0.0)
    return {0.0, 0.0};
  return {(base < 0.0 && (m % 2) != 0) ? -1.0 : 1.0, m * std::log(std::abs(base))};
}

/// Incoherent co-polarised sigma0 of the improved IEM (Fung et al. 2002; Ulaby & Long 2014,
/// sec. 10-3.9): sigma0_pp = (k^2/2) exp(-s^2 (k_z^2 + k_sz^2)) sum_n s^(2n)/n! |I_n|^2 W^(n),
///   I_n = (k_z + k_sz)^n f_pp exp(-s^2 k_z k_sz)
///       + (1/4) [F_up,i (k_sz - k_z)^(n-1) exp(-s^2 (2 k_z^2 - k_z k_sz))
///              + F_dn,i (k_sz + k_z)^(n-1) exp(-s^2 k_z k_sz)
///              + F_up,s (k_z + k_sz)^(n-1) exp(-s^2 k_z k_sz)
///              + F_dn,s (k_z - k_sz)^(n-1) exp(-s^2 (2 k_sz^2 - k_z k_sz))].
/// Every term is formed in logarithms (powers, factorial, exponentials together), so that no
/// partial product overflows however many terms the series needs.
CoPolPower iem_copol_series(cplx eps, const Roughness& r, double k, const Frame& f, double cos_phi,
                            double sin_phi, const CoPol& fk, const Fresnel& ri,
                            std::uint32_t* invalid) {
  const double s = r.rms_height_m;
  if (!(s > 0.0))
    return {};
  const CoPol up_i = iem_complementary(true, false, eps, k, f, cos_phi, sin_phi, ri);
  const CoPol dn_i = iem_complementary(false, false, eps, k, f, cos_phi, sin_phi, ri);
  const CoPol up_s = iem_complementary(true, true, eps, k, f, cos_phi, sin_phi, ri);
  const CoPol dn_s = iem_complementary(false, true, eps, k, f, cos_phi, sin_phi, ri);
  const double kz = k * f.ci, ksz = k * f.cs, s2 = s * s;
  const double sum_z = kz + ksz, diff_z = ksz - kz;
  const double big_k = horizontal_transfer(f, k);
  const double e_common = -0.5 * s2 * (kz * kz + ksz * ksz);
  const double e_kirch = -s2 * kz * ksz;
  const double e_up_i = -s2 * (2.0 * kz * kz - kz * ksz);
  const double e_dn_s = -s2 * (2.0 * ksz * ksz - kz * ksz);
  // First-order anchor. In backscatter the n = 1 amplitude of these coefficients is exactly the
  // SPM amplitude (+4 k cos^2 alpha_hh, -4 k cos^2 alpha_vv in this file's alpha basis; checked
  // to 1e-17 by the tests); in other directions the published closed forms, which take the
  // scattered-side expansions at the incident wave numbers, miss it by a real factor of 0.8 to
  // 1.25 (up to 4 dB at ks -> 0, where the IEM must be SPM). The difference is restored as one
  // more complementary term of the (k_z + k_sz)^(n-1) family, so that every direction reduces
  // to SPM and the backscatter result is untouched.
  CoPol mid{0.25 * (dn_i.hh + up_s.hh), 0.25 * (dn_i.vv + up_s.vv)};
  {
    const Pol alpha = spm_alpha(eps, f, cos_phi, sin_phi);
    const CoPol fi = iem_kirchhoff_coefficients(f, cos_phi, ri.h, ri.v);
    const double target = 4.0 * k * f.ci * f.cs;
    const double sz = kz + ksz;
    mid.hh += target * alpha.hh - (sz * fi.hh + 0.25 * (up_i.hh + dn_i.hh + up_s.hh + dn_s.hh));
    mid.vv += -target * alpha.vv - (sz * fi.vv + 0.25 * (up_i.vv + dn_i.vv + up_s.vv + dn_s.vv));
  }
  const int terms = series_terms(s2 * sum_z * sum_z, invalid);
  CoPolPower sum;
  for (int n = 1; n <= terms; ++n) {
    const double w = roughness_spectrum(r, n, big_k);
    if (!(w > 0.0))
      continue;
    const double dn = static_cast<double>(n);
    const double scale = dn * std::log(s) - 0.5 * std::lgamma(dn + 1.0) + e_common;
    const SignedLog p_sum_n = signed_power(sum_z, n), p_sum_m = signed_power(sum_z, n - 1);
    const SignedLog p_up = signed_power(diff_z, n - 1), p_dn = signed_power(-diff_z, n - 1);
    const double a_kirch = p_sum_n.sign * std::exp(scale + p_sum_n.log_mag + e_kirch);
    const double a_mid = p_sum_m.sign * std::exp(scale + p_sum_m.log_mag + e_kirch);
    const double a_up = p_up.sign * std::exp(scale + p_up.log_mag + e_up_i);
    const double a_dn = p_dn.sign * std::exp(scale + p_dn.log_mag + e_dn_s);
    const cplx i_hh = fk.hh * a_kirch + mid.hh * a_mid + 0.25 * (up_i.hh * a_up + dn_s.hh * a_dn);
    const cplx i_vv = fk.vv * a_kirch + mid.vv * a_mid + 0.25 * (up_i.vv * a_up + dn_s.vv * a_dn);
    sum.hh += std::norm(i_hh) * w;
    sum.vv += std::norm(i_vv) * w;
  }
  return {0.5 * k * k * sum.hh, 0.5 * k * k * sum.vv};
}

/// Rms slope used by I2EM's shadowing functions (Ulaby & Long 2014, Code 10.3): sqrt(2) s / l
/// for the Gaussian, s / l for the exponential (which has no finite slope variance), sqrt(2 x)
/// s / l for the x-power function.
double smith_rms_slope(const Roughness& r) {
  const double s_l = r.rms_height_m / r.corr_length_m;
  if (r.correlation == Correlation::kGaussian)
    return std::sqrt(2.0) * s_l;
  if (r.correlation == Correlation::kXPower)
    return std::sqrt(2.0 * r.x_power) * s_l;
  return s_l;
}

/// Smith (1967, IEEE TAP 15(5)) shadowing function Lambda(theta) = (1/2) [exp(-mu^2) /
/// (sqrt(pi) mu) - erfc(mu)], mu = cot(theta) / (sqrt(2) m), m the rms slope.
double smith_lambda(double cos_t, double sin_t, const Roughness& r) {
  const double m = smith_rms_slope(r);
  if (!(m > 0.0) || !(sin_t > 1e-12))
    return 0.0;
  const double mu = cos_t / sin_t / (std::sqrt(2.0) * m);
  if (!(mu > 1e-12))
    return 1e12;  // grazing: fully shadowed
  if (mu > 25.0)
    return 0.0;  // exp(-mu^2) below 1e-270
  return 0.5 * (std::exp(-mu * mu) / (std::sqrt(kPi) * mu) - std::erfc(mu));
}

/// 16-point Gauss-Legendre nodes and weights on [-1, 1], by Newton iteration on P_16 (Press et
/// al. 2007, Numerical Recipes, 3rd ed., sec. 4.6.1), computed once.
struct GaussLegendre16 {
  std::array<double, 16> x{}, w{};
  GaussLegendre16() {
    constexpr std::size_t n = 16;
    for (std::size_t i = 0; i < n / 2; ++i) {
      const double di = static_cast<double>(i), dn = static_cast<double>(n);
      double z = std::cos(kPi * (di + 0.75) / (dn + 0.5));
      double dp = 0.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = 0.0;
        for (double j = 1.0; j <= dn; j += 1.0) {
          const double p2 = p1;
          p1 = p0;
          p0 = ((2.0 * j - 1.0) * z * p1 - (j - 1.0) * p2) / j;
        }
        dp = dn * (z * p0 - p1) / (z * z - 1.0);
        const double step = p0 / dp;
        z -= step;
        if (std::abs(step) < 1e-15)
          break;
      }
      x[i] = -z;
      x[n - 1 - i] = z;
      w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
  }
};
const GaussLegendre16& gauss_legendre16() {
  static const GaussLegendre16 rule;
  return rule;
}

/// G(rho) = k^2 sum_n W^(n)(k rho) x^n / n! e^(-x) on rho in [0, 2] (the Poisson-weighted
/// spectrum series of the cross-polarised term, dimensionless), tabulated once per evaluation
/// and interpolated linearly: the double integral then costs two look-ups per node.
class WeightedSpectrum {
 public:
  static constexpr std::size_t kIntervals = 2048;
  static constexpr double kRhoMax = 2.0;
  WeightedSpectrum(const Roughness& r, double k, double x, int terms) {
    // Poisson weights x^n / n! e^(-x) by recurrence (x <= 25 where the IEM series is used).
    std::array<double, kMaxSeriesTerms + 1> weight{};
    const std::size_t count = static_cast<std::size_t>(std::clamp(terms, 1, kMaxSeriesTerms));
    weight[1] = x * std::exp(-x);
    for (std::size_t n = 2; n <= count; ++n)
      weight[n] = weight[n - 1] * x / static_cast<double>(n);
    // W^(n)(K) <= W^(n)(0) (rho^n >= 0), and past n = 2x + 1 the weights fall faster than
    // geometrically (ratio < 1/2): the sum stops once weight * W^(n)(0) < 1e-12 of it.
    std::array<double, kMaxSeriesTerms + 1> bound{};
    for (std::size_t n = 1; n <= count; ++n)
      bound[n] = weight[n] * roughness_spectrum(r, static_cast<int>(n), 0.0);
    for (std::size_t i = 0; i <= kIntervals; ++i) {
      const double rho = kRhoMax * static_cast<double>(i) / kIntervals;
      double sum = 0.0;
      for (std::size_t n = 1; n <= count; ++n) {
        if (static_cast<double>(n) > 2.0 * x + 1.0 && bound[n] < 1e-12 * sum)
          break;
        sum += weight[n] * roughness_spectrum(r, static_cast<int>(n), k * rho);
      }
      g_[i] = sum * k * k;
    }
  }
  [[nodiscard]] double operator()(double rho) const noexcept {
    const double at = std::clamp(rho, 0.0, kRhoMax) * (kIntervals / kRhoMax);
    const std::size_t i = std::min(static_cast<std::size_t>(at), kIntervals - 1);
    const double w = at - static_cast<double>(i);
    return g_[i] + w * (g_[i + 1] - g_[i]);
  }

 private:
  std::array<double, kIntervals + 1> g_{};
};

/// Multiple-scattering cross-polarised backscatter of the IEM (Fung 1994, Microwave Scattering
/// and Emission Models and Their Applications, ch. 4, the cross term of the second-order
/// field; in the form of Ulaby & Long 2014, sec. 10-3.9, code IEMX):
///   sigma0_hv = S(theta) / (4 pi) int_0^1 int_0^pi |F_hv(u, phi)|^2 G(|u - sin|) G(|u + sin|)
///               S_m(u) u dphi du,
///   F_hv = (u_x u_y / cos) [(b - c)(1 - 3 R) - (b - c/eps)(1 + R) + (a - d)(1 + 3 R)
///           - (a - d eps)(1 - R)],  R = (R_v - R_h)/2, a = (1 + R)/q, b = (1 - R)/q,
///           c = (1 + R)/q_t, d = (1 - R)/q_t, q = sqrt(1 - u^2), q_t = sqrt(eps - u^2),
/// with G the Poisson-weighted spectrum series at x = (ks cos)^2 (WeightedSpectrum, which holds
/// the exp(-2 x) of the published form), u - sin = (u cos phi - sin, u sin phi) and u + sin =
/// (u cos phi + sin, u sin phi), S the Smith shadowing 1/(1 + Lambda(theta)) and S_m =
/// 1/(1 + Lambda_m(u)) its counterpart for the intermediate direction (Lambda_m = exp(-a^2) /
/// (2 sqrt(pi) a) - erfc(a)/2, a = q/(sqrt(2) u m)). Integrated over u = sin(t) by composite
/// 16-point Gauss-Legendre rules, panels refined where the spectra peak (width ~ 1/kl) and
/// geometrically towards u = 1, where the shadowed integrand behaves as 1/q down to q ~ m.
/// `book_code`: q = sqrt(1.0001 - u^2) as in the distributed IEMX code, which cuts the
/// integrand off at q = 0.01 (it lowers sigma0_hv by up to 0.8 dB when the rms slope is below
/// about 0.03).
double iem_cross_pol_backscatter(cplx eps, const Roughness& r, double k, double cos_t, double sin_t,
                                 bool book_code, std::uint32_t* invalid) {
  const double s = r.rms_height_m;
  if (!(s > 0.0))
    return 0.0;
  const double m = smith_rms_slope(r);
  const Fresnel rf = fresnel(eps, cos_t);
  const cplx rvh = 0.5 * (rf.v - rf.h);
  const cplx rp = 1.0 + rvh, rm = 1.0 - rvh;
  const double x = std::pow(k * s * cos_t, 2);
  const WeightedSpectrum spectrum(r, k, x, series_terms(x, invalid));
  const double kl = k * r.corr_length_m;

  // Panel edges in t (u = sin t) on [0, pi/2], and panels in phi on [0, pi].
  constexpr std::size_t kMaxEdges = 160;
  std::array<double, kMaxEdges> t_edges{};
  std::size_t nt = 0;
  const int uniform = std::clamp(static_cast<int>(std::ceil(kl / 3.0)), 4, 96);
  for (int i = 0; i <= uniform; ++i)
    t_edges[nt++] = 0.5 * kPi * i / uniform;
  const double last_uniform = 0.5 * kPi * (uniform - 1) / uniform;
  const int graded = std::clamp(static_cast<int>(std::ceil(std::log2(20.0 / std::max(m, 1e-9)))), 1,
                                static_cast<int>(kMaxEdges) - uniform - 2);
  for (int j = 1; j <= graded; ++j)
    t_edges[nt++] = 0.5 * kPi - (0.5 * kPi - last_uniform) * std::ldexp(1.0, -j);
  std::sort(t_edges.begin(), t_edges.begin() + static_cast<std::ptrdiff_t>(nt));
  const GaussLegendre16& gl = gauss_legendre16();

  double total = 0.0;
  for (std::size_t it = 0; it + 1 < nt; ++it) {
    const double t0 = t_edges[it], t1 = t_edges[it + 1];
    if (!(t1 > t0))
      continue;
    for (std::size_t a = 0; a < 16; ++a) {
      const double t = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * gl.x[a];
      const double du = 0.5 * (t1 - t0) * gl.w[a] * std::cos(t);  // du = cos(t) dt
      const double u = std::sin(t);
      const double q = book_code ? std::sqrt(1.0001 - u * u) : std::cos(t);
      if (!(u > 0.0) || !(q > 0.0))
        continue;
      const cplx qt = std::sqrt(eps - u * u);
      const cplx fa = rp / q, fb = rm / q, fc = rp / qt, fd = rm / qt;
      const cplx f_common = (fb - fc) * (1.0 - 3.0 * rvh) - (fb - fc / eps) * rp +
                            (fa - fd) * (1.0 + 3.0 * rvh) - (fa - fd * eps) * rm;
      const double au = q / (u * std::sqrt(2.0) * m);
      const double lambda_m =
          au > 25.0 ? 0.0 : std::exp(-au * au) / (2.0 * std::sqrt(kPi) * au) - 0.5 * std::erfc(au);
      const double radial = std::norm(f_common) * u * du / ((1.0 + lambda_m) * cos_t * cos_t);
      // |u -+ sin|^2 = u^2 + sin^2 -+ 2 u_x sin
      const double base = u * u + sin_t * sin_t;
      double inner = 0.0;
      for (int ip = 0; ip < uniform; ++ip) {
        const double p0 = kPi * ip / uniform, p1 = kPi * (ip + 1) / uniform;
        for (std::size_t b = 0; b < 16; ++b) {
          const double phi = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * gl.x[b];
          const double ux = u * std::cos(phi), uy = u * std::sin(phi);
          const double cross = 2.0 * ux * sin_t;
          inner += 0.5 * (p1 - p0) * gl.w[b] * ux * ux * uy * uy *
                   spectrum(std::sqrt(std::max(base - cross, 0.0))) *
                   spectrum(std::sqrt(base + cross));
        }
      }
      total += radial * inner;
    }
  }
  // Smith (1967) shadowing of the incident and scattered direction, as in IEMX: 1/(1+Lambda).
  return total / ((1.0 + smith_lambda(cos_t, sin_t, r)) * 4.0 * kPi);
}

}  // namespace

bool Geometry::is_backscatter() const noexcept {
  return std::abs(theta_i_rad - theta_s_rad) < 1e-12 &&
         std::abs(std::remainder(phi_s_rad - kPi, 2.0 * kPi)) < 1e-12;
}

std::string describe_validity(std::uint32_t flags) {
  if (flags == kValid)
    return "valid";
  static constexpr struct {
    std::uint32_t bit;
    const char* text;
  } kNames[] = {
      {kSpmTooRough, "SPM: ks >= 0.3 or rms slope >= 0.3"},
      {kSpmCorrelationLong, "SPM: kl > 3"},
      {kKaCorrelationShort, "KA: kl < 6 or l^2 < 2.76 s lambda"},
      {kKaNoSlope, "KA: exponential spectrum has no slope variance (Gaussian value used)"},
      {kIemTooRough, "IEM: ks > 3"},
      {kGrazing,
       "beyond 70 deg: shadowing and multiple bounces not modelled (IEM: Smith shadowing only)"},
      {kSeriesTruncated, "spectrum series truncated"},
      {kCrossPolNotModelled,
       "this model has no cross-polarised backscatter (SPM, KA first order; RT spheres)"},
      {kAlbedoHigh, "RT: albedo > 0.2 (first order only)"},
      {kOutsideMeasuredRange,
       "catalogue: extrapolated beyond the measured angles or frequencies of its source"},
      {kAssumedValue, "catalogue: assumed value (no published data found)"},
  };
  std::string out;
  for (const auto& n : kNames) {
    if ((flags & n.bit) != 0u) {
      out += out.empty() ? "" : "; ";
      out += n.text;
    }
  }
  return out;
}

double roughness_spectrum(const Roughness& r, int n, double k_rad_per_m) noexcept {
  const double l = r.corr_length_m;
  const double dn = static_cast<double>(n);
  const double kl = k_rad_per_m * l;
  switch (r.correlation) {
    case Correlation::kGaussian:  // W^(n) = l^2/(2n) exp(-K^2 l^2 / (4n))
      return l * l / (2.0 * dn) * std::exp(-kl * kl / (4.0 * dn));
    case Correlation::kExponential:  // W^(n) = (l/n)^2 (1 + (K l / n)^2)^(-3/2)
      return (l / dn) * (l / dn) * std::pow(1.0 + (kl / dn) * (kl / dn), -1.5);
    case Correlation::kXPower: {
      // rho^n = (1 + r^2/l^2)^(-nu), nu = x n: W^(n) = l^2 (K l)^(nu-1) K_(nu-1)(K l) /
      // (2^(nu-1) Gamma(nu)) (Hankel transform, Gradshteyn & Ryzhik 6.565.4), -> l^2/(2(nu-1))
      // as K -> 0.
      const double nu = r.x_power * dn;
      const double at_zero = l * l / (2.0 * (nu - 1.0));
      if (kl < 1e-9)
        return at_zero;
      const double bessel = std::cyl_bessel_k(nu - 1.0, kl);
      if (!std::isfinite(bessel) || bessel <= 0.0)
        return at_zero;  // order far above the argument: the small-argument limit holds
      const double log_w = 2.0 * std::log(l) + (nu - 1.0) * std::log(kl) + std::log(bessel) -
                           (nu - 1.0) * std::log(2.0) - std::lgamma(nu);
      return std::exp(log_w);
    }
  }
  return 0.0;
}

void validate(const SurfaceParams& surface, double carrier_hz) {
  const Roughness& r = surface.roughness;
  auto fail = [](const std::string& why) { throw std::invalid_argument("surface: " + why); };
  if (!(carrier_hz > 0.0) || !std::isfinite(carrier_hz))
    fail("frequency must be finite and > 0");
  if (!(r.rms_height_m >= 0.0) || !std::isfinite(r.rms_height_m))
    fail("rms height must be finite and >= 0 m (got " + std::to_string(r.rms_height_m) + ")");
  if (!(r.corr_length_m > 0.0) || !std::isfinite(r.corr_length_m))
    fail("correlation length must be finite and > 0 m (got " + std::to_string(r.corr_length_m) +
         ")");
  if (r.correlation == Correlation::kXPower && !(r.x_power > 1.0 && r.x_power <= 20.0))
    fail("x-power exponent must be in (1, 20]");
  const cplx eps = surface.relative_permittivity;
  if (!std::isfinite(eps.real()) || !std::isfinite(eps.imag()) || eps.real() < 1.0)
    fail("relative permittivity real part must be finite and >= 1");
  if (eps.imag() > 0.0)
    fail("relative permittivity must be eps' - j eps'' with eps'' >= 0 (a gain is not a surface)");
  const double ks = wavenumber(carrier_hz) * r.rms_height_m;
  if (ks > 1000.0)
    fail("ks = " + std::to_string(ks) + " is beyond 1000: not a surface at this wavelength");
}

SurfaceScatter spm(const SurfaceParams& surface, double carrier_hz, const Geometry& g) noexcept {
  const Roughness& r = surface.roughness;
  const double k = wavenumber(carrier_hz);
  const double ks = k * r.rms_height_m, kl = k * r.corr_length_m;
  const Frame f = make_frame(g);
  SurfaceScatter out;
  out.invalid = grazing_flags(g);
  if (ks >= 0.3 || rms_slope_sq(r) >= 0.09)
    out.invalid |= kSpmTooRough;
  if (kl > 3.0)
    out.invalid |= kSpmCorrelationLong;
  // sigma0_qp = 8 k^4 s^2 cos^2 t cos^2 t_s |alpha_qp|^2 W(k_s,xy - k_i,xy) (Ulaby, Moore &
  // Fung 1982, vol. II, sec. 12-6; backscatter: Ulaby & Long 2014, sec. 10-4).
  const double w = roughness_spectrum(r, 1, horizontal_transfer(f, k));
  const double scale =
      8.0 * std::pow(k, 4) * r.rms_height_m * r.rms_height_m * f.ci * f.ci * f.cs * f.cs * w;
  const Pol a =
      spm_alpha(surface.relative_permittivity, f, std::cos(g.phi_s_rad), std::sin(g.phi_s_rad));
  out.incoherent = {scale * std::norm(a.hh), scale * std::norm(a.vv), scale * std::norm(a.hv),
                    scale * std::norm(a.vh)};
  if (g.is_backscatter())
    out.invalid |= kCrossPolNotModelled;  // first order: no cross-polarised backscatter
  // Coherent reflectivity |R|^2 exp(-(2 k s cos t)^2) (Beckmann & Spizzichino 1963; Ulaby &
  // Long 2014, sec. 10-2): the specular power that survives the roughness.
  const Fresnel rf = fresnel(surface.relative_permittivity, f.ci);
  const double loss = std::exp(-std::pow(2.0 * ks * f.ci, 2));
  out.coherent_hh = std::norm(rf.h) * loss;
  out.coherent_vv = std::norm(rf.v) * loss;
  return out;
}

SurfaceScatter kirchhoff(const SurfaceParams& surface, double carrier_hz,
                         const Geometry& g) noexcept {
  const Roughness& r = surface.roughness;
  const double k = wavenumber(carrier_hz);
  const double s = r.rms_height_m, l = r.corr_length_m;
  const double lambda = 2.0 * kPi / k;
  const Frame f = make_frame(g);
  SurfaceScatter out;
  out.invalid = grazing_flags(g);
  if (k * l < 6.0 || l * l < 2.76 * s * lambda)
    out.invalid |= kKaCorrelationShort;
  const dvec3 q = f.ks - f.ki;  // scattering vector / k
  const double q2 = glm::dot(q, q);
  const double cos_iota = std::sqrt(q2) / 2.0;  // local incidence on the specular facet
  const Fresnel local = fresnel(surface.relative_permittivity, cos_iota);
  const Pol beta = kirchhoff_beta(f, local.h, local.v);
  const double lambda_k = std::pow(s * k * q.z, 2);  // (k s (cos t + cos t_s))^2
  if (lambda_k > 10.0) {
    // Geometrical optics (stationary phase): sigma0 = pi (|q|^2/q_z^2)^2 |beta|^2 p(z_x, z_y),
    // Gaussian slopes of variance m^2 per axis (Barrick 1968; Ulaby & Long 2014, sec. 10-4:
    // backscatter |R(0)|^2 exp(-tan^2 t / 2m^2) / (2 m^2 cos^4 t)).
    const double m2 = rms_slope_sq(r);
    if (r.correlation == Correlation::kExponential)
      out.invalid |= kKaNoSlope;
    const double zx = -q.x / q.z, zy = -q.y / q.z;
    const double pdf = std::exp(-(zx * zx + zy * zy) / (2.0 * m2)) / (2.0 * kPi * m2);
    const double scale = kPi * std::pow(q2 / (q.z * q.z), 2) * pdf;
    out.incoherent = {scale * std::norm(beta.hh), scale * std::norm(beta.vv),
                      scale * std::norm(beta.hv), scale * std::norm(beta.vh)};
  } else {
    // Physical-optics series of the Kirchhoff field (the IEM's f_qp term alone, Fung 1994,
    // sec. 4): sigma0 = (k^2/2) sum_n |f|^2 W^(n) (k s q_z)^(2n)/n! exp(-(k s q_z)^2), with
    // f_qp = |q|^2 beta_qp / q_z (backscatter: 2 R / cos t).
    const double big_k = horizontal_transfer(f, k);
    double sum = 0.0;
    const int terms = series_terms(lambda_k, &out.invalid);
    for (int n = 1; n <= terms; ++n)
      sum += poisson_term(n, lambda_k, lambda_k) * roughness_spectrum(r, n, big_k);
    const double scale = 0.5 * k * k * sum * std::pow(q2 / q.z, 2);
    out.incoherent = {scale * std::norm(beta.hh), scale * std::norm(beta.vv),
                      scale * std::norm(beta.hv), scale * std::norm(beta.vh)};
  }
  if (g.is_backscatter())
    out.invalid |= kCrossPolNotModelled;  // tangent plane: no cross-polarised backscatter
  const Fresnel rf = fresnel(surface.relative_permittivity, f.ci);
  const double loss = std::exp(-std::pow(2.0 * k * s * f.ci, 2));
  out.coherent_hh = std::norm(rf.h) * loss;
  out.coherent_vv = std::norm(rf.v) * loss;
  return out;
}

SurfaceScatter iem(const SurfaceParams& surface, double carrier_hz, const Geometry& g,
                   IemConventions conventions, bool cross_pol_backscatter) noexcept {
  const bool book_code = conventions == IemConventions::kUlabyLongCode;
  const Roughness& r = surface.roughness;
  const cplx eps = surface.relative_permittivity;
  const double k = wavenumber(carrier_hz);
  const double s = r.rms_height_m;
  const Frame f = make_frame(g);
  SurfaceScatter out;
  out.invalid = grazing_flags(g);
  if (k * s > 3.0)
    out.invalid |= kIemTooRough;
  const bool backscatter = g.is_backscatter();
  if (k * s > kIemGeometricalOpticsKs) {
    // Far beyond the IEM's domain: its Kirchhoff term dominates, the transition coefficient is
    // R(iota) and the series tends to geometrical optics, which is evaluated directly (the
    // series would need thousands of terms). GO has no cross-polarised backscatter (flagged).
    SurfaceScatter go = kirchhoff(surface, carrier_hz, g);
    go.invalid |= out.invalid;
    return go;
  }

  // Reflection coefficient of the Kirchhoff term: Wu, Chen & Fung (2001) transition from
  // R(theta_i) to R at the stationary-phase facet (R(0) in backscatter, as in I2EM).
  const dvec3 q = f.ks - f.ki;
  const double cos_iota = std::sqrt(glm::dot(q, q)) / 2.0;
  const Fresnel at_incidence = fresnel(eps, f.ci);
  const Fresnel at_facet = fresnel(eps, cos_iota);
  const double gamma = transition_weight(eps, r, k, f.ci, f.si, book_code, &out.invalid);
  const cplx rh_t = at_incidence.h + (at_facet.h - at_incidence.h) * gamma;
  const cplx rv_t = at_incidence.v + (at_facet.v - at_incidence.v) * gamma;

  const double cos_phi = std::cos(g.phi_s_rad), sin_phi = std::sin(g.phi_s_rad);
  const CoPol kirchhoff_coef = iem_kirchhoff_coefficients(f, cos_phi, rh_t, rv_t);
  const CoPolPower series =
      iem_copol_series(eps, r, k, f, cos_phi, sin_phi, kirchhoff_coef, at_incidence, &out.invalid);
  // Smith (1967) shadowing, 1 / (1 + Lambda(theta_i) + Lambda(theta_s)) (I2EM, Ulaby & Long
  // 2014, sec. 10-3.9, applies it in backscatter; here in every direction, so that backscatter
  // and the bistatic directions next to it meet).
  const double shadow = 1.0 / (1.0 + smith_lambda(f.ci, f.si, r) + smith_lambda(f.cs, f.ss, r));
  out.incoherent.hh = series.hh * shadow;
  out.incoherent.vv = series.vv * shadow;

  if (backscatter) {
    // Single scattering gives no cross-polarised backscatter (Fung 1994, sec. 4): HV = VH
    // comes from the multiple-scattering term.
    if (cross_pol_backscatter)
      out.incoherent.hv = out.incoherent.vh =
          iem_cross_pol_backscatter(eps, r, k, f.ci, f.si, book_code, &out.invalid);
  } else {
    // Bistatic cross-polarisation: the n = 1 term from SPM (exact there) plus the Kirchhoff
    // terms n >= 2 of the tangent-plane field (the complementary part of n >= 2 left out:
    // documented approximation).
    const Pol beta = kirchhoff_beta(f, rh_t, rv_t);
    const double q2 = glm::dot(q, q);
    const double f_scale = q2 / q.z;
    const double kz = k * f.ci, ksz = k * f.cs;
    const double big_k = horizontal_transfer(f, k);
    const double lambda_k = s * s * (kz + ksz) * (kz + ksz);
    double higher = 0.0;
    const int terms = series_terms(lambda_k, &out.invalid);
    for (int n = 2; n <= terms; ++n)
      higher += poisson_term(n, lambda_k, lambda_k) * roughness_spectrum(r, n, big_k);
    const Pol alpha = spm_alpha(eps, f, cos_phi, sin_phi);
    const double first = 8.0 * std::pow(k, 4) * s * s * f.ci * f.ci * f.cs * f.cs *
                         std::exp(-s * s * (kz * kz + ksz * ksz)) * roughness_spectrum(r, 1, big_k);
    const double hv_k = 0.5 * k * k * std::norm(beta.hv * f_scale) * higher;
    const double vh_k = 0.5 * k * k * std::norm(beta.vh * f_scale) * higher;
    out.incoherent.hv = (first * std::norm(alpha.hv) + hv_k) * shadow;
    out.incoherent.vh = (first * std::norm(alpha.vh) + vh_k) * shadow;
  }
  const double loss = std::exp(-std::pow(2.0 * k * s * f.ci, 2));
  out.coherent_hh = std::norm(at_incidence.h) * loss;
  out.coherent_vv = std::norm(at_incidence.v) * loss;
  return out;
}

Sigma0 rt_volume(const VolumeLayer& layer, const SurfaceParams& ground, double /*carrier_hz*/,
                 const Geometry& g, std::uint32_t* invalid) noexcept {
  if (layer.albedo > 0.2 && invalid != nullptr)
    *invalid |= kAlbedoHigh;
  const bool inside = layer.placement == VolumeLayer::Placement::kInsideGround;
  const cplx eps = ground.relative_permittivity;
  // Directions inside the host: Snell refraction through the (mean) interface for inclusions in
  // the ground, none for a canopy in air.
  Geometry inner = g;
  if (inside) {
    const double n_host = std::sqrt(eps).real();
    inner.theta_i_rad = std::asin(std::sin(g.theta_i_rad) / n_host);
    inner.theta_s_rad = std::asin(std::sin(g.theta_s_rad) / n_host);
  }
  const Frame f = make_frame(inner);
  const double mu_i = std::max(f.ci, 1e-6), mu_s = std::max(f.cs, 1e-6);
  const double path = layer.extinction_np_per_m * layer.thickness_m * (1.0 / mu_i + 1.0 / mu_s);
  const double fill = -std::expm1(-path);  // 1 - exp(-kappa_e d (sec t_i + sec t_s))
  // First-order radiative transfer in a layer of Rayleigh scatterers (Ulaby, Moore & Fung 1986,
  // vol. III, ch. 13; backscatter: Ulaby & Long 2014, eq. 11.23 first term):
  //   sigma0_qp = 4 pi a P_qp mu_i mu_s / (mu_i + mu_s) [1 - exp(-kappa_e d (1/mu_i + 1/mu_s))],
  //   P_qp = (3 / 8 pi) |q_s . p_i|^2 (dipole phase function, normalised over 4 pi).
  // Backscatter co-pol: (3/4) a cos t (1 - Y^2), Y = exp(-kappa_e d sec t).
  auto phase = [](const dvec3& rx, const dvec3& tx) {
    const double d = glm::dot(rx, tx);
    return 3.0 / (8.0 * kPi) * d * d;
  };
  const double common = 4.0 * kPi * layer.albedo * mu_i * mu_s / (mu_i + mu_s) * fill;
  Sigma0 out{common * phase(f.hs, f.hi), common * phase(f.vs, f.vi), common * phase(f.hs, f.vi),
             common * phase(f.vs, f.hi)};
  if (inside) {
    // The part of the incident power transmitted into the host, and out again (seed paper,
    // Bistatic IEM/RT, sec. IV: "the incident power is only the part of power transmitted in
    // the host medium"): smooth-interface transmissivities 1 - |R|^2 (Ulaby & Long 2014,
    // sec. 11-2, Rayleigh layer with a distinct upper boundary).
    const Fresnel ri = fresnel(eps, std::cos(g.theta_i_rad));
    const Fresnel rs = fresnel(eps, std::cos(g.theta_s_rad));
    const double th_i = 1.0 - std::norm(ri.h), tv_i = 1.0 - std::norm(ri.v);
    const double th_s = 1.0 - std::norm(rs.h), tv_s = 1.0 - std::norm(rs.v);
    out.hh *= th_i * th_s;
    out.vv *= tv_i * tv_s;
    out.hv *= tv_i * th_s;
    out.vh *= th_i * tv_s;
  }
  if (g.is_backscatter() && invalid != nullptr)
    *invalid |= kCrossPolNotModelled;  // spheres: no first-order cross-pol in backscatter
  return out;
}

SurfaceScatter rt_total(const VolumeLayer& layer, const SurfaceParams& ground, double carrier_hz,
                        const Geometry& g, bool cross_pol_backscatter) noexcept {
  SurfaceScatter out =
      iem(ground, carrier_hz, g, IemConventions::kPublishedEquations, cross_pol_backscatter);
  out.invalid &= ~kCrossPolNotModelled;
  std::uint32_t flags = 0;
  const Sigma0 vol = rt_volume(layer, ground, carrier_hz, g, &flags);
  out.invalid |= flags & ~kCrossPolNotModelled;
  if (layer.placement == VolumeLayer::Placement::kCanopyAboveGround) {
    // Ulaby & Long 2014, eq. 11.23: sigma0 = Y^2 sigma_ground + volume + ground-volume terms,
    // Y^2 = exp(-kappa_e d (sec t_i + sec t_s)) here (the two-way layer loss, bistatic).
    const double ci = std::max(std::cos(g.theta_i_rad), 1e-6);
    const double cs = std::max(std::cos(g.theta_s_rad), 1e-6);
    const double y2 =
        std::exp(-layer.extinction_np_per_m * layer.thickness_m * (1.0 / ci + 1.0 / cs));
    const double gh = out.coherent_hh, gv = out.coherent_vv;  // ground reflectivity G
    out.incoherent.hh *= y2;
    out.incoherent.vv *= y2;
    out.incoherent.hv *= y2;
    out.incoherent.vh *= y2;
    out.coherent_hh *= y2;
    out.coherent_vv *= y2;
    if (g.is_backscatter()) {
      // (3/4) a cos t (1 - Y^2) G^2 Y^2: volume scattering reflected by the ground both ways,
      // and 6 kappa_s d G Y^2: the ground-volume and volume-ground paths (eq. 11.23), with
      // G the ground's coherent reflectivity.
      const double a = layer.albedo;
      const double kappa_s = a * layer.extinction_np_per_m;
      auto ground_volume = [&](double refl) {
        return 0.75 * a * ci * (1.0 - y2) * refl * refl * y2 +
               6.0 * kappa_s * layer.thickness_m * refl * y2;
      };
      out.incoherent.hh += ground_volume(gh);
      out.incoherent.vv += ground_volume(gv);
    }
  }
  out.incoherent.hh += vol.hh;
  out.incoherent.vv += vol.vv;
  out.incoherent.hv += vol.hv;
  out.incoherent.vh += vol.vh;
  // Backscatter HV/VH here is the ground's (IEM multiple scattering, through the layer): the
  // first-order volume of spheres depolarises nothing in backscatter, so canopies whose
  // elements are not spheres are underestimated in HV (docs/validation_environment.md). With a
  // ground beyond the IEM (geometrical optics) there is none at all: flagged.
  if (g.is_backscatter() && !(out.incoherent.hv > 0.0))
    out.invalid |= kCrossPolNotModelled;
  return out;
}

}  // namespace radar_emu::radar::clutter
