#pragma once
// Radar cross section of a faceted target by physical optics plus shooting and bouncing rays
// (Ling, Chou & Lee, "Shooting and bouncing rays: calculating the RCS of an arbitrarily shaped
// cavity", IEEE TAP 37(2), 1989), fully polarimetric, monostatic or bistatic, over any set of
// frequencies from one trace.
//
//   bounce 1   Physical optics as classical PO has it: the currents the transmitter's wave
//              induces on the lit surface radiate toward the receiver with no receiver-visibility
//              cut (which gives forward scatter and the shadow-boundary terms). Lighting is the
//              rule shared with the frame tracer (radar/em/sbr_core.hpp, FacetLight): a facet
//              whose seven visibility samples all see the transmitter contributes the exact PO
//              integral over the triangle (radar/em/facet_po.hpp: no ray-density error); a
//              partly seen one is cut into congruent sub-triangles of about lambda / 4, each
//              contributing its exact integral when its centroid sees the transmitter; one not
//              seen at all contributes nothing. Both sides of a facet can be lit (sheets such
//              as plates are two-sided).
//   bounce 2+  A grid of parallel ray tubes (the incident plane wave, `rays_per_wavelength` along
//              each axis at the highest frequency) is traced by geometrical optics; the field is
//              carried through every reflection with its polarisation (PEC: R_perp = -1,
//              R_par = +1; dielectric and coated surfaces: Fresnel coefficients); at every hit
//              after the first the tube's footprint radiates by PO toward the receiver when the
//              receiver sees the lit side of the hit (n.s >= kGrazingCos, no obstruction). A
//              tube stops at a grazing hit (cos theta_i < kGrazingCos) or at the bounce cap.
//   edges      With RcsConfig::edges: edge diffraction, the fringe equivalent edge currents of the
//              mesh's wedge edges and open-sheet boundaries (PTD; radar/em/edges.hpp), each
//              integrated exactly along its straight edge and added to bounce 1; an edge
//              radiates when a face of it is lit and its midpoint sees the transmitter. With
//              edge_order 2, the hard polarisation's double diffraction between parallel edges
//              across a flat face (edges.hpp) is added too, when the launching edge's midpoint
//              sees the transmitter and the receiving edge's sees the receiver. Edges are
//              also lit and seen by way of one reflection off the target's largest flat PEC
//              faces (reflection-diffraction, diffraction-reflection and both; image theory: the
//              edge term with the mirrored directions and polarisations and the image phase).
//   sweeps     Facet geometry and ray paths do not depend on frequency: they are found once per
//              direction and every frequency is summed from them.
//
// Conventions (../shared/design.md): target frame = the scene's world frame, phase reference at
// its origin; a direction (theta, phi) is where the radar sits, theta from +z, phi from +x toward
// +y; V = theta-hat, H = phi-hat of that direction; time convention exp(+j w t). The scattering
// amplitude S_pq (receive p, transmit q) is in metres with sigma_pq = |S_pq|^2 [m^2]:
//   S = sqrt(4 pi) r e^{jkr} (p . E_s) / |E_i|,
// so a PEC plate of area A at normal incidence gives S_HH = S_VV = -j k A / sqrt(pi).
// The ray-tube and PO machinery is the SBR core shared with the frame tracer
// (radar/em/sbr_core.hpp). PO radiation: E_s = -j k e^{-jkr} / (4 pi r) integral [eta J_perp - s x
// M] e^{jk s.r'} dS' (Balanis, Advanced Engineering Electromagnetics, 2nd ed., 2012, sec. 6.7: far
// fields of electric and magnetic surface currents), with the PO currents eta J = n x (d_i x E_i +
// d_r x E_r), M = (E_i + E_r) x n of the local reflection (J = 2 n x H_i, M = 0 on a PEC). Offline
// product code: allocates, uses TBB worker threads; not for the real-time frame path.

#include <array>
#include <complex>
#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <span>
#include <string>
#include <vector>

#include "radar/em/edges.hpp"
#include "radar/em/sbr_core.hpp"
#include "scene/scene.hpp"

namespace radar_emu::radar {

// SurfaceModel, ReflectionCoefficients and reflection_coefficients(): radar/em/sbr_core.hpp.

/// Where the radar is, seen from the target (design.md).
struct Direction {
  double theta_rad = 0.0;  ///< from +z
  double phi_rad = 0.0;    ///< from +x toward +y
};
[[nodiscard]] glm::dvec3 unit_vector(const Direction& d) noexcept;
[[nodiscard]] glm::dvec3 theta_hat(const Direction& d) noexcept;  ///< V polarisation
[[nodiscard]] glm::dvec3 phi_hat(const Direction& d) noexcept;    ///< H polarisation

/// Scattering matrix [m], receive polarisation first: hv = receive H, transmit V.
struct ScatteringMatrix {
  std::complex<double> hh{0.0, 0.0}, hv{0.0, 0.0}, vh{0.0, 0.0}, vv{0.0, 0.0};
};

/// Mesh joints turning by less than this [rad] are flat (coplanar within rounding) and no
/// candidate wedge; the others are sorted by the wedge rule (edges.hpp, wedge_weight).
inline constexpr double kWedgeCandidateTurnRad = 1e-3;

/// The largest RcsConfig::max_bounces.
inline constexpr int kMaxRcsBounces = 64;

struct RcsConfig {
  /// 1: bounce-1 PO only (no ray tube); n >= 2: ray tubes carry bounces 2..n
  /// (n <= kMaxRcsBounces).
  int max_bounces = 3;
  /// Ray tubes per wavelength along each axis of the incident wavefront, at the highest
  /// frequency of a call. May be below 1: a tube's footprint integral is exact on flat facets,
  /// so coarse tubes lose accuracy only at edges (check convergence by doubling it).
  double rays_per_wavelength = 4.0;
  /// Frequency at which coatings' (frequency-dependent) reflection coefficients are evaluated
  /// for a sweep [Hz]; 0 = the middle of the frequencies of each call. PEC and dielectric
  /// half-spaces do not depend on frequency.
  double coating_reference_hz = 0.0;
  bool shadowing = true;                ///< occlusion tests for facets and ray-path exits
  std::uint64_t max_rays = 50'000'000;  ///< per call; more is an error (say so, don't stall)
  /// Edge diffraction (radar/em/edges.hpp): fringe equivalent edge currents of the mesh's wedge
  /// edges and open-sheet boundaries, added to bounce-1 PO. Off here (the closed-form PO tests
  /// compare PO alone); the CLI turns it on by default.
  bool edges = false;
  /// A shared edge turning by at least this [rad] (its exterior wedge angle minus pi) is a
  /// wedge whatever its facets' size; one turning less is a wedge or a joint of a smooth
  /// surface by the wedge rule (edges.hpp, wedge_weight: the turn against the facets' width in
  /// wavelengths at the call's highest frequency); joints of a smooth surface are left to PO.
  double edge_min_turn_rad = 30.0 * 3.14159265358979323846 / 180.0;
  /// With edges: 1 = first-order edge currents only; 2 = also the double diffraction of the hard
  /// polarisation between parallel edges across a flat face (edges.hpp, find_edge_pairs).
  int edge_order = 2;
};

struct RcsStats {
  std::uint64_t facets_lit = 0;       ///< FacetLight::kLit: exact facet PO
  std::uint64_t facets_partial = 0;   ///< FacetLight::kPartial: cut into sub-triangles
  std::uint64_t lit_subfacets = 0;    ///< lit sub-triangles of the partly lit facets
  std::uint64_t facets_shadowed = 0;  ///< FacetLight::kDark
  std::uint64_t facets_edge_on = 0;   ///< |cos theta_i| <= kEdgeOnCos: contribute nothing
  std::uint64_t rays = 0;
  std::uint64_t ray_hits = 0;
  std::uint64_t paths = 0;          ///< tube footprints radiated (bounces >= 2)
  std::uint64_t grazing_stops = 0;  ///< tubes stopped at cos theta_i < kGrazingCos
  /// Tubes still bouncing at the cap: after their max_bounces-th reflection the reflected ray
  /// meets the target again (what a higher cap would add; 0 when no tube was traced).
  std::uint64_t tubes_cut_off = 0;
  std::uint64_t occlusion_queries = 0;
  std::uint64_t segments = 0;  ///< intersection queries of the ray tubes (rays x bounces)
  std::uint64_t paths_by_bounce[kMaxRcsBounces + 1] = {};  ///< [n]: footprints at bounce n >= 2
  std::uint64_t edges_used = 0;                            ///< edge terms added (config.edges)
  std::uint64_t edges_shadowed = 0;   ///< lit faces, but the path to the transmitter is blocked
  std::uint64_t edges_skipped = 0;    ///< no lit face, along the edge (Keller-cone guard) or the
                                      ///< receiver inside the wedge (edges.hpp, EdgeSkip)
  std::uint64_t edges_guarded = 0;    ///< boundary singularities stepped around (edges.hpp)
  std::uint64_t edges_double = 0;     ///< edge-to-edge double-diffraction terms added
  std::uint64_t edges_reflected = 0;  ///< edge terms by way of a reflecting plane (RD, DR, RDR)
  /// Mesh joints that are no wedge at this call's highest frequency (edges.hpp, wedge_weight 0):
  /// facets of a smooth surface, left to PO.
  std::uint64_t edges_smooth = 0;
};

/// A flat PEC face of the target large enough to light edges by reflection (RcsEngine).
struct ReflectingPlane {
  glm::dvec3 normal{0.0, 0.0, 1.0};  ///< unit (sign-folded: largest component positive)
  double offset_m = 0.0;             ///< normal . x on the plane
  double area_m2 = 0.0;              ///< of the PEC facets in it
};
/// At most this many planes, each at least kReflectingPlaneShare of the largest one's area.
inline constexpr std::size_t kMaxReflectingPlanes = 8;
inline constexpr double kReflectingPlaneShare = 0.25;
/// A plane reflects toward edges only when its PEC area is at least this many square
/// wavelengths (at the lowest frequency of a call).
inline constexpr double kReflectingPlaneMinWavelengths2 = 4.0;

/// One reflection of a ray tube (for tests of the GO tracer). Reported from worker threads.
struct BounceEvent {
  int bounce = 0;             ///< 1 = first hit
  glm::dvec3 incident{0.0};   ///< unit propagation direction before
  glm::dvec3 normal{0.0};     ///< unit normal on the side the ray meets
  glm::dvec3 reflected{0.0};  ///< unit propagation direction after
  double field_before = 0.0;  ///< |E| of the V-transmit field before and after
  double field_after = 0.0;
  double field_h_before = 0.0;  ///< |E| of the H-transmit field before and after
  double field_h_after = 0.0;
  bool pec = true;
};

/// The incident ray-tube grid of one call: ray (i, j) starts at origin_m + i du_m + j dv_m and
/// travels along direction; each tube has cross-section |du x dv|.
struct RayGrid {
  glm::dvec3 origin_m{0.0}, du_m{0.0}, dv_m{0.0}, direction{0.0, 0.0, -1.0};
  std::uint64_t cols = 0, rows = 0;
};

class RcsEngine {
 public:
  /// `surfaces[i]` models scene material i. Throws std::invalid_argument (bad config, size
  /// mismatch, non-finite permittivity, negative thickness, no non-degenerate facet).
  RcsEngine(const scene::Scene& scene, std::vector<SurfaceModel> surfaces, RcsConfig config);

  /// Scattering matrix at every frequency in `freqs_hz` (out.size() == freqs_hz.size()) for
  /// the transmitter in direction `tx` and the receiver in `rx` (monostatic: rx == tx).
  /// `stats` is added to. `on_bounce` (may be null) sees every GO reflection, possibly from
  /// several threads at once. Throws std::invalid_argument for empty/non-positive/non-finite
  /// frequencies, mismatched sizes, or a ray grid over config.max_rays. Several calls may run
  /// at once on one engine (the CLI's sweeps run directions side by side).
  void compute(const Direction& tx, const Direction& rx, std::span<const double> freqs_hz,
               std::span<ScatteringMatrix> out, RcsStats& stats,
               const std::function<void(const BounceEvent&)>* on_bounce = nullptr) const;

  /// The tube grid compute() shoots for a transmitter in `tx` when the highest frequency is
  /// `max_freq_hz` (for benchmarks against raw ray casting on the same rays). Throws
  /// std::invalid_argument when it exceeds config().max_rays.
  [[nodiscard]] RayGrid ray_grid(const Direction& tx, double max_freq_hz) const;

  [[nodiscard]] double bounding_radius_m() const noexcept { return radius_m_; }
  [[nodiscard]] glm::dvec3 bounding_centre_m() const noexcept { return centre_m_; }
  [[nodiscard]] std::size_t facet_count() const noexcept { return facets_.size(); }
  [[nodiscard]] std::size_t degenerate_facets() const noexcept { return degenerate_; }
  [[nodiscard]] const RcsConfig& config() const noexcept { return config_; }
  /// The diffracting edges found (empty unless config.edges) and how the mesh's edges sorted.
  [[nodiscard]] std::span<const WedgeEdge> edges() const noexcept { return edges_; }
  [[nodiscard]] const EdgeCensus& edge_census() const noexcept { return census_; }
  /// The edge pairs whose double diffraction is added (empty unless edges and edge_order 2).
  [[nodiscard]] std::span<const EdgePair> edge_pairs() const noexcept { return pairs_; }
  /// The planes that light and relay edge terms by one reflection (empty unless edges).
  [[nodiscard]] std::span<const ReflectingPlane> reflecting_planes() const noexcept {
    return planes_;
  }

 private:
  struct Facet {
    glm::dvec3 v0, v1, v2, centroid, normal;
    double area_m2;
    double longest_m;  ///< its longest edge
    std::uint16_t surface;
    /// +1: `normal` points out of the closed part the facet belongs to, -1: into it, 0: open
    /// part (sbr_core.hpp, closed parts).
    std::int8_t outward;
    /// The same for the bounce-1 lighting, with parts closed up to T-junctions counted closed
    /// (rcs.cpp, solid_winding).
    std::int8_t solid;
    /// Bit 0: the half-space on the normal's side of the facet's plane holds no geometry (the
    /// facet is on the target's convex hull, facing that way); bit 1: the same on the other side
    /// (rcs.cpp, find_supporting_sides).
    std::uint8_t empty_side = 0;
  };
  void find_supporting_sides(std::vector<glm::dvec3> vertices_m);
  const scene::Scene* scene_;
  std::vector<SurfaceModel> surfaces_;
  RcsConfig config_;
  std::vector<Facet> facets_;
  std::vector<glm::dvec3> facet_vertices_m_;  ///< the facets' vertices, each once
  /// Facet::empty_side of triangle t of object o (as the scene winds it; 0 for a degenerate
  /// one): triangle_empty_side_[first_triangle_[o] + t], a byte per triangle (the tubes read it
  /// at every hit).
  std::vector<std::size_t> first_triangle_;
  std::vector<std::uint8_t> triangle_empty_side_;
  std::size_t degenerate_ = 0;
  glm::dvec3 centre_m_{0.0};
  double radius_m_ = 0.0;
  double epsilon_m_ = 0.0;  ///< ray offset, scaled with the target
  std::vector<WedgeEdge> edges_;
  std::vector<EdgePair> pairs_;
  std::vector<ReflectingPlane> planes_;
  EdgeCensus census_;
};

/// sigma = |S|^2 in dBsm, floored at -400 dBsm for an exact zero.
[[nodiscard]] double dbsm(std::complex<double> amplitude_m) noexcept;

}  // namespace radar_emu::radar
