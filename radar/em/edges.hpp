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

namespace radar_emu::radar {

/// A diffracting wedge edge of the mesh, in world coordinates.
struct WedgeEdge {
  glm::dvec3 a_m{0.0}, b_m{0.0};  ///< end points
  glm::dvec3 t{0.0};              ///< unit (b - a)
  glm::dvec3 x0{0.0};      ///< unit, normal to t, in face 0, pointing from the edge into the face
  glm::dvec3 y0{0.0};      ///< unit normal of face 0 on the free-space side
  double alpha_rad = 0.0;  ///< exterior (free-space) wedge angle, in (pi, 2 pi]
  double length_m = 0.0;
};

/// How the mesh's edges were sorted.
struct EdgeCensus {
  std::uint64_t half_planes = 0;  ///< boundary edges of open sheets (alpha = 2 pi)
  std::uint64_t wedges = 0;       ///< shared edges turning by more than the threshold
  std::uint64_t smooth = 0;       ///< shared edges turning less (no edge term)
  std::uint64_t unsupported = 0;  ///< shared by > 2 facets, inconsistent winding, non-PEC
};

/// Finds the diffracting edges of a triangle mesh (world coordinates; vertices welded by exact
/// position). `outward[i]` is +1/-1/0 as sbr_core.hpp's closed_part_winding (times mirroring):
/// for closed parts the free space is on the outward side; for an edge of an open part the
/// convex side (alpha > pi) is taken. `pec[i]`: only PEC faces diffract here. An edge shared by
/// two facets is kept when its exterior angle departs from pi by more than min_turn_rad.
[[nodiscard]] std::vector<WedgeEdge> find_wedge_edges(
    std::span<const std::array<glm::dvec3, 3>> tris, std::span<const std::int8_t> outward,
    std::span<const std::uint8_t> pec, double min_turn_rad, EdgeCensus& census);

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
[[nodiscard]] EdgeSkip edge_term(const WedgeEdge& edge, const glm::dvec3& d, const glm::dvec3& s,
                                 const glm::dvec3& tx_h, const glm::dvec3& tx_v,
                                 const glm::dvec3& rx_h, const glm::dvec3& rx_v,
                                 EdgeCoefficient kind, EdgeTerm& term, bool& guarded) noexcept;

/// A point beside the edge's midpoint in the free space (along the exterior bisector), offset_m
/// away: where the engine's occlusion test toward the transmitter starts.
[[nodiscard]] glm::dvec3 edge_probe(const WedgeEdge& edge, double offset_m) noexcept;

}  // namespace radar_emu::radar
