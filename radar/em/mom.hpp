#pragma once
// Method of moments for perfectly conducting targets: the surface integral equations solved on
// Rao-Wilton-Glisson (RWG) basis functions, Galerkin tested, by dense LU factorisation. Exact up
// to discretisation: creeping waves, travelling waves, tip and edge diffraction and every
// multiple interaction come out of the currents, which is what physical optics plus edge
// diffraction (radar/em/rcs.hpp) cannot carry on electrically small targets (the NASA almond's
// nose-on return, spheres below ka ~ 10). Its cost, O(N^2) memory and O(N^3) time in the number
// of unknowns N (about 1.5 per triangle, triangles about lambda / 10 on a side), limits it to
// targets a few wavelengths across: a reference and an offline tool, never the frame path.
//
// Formulation (time convention exp(+j w t), G = e^{-jkR} / (4 pi R)):
//   EFIE  jk eta [ <f_m, f_n G> - <div f_m, div' f_n G> / k^2 ] I_n = <f_m, E_i>
//         (Rao, Wilton & Glisson, "Electromagnetic scattering by surfaces of arbitrary shape",
//         IEEE TAP 30(3), 1982, eqs. 8, 17-19; the div-div form of the scalar potential term);
//   MFIE  [ <f_m, f_n> / 2 - <f_m, n x PV int grad G x f_n dS'> ] I_n = <f_m, n x H_i>
//         (Gibson, The Method of Moments in Electromagnetics, 2nd ed., 2014, sec. 6.2; grad G =
//         -(1 + jkR) e^{-jkR} (r - r') / (4 pi R^3); the principal value vanishes on the
//         observation point's own flat triangle);
//   CFIE  alpha EFIE + (1 - alpha) eta MFIE, row by row (Mautz & Harrington, "H-field, E-field
//         and combined-field solutions for conducting bodies of revolution", AEU 32, 1978): free
//         of the interior resonances at which EFIE and MFIE alone fail. The MFIE holds on closed
//         surfaces only, so rows of basis functions on an open sheet use the EFIE whatever the
//         choice.
// The EFIE is the default: with RWG testing it is the accurate one (a sphere converges to Mie at
// second order in the mesh size), while the RWG-tested MFIE stays off by tenths of a dB on
// curved surfaces and by dB at tips (Ergul & Gurel, Radio Science 41, 2006; tests/radar/
// mom_test.cpp, docs/validation.md). The EFIE's interior resonances are narrow and spoil the
// currents more than the far field (a resonant interior mode's current radiates nothing
// outside); the CFIE is there to cross-check a frequency that looks suspect.
// Quadrature: Dunavant's 6-point degree-4 rule on the observation triangle (D. A. Dunavant, "High
// degree efficient symmetrical Gaussian quadrature rules for the triangle", IJNME 21, 1985) and
// on nearby source triangles, the 3-point degree-2 rule on distant ones; on the source triangle
// itself and its neighbours the inner integral is taken in Duffy coordinates about the
// observation point's projection (M. G. Duffy, "Quadrature over a pyramid or cube of integrands
// with a singularity at a vertex", SIAM J. Numer. Anal. 19(6), 1982), which removes the 1/R
// singularity, with Gauss-Legendre points graded toward it.
// Far field: E_s = -jk eta e^{-jkr} / (4 pi r) (I - s s) . int J e^{jk s.r'} dS', so the
// scattering amplitude of rcs.hpp is S = -jk eta / sqrt(4 pi) p . int J e^{jk s.r'} dS' for a
// unit incident field (phase reference at the world origin, as RcsEngine).
// Offline product code: allocates (N^2 complex doubles), uses TBB and the BLAS's threads.

#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <string>
#include <vector>

#include "radar/em/rcs.hpp"
#include "scene/types.hpp"

namespace radar_emu::radar {

enum class MomEquation {
  kEfie,  ///< electric field equation everywhere (the default; see above for resonances)
  kMfie,  ///< magnetic field equation (closed surfaces only)
  kCfie,  ///< combined, alpha = MomConfig::cfie_alpha (rows on open sheets: EFIE)
};
[[nodiscard]] const char* equation_name(MomEquation e) noexcept;

struct MomConfig {
  MomEquation equation = MomEquation::kEfie;
  double cfie_alpha = 0.5;  ///< EFIE weight of the CFIE, in (0, 1)
  /// More unknowns is an error at construction (the matrix takes 16 N^2 bytes: 20,000 is 6.4 GB).
  std::size_t max_unknowns = 20'000;
};

/// The discretisation, as the solver found it.
struct MomMeshInfo {
  std::size_t triangles = 0;
  std::size_t degenerate_skipped = 0;  ///< zero-area triangles left out
  std::size_t vertices = 0;            ///< after welding (scene/mesh/topology.hpp)
  std::size_t unknowns = 0;            ///< RWG functions: interior edges
  std::size_t boundary_edges = 0;      ///< edges of open sheets (no current across them)
  std::size_t components = 0;          ///< connected surfaces
  std::size_t closed_components = 0;
  std::size_t flipped_components = 0;  ///< closed surfaces wound inward, turned outward
  double mean_edge_m = 0.0, max_edge_m = 0.0;
};

/// Timings and conditioning of one frequency (MomSolver::factor).
struct MomFactorInfo {
  double frequency_hz = 0.0;
  double fill_s = 0.0, factor_s = 0.0;
  std::size_t near_pairs = 0;  ///< triangle pairs integrated in Duffy coordinates
};

class MomSolver {
 public:
  /// Every triangle of every object of `description` (world placement; static objects only),
  /// `surfaces[i]` the model of material i: all must be PEC. Throws std::invalid_argument with
  /// the reason and a location: a moving object, a non-PEC material, a non-finite vertex, an edge
  /// shared by more than two triangles, a surface that cannot be oriented, the MFIE asked of an
  /// open surface, no unknown at all, more unknowns than config.max_unknowns, alpha outside
  /// (0, 1). Neighbours wound inconsistently are turned to agree.
  MomSolver(const scene::SceneDescription& description, std::span<const SurfaceModel> surfaces,
            MomConfig config = {});

  [[nodiscard]] const MomMeshInfo& mesh_info() const noexcept { return info_; }
  /// The equation of the rows on closed surfaces (rows on open sheets use the EFIE).
  [[nodiscard]] MomEquation equation() const noexcept { return equation_; }

  /// Fills the impedance matrix at `frequency_hz` and factorises it (replaces the previous
  /// frequency). Throws std::invalid_argument for a non-positive or non-finite frequency and
  /// std::runtime_error when the matrix cannot be allocated or is singular.
  MomFactorInfo factor(double frequency_hz);

  /// Scattering matrices (rcs.hpp's convention) at the factored frequency for transmitters
  /// `tx[i]` and receivers `rx[i]` (monostatic: equal), out.size() == tx.size() == rx.size().
  /// Throws std::logic_error before factor(), std::invalid_argument on mismatched sizes.
  void scatter(std::span<const Direction> tx, std::span<const Direction> rx,
               std::span<ScatteringMatrix> out) const;

 private:
  struct Triangle {
    std::array<std::uint32_t, 3> v{};
    glm::dvec3 normal{0.0};  ///< unit, outward on closed surfaces
    glm::dvec3 centroid{0.0};
    double area_m2 = 0.0;
    double size_m = 0.0;                  ///< longest edge
    std::array<std::int64_t, 3> basis{};  ///< RWG index of the edge opposite vertex i, or -1
    std::array<double, 3> coefficient{};  ///< +-l / (2 A): f = coefficient (r - v_i)
    bool closed = false;                  ///< on a closed surface (MFIE rows allowed)
    std::array<glm::dvec3, 6> points{};   ///< the 6-point rule's points (fill, RHS, far field)
  };
  /// The EFIE's weight alpha in the rows of `t`'s functions: 1 on open sheets and with the EFIE.
  [[nodiscard]] double efie_weight(const Triangle& t) const noexcept;
  std::vector<glm::dvec3> vertices_m_;  ///< relative to centre_m_
  std::vector<Triangle> triangles_;
  std::vector<std::uint8_t> colour_;  ///< neighbours differ: columns filled in parallel per colour
  glm::dvec3 centre_m_{0.0};
  std::size_t unknowns_ = 0;
  MomConfig config_;
  MomEquation equation_ = MomEquation::kEfie;
  MomMeshInfo info_;
  double k_rad_per_m_ = 0.0;
  std::vector<std::complex<double>> lu_;  ///< column-major N x N, LU factors after factor()
  std::vector<int> pivots_;
};

}  // namespace radar_emu::radar
