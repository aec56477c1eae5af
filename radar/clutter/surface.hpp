#pragma once
// Scattering from a randomly rough interface between air and a homogeneous half-space, per unit
// area (sigma0, linear m^2/m^2), and from a Rayleigh volume layer. Pure computation: no I/O, no
// allocation; every evaluation reports the validity conditions it breaks as a bit mask.
//
// Models (equations cited beside the code in surface.cpp):
//   SPM   first-order small-perturbation (Rice 1951), backscatter and bistatic;
//   KA    Kirchhoff approximation: the physical-optics series of the Kirchhoff field (the
//         f_qp term of the IEM alone) below ks cos(theta) = 1.58, the geometrical-optics
//         (stationary-phase) limit above it;
//   IEM   the improved integral-equation model (I2EM: Fung, Li & Chen 1992; Fung, Liu, Chen &
//         Tsay 2002; Ulaby & Long 2014, sec. 10-3.9): single-scattering co-polarised terms with
//         the transition reflection coefficient of Wu, Chen & Fung (2001) and Smith (1967)
//         shadowing, the multiple-scattering cross-polarised backscatter term (Fung 1994,
//         ch. 4; "IEMX"); Gaussian, exponential and x-power spectra; coherent and incoherent
//         parts; bistatic (co-pol anchored to SPM at first order, cross-pol single
//         scattering). Checked against the published I2EM/IEMX code (tests/data/
//         iem_reference.md);
//   RT    first-order radiative transfer in a layer of Rayleigh scatterers over the rough
//         ground (Ulaby & Long 2014, sec. 11-2, eq. 11.23), bistatic by the same first-order
//         solution (Ulaby, Moore & Fung 1986, vol. III, ch. 13).
//
// Geometry (Fung 1994 convention): the incident wave arrives at theta_i from the mean normal in
// the x-z plane; the scattered direction is (theta_s, phi_s) with phi_s measured from the plane
// of incidence, so phi_s = 0, theta_s = theta_i is the specular direction and phi_s = pi,
// theta_s = theta_i is backscatter. Polarisations: h horizontal (perpendicular to the plane of
// incidence or scattering), v vertical; sigma0 "qp" receives q from a transmitted p. Permittivity
// eps' - j eps'' (exp(+j w t), as in radar/em): losses have a negative imaginary part.

#include <complex>
#include <cstdint>
#include <string>

namespace radar_emu::radar::clutter {

enum class Correlation : std::uint8_t {
  kGaussian,     ///< rho(r) = exp(-r^2 / l^2)
  kExponential,  ///< rho(r) = exp(-r / l)
  kXPower        ///< rho(r) = (1 + r^2 / l^2)^(-x), x > 1 (1.5-power: Ulaby & Long 2014 sec. 10-3)
};

struct Roughness {
  double rms_height_m = 0.0;   ///< s
  double corr_length_m = 0.0;  ///< l (1/e length for the Gaussian and exponential functions)
  Correlation correlation = Correlation::kExponential;
  double x_power = 1.5;  ///< exponent x of kXPower
};

struct SurfaceParams {
  std::complex<double> relative_permittivity{1.0, 0.0};
  Roughness roughness;
};

struct Geometry {
  double theta_i_rad = 0.0;
  double theta_s_rad = 0.0;
  double phi_s_rad = 3.14159265358979323846;
  [[nodiscard]] static Geometry backscatter(double theta_rad) noexcept {
    return {theta_rad, theta_rad, 3.14159265358979323846};
  }
  [[nodiscard]] bool is_backscatter() const noexcept;
};

/// Linear sigma0 per polarisation (m^2/m^2).
struct Sigma0 {
  double hh = 0.0, vv = 0.0, hv = 0.0, vh = 0.0;
};

/// Validity conditions a model evaluation breaks (0: inside the model's stated domain).
enum Invalid : std::uint32_t {
  kValid = 0,
  kSpmTooRough = 1u << 0,          ///< SPM: ks >= 0.3 or rms slope >= 0.3
  kSpmCorrelationLong = 1u << 1,   ///< SPM: kl > 3
  kKaCorrelationShort = 1u << 2,   ///< KA: kl < 6 or l^2 < 2.76 s lambda
  kKaNoSlope = 1u << 3,            ///< KA geometrical optics with an exponential spectrum
                                   ///< (infinite slope variance): Gaussian-equivalent slope used
  kIemTooRough = 1u << 4,          ///< IEM: ks > 3
  kGrazing = 1u << 5,              ///< incidence or scattering beyond 70 deg: shadowing and
                                   ///< multiple bounces not (or, IEM, only roughly) modelled
  kSeriesTruncated = 1u << 6,      ///< spectrum series stopped before convergence
  kCrossPolNotModelled = 1u << 7,  ///< backscatter HV/VH from a model that has none (SPM and
                                   ///< KA first order, RT volume of spheres)
  kAlbedoHigh = 1u << 8,           ///< RT: albedo > 0.2, multiple volume scattering ignored
  // (1u << 9: kEmpiricalOutside, terrain.hpp)
  kOutsideMeasuredRange = 1u << 10,  ///< catalogue: extrapolated beyond the angles or
                                     ///< frequencies of its source (terrain.hpp)
  kAssumedValue = 1u << 11,          ///< catalogue: rests on an assumed value (no published
                                     ///< data found; docs/validation.md)
};
/// One line naming every condition set in `flags` ("valid" when none).
[[nodiscard]] std::string describe_validity(std::uint32_t flags);

struct SurfaceScatter {
  Sigma0 incoherent;         ///< diffuse sigma0
  double coherent_hh = 0.0;  ///< coherent (specular) reflectivity |R_h|^2 exp(-(2 k s cos)^2)
  double coherent_vv = 0.0;  ///< same for V; power fraction in the specular direction
  std::uint32_t invalid = kValid;
};

/// W^(n)(K) = integral_0^inf rho(r)^n J0(K r) r dr [m^2]: the roughness spectrum of the n-th
/// power of the correlation function (Fung 1994, Microwave Scattering and Emission Models,
/// sec. 2; closed forms in surface.cpp).
[[nodiscard]] double roughness_spectrum(const Roughness& r, int n,
                                        double wavenumber_rad_per_m) noexcept;

/// Throws std::invalid_argument with a one-line reason (negative roughness, x <= 1, eps with a
/// gain, ks beyond the series' reach, ...). Setup only.
void validate(const SurfaceParams& surface, double carrier_hz);

[[nodiscard]] SurfaceScatter spm(const SurfaceParams& surface, double carrier_hz,
                                 const Geometry& g) noexcept;
[[nodiscard]] SurfaceScatter kirchhoff(const SurfaceParams& surface, double carrier_hz,
                                       const Geometry& g) noexcept;
/// Where published IEM implementations differ in detail (each within the model's accuracy).
enum class IemConventions : std::uint8_t {
  /// The papers' equations: transition function F = 8 R(0)^2 sin^2(theta) ... (Wu, Chen &
  /// Fung 2001; Fung & Chen 2009, p. 164) with its weight kept in [0, 1]; the cross-polarised
  /// integral over the whole propagating spectrum (q = sqrt(1 - u^2)).
  kPublishedEquations,
  /// As Ulaby & Long's distributed I2EM/IEMX MATLAB code (2014, Codes 10.1/10.3): sin(theta)
  /// in F, the weight unclamped, q = sqrt(1.0001 - u^2). For comparisons with that code.
  kUlabyLongCode,
};

/// `cross_pol_backscatter` false skips the multiple-scattering HV/VH double integral (about
/// 0.5 ms; HV = VH = 0 then): for callers that sample it on a coarser grid (Sigma0Table).
[[nodiscard]] SurfaceScatter iem(const SurfaceParams& surface, double carrier_hz, const Geometry& g,
                                 IemConventions conventions = IemConventions::kPublishedEquations,
                                 bool cross_pol_backscatter = true) noexcept;

/// A layer of Rayleigh (small spherical) scatterers of thickness d, extinction kappa_e and
/// single-scattering albedo a = kappa_s / kappa_e. Either a canopy in air above the rough ground
/// (grass, crops, forest), or inclusions inside the ground material under its rough surface
/// (aggregate in asphalt and concrete, grains in snow): then the host is the ground's
/// permittivity and the wave crosses the surface twice (smooth-interface transmissivities).
struct VolumeLayer {
  enum class Placement : std::uint8_t { kCanopyAboveGround, kInsideGround };
  Placement placement = Placement::kCanopyAboveGround;
  double thickness_m = 0.0;
  double extinction_np_per_m = 0.0;
  double albedo = 0.0;
};

/// Volume term alone (ground contributions excluded).
[[nodiscard]] Sigma0 rt_volume(const VolumeLayer& layer, const SurfaceParams& ground,
                               double carrier_hz, const Geometry& g,
                               std::uint32_t* invalid) noexcept;

/// Surface + volume as in the seed paper (Bistatic IEM/RT paper, sec. IV: "Surface and volume
/// contributions are summed up"): the ground's IEM sigma0 seen through the layer (two-way
/// loss Y^2), the volume term, and in backscatter the ground-volume term of eq. 11.23.
[[nodiscard]] SurfaceScatter rt_total(const VolumeLayer& layer, const SurfaceParams& ground,
                                      double carrier_hz, const Geometry& g,
                                      bool cross_pol_backscatter = true) noexcept;

}  // namespace radar_emu::radar::clutter
