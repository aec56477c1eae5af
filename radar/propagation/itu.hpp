#pragma once
// Atmospheric propagation after the ITU-R Recommendations, pure computation:
//   gases          ITU-R P.676-13 (08/2022), Annex 1: line-by-line oxygen and water-vapour sums
//                  with the full line tables (Tables 1 and 2) and the dry continuum, 1-1000 GHz;
//   rain           ITU-R P.838-3 (03/2005): gamma_R = k R^alpha, k and alpha from the
//                  Recommendation's Gaussian-sum fits (Tables 1-4, eqs. 2-5), 1-1000 GHz;
//   cloud and fog  ITU-R P.840-9 (08/2023), sec. 2: Rayleigh absorption by liquid water with the
//                  double-Debye permittivity of water, gamma_c = K_l(f, T) M, up to 200 GHz.
// Frequencies and temperatures in SI (Hz, K); results in dB/km, the Recommendations' unit.
// Out-of-range or non-finite inputs throw std::invalid_argument (setup/offline functions; the
// frame path reads tables built from them).

#include <complex>
#include <string>

namespace radar_emu::radar {

/// Local atmosphere (P.676 Annex 1 inputs). The dry-air pressure and the water-vapour density
/// enter separately: e = rho T / 216.7 hPa (eq. 4 of P.676-13 Annex 1, written for the vapour
/// partial pressure).
struct Atmosphere {
  double dry_pressure_hpa = 1013.25;
  double temperature_k = 288.15;
  double water_vapour_density_gm3 = 7.5;
};

struct GasAttenuation {
  double dry_db_per_km = 0.0;     ///< oxygen lines + dry continuum (gamma_o)
  double vapour_db_per_km = 0.0;  ///< water-vapour lines (gamma_w)
  [[nodiscard]] double total_db_per_km() const noexcept { return dry_db_per_km + vapour_db_per_km; }
};

/// P.676-13 Annex 1, eqs. (1)-(9). Valid 1-1000 GHz.
[[nodiscard]] GasAttenuation gaseous_specific_attenuation(double freq_hz,
                                                          const Atmosphere& atmosphere);

struct RainCoefficients {
  double k = 0.0;      ///< [dB/km / (mm/h)^alpha]
  double alpha = 0.0;  ///< exponent
};
/// P.838-3 k and alpha for a path at `elevation_rad` and polarisation tilt `tilt_rad` from the
/// horizontal (0: horizontal polarisation, pi/2: vertical, pi/4: circular), eqs. (2)-(5).
[[nodiscard]] RainCoefficients rain_coefficients(double freq_hz, double elevation_rad,
                                                 double tilt_rad);
/// gamma_R = k R^alpha [dB/km], eq. (1); rain rate R >= 0 mm/h.
[[nodiscard]] double rain_specific_attenuation_db_per_km(double freq_hz, double rain_mm_per_h,
                                                         double elevation_rad, double tilt_rad);

/// Relative permittivity of liquid water eps' - j eps'' (P.840-9 double-Debye model, eqs. (4)-(9),
/// written for 1-1000 GHz; the convention of radar/em: losses negative imaginary).
[[nodiscard]] std::complex<double> water_permittivity(double freq_hz, double temperature_k);

/// P.840-9 specific attenuation coefficient K_l [(dB/km)/(g/m^3)] of liquid water droplets at
/// temperature T, eqs. (2)-(9) (Rayleigh regime: up to 200 GHz).
[[nodiscard]] double liquid_water_coefficient(double freq_hz, double temperature_k);
/// Cloud or fog of liquid water density M [g/m^3]: gamma_c = K_l M [dB/km], eq. (1).
[[nodiscard]] double cloud_fog_specific_attenuation_db_per_km(double freq_hz,
                                                              double liquid_water_gm3,
                                                              double temperature_k);

}  // namespace radar_emu::radar

namespace radar_emu::radar {

/// ITU-R P.833-10 (09/2021), Annex 1 sec. 2, "obstruction by woodland" (one terminal in
/// woodland), eq. (1): the excess attenuation through d metres of woodland
///   A_ev = A_m [1 - exp(-d gamma / A_m)] [dB],
/// gamma the specific attenuation of very short vegetative paths [dB/m], A_m the maximum
/// attenuation [dB]. Pure formula; the inputs come from the functions below or from the
/// Recommendation's Table 1.
[[nodiscard]] double woodland_excess_attenuation_db(double specific_db_per_m, double max_db,
                                                    double depth_m);

/// gamma of P.833 Figure 2 ("specific attenuation due to woodland", in leaf), which the
/// Recommendation gives only as a curve: the power-law reading gamma = 0.19 f_GHz^1.02 dB/m of
/// the curve over 1-30 GHz (three independent digitisations agree within their reading error;
/// docs/notes/clutter_data_sources.md sec. 1.1). Out of leaf: the Recommendation's only
/// statement is that trees in leaf attenuate about 20 % more (dB/m) near 1 GHz, applied here
/// as gamma / 1.2 at every frequency (stated as such by the CLI). Throws outside 1-30 GHz.
[[nodiscard]] double woodland_specific_attenuation_db_per_m(double freq_hz, bool in_leaf);

/// A_m = A_1 f^alpha, f in MHz (P.833 eq. (2)), with the Mulhouse (France) mixed-forest
/// parameters A_1 = 1.15, alpha = 0.43 (P.833-7, measured 0.9-2.2 GHz; used beyond that range
/// only by extrapolation, which the CLI states). Throws outside 1-30 GHz.
[[nodiscard]] double woodland_max_attenuation_db(double freq_hz);

}  // namespace radar_emu::radar
