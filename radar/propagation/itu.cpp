#include "radar/propagation/itu.hpp"

#include <array>
#include <cmath>
#include <complex>
#include <stdexcept>

namespace radar_emu::radar {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok)
    throw std::invalid_argument(what);
}

double ghz_in(double freq_hz, double lo_ghz, double hi_ghz, const char* model) {
  const double f = freq_hz * 1e-9;
  require(std::isfinite(f) && f >= lo_ghz && f <= hi_ghz,
          std::string(model) + ": frequency " + std::to_string(f) + " GHz is outside " +
              std::to_string(lo_ghz).substr(0, 4) + "-" + std::to_string(hi_ghz).substr(0, 6) +
              " GHz");
  return f;
}

// ITU-R P.676-13 Annex 1, Table 1: oxygen lines {f0 [GHz], a1, a2, a3, a4, a5, a6}.
constexpr std::array<std::array<double, 7>, 44> kOxygen{{
    {50.474214, 0.975, 9.651, 6.69, 0.0, 2.566, 6.85},
    {50.987745, 2.529, 8.653, 7.17, 0.0, 2.246, 6.8},
    {51.50336, 6.193, 7.709, 7.64, 0.0, 1.947, 6.729},
    {52.021429, 14.32, 6.819, 8.11, 0.0, 1.667, 6.64},
    {52.542418, 31.24, 5.983, 8.58, 0.0, 1.388, 6.526},
    {53.066934, 64.29, 5.201, 9.06, 0.0, 1.349, 6.206},
    {53.595775, 124.6, 4.474, 9.55, 0.0, 2.227, 5.085},
    {54.130025, 227.3, 3.8, 9.96, 0.0, 3.17, 3.75},
    {54.67118, 389.7, 3.182, 10.37, 0.0, 3.558, 2.654},
    {55.221384, 627.1, 2.618, 10.89, 0.0, 2.56, 2.952},
    {55.783815, 945.3, 2.109, 11.34, 0.0, -1.172, 6.135},
    {56.264774, 543.4, 0.014, 17.03, 0.0, 3.525, -0.978},
    {56.363399, 1331.8, 1.654, 11.89, 0.0, -2.378, 6.547},
    {56.968211, 1746.6, 1.255, 12.23, 0.0, -3.545, 6.451},
    {57.612486, 2120.1, 0.91, 12.62, 0.0, -5.416, 6.056},
    {58.323877, 2363.7, 0.621, 12.95, 0.0, -1.932, 0.436},
    {58.446588, 1442.1, 0.083, 14.91, 0.0, 6.768, -1.273},
    {59.164204, 2379.9, 0.387, 13.53, 0.0, -6.561, 2.309},
    {59.590983, 2090.7, 0.207, 14.08, 0.0, 6.957, -0.776},
    {60.306056, 2103.4, 0.207, 14.15, 0.0, -6.395, 0.699},
    {60.434778, 2438.0, 0.386, 13.39, 0.0, 6.342, -2.825},
    {61.150562, 2479.5, 0.621, 12.92, 0.0, 1.014, -0.584},
    {61.800158, 2275.9, 0.91, 12.63, 0.0, 5.014, -6.619},
    {62.41122, 1915.4, 1.255, 12.17, 0.0, 3.029, -6.759},
    {62.486253, 1503.0, 0.083, 15.13, 0.0, -4.499, 0.844},
    {62.997984, 1490.2, 1.654, 11.74, 0.0, 1.856, -6.675},
    {63.568526, 1078.0, 2.108, 11.34, 0.0, 0.658, -6.139},
    {64.127775, 728.7, 2.617, 10.88, 0.0, -3.036, -2.895},
    {64.67891, 461.3, 3.181, 10.38, 0.0, -3.968, -2.59},
    {65.224078, 274.0, 3.8, 9.96, 0.0, -3.528, -3.68},
    {65.764779, 153.0, 4.473, 9.55, 0.0, -2.548, -5.002},
    {66.302096, 80.4, 5.2, 9.06, 0.0, -1.66, -6.091},
    {66.836834, 39.8, 5.982, 8.58, 0.0, -1.68, -6.393},
    {67.369601, 18.56, 6.818, 8.11, 0.0, -1.956, -6.475},
    {67.900868, 8.172, 7.708, 7.64, 0.0, -2.216, -6.545},
    {68.431006, 3.397, 8.652, 7.17, 0.0, -2.492, -6.6},
    {68.960312, 1.334, 9.65, 6.69, 0.0, -2.773, -6.65},
    {118.750334, 940.3, 0.01, 16.64, 0.0, -0.439, 0.079},
    {368.498246, 67.4, 0.048, 16.4, 0.0, 0.0, 0.0},
    {424.76302, 637.7, 0.044, 16.4, 0.0, 0.0, 0.0},
    {487.249273, 237.4, 0.049, 16.0, 0.0, 0.0, 0.0},
    {715.392902, 98.1, 0.145, 16.0, 0.0, 0.0, 0.0},
    {773.83949, 572.3, 0.141, 16.2, 0.0, 0.0, 0.0},
    {834.145546, 183.1, 0.145, 14.7, 0.0, 0.0, 0.0},
}};

// ITU-R P.676-13 Annex 1, Table 2: water-vapour lines {f0 [GHz], b1, b2, b3, b4, b5, b6}.
constexpr std::array<std::array<double, 7>, 35> kWaterVapour{{
    {22.23508, 0.1079, 2.144, 26.38, 0.76, 5.087, 1.0},
    {67.80396, 0.0011, 8.732, 28.58, 0.69, 4.93, 0.82},
    {119.99594, 0.0007, 8.353, 29.48, 0.7, 4.78, 0.79},
    {183.310087, 2.273, 0.668, 29.06, 0.77, 5.022, 0.85},
    {321.22563, 0.047, 6.179, 24.04, 0.67, 4.398, 0.54},
    {325.152888, 1.514, 1.541, 28.23, 0.64, 4.893, 0.74},
    {336.227764, 0.001, 9.825, 26.93, 0.69, 4.74, 0.61},
    {380.197353, 11.67, 1.048, 28.11, 0.54, 5.063, 0.89},
    {390.134508, 0.0045, 7.347, 21.52, 0.63, 4.81, 0.55},
    {437.346667, 0.0632, 5.048, 18.45, 0.6, 4.23, 0.48},
    {439.150807, 0.9098, 3.595, 20.07, 0.63, 4.483, 0.52},
    {443.018343, 0.192, 5.048, 15.55, 0.6, 5.083, 0.5},
    {448.001085, 10.41, 1.405, 25.64, 0.66, 5.028, 0.67},
    {470.888999, 0.3254, 3.597, 21.34, 0.66, 4.506, 0.65},
    {474.689092, 1.26, 2.379, 23.2, 0.65, 4.804, 0.64},
    {488.490108, 0.2529, 2.852, 25.86, 0.69, 5.201, 0.72},
    {503.568532, 0.0372, 6.731, 16.12, 0.61, 3.98, 0.43},
    {504.482692, 0.0124, 6.731, 16.12, 0.61, 4.01, 0.45},
    {547.67644, 0.9785, 0.158, 26.0, 0.7, 4.5, 1.0},
    {552.02096, 0.184, 0.158, 26.0, 0.7, 4.5, 1.0},
    {556.935985, 497.0, 0.159, 30.86, 0.69, 4.552, 1.0},
    {620.700807, 5.015, 2.391, 24.38, 0.71, 4.856, 0.68},
    {645.766085, 0.0067, 8.633, 18.0, 0.6, 4.0, 0.5},
    {658.00528, 0.2732, 7.816, 32.1, 0.69, 4.14, 1.0},
    {752.033113, 243.4, 0.396, 30.86, 0.68, 4.352, 0.84},
    {841.051732, 0.0134, 8.177, 15.9, 0.33, 5.76, 0.45},
    {859.965698, 0.1325, 8.055, 30.6, 0.68, 4.09, 0.84},
    {899.303175, 0.0547, 7.914, 29.85, 0.68, 4.53, 0.9},
    {902.611085, 0.0386, 8.429, 28.65, 0.7, 5.1, 0.95},
    {906.205957, 0.1836, 5.11, 24.08, 0.7, 4.7, 0.53},
    {916.171582, 8.4, 1.441, 26.73, 0.7, 5.15, 0.78},
    {923.112692, 0.0079, 10.293, 29.0, 0.7, 5.0, 0.8},
    {970.315022, 9.009, 1.919, 25.5, 0.64, 4.94, 0.67},
    {987.926764, 134.6, 0.257, 29.85, 0.68, 4.55, 0.9},
    {1780.0, 17506.0, 0.952, 196.3, 2.0, 24.15, 5.0},
}};

// Line shape, P.676-13 Annex 1 eq. (5).
double line_shape(double f, double fi, double df, double delta) {
  return f / fi *
         ((df - delta * (fi - f)) / ((fi - f) * (fi - f) + df * df) +
          (df - delta * (fi + f)) / ((fi + f) * (fi + f) + df * df));
}

// P.838-3 Gaussian-sum fits (Tables 1-4): log10 k or alpha = sum_j a_j exp(-((log10 f - b_j) /
// c_j)^2) + m log10 f + c.
struct Fit {
  std::array<double, 5> a, b, c;
  int terms;
  double m, c0;
  double operator()(double log_f) const {
    double s = m * log_f + c0;
    for (int j = 0; j < terms; ++j) {
      const auto i = static_cast<std::size_t>(j);
      const double x = (log_f - b[i]) / c[i];
      s += a[i] * std::exp(-x * x);
    }
    return s;
  }
};
constexpr Fit kKh{{-5.33980, -0.35351, -0.23789, -0.94158, 0.0},
                  {-0.10008, 1.26970, 0.86036, 0.64552, 0.0},
                  {1.13098, 0.45400, 0.15354, 0.16817, 1.0},
                  4,
                  -0.18961,
                  0.71147};
constexpr Fit kKv{{-3.80595, -3.44965, -0.39902, 0.50167, 0.0},
                  {0.56934, -0.22911, 0.73042, 1.07319, 0.0},
                  {0.81061, 0.51059, 0.11899, 0.27195, 1.0},
                  4,
                  -0.16398,
                  0.63297};
constexpr Fit kAlphaH{{-0.14318, 0.29591, 0.32177, -5.37610, 16.1721},
                      {1.82442, 0.77564, 0.63773, -0.96230, -3.29980},
                      {-0.55187, 0.19822, 0.13164, 1.47828, 3.43990},
                      5,
                      0.67849,
                      -1.95537};
constexpr Fit kAlphaV{{-0.07771, 0.56727, -0.20238, -48.2991, 48.5833},
                      {2.33840, 0.95545, 1.14520, 0.791669, 0.791459},
                      {-0.76284, 0.54039, 0.26809, 0.116226, 0.116479},
                      5,
                      -0.053739,
                      0.83433};

}  // namespace

GasAttenuation gaseous_specific_attenuation(double freq_hz, const Atmosphere& a) {
  const double f = ghz_in(freq_hz, 1.0, 1000.0, "ITU-R P.676");
  require(std::isfinite(a.dry_pressure_hpa) && a.dry_pressure_hpa >= 0.0 &&
              a.dry_pressure_hpa <= 1200.0,
          "ITU-R P.676: dry-air pressure must be in 0-1200 hPa");
  require(std::isfinite(a.temperature_k) && a.temperature_k >= 150.0 && a.temperature_k <= 350.0,
          "ITU-R P.676: temperature must be in 150-350 K");
  require(std::isfinite(a.water_vapour_density_gm3) && a.water_vapour_density_gm3 >= 0.0 &&
              a.water_vapour_density_gm3 <= 100.0,
          "ITU-R P.676: water-vapour density must be in 0-100 g/m^3");
  const double p = a.dry_pressure_hpa, t = a.temperature_k;
  const double theta = 300.0 / t;                           // eq. (3)
  const double e = a.water_vapour_density_gm3 * t / 216.7;  // vapour partial pressure [hPa]
  // Oxygen, eqs. (3), (6a), (6b), (7).
  double n_oxygen = 0.0;
  for (const auto& l : kOxygen) {
    const double s = l[1] * 1e-7 * p * theta * theta * theta * std::exp(l[2] * (1.0 - theta));
    double df = l[3] * 1e-4 * (p * std::pow(theta, 0.8 - l[4]) + 1.1 * e * theta);
    df = std::sqrt(df * df + 2.25e-6);  // Zeeman splitting
    const double delta = (l[5] + l[6] * theta) * 1e-4 * (p + e) * std::pow(theta, 0.8);
    n_oxygen += s * line_shape(f, l[0], df, delta);
  }
  // Dry continuum (Debye spectrum of oxygen and pressure-induced nitrogen absorption),
  // eqs. (8), (9).
  const double d = 5.6e-4 * (p + e) * std::pow(theta, 0.8);
  n_oxygen += f * p * theta * theta *
              (6.14e-5 / (d * (1.0 + (f / d) * (f / d))) +
               1.4e-12 * p * std::pow(theta, 1.5) / (1.0 + 1.9e-5 * std::pow(f, 1.5)));
  // Water vapour, eqs. (3), (6a), (6b) (Doppler broadening), delta = 0.
  double n_vapour = 0.0;
  for (const auto& l : kWaterVapour) {
    const double s = l[1] * 1e-1 * e * std::pow(theta, 3.5) * std::exp(l[2] * (1.0 - theta));
    double df = l[3] * 1e-4 * (p * std::pow(theta, l[4]) + l[5] * e * std::pow(theta, l[6]));
    df = 0.535 * df + std::sqrt(0.217 * df * df + 2.1316e-12 * l[0] * l[0] / theta);
    n_vapour += s * line_shape(f, l[0], df, 0.0);
  }
  // eq. (1): gamma = 0.1820 f N''(f).
  return {0.1820 * f * n_oxygen, 0.1820 * f * n_vapour};
}

RainCoefficients rain_coefficients(double freq_hz, double elevation_rad, double tilt_rad) {
  const double f = ghz_in(freq_hz, 1.0, 1000.0, "ITU-R P.838");
  require(std::isfinite(elevation_rad) && std::isfinite(tilt_rad),
          "ITU-R P.838: elevation and tilt must be finite");
  const double lf = std::log10(f);
  const double kh = std::pow(10.0, kKh(lf)), kv = std::pow(10.0, kKv(lf));  // eq. (2)
  const double ah = kAlphaH(lf), av = kAlphaV(lf);                          // eq. (3)
  const double c = std::cos(elevation_rad);
  const double mix = c * c * std::cos(2.0 * tilt_rad);
  RainCoefficients r;
  r.k = 0.5 * (kh + kv + (kh - kv) * mix);                                // eq. (4)
  r.alpha = 0.5 * (kh * ah + kv * av + (kh * ah - kv * av) * mix) / r.k;  // eq. (5)
  return r;
}

double rain_specific_attenuation_db_per_km(double freq_hz, double rain_mm_per_h,
                                           double elevation_rad, double tilt_rad) {
  require(std::isfinite(rain_mm_per_h) && rain_mm_per_h >= 0.0 && rain_mm_per_h <= 500.0,
          "ITU-R P.838: rain rate must be in 0-500 mm/h");
  const RainCoefficients c = rain_coefficients(freq_hz, elevation_rad, tilt_rad);
  return c.k * std::pow(rain_mm_per_h, c.alpha);
}

std::complex<double> water_permittivity(double freq_hz, double temperature_k) {
  const double f = ghz_in(freq_hz, 1e-3, 1000.0, "ITU-R P.840 water permittivity");
  require(std::isfinite(temperature_k) && temperature_k >= 233.0 && temperature_k <= 323.0,
          "ITU-R P.840: temperature must be in 233-323 K (liquid water)");
  // Double-Debye model of the permittivity of water, eqs. (4)-(9).
  const double theta = 300.0 / temperature_k;
  const double eps0 = 77.66 + 103.3 * (theta - 1.0);
  const double eps1 = 0.0671 * eps0;
  const double eps2 = 3.52;
  const double fp = 20.20 - 146.0 * (theta - 1.0) + 316.0 * (theta - 1.0) * (theta - 1.0);
  const double fs = 39.8 * fp;
  const double eps_im = f * (eps0 - eps1) / (fp * (1.0 + (f / fp) * (f / fp))) +
                        f * (eps1 - eps2) / (fs * (1.0 + (f / fs) * (f / fs)));
  const double eps_re = (eps0 - eps1) / (1.0 + (f / fp) * (f / fp)) +
                        (eps1 - eps2) / (1.0 + (f / fs) * (f / fs)) + eps2;
  return {eps_re, -eps_im};
}

double liquid_water_coefficient(double freq_hz, double temperature_k) {
  const double f = ghz_in(freq_hz, 1e-3, 200.0, "ITU-R P.840");
  const std::complex<double> eps = water_permittivity(freq_hz, temperature_k);
  const double eps_re = eps.real(), eps_im = -eps.imag();
  const double eta = (2.0 + eps_re) / eps_im;       // eq. (3)
  return 0.819 * f / (eps_im * (1.0 + eta * eta));  // eq. (2)
}

double cloud_fog_specific_attenuation_db_per_km(double freq_hz, double liquid_water_gm3,
                                                double temperature_k) {
  require(std::isfinite(liquid_water_gm3) && liquid_water_gm3 >= 0.0 && liquid_water_gm3 <= 5.0,
          "ITU-R P.840: liquid water density must be in 0-5 g/m^3");
  return liquid_water_coefficient(freq_hz, temperature_k) * liquid_water_gm3;
}

}  // namespace radar_emu::radar

namespace radar_emu::radar {

namespace {
void require_woodland_band(double freq_hz) {
  if (!(freq_hz >= 1e9 && freq_hz <= 30e9))
    throw std::invalid_argument("ITU-R P.833: woodland attenuation is given for 1-30 GHz (got " +
                                std::to_string(freq_hz * 1e-9) + " GHz)");
}
}  // namespace

double woodland_excess_attenuation_db(double specific_db_per_m, double max_db, double depth_m) {
  if (!(specific_db_per_m >= 0.0) || !(max_db > 0.0) || !(depth_m >= 0.0) ||
      !std::isfinite(depth_m))
    throw std::invalid_argument("ITU-R P.833: need gamma >= 0, A_m > 0 and a finite depth >= 0");
  return max_db * -std::expm1(-depth_m * specific_db_per_m / max_db);  // eq. (1)
}

double woodland_specific_attenuation_db_per_m(double freq_hz, bool in_leaf) {
  require_woodland_band(freq_hz);
  const double in_leaf_db_per_m = 0.19 * std::pow(freq_hz * 1e-9, 1.02);  // Figure 2 reading
  return in_leaf ? in_leaf_db_per_m : in_leaf_db_per_m / 1.2;
}

double woodland_max_attenuation_db(double freq_hz) {
  require_woodland_band(freq_hz);
  return 1.15 * std::pow(freq_hz * 1e-6, 0.43);  // eq. (2), Mulhouse parameters
}

}  // namespace radar_emu::radar
