#include "radar/clutter/surface.hpp"

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <stdexcept>

#include "radar/constants.hpp"

namespace radar_emu::radar::clutter {

namespace {

using cplx = std::complex<double>;
using glm::dvec3;

constexpr double kGrazingLimit_rad = 70.0 * kPi / 180.0;
constexpr int kMaxSeriesTerms = 2000;
constexpr double kGeometricalOpticsLambda = 100.0;  // (k s (cos t + cos t_s))^2

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
                         std::uint32_t* invalid) {
  if (sin_t < 1e-9)
    return 0.0;  // normal incidence: R(theta) = R(0)
  const cplx sq_eps = std::sqrt(eps);
  const cplx r0 = (sq_eps - 1.0) / (sq_eps + 1.0);
  const cplx root = std::sqrt(eps - sin_t * sin_t);
  const cplx big_f = 8.0 * r0 * r0 * sin_t * sin_t * (cos_t + root) / (cos_t * root);
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
  return std::clamp(1.0 - s / s0, 0.0, 1.0);
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
      {kGrazing, "beyond 70 deg: no shadowing in the model"},
      {kSeriesTruncated, "spectrum series truncated"},
      {kCrossPolNotModelled, "cross-polarisation not modelled here"},
      {kAlbedoHigh, "RT: albedo > 0.2 (first order only)"},
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
  const Fresnel rf = fresnel(surface.relative_permittivity, f.ci);
  const double loss = std::exp(-std::pow(2.0 * k * s * f.ci, 2));
  out.coherent_hh = std::norm(rf.h) * loss;
  out.coherent_vv = std::norm(rf.v) * loss;
  return out;
}

SurfaceScatter iem(const SurfaceParams& surface, double carrier_hz, const Geometry& g) noexcept {
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
  if (std::pow(k * s * (f.ci + f.cs), 2) > kGeometricalOpticsLambda) {
    // Far beyond the IEM's domain (ks cos > 5): its Kirchhoff term dominates, the transition
    // coefficient is R(iota) and the series tends to geometrical optics, which is evaluated
    // directly (the series would need thousands of terms).
    SurfaceScatter go = kirchhoff(surface, carrier_hz, g);
    go.invalid |= out.invalid;
    return go;
  }

  const dvec3 q = f.ks - f.ki;
  const double q2 = glm::dot(q, q);
  const double cos_iota = std::sqrt(q2) / 2.0;
  const Fresnel at_incidence = fresnel(eps, f.ci);
  const Fresnel at_facet = fresnel(eps, cos_iota);
  const double gamma = transition_weight(eps, r, k, f.ci, f.si, &out.invalid);
  const cplx rh_t = at_incidence.h + (at_facet.h - at_incidence.h) * gamma;
  const cplx rv_t = at_incidence.v + (at_facet.v - at_incidence.v) * gamma;
  // Kirchhoff field coefficients f_qp = |q|^2 beta_qp / q_z (backscatter: f_vv = 2 R_v / cos,
  // f_hh = -2 R_h / cos up to the sign of this file's v basis; Fung, Li & Chen 1992).
  const Pol beta = kirchhoff_beta(f, rh_t, rv_t);
  const double f_scale = q2 / q.z;
  const Pol fk{beta.hh * f_scale, beta.vv * f_scale, beta.hv * f_scale, beta.vh * f_scale};

  // Complementary field coefficients, as Fbar with C_n = Fbar (k_z^n + k_sz^n) / 2.
  // Backscatter: Fung, Li & Chen (1992), IEEE TGRS 30(2) (Ulaby & Long 2014, sec. 10-5),
  // Fbar = [F_pp(-k_x, 0) + F_pp(k_x, 0)] / 2 with
  //   F_vv sum =  2 sin^2 (1 + R_v)^2 / cos [(1 - 1/eps) + (eps - sin^2 - eps cos^2) / (eps^2
  //   cos^2)] F_hh sum = -2 sin^2 (1 + R_h)^2 / cos (eps - 1) / cos^2            (non-magnetic),
  // the vv sign turned to this file's v basis (f_vv = -2 R_v / cos here).
  // Bistatic: the closed forms of the improved IEM are not carried here; Fbar is the symmetric
  // complementary field fixed by the SPM limit, k (cos t + cos t_s)(f + Fbar/2) = 4 k cos t
  // cos t_s alpha (exact at n = 1, so the bistatic IEM reduces to SPM), which is exact in
  // backscatter and an approximation elsewhere (docs/validation.md).
  cplx fbar_hh, fbar_vv;
  const double c = f.ci, s2 = f.si * f.si;
  if (backscatter) {
    fbar_vv = -(s2 * (1.0 + rv_t) * (1.0 + rv_t) / c) *
              ((1.0 - 1.0 / eps) + (eps - s2 - eps * c * c) / (eps * eps * c * c));
    fbar_hh = -(s2 * (1.0 + rh_t) * (1.0 + rh_t) / c) * (eps - 1.0) / (c * c);
  } else {
    const Pol alpha = spm_alpha(eps, f, std::cos(g.phi_s_rad), std::sin(g.phi_s_rad));
    const double anchor = 4.0 * f.ci * f.cs / (f.ci + f.cs);
    fbar_hh = 2.0 * (anchor * alpha.hh - fk.hh);
    fbar_vv = 2.0 * (anchor * alpha.vv - fk.vv);
  }

  const double kz = k * f.ci, ksz = k * f.cs;
  const double big_k = horizontal_transfer(f, k);
  const double lambda_k = s * s * (kz + ksz) * (kz + ksz);
  const double e_cross = s * s * (kz * kz + ksz * ksz + kz * ksz);
  const double e_comp = s * s * (kz * kz + ksz * ksz);
  // sigma0_qp = (k^2/2) exp(-s^2 (k_z^2 + k_sz^2)) sum_n s^(2n)/n! |I_n|^2 W^(n),
  // I_n = (k_z + k_sz)^n f_qp exp(-s^2 k_z k_sz) + C_n (Fung, Li & Chen 1992; Fung 1994,
  // sec. 4), expanded in Poisson-weighted terms so that nothing overflows.
  double kirch = 0.0;    // sum P(n; lambda_k) W
  double cross_a = 0.0;  // sum [(s^2 (kz+ksz) kz)^n + (s^2 (kz+ksz) ksz)^n]/n! e^-E W
  double comp_a = 0.0;   // sum [(s^2 kz^2)^n + 2 (s^2 kz ksz)^n + (s^2 ksz^2)^n]/n! e^-E W
  double spm_w = 0.0;    // n = 1 weight for the bistatic cross-polarisations
  const int terms = series_terms(lambda_k, &out.invalid);
  for (int n = 1; n <= terms; ++n) {
    const double w = roughness_spectrum(r, n, big_k);
    kirch += poisson_term(n, lambda_k, lambda_k) * w;
    cross_a += (poisson_term(n, s * s * (kz + ksz) * kz, e_cross) +
                poisson_term(n, s * s * (kz + ksz) * ksz, e_cross)) *
               w;
    comp_a += (poisson_term(n, s * s * kz * kz, e_comp) +
               2.0 * poisson_term(n, s * s * kz * ksz, e_comp) +
               poisson_term(n, s * s * ksz * ksz, e_comp)) *
              w;
    if (n == 1)
      spm_w = w;
  }
  auto copol = [&](cplx fq, cplx fb) {
    const double value = std::norm(fq) * kirch + std::real(std::conj(fq) * fb) * cross_a +
                         0.25 * std::norm(fb) * comp_a;
    return std::max(0.5 * k * k * value, 0.0);
  };
  out.incoherent.hh = copol(fk.hh, fbar_hh);
  out.incoherent.vv = copol(fk.vv, fbar_vv);
  if (backscatter) {
    // Single scattering gives no cross-polarised backscatter (Fung 1994, sec. 4); the
    // multiple-scattering term that does is not implemented yet (flagged).
    out.invalid |= kCrossPolNotModelled;
  } else {
    // Bistatic cross-polarisation: the n = 1 term from SPM (exact there) plus the Kirchhoff
    // terms n >= 2 (the complementary part of n >= 2 left out: documented approximation).
    const Pol alpha = spm_alpha(eps, f, std::cos(g.phi_s_rad), std::sin(g.phi_s_rad));
    const double first =
        8.0 * std::pow(k, 4) * s * s * f.ci * f.ci * f.cs * f.cs * std::exp(-e_comp) * spm_w;
    const double higher = kirch - poisson_term(1, lambda_k, lambda_k) * spm_w;
    out.incoherent.hv = first * std::norm(alpha.hv) + 0.5 * k * k * std::norm(fk.hv) * higher;
    out.incoherent.vh = first * std::norm(alpha.vh) + 0.5 * k * k * std::norm(fk.vh) * higher;
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
                        const Geometry& g) noexcept {
  SurfaceScatter out = iem(ground, carrier_hz, g);
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
  if (g.is_backscatter())
    out.invalid |= kCrossPolNotModelled;
  return out;
}

}  // namespace radar_emu::radar::clutter
