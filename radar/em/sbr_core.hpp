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

#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

#include "common/polarisation.hpp"
#include "common/sinc.hpp"
#include "common/units.hpp"

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
using common::Polarisation;

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
/// (Inline: the PEC case is a few products; the general case is reflect_field_general.)
[[nodiscard]] CVec reflect_field_general(const CVec& e, const glm::dvec3& d, const glm::dvec3& d_r,
                                         const glm::dvec3& n,
                                         const ReflectionCoefficients& r) noexcept;
[[nodiscard]] inline CVec reflect_field(const CVec& e, const glm::dvec3& d, const glm::dvec3& d_r,
                                        const glm::dvec3& n, const ReflectionCoefficients& r,
                                        bool pec) noexcept {
  if (pec)  // tangential E flips, normal E stays: E_r = -E + 2 (n.E) n
    return {2.0 * glm::dot(n, e.re) * n - e.re, 2.0 * glm::dot(n, e.im) * n - e.im};
  return reflect_field_general(e, d, d_r, n, r);
}

/// eta J - s x M of the PO currents of the local reflection (header), per unit area, radiating
/// toward s.
[[nodiscard]] CVec po_source_general(const CVec& e, const glm::dvec3& d, const glm::dvec3& n,
                                     const glm::dvec3& s, const ReflectionCoefficients& r) noexcept;
[[nodiscard]] inline CVec po_source(const CVec& e, const glm::dvec3& d, const glm::dvec3& n,
                                    const glm::dvec3& s, const ReflectionCoefficients& r,
                                    bool pec) noexcept {
  if (pec)  // eta J = 2 n x (d x E), M = 0
    return {2.0 * glm::cross(n, glm::cross(d, e.re)), 2.0 * glm::cross(n, glm::cross(d, e.im))};
  return po_source_general(e, d, n, s, r);
}

/// sin(x) and cos(x) [x in rad] to within 2.3e-16 absolute, for the per-return amplitude's
/// phase exp(-j k L) and footprint sincs, at about half the cost of the libm calls. The argument
/// is reduced to r = x - n pi/2, |r| <= pi/4, with pi/2 split into three 28-bit parts and a
/// fourth (Cody & Waite, "Software Manual for the Elementary Functions", 1980, ch. 8: each
/// n * part is exact for |n| < 2^24, so r carries no cancellation error up to |x| ~ 2.6e7 rad);
/// sin and cos of r are fdlibm's minimax polynomials (k_sin.c, k_cos.c, Sun Microsystems,
/// 1993), and the quadrant n mod 4 maps them to sin x and cos x. Larger or non-finite x take
/// std::sin and std::cos. (tests/radar/sbr_core_test.cpp checks it against libm.)
struct SinCos {
  double sin = 0.0, cos = 1.0;
};
namespace detail {
/// sin_cos's reduction and polynomials for an x with |x 2/pi| < 2^24, on any T with double's
/// arithmetic (double, or a SIMD type whose lanes each do what double does: each lane then gets
/// the scalar's result bit for bit): n (fn, an integer in T), sin r (s) and cos r (c).
template <class T>
inline void sin_cos_reduced(T x, T& fn, T& s, T& c) noexcept {
  constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
  // pi/2 = kC1 + kC2 + kC3 + kC4 to 1.5e-43; kC1..kC3 have 28 significant bits.
  constexpr double kC1 = 0x1.921fb54p+0, kC2 = 0x1.10b4612p-30, kC3 = -0x1.676733ap-60,
                   kC4 = -0x1.d1fc8f8cbb5bfp-89;
  constexpr double kShift = 0x1.8p52;  // adding and removing it rounds q to the nearest integer
  const T q = x * kTwoOverPi;
  fn = (q + kShift) - kShift;
  const T r = ((x - fn * kC1) - fn * kC2) - fn * kC3 - fn * kC4;
  const T z = r * r;
  s = r + r * z *
              (-0x1.5555555555549p-3 +
               z * (0x1.111111110f8a6p-7 +
                    z * (-0x1.a01a019c161d5p-13 +
                         z * (0x1.71de357b1fe7dp-19 +
                              z * (-0x1.ae5e68a2b9cebp-26 + z * 0x1.5d93a5acfd57cp-33)))));
  c = 1.0 - 0.5 * z +
      z * z *
          (0x1.555555555554cp-5 +
           z * (-0x1.6c16c16c15177p-10 +
                z * (0x1.a01a019cb159p-16 +
                     z * (-0x1.27e4f809c52adp-22 +
                          z * (0x1.1ee9ebdb4b1c4p-29 + z * -0x1.8fae9be8838d4p-37)))));
}
/// The quadrant n mod 4 maps sin r and cos r to sin x and cos x.
[[nodiscard]] inline SinCos sin_cos_quadrant(double fn, double s, double c) noexcept {
  switch (static_cast<std::int64_t>(fn) & 3) {
    case 0:
      return {s, c};
    case 1:
      return {c, -s};
    case 2:
      return {-s, -c};
    default:
      return {-c, s};
  }
}
/// Whether sin_cos_reduced holds for x (else sin_cos takes libm's).
[[nodiscard]] inline bool sin_cos_reducible(double x) noexcept {
  return std::abs(x * 0x1.45f306dc9c883p-1) < 0x1p24;
}
}  // namespace detail

[[nodiscard]] inline SinCos sin_cos(double x) noexcept {
  if (!detail::sin_cos_reducible(x))
    return {std::sin(x), std::cos(x)};
  double fn = 0.0, s = 0.0, c = 0.0;
  detail::sin_cos_reduced(x, fn, s, c);
  return detail::sin_cos_quadrant(fn, s, c);
}

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
[[nodiscard]] inline TubeFootprint tube_footprint(const glm::dvec3& tube_u_m,
                                                  const glm::dvec3& tube_v_m, const glm::dvec3& d,
                                                  const glm::dvec3& n,
                                                  const glm::dvec3& s) noexcept {
  const double n_d = glm::dot(n, d);
  TubeFootprint f;
  f.u_m = tube_u_m - d * (glm::dot(n, tube_u_m) / n_d);
  f.v_m = tube_v_m - d * (glm::dot(n, tube_v_m) / n_d);
  f.area_m2 = glm::length(glm::cross(f.u_m, f.v_m));
  f.taper_u_m = 0.5 * glm::dot(s - d, f.u_m);
  f.taper_v_m = 0.5 * glm::dot(s - d, f.v_m);
  return f;
}
/// area sinc(k taper_u) sinc(k taper_v) [m^2] at wavenumber k [rad/m]. Away from 0 (both
/// arguments at least 1e-3, sinc's series threshold) as area sin(a) sin(b) / (a b) with sin_cos:
/// one division instead of two, the same value to rounding.
[[nodiscard]] inline double footprint_integral(const TubeFootprint& f,
                                               double wavenumber_rad_per_m) noexcept {
  const double a = wavenumber_rad_per_m * f.taper_u_m, b = wavenumber_rad_per_m * f.taper_v_m;
  if (std::abs(a) < 1e-3 || std::abs(b) < 1e-3)
    return f.area_m2 * common::sinc(a) * common::sinc(b);
  return f.area_m2 * (sin_cos(a).sin * sin_cos(b).sin) / (a * b);
}

/// The scattering amplitude [m] of a footprint (header): -j k / sqrt(pi) * (p . src) / 2 *
/// integral, phase referred to the hit point (the caller multiplies by its path phase).
[[nodiscard]] inline std::complex<double> po_amplitude_m(double wavenumber_rad_per_m,
                                                         const glm::dvec3& receive_polarisation,
                                                         const CVec& source,
                                                         double footprint_integral_m2) noexcept {
  // -j c z for c = k / sqrt(pi), z = (p . src) / 2: (c Im z, -c Re z), the products the complex
  // multiplication by (0, -c) forms, without its NaN recovery (libgcc's __muldc3) that finite
  // operands never need.
  const double c = wavenumber_rad_per_m / std::sqrt(common::kPi);
  const std::complex<double> z = 0.5 * dot(receive_polarisation, source);
  return {c * z.imag() * footprint_integral_m2, -c * z.real() * footprint_integral_m2};
}

// --- Visibility rules shared by both engines (docs/validation.md, "Visibility rules"). ---------

/// A ray tube meeting a surface at cos(theta_i) under this stops there (no footprint, no
/// reflection); at bounces after the first, a footprint radiates toward a receiver only when the
/// receiver sees its lit side at n.s >= kGrazingCos. The same bound on entry and exit keeps the
/// rule reciprocal (a path cut at a grazing exit is the reverse of one cut at a grazing entry).
inline constexpr double kGrazingCos = 1e-3;
/// Reflected rays are shot from the hit lifted a small offset along the lit normal (no
/// self-hit, however grazing); the hit they find is then moved back onto the unlifted ray:
/// the point where the ray from `origin` along unit `d` meets the plane through `hit` of unit
/// normal `normal` (unchanged when the ray runs parallel to that plane). So the lift changes no
/// path length.
[[nodiscard]] inline glm::dvec3 onto_ray(const glm::dvec3& origin, const glm::dvec3& d,
                                         const glm::dvec3& hit, const glm::dvec3& normal) noexcept {
  const double n_d = glm::dot(normal, d);
  if (std::abs(n_d) < 1e-9)
    return hit;
  return origin + d * (glm::dot(normal, hit - origin) / n_d);
}

/// One segment added to a ray's unfolded path: on the first segment (shot from outside the
/// scene) the hit's ray distance `t_m`; after a lifted shot, the hit moved back onto the unlifted
/// ray from `origin` (onto_ray) and its distance from there. Returns the hit's position on the
/// path; `path_m` grows by the segment.
[[nodiscard]] inline glm::dvec3 extend_path(bool first_segment, double t_m,
                                            const glm::dvec3& origin, const glm::dvec3& d,
                                            const glm::dvec3& hit, const glm::dvec3& normal,
                                            double& path_m) noexcept {
  if (first_segment) {
    path_m += t_m;
    return hit;
  }
  const glm::dvec3 on_ray = onto_ray(origin, d, hit, normal);
  path_m += glm::length(on_ray - origin);
  return on_ray;
}

/// A facet met at |cos theta_i| <= kEdgeOnCos is edge-on: no bounce-1 PO at all.
inline constexpr double kEdgeOnCos = 1e-12;

/// How the incident wave lights a facet at bounce 1 (its first hits), judged by visibility
/// samples (facet_samples) toward the source (the transmitter's plane wave or the radar's phase
/// centre). Both engines return, at bounce 1, exactly what this rule gives; their ray tubes
/// carry bounces 2 and up only.
enum class FacetLight : std::uint8_t {
  kLit,      ///< every sample sees the source: the exact PO integral over the whole facet
  kPartial,  ///< some samples see it, some do not: the facet is cut into m x m congruent
             ///< sub-triangles (facet_subdivisions) and each whose lifted centroid sees the
             ///< source contributes its exact PO integral
  kDark,     ///< no sample sees it: no bounce-1 return
};

/// The visibility samples of a facet: its centroid, then its three vertices and three edge
/// midpoints each moved kFacetSampleInset of the way toward the centroid, all lifted offset_m
/// along the unit normal of the lit side (toward the source): a ray from a sample toward the
/// source leaves the facet's plane and cannot meet the facet itself, however grazing.
inline constexpr std::size_t kFacetSamples = 7;
inline constexpr double kFacetSampleInset = 1e-2;
[[nodiscard]] std::array<glm::dvec3, kFacetSamples> facet_samples(const glm::dvec3& v0,
                                                                  const glm::dvec3& v1,
                                                                  const glm::dvec3& v2,
                                                                  const glm::dvec3& lit_normal,
                                                                  double offset_m) noexcept;

/// Closed parts (scene::closed_part_winding over the mesh's one topology, scene/mesh/
/// topology.hpp: +1 on a closed, consistently wound part wound outward, -1 inward, 0 open). The
/// inside of a closed part is never lit from outside, so a facet of a closed part whose outward
/// side faces away from the source is dark at bounce 1 without a visibility sample: the seven
/// samples would all be blocked by the part itself; both engines take this shortcut.

/// The bounce-1 lighting rule: `blocked(origin)` tells whether the path from `origin` toward the
/// source is obstructed. All samples clear: kLit; all blocked: kDark; otherwise kPartial (stops
/// as soon as both have been seen). Real-time safe when `blocked` is.
template <class Blocked>
[[nodiscard]] FacetLight facet_light(const std::array<glm::dvec3, kFacetSamples>& samples,
                                     Blocked&& blocked) noexcept {
  std::size_t clear = 0;
  for (std::size_t i = 0; i < kFacetSamples; ++i) {
    clear += blocked(samples[i]) ? 0u : 1u;
    if (clear != 0 && clear != i + 1)
      return FacetLight::kPartial;
  }
  return clear == kFacetSamples ? FacetLight::kLit : FacetLight::kDark;
}

/// The same rule from the samples' answers found beforehand (blocked[i] != 0: samples[i] does
/// not see the source), e.g. by a batched query (scene::Scene::occluded over spans).
[[nodiscard]] inline FacetLight facet_light(
    std::span<const std::uint8_t, kFacetSamples> blocked) noexcept {
  std::size_t clear = 0;
  for (const std::uint8_t b : blocked)
    clear += b != 0 ? 0u : 1u;
  return clear == kFacetSamples ? FacetLight::kLit
         : clear == 0           ? FacetLight::kDark
                                : FacetLight::kPartial;
}

/// Sub-triangles per edge of a partly lit facet: its longest edge over the engine's ray spacing
/// (`resolution_m`: the RCS engine's tube spacing, the tracer's bundle spacing at the target),
/// rounded up, in 1..kMaxFacetSubdivisions. The shadow boundary across a partly lit facet is
/// so resolved as finely as the ray tubes resolve everything else (the same fidelity knob), to
/// a sixteenth of the facet at most.
inline constexpr int kMaxFacetSubdivisions = 16;
[[nodiscard]] int facet_subdivisions(double longest_edge_m, double resolution_m) noexcept;

/// Calls each(a, b, c) for every one of the m x m congruent sub-triangles of (v0, v1, v2) (the
/// barycentric grid of step 1/m), always in the same order: row i = 0..m-1, then j, the "up"
/// triangle (i, j), (i + 1, j), (i, j + 1) before the "down" one (i + 1, j), (i + 1, j + 1),
/// (i, j + 1).
template <class Each>
void for_each_subtriangle(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2, int m,
                          Each&& each) noexcept {
  const glm::dvec3 e1 = (v1 - v0) / static_cast<double>(m), e2 = (v2 - v0) / static_cast<double>(m);
  for (int i = 0; i < m; ++i) {
    for (int j = 0; i + j < m; ++j) {
      const glm::dvec3 p = v0 + static_cast<double>(i) * e1 + static_cast<double>(j) * e2;
      const glm::dvec3 a = p, b = p + e1, c = p + e2;
      each(a, b, c);
      if (i + j + 2 <= m)
        each(b, p + e1 + e2, c);
    }
  }
}

/// Where the visibility test of sub-triangle (a, b, c) starts: its centroid lifted offset_m
/// along the unit normal of the lit side (as facet_samples).
[[nodiscard]] inline glm::dvec3 subtriangle_sample(const glm::dvec3& a, const glm::dvec3& b,
                                                   const glm::dvec3& c,
                                                   const glm::dvec3& lit_normal,
                                                   double offset_m) noexcept {
  return (a + b + c) / 3.0 + offset_m * lit_normal;
}

/// Calls lit(a, b, c) for every sub-triangle of for_each_subtriangle whose sample
/// (subtriangle_sample) is not `blocked` (the same test as facet_light). Returns the number of
/// occlusion tests (m^2).
template <class Blocked, class Lit>
std::size_t for_each_lit_subtriangle(const glm::dvec3& v0, const glm::dvec3& v1,
                                     const glm::dvec3& v2, const glm::dvec3& lit_normal,
                                     double offset_m, int m, Blocked&& blocked,
                                     Lit&& lit) noexcept {
  std::size_t tests = 0;
  for_each_subtriangle(v0, v1, v2, m,
                       [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
                         ++tests;
                         if (!blocked(subtriangle_sample(a, b, c, lit_normal, offset_m)))
                           lit(a, b, c);
                       });
  return tests;
}

/// Whether a facet at distance range_m [m] from a point source is in its own far field, so that
/// a plane wave over it (the exact facet integral with the phase linearised at its centroid)
/// holds: the two-way phase the linearisation drops, k rho^2 / R at the vertex farthest from
/// the centroid (rho), stays under pi/8 -- the far-field criterion R >= 2 D^2 / lambda (one-way
/// phase error pi/8 over an aperture D; Balanis, Antenna Theory, 4th ed., 2016, sec. 2.2.4)
/// applied to the two-way path. Plane-wave illumination (the RCS engine) is always far field.
[[nodiscard]] bool facet_in_far_field(double max_vertex_distance_m, double range_m,
                                      double wavenumber_rad_per_m) noexcept;

}  // namespace radar_emu::radar
