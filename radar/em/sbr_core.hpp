#pragma once
// The shooting-and-bouncing-rays core shared by the offline RCS engine (radar/em/rcs.hpp,
// plane-wave illumination) and the frame tracer (radar/em/sbr.hpp, spherical-wave illumination
// from the antenna): polarimetric fields carried along a ray tube, local reflection
// coefficients (PEC, Fresnel dielectric half-space, coated PEC), the reflected field, the
// physical-optics source of a tube's footprint and the footprint's integral with its sinc taper
// (Ling, Chou & Lee, "Shooting and bouncing rays: calculating the RCS of an arbitrarily shaped
// cavity", IEEE TAP 37(2), 1989).
//
// Scattering amplitude of one footprint F on a facet of unit normal n (facing the wave), met by a
// local plane wave of field E along d, radiating toward unit direction s, received on unit
// polarisation p (time convention exp(+j w t); sigma = |S|^2):
//   S = -j k / sqrt(pi) * (p . (eta J - s x M)) / 2 * integral_F exp(j k (s - d) . r') dS'
// with the PO currents eta J = n x (d x E + d_r x E_r), M = (E + E_r) x n of the local
// reflection (J = 2 n x H, M = 0 on a PEC): Balanis, Advanced Engineering Electromagnetics,
// 2nd ed., 2012, sec. 6.7 (far fields of electric and magnetic surface currents) and sec. 7.10
// (physical optics). A PEC plate of area A at normal incidence gives S = -j k A / sqrt(pi).
// Pure computation, real-time safe (no allocation, no exceptions), thread-safe.

#include <complex>
#include <cstdint>
#include <glm/glm.hpp>

namespace radar_emu::radar {

/// How a surface reflects.
struct SurfaceModel {
  enum class Kind : std::uint8_t {
    kPec,         ///< perfect electric conductor
    kDielectric,  ///< homogeneous half-space of relative permittivity eps
    kCoatedPec    ///< a layer of permittivity eps and thickness_m on a PEC
  };
  Kind kind = Kind::kPec;
  /// eps' - j eps'' (exp(+j w t): losses have a negative imaginary part); non-magnetic.
  std::complex<double> relative_permittivity{1.0, 0.0};
  double thickness_m = 0.0;  ///< coating thickness (kCoatedPec) [m]
};

/// Local reflection coefficients in the basis e_perp = unit(d_i x n), e_par = e_perp x d
/// (incident d_i, reflected d_r): E_r = R_perp (E.e_perp) e_perp + R_par (E.e_par_i) e_par_r.
/// In this basis a PEC has R_perp = -1, R_par = +1 at every angle.
struct ReflectionCoefficients {
  std::complex<double> perp{-1.0, 0.0};
  std::complex<double> par{1.0, 0.0};
};

/// Fresnel coefficients of `surface` for a wave meeting it at cos(theta_i) = cos_incidence in
/// (0, 1] and free-space wavenumber k [rad/m] (used by coatings only):
/// half-space: Balanis 2012, sec. 5.3 (oblique incidence, perpendicular and parallel
/// polarisation), non-magnetic, written in the basis above,
///   R_perp = (cos t - sqrt(eps - sin^2 t)) / (cos t + sqrt(eps - sin^2 t)),
///   R_par  = (eps cos t - sqrt(eps - sin^2 t)) / (eps cos t + sqrt(eps - sin^2 t));
/// coated PEC: the single-layer (Airy) sum, Orfanidis, Electromagnetic Waves and Antennas, 2016,
/// sec. 8.1 (single dielectric slab; oblique incidence as in ch. 7) with r_12 = -1 (perp),
/// +1 (par): R = (r01 + r12 e^{-2 j beta d}) / (1 + r01 r12 e^{-2 j beta d}),
/// beta = k sqrt(eps - sin^2 t).
[[nodiscard]] ReflectionCoefficients reflection_coefficients(const SurfaceModel& surface,
                                                             double cos_incidence,
                                                             double wavenumber_rad_per_m) noexcept;

/// Polarisation channel, receive first ("HV" = receive H, transmit V), as in the RCS engine.
enum class Polarisation : std::uint8_t { kHH, kHV, kVH, kVV };

/// A complex 3-vector (a field) as real and imaginary parts (GLM's functions need arithmetic
/// types).
struct CVec {
  glm::dvec3 re{0.0}, im{0.0};
};
[[nodiscard]] inline CVec operator+(const CVec& a, const CVec& b) noexcept {
  return {a.re + b.re, a.im + b.im};
}
[[nodiscard]] inline CVec operator-(const CVec& a, const CVec& b) noexcept {
  return {a.re - b.re, a.im - b.im};
}
[[nodiscard]] inline CVec scale(std::complex<double> s, const glm::dvec3& v) noexcept {
  return {s.real() * v, s.imag() * v};
}
[[nodiscard]] inline CVec cross(const glm::dvec3& a, const CVec& b) noexcept {
  return {glm::cross(a, b.re), glm::cross(a, b.im)};
}
[[nodiscard]] inline CVec cross(const CVec& a, const glm::dvec3& b) noexcept {
  return {glm::cross(a.re, b), glm::cross(a.im, b)};
}
[[nodiscard]] inline std::complex<double> dot(const glm::dvec3& a, const CVec& b) noexcept {
  return {glm::dot(a, b.re), glm::dot(a, b.im)};
}
[[nodiscard]] inline double norm(const CVec& v) noexcept {
  return std::sqrt(glm::dot(v.re, v.re) + glm::dot(v.im, v.im));
}

/// Mirror image of direction (or tube edge) `d` in the plane of unit normal `n` (law of
/// reflection: d_r = d - 2 (n.d) n).
[[nodiscard]] inline glm::dvec3 mirror(const glm::dvec3& d, const glm::dvec3& n) noexcept {
  return d - 2.0 * glm::dot(n, d) * n;
}

/// The local reflection of field `e` travelling along `d` off a surface with unit normal `n`
/// facing the wave (n.d < 0), reflected direction d_r = mirror(d, n), in the basis of
/// ReflectionCoefficients. `pec`: E_r = -E + 2 (n.E) n (tangential E flips, normal E stays).
[[nodiscard]] CVec reflect_field(const CVec& e, const glm::dvec3& d, const glm::dvec3& d_r,
                                 const glm::dvec3& n, const ReflectionCoefficients& r,
                                 bool pec) noexcept;

/// eta J - s x M of the PO currents of the local reflection (header), per unit area, radiating
/// toward s.
[[nodiscard]] CVec po_source(const CVec& e, const glm::dvec3& d, const glm::dvec3& n,
                             const glm::dvec3& s, const ReflectionCoefficients& r,
                             bool pec) noexcept;

/// A ray tube's footprint on a facet: its edge vectors (tube_u, tube_v at the hit, [m])
/// projected along d onto the plane of normal n, and the taper lengths of the footprint
/// integral toward s: integral_F exp(j k (s - d) . (r' - hit)) dS' = area sinc(k taper_u)
/// sinc(k taper_v) with taper = (s - d) . edge / 2: the exact integral of a linear phase over a
/// parallelogram centred on the hit (the ray-tube integration of Ling, Chou & Lee 1989, sec. II).
struct TubeFootprint {
  glm::dvec3 u_m{0.0}, v_m{0.0};
  double area_m2 = 0.0;
  double taper_u_m = 0.0, taper_v_m = 0.0;
};
[[nodiscard]] TubeFootprint tube_footprint(const glm::dvec3& tube_u_m, const glm::dvec3& tube_v_m,
                                           const glm::dvec3& d, const glm::dvec3& n,
                                           const glm::dvec3& s) noexcept;
/// area sinc(k taper_u) sinc(k taper_v) [m^2] at wavenumber k [rad/m].
[[nodiscard]] double footprint_integral(const TubeFootprint& f,
                                        double wavenumber_rad_per_m) noexcept;

/// The scattering amplitude [m] of a footprint (header): -j k / sqrt(pi) * (p . src) / 2 *
/// integral, phase referred to the hit point (the caller multiplies by its path phase).
[[nodiscard]] std::complex<double> po_amplitude_m(double wavenumber_rad_per_m,
                                                  const glm::dvec3& receive_polarisation,
                                                  const CVec& source,
                                                  double footprint_integral_m2) noexcept;

}  // namespace radar_emu::radar
