#pragma once
// Edge diffraction for the offline RCS engine (radar/em/rcs.hpp): equivalent edge currents in
// their fringe form, added to physical optics (PO) so that nothing is counted twice.
//
// Method: the physical theory of diffraction (PTD) of Ufimtsev, with the fringe ("non-uniform")
// part of the wedge's diffraction coefficients carried by equivalent edge currents (EEC) in the
// Keller-cone form. References and the equations implemented (time convention exp(+j w t),
// converted from Ufimtsev's exp(-i w t)):
//
//  [U]  P. Ya. Ufimtsev, Fundamentals of the Physical Theory of Diffraction, 2nd ed., Wiley,
//       2014: ch. 2 (the wedge: exact diffraction coefficients f, g and the PO coefficients
//       f(0), g(0) of its faces) and ch. 7 (elementary edge waves: the fringe coefficients
//       f(1) = f - f(0), g(1) = g - g(0), finite at the shadow and reflection boundaries).
//  [K]  E. F. Knott, "The relationship between Mitzner's ILDC and Michaeli's equivalent
//       currents", IEEE TAP 33(1), 1985, and A. Michaeli, "Equivalent edge currents for
//       arbitrary aspects of observation", IEEE TAP 32(3), 1984: on the Keller cone
//         I = 2 j (E_i . t) f / (k eta sin^2 beta),   M = 2 j eta (H_i . t) g / (k sin^2 beta).
//
// Wedge of exterior angle alpha = n pi (1 < n <= 2; a half-plane, the boundary of an open sheet,
// has n = 2), face 0 at angle 0, face 1 at alpha, angles measured about the edge t from face 0
// through the free space; the wave arrives from phi0 (the source's direction projected on the
// plane normal to t), the receiver is toward phi. Exact (Sommerfeld/Keller) coefficients [U]:
//   f, g = (sin(pi/n) / n) [1/(cos(pi/n) - cos((phi - phi0)/n)) -+ 1/(cos(pi/n) - cos((phi +
//   phi0)/n))]
// (f soft: E along the edge, minus; g hard: H along the edge, plus). PO of face 0 (lit when
// phi0 < pi) and of face 1 (lit when phi0 > alpha - pi), as the end-point term of the PO
// integral over the face [U, ch. 2] (rederived in docs/validation.md, "Edge diffraction"):
//   f0 = sin phi0 / (cos phi + cos phi0),       g0 = -sin phi / (cos phi + cos phi0),
//   f0' = sin(alpha - phi0) / (cos(alpha - phi) + cos(alpha - phi0)),
//   g0' = -sin(alpha - phi) / (cos(alpha - phi) + cos(alpha - phi0)).
// The fringe f1 = f - f0 - f0', g1 = g - g0 - g0' is finite everywhere (the singular parts
// cancel at phi = pi -+ phi0 and alpha - pi -+ ...): near those boundaries it is evaluated at
// phi +- delta and averaged (counted as a guard).
//
// Far field of the currents of a straight edge of length L (centre c), radiating toward s, with
// the incident phase exp(-j k d . r) along it; S = sqrt(4 pi) r e^{jkr} p . E_s / |E_i| as in
// rcs.hpp:
//   S = -(1 / (sqrt(pi) sin^2 beta)) [ (e . t) f1 p . (s x (s x t)) + ((d x e) . t) g1 p . (s x t)
//   ]
//       * L sinc(k (s - d) . t L / 2) exp(j k (s - d) . c),
// where the last line is the exact integral of a linear-phase, uniform-amplitude current along
// the segment. Off the Keller cone (monostatic views of an edge away from its broadside), phi is
// the receiver's direction projected on the plane normal to the edge (the Keller-cone form of
// [K]); the sinc makes those contributions small for long edges.
// Pure computation, no I/O.

#include <array>
#include <complex>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

#include "scene/mesh/topology.hpp"

namespace radar_emu::radar {

/// A diffracting wedge edge of the mesh, in world coordinates.
struct WedgeEdge {
  glm::dvec3 a_m{0.0}, b_m{0.0};  ///< end points
  glm::dvec3 t{0.0};              ///< unit (b - a)
  glm::dvec3 x0{0.0};      ///< unit, normal to t, in face 0, pointing from the edge into the face
  glm::dvec3 y0{0.0};      ///< unit normal of face 0 on the free-space side
  double alpha_rad = 0.0;  ///< exterior (free-space) wedge angle, in (pi, 2 pi]
  double length_m = 0.0;
  /// Mean width of the facets across the edge: the distance from the edge's line to each
  /// facet's third vertex, averaged over its one or two facets [m] (wedge_weight).
  double width_m = 0.0;
};

// ---------------------------------------------------------------------------------------------
// Which joints are wedges (docs/validation.md, "Edge diffraction": the wedge rule).
//
// A mesh joint turning by psi = alpha - pi between facets of width h (WedgeEdge::width_m) is
// either a real wedge or the trace of a tessellated smooth surface. Seen as a smooth arc of
// radius R = h / psi cut into chords of width h, each facet departs from the arc by its sagitta
// delta = h^2 / (8 R) = h psi / 8, and the wave reflected by the facets instead of the arc is
// off in phase by at most 2 k delta = (pi / 2) q with
//   q = psi h / lambda,
// the turn against the facet width in wavelengths. Where 2 k delta < pi / 4 (q < 1/2: the
// Rayleigh criterion for a smooth surface, Beckmann & Spizzichino, The Scattering of
// Electromagnetic Waves from Rough Surfaces, 1963, ch. 2 sec. 1) the faceted surface reflects
// as the smooth one it stands for and PO of its facets is the whole answer: the joint diffracts
// nothing. Where 2 k delta > pi / 2 (q > 1) the facets are flat over more than the scale the
// wave resolves: a wedge. A joint turning by at least `full_turn_rad` (RcsConfig::
// edge_min_turn_rad, 30 deg by default: no tessellation of a smooth surface meant for PO turns
// that much at one joint) is a wedge at any facet size (a finely meshed box or plate keeps its
// edges). In between, the weight rises as the smoothstep 3 x^2 - 2 x^3 of each ramp (q from 1/2
// to 1, psi from full_turn_rad / 2 to full_turn_rad), the larger one taken: the edge terms go to
// zero continuously as a wedge flattens (psi -> 0 at fixed h, or h -> 0 at fixed psi). An open
// sheet's boundary (psi = pi) is always a wedge.
/// The weight in [0, 1] that multiplies `edge`'s terms at wavelength lambda_m (above).
[[nodiscard]] double wedge_weight(const WedgeEdge& edge, double lambda_m,
                                  double full_turn_rad) noexcept;

/// How the mesh's edges were sorted.
struct EdgeCensus {
  std::uint64_t half_planes = 0;  ///< boundary edges of open sheets (alpha = 2 pi)
  std::uint64_t wedges = 0;       ///< shared edges turning by more than the threshold
  std::uint64_t smooth = 0;       ///< shared edges turning less (no edge term)
  std::uint64_t unsupported = 0;  ///< shared by > 2 facets, inconsistent winding, non-PEC
};

/// Finds the diffracting edges of a triangle mesh `tris` (world coordinates) among the edges of
/// `topology`, its topology (scene/mesh/topology.hpp: triangle i of the one is triangle i of the
/// other; vertices welded by the one rule; the edge list's order is the output's). `outward[i]`
/// is +1/-1/0 as scene::closed_part_winding (times mirroring): for closed parts the free space
/// is on the outward side; for an edge of an open part the convex side (alpha > pi) is taken.
/// `pec[i]`: only PEC faces diffract here. An edge of one triangle is an open sheet's boundary
/// (a half-plane); an edge shared by two facets is kept when its exterior angle departs from pi
/// by more than min_turn_rad. Throws std::invalid_argument when the sizes disagree.
[[nodiscard]] std::vector<WedgeEdge> find_wedge_edges(
    std::span<const std::array<glm::dvec3, 3>> tris, const scene::MeshTopology& topology,
    std::span<const std::int8_t> outward, std::span<const std::uint8_t> pec, double min_turn_rad,
    EdgeCensus& census);

/// Which diffraction coefficient to use (the engine uses kFringe; the others are for tests: the
/// PO end-point currents of a flat plate's edges reproduce its exact facet PO in a principal
/// cut).
enum class EdgeCoefficient : std::uint8_t { kFringe, kPhysicalOptics, kExact };

/// Soft (f) and hard (g) coefficients of the wedge (header), for a wave from phi0_rad toward
/// phi_rad. `guarded` is set when a boundary singularity was stepped around.
struct WedgeCoefficients {
  double f = 0.0, g = 0.0;
};
[[nodiscard]] WedgeCoefficients wedge_coefficients(double alpha_rad, double phi_rad,
                                                   double phi0_rad, EdgeCoefficient kind,
                                                   bool& guarded) noexcept;

/// Why an edge gave no term for one direction pair.
enum class EdgeSkip : std::uint8_t {
  kNone,
  kBackFace,     ///< the source is inside the wedge (no face lit)
  kAlongEdge,    ///< sin beta or the receiver's projection below kEdgeMinSin (Keller-cone guard)
  kInsideWedge,  ///< the receiver's direction lies inside the wedge (bistatic)
};
inline constexpr double kEdgeMinSin = 1e-3;

/// One edge's contribution, frequency-free: S(k) = sum_p c[p] L sinc(k taper_m) exp(j k phase_m)
/// (p = hh, hv, vh, vv as ScatteringMatrix).
struct EdgeTerm {
  std::array<std::complex<double>, 4> c{};
  double length_m = 0.0;
  double taper_m = 0.0;  ///< (s - d) . t L / 2
  double phase_m = 0.0;  ///< (s - d) . centre
};

/// The term of `edge` for propagation direction d (unit, from the transmitter), receiver
/// direction s (unit, toward the receiver), transmit polarisations tx_h, tx_v and receive rx_h,
/// rx_v (header formula). Returns kNone and fills `term`, or the reason for no term.
///
/// Bounds (issue 30: no edge term may invent a return):
///  - `min_sin2_beta` (m): the Keller-cone factor 1 / sin^2 beta is kept where sin^2 beta >= m
///    and becomes sin^2 beta / m^2 below: continuous, never above 1 / m, and falling to 0 as the
///    edge is seen end-on (where no term is made, kEdgeMinSin). A segment of length L
///    resolves directions along itself only to d(cos beta) ~ lambda / (2 L) (the main lobe of its
///    sinc), hence beta near 0 only to sin^2 beta ~ lambda / L: the engine passes lambda / L
///    (lambda at the call's highest frequency), so that an edge seen nearly end-on (a plate
///    edge-on, the radar along one of its edges) gives a term of the order of L^2 / lambda, not 1 /
///    (k sin^2 beta).
///  - `coefficient_bound`: |f| and |g| are clamped to it. The fringe coefficients of every
///    wedge (1 < n <= 2) stay at or under 1 in magnitude for all monostatic directions (scanned
///    in tests/radar/edges_test.cpp); they grow without bound only in bistatic directions near
///    a shadow or reflection boundary of a face lit at grazing incidence, where they cancel a PO
///    end-point term growing as fast (Ufimtsev 2014, ch. 2: PO of a face at grazing). The
///    engine (rcs.hpp) limits every term to that monostatic bound, kMonostaticFringeBound: its
///    reflected paths (reflection-diffraction) are bistatic edge terms whose PO counterpart (a
///    face's PO radiating into the mirrored direction) is not part of the model, so nothing
///    would cancel the growth there (it put 34.6 dBsm at theta 0.5 deg on a 15.8 dBsm
///    trihedral); direct and reflected terms keep the same bound so that image theory holds
///    between them. Monostatic terms are unchanged; bistatic ones near a face's shadow or
///    reflection boundary are limited (the PTD fringe there is non-uniform anyway).
[[nodiscard]] EdgeSkip edge_term(const WedgeEdge& edge, const glm::dvec3& d, const glm::dvec3& s,
                                 const glm::dvec3& tx_h, const glm::dvec3& tx_v,
                                 const glm::dvec3& rx_h, const glm::dvec3& rx_v,
                                 EdgeCoefficient kind, EdgeTerm& term, bool& guarded,
                                 double min_sin2_beta = 0.0,
                                 double coefficient_bound = 1e300) noexcept;
/// The engines pass min(lambda / L, kMaxMinSin2Beta) as min_sin2_beta: a segment shorter than
/// ~30 wavelengths is one piece of a longer edge (a curved rim cut into chords), which together
/// resolve beta; the regularisation then acts only within 10 deg of end-on (sin^2 10 deg).
inline constexpr double kMaxMinSin2Beta = 0.03;
/// The largest |f1|, |g1| of a wedge's fringe coefficients over monostatic directions (above).
inline constexpr double kMonostaticFringeBound = 1.0;

// ---------------------------------------------------------------------------------------------
// Double diffraction across a flat face (second order, hard polarisation).
//
// A wedge edge lit by the plane wave launches a diffracted wave along each of its faces. For the
// soft scalar (E along the edge) that wave vanishes on the face; for the hard scalar (eta H . t)
// it does not, and it crosses the face to a parallel edge bounding the same face, which
// diffracts it again. First-order edge currents miss this: it is what separates a plate's HH
// from its VV in a principal plane and makes the hard polarisation's travelling-wave lobe and its
// fall at grazing (Ross, "Radar cross section of rectangular flat plates as a function of aspect
// angle", IEEE TAP 14(3), 1966; Balanis, Advanced Engineering Electromagnetics, 2nd ed., 2012,
// sec. 13.3: multiple diffractions of a strip, with the factor 1/2 of grazing incidence).
//
// Ray picture (Keller's GTD with the uniform coefficients of Kouyoumjian & Pathak, "A uniform
// geometrical theory of diffraction for an edge in a perfectly conducting surface", Proc. IEEE
// 62(11), 1974, eqs. 25-29; time convention exp(+j w t)): a point Q1 of the launching edge emits
// on its Keller cone, along the face (angle phi_L = 0 or alpha of that edge), the ray
// u = (d . t) t + sin(beta) x_face, which meets the parallel edge at Q2 = Q1 + s u after
// s = w / sin(beta) (w: distance between the edges). There the hard scalar is
//   psi(Q2) = psi_i(Q1) D_h(phi_L, phi0) exp(-j k s) / sqrt(s),
//   D_h = exp(-j pi/4) g_utd(phi, phi0; k L) / (sqrt(2 pi k) sin(beta)),
//   g_utd = -(1 / 2n) sum_{x = phi -+ phi0} [cot((pi + x) / 2n) F(k L a+(x))
//                                          + cot((pi - x) / 2n) F(k L a-(x))]   (hard: +),
//   a+-(x) = 2 cos^2((2 pi n N+- - x) / 2), N+- the integers nearest (x +- pi) / (2 pi n),
//   F(X) = 2 j sqrt(X) exp(j X) int_sqrt(X)^inf exp(-j tau^2) d tau   (the transition function;
// with F = 1, g_utd is the Sommerfeld g of the header), L = s sin^2(beta) = w sin(beta). The phase
// of psi(Q2) advances along the second edge as the incident wave's does (d . t), so the second
// edge carries the header's equivalent current with psi(Q2) for (d x e) . t and the exact
// coefficient for grazing incidence from the face (phi0 = 0 or alpha), halved (incident and
// reflected waves coincide at grazing; KP sec. V), with L = w sin(beta) again (a cylindrical
// wave from the first edge, the receiver far). The far-field term of the segment of the second
// edge that rays from the first reach:
//   S = -(1 / (sqrt(pi) sin^2 beta)) ((d x e) . t1) (t1 . t2) p . (s x t2)
//       * exp(-j pi/4) / sqrt(2 pi k w sin beta) g_utd1 (g_utd2 / 2)
//       * L_seg sinc(k (s - d) . t2 L_seg / 2) exp(j k [(s - d) . c_seg - w sin(beta) (1 +
//       cos(phi_L
//       - phi0))]).
// The soft scalar's grazing wave (slope diffraction) and third and higher orders are left out.
// An open sheet's boundary launches along both sides of the sheet: two terms. The face must be
// continuous between the edges (checked at the middle of the strip between them).

/// An ordered pair of parallel edges bounding the same flat face, facing each other across it.
struct EdgePair {
  std::uint32_t from = 0, to = 0;       ///< indices into the edge list (launching, receiving edge)
  double phi_launch_rad = 0.0;          ///< the face's angle at `from` (0 or its alpha)
  double phi_arrive_rad = 0.0;          ///< the face's angle at `to` (0 or its alpha)
  double width_m = 0.0;                 ///< distance between the two edges' lines
  double to_lo_m = 0.0, to_hi_m = 0.0;  ///< `to`'s extent along from.t, from from.a_m
};

/// Finds the pairs among `edges` (as find_wedge_edges returns them; tris: the same mesh) whose
/// double diffraction is carried: parallel within 1e-6 rad, on the same face plane within
/// tolerance_m, each edge's face pointing toward the other, the two extents overlapping along
/// the edges, and a facet of that plane under the middle of the strip between them.
[[nodiscard]] std::vector<EdgePair> find_edge_pairs(std::span<const WedgeEdge> edges,
                                                    std::span<const std::array<glm::dvec3, 3>> tris,
                                                    double tolerance_m);

/// One pair's double-diffraction term for a direction pair: frequency-free parts; the value at
/// wavenumber k is pol[p] * double_edge_factor(term, k) (p = hh, hv, vh, vv).
struct DoubleEdgeTerm {
  std::array<double, 4> pol{};
  double alpha_from_rad = 0.0, phi_launch_rad = 0.0, phi0_rad = 0.0;
  double alpha_to_rad = 0.0, phi_arrive_rad = 0.0, phi_rad = 0.0;
  double l_m = 0.0;  ///< w sin(beta): the UTD distance parameter of both diffractions
  double length_m = 0.0, taper_m = 0.0, phase_m = 0.0;
  glm::dvec3 centre_m{0.0};  ///< the middle of the receiving edge's segment
};

/// The term of `pair` (header of this section) for propagation direction d and receiver
/// direction s. Returns kNone and fills `term`, kBackFace when the source is inside the
/// launching wedge, kAlongEdge at the Keller-cone guard or when no ray from the launching edge
/// reaches the receiving one, kInsideWedge when the receiver is inside the receiving wedge.
[[nodiscard]] EdgeSkip double_edge_term(const EdgePair& pair, std::span<const WedgeEdge> edges,
                                        const glm::dvec3& d, const glm::dvec3& s,
                                        const glm::dvec3& tx_h, const glm::dvec3& tx_v,
                                        const glm::dvec3& rx_h, const glm::dvec3& rx_v,
                                        DoubleEdgeTerm& term) noexcept;

/// The polarisation-free factor of a double-diffraction term at wavenumber k [rad/m]:
/// exp(-j pi/4) / sqrt(2 pi k l) g_utd1 (g_utd2 / 2) L sinc(k taper) exp(j k phase).
[[nodiscard]] std::complex<double> double_edge_factor(const DoubleEdgeTerm& term,
                                                      double k) noexcept;

/// The uniform hard (hard = true) or soft wedge coefficient g_utd / f_utd of Kouyoumjian and
/// Pathak in the header's normalisation (it tends to wedge_coefficients' kExact far from the
/// shadow and reflection boundaries); kl = k L, the distance parameter times the wavenumber.
[[nodiscard]] std::complex<double> utd_wedge_coefficient(double alpha_rad, double phi_rad,
                                                         double phi0_rad, double kl,
                                                         bool hard) noexcept;

/// The UTD transition function F(X) = 2 j sqrt(X) exp(j X) int_sqrt(X)^inf exp(-j tau^2) d tau
/// (Kouyoumjian & Pathak 1974, eq. 27), X >= 0: power series of the Fresnel integral up to
/// X = 16, the asymptotic series sum (-1)^m (2m - 1)!! / (2 j X)^m beyond.
[[nodiscard]] std::complex<double> utd_transition(double x) noexcept;

/// `v` or -v, whichever has its largest-magnitude component positive: one representative of a
/// direction and its opposite (for grouping parallel edges and coplanar facets).
[[nodiscard]] glm::dvec3 sign_folded(const glm::dvec3& v) noexcept;

/// A point beside the edge's midpoint in the free space (along the exterior bisector), offset_m
/// away: where the engine's occlusion test toward the transmitter starts.
[[nodiscard]] glm::dvec3 edge_probe(const WedgeEdge& edge, double offset_m) noexcept;

}  // namespace radar_emu::radar
