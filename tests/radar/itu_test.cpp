// ITU-R propagation models against the Recommendations' published validation values (ITU-R
// Study Group 3 validation examples CG-3M3J-13-ValEx-Rev8.3.0, sheets "P.676-13 SpAtt" and
// "P.838-3"; values as transcribed in ITU-Rpy's test data, test/test_data/676 and /838) and the
// standard cases of ../shared/reference/physics.md. Acceptance: within 0.5 %.
#include "radar/propagation/itu.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "radar/constants.hpp"
#include "radar/em/sbr.hpp"
#include "radar/propagation/path.hpp"

namespace radar_emu::radar {
namespace {

constexpr double kRel = 0.005;  // 0.5 %
double deg(double d) {
  return d * kPi / 180.0;
}

TEST(ItuP676, ValidationExamplesSpecificAttenuation) {
  // Sheet "P.676-13 SpAtt": p = 1013.25 hPa (dry), T = 288.15 K, rho = 7.5 g/m^3.
  struct Row {
    double f_ghz, gamma_o, gamma_w;
  };
  const Row rows[] = {{12, 0.00869826406877357, 0.00953538822024593},
                      {20, 0.0118835504778076, 0.0970473048151117},
                      {60, 14.6234747964861, 0.154841841},
                      {90, 0.0388697110724235, 0.341973394},
                      {130, 0.0415090835995228, 0.751844704}};
  const Atmosphere std_atm{1013.25, 288.15, 7.5};
  for (const Row& r : rows) {
    const GasAttenuation g = gaseous_specific_attenuation(r.f_ghz * 1e9, std_atm);
    std::cout << r.f_ghz << " GHz: dry " << g.dry_db_per_km << " (ITU " << r.gamma_o << "), vapour "
              << g.vapour_db_per_km << " (ITU " << r.gamma_w << ") dB/km\n";
    EXPECT_NEAR(g.dry_db_per_km / r.gamma_o, 1.0, kRel) << r.f_ghz;
    EXPECT_NEAR(g.vapour_db_per_km / r.gamma_w, 1.0, kRel) << r.f_ghz;
  }
}

TEST(ItuP676, StandardCaseOfPhysicsMd) {
  // 35 GHz: dry 0.0318, vapour 0.0696 dB/km; 94 GHz: dry 0.0345, vapour 0.3736 dB/km (three to
  // four published digits: the tolerance is 0.5 % or half a unit of the last digit).
  const Atmosphere std_atm{1013.25, 288.15, 7.5};
  const GasAttenuation g35 = gaseous_specific_attenuation(35e9, std_atm);
  const GasAttenuation g94 = gaseous_specific_attenuation(94e9, std_atm);
  EXPECT_NEAR(g35.dry_db_per_km, 0.0318, std::max(0.00005, 0.0318 * kRel));
  EXPECT_NEAR(g35.vapour_db_per_km, 0.0696, 0.0696 * kRel);
  EXPECT_NEAR(g94.dry_db_per_km, 0.0345, 0.0345 * kRel);
  EXPECT_NEAR(g94.vapour_db_per_km, 0.3736, 0.3736 * kRel);
  EXPECT_NEAR(g94.total_db_per_km(), 0.4081, 0.4081 * kRel);
  // Dry air has no vapour term; the vapour term scales with rho (lines' strength ~ e).
  const GasAttenuation dry = gaseous_specific_attenuation(94e9, {1013.25, 288.15, 0.0});
  EXPECT_EQ(dry.vapour_db_per_km, 0.0);
}

TEST(ItuP838, ValidationExamples) {
  // Sheet "P.838-3": elevation, frequency, rain rate, tilt -> k, alpha, gamma_R.
  struct Row {
    double el_deg, f_ghz, rain, tau_deg, k, alpha, gamma;
  };
  const Row rows[] = {
      {31.07699124, 14.25, 26.48052, 0, 0.03975488, 1.12418043, 1.58130839},
      {40.232036, 14.25, 33.936232, 0, 0.04007624, 1.11804138, 2.06173213},
      {31.07699124, 29, 26.48052, 0, 0.22106804, 0.95320005, 5.02180189},
      {52.67898486, 29, 78.2994993, 0, 0.21923716, 0.9464763, 13.59290086},
      {48.24117054, 14.25, 63.62668149, 90, 0.04226474, 1.07871664, 3.72901264},
      {85.80459566, 29, 99.13558978, 90, 0.21737148, 0.93950825, 16.3183686},
      {20.14335809, 29, 42.91007183, 90, 0.21298877, 0.92265917, 6.83364556},
  };
  for (const Row& r : rows) {
    const RainCoefficients c = rain_coefficients(r.f_ghz * 1e9, deg(r.el_deg), deg(r.tau_deg));
    EXPECT_NEAR(c.k / r.k, 1.0, kRel) << r.f_ghz << " " << r.el_deg;
    EXPECT_NEAR(c.alpha / r.alpha, 1.0, kRel) << r.f_ghz << " " << r.el_deg;
    EXPECT_NEAR(
        rain_specific_attenuation_db_per_km(r.f_ghz * 1e9, r.rain, deg(r.el_deg), deg(r.tau_deg)) /
            r.gamma,
        1.0, kRel)
        << r.f_ghz << " " << r.el_deg;
  }
  // physics.md: horizontal path, 10 mm/h: 35 GHz H/V 2.709/2.424, 94 GHz 6.436/6.347 dB/km.
  EXPECT_NEAR(rain_specific_attenuation_db_per_km(35e9, 10, 0, 0), 2.709, 2.709 * kRel);
  EXPECT_NEAR(rain_specific_attenuation_db_per_km(35e9, 10, 0, kPi / 2), 2.424, 2.424 * kRel);
  EXPECT_NEAR(rain_specific_attenuation_db_per_km(94e9, 10, 0, 0), 6.436, 6.436 * kRel);
  EXPECT_NEAR(rain_specific_attenuation_db_per_km(94e9, 10, 0, kPi / 2), 6.347, 6.347 * kRel);
  EXPECT_EQ(rain_specific_attenuation_db_per_km(35e9, 0, 0, 0), 0.0);
}

TEST(ItuP840, FogAt94GHz) {
  // physics.md: fog M = 0.05 g/m^3 at 94 GHz: 0.227 dB/km at 0 C, 0.201 dB/km at 15 C (three
  // published digits).
  const double at0 = cloud_fog_specific_attenuation_db_per_km(94e9, 0.05, 273.15);
  const double at15 = cloud_fog_specific_attenuation_db_per_km(94e9, 0.05, 288.15);
  std::cout << "fog 0.05 g/m^3 at 94 GHz: " << at0 << " dB/km at 0 C, " << at15
            << " dB/km at 15 C\n";
  EXPECT_NEAR(at0, 0.227, 0.0011);
  EXPECT_NEAR(at15, 0.201, 0.0011);
  // Rayleigh regime: K_l grows as f^2 at low frequency (ratio of 2 and 1 GHz -> 4 within 1 %).
  EXPECT_NEAR(liquid_water_coefficient(2e9, 273.15) / liquid_water_coefficient(1e9, 273.15), 4.0,
              0.04);
}

TEST(PathAttenuation, TwoWayLossSumsTheMediaItCrosses) {
  // Clear air, rain 10 mm/h and fog 0.05 g/m^3 at 94 GHz, horizontal polarisation; a 10 km
  // path: 6 km clear, 3 km rain, 1 km fog. Two-way loss = 2 sum gamma_i L_i with each gamma from
  // the models above (the table only adds them up).
  const Atmosphere air{1013.25, 288.15, 7.5};
  const MediumSpec media[] = {
      {"clear", air, 0.0, 0.0}, {"rain", air, 10.0, 0.0}, {"fog", air, 0.0, 0.05}};
  const PathAttenuation table(94e9, 0.0, media);
  const double gas = gaseous_specific_attenuation(94e9, air).total_db_per_km();
  const double rain = rain_specific_attenuation_db_per_km(94e9, 10.0, 0.0, 0.0);
  const double fog = cloud_fog_specific_attenuation_db_per_km(94e9, 0.05, 288.15);
  const PathSegment path[] = {{0, 6000.0}, {1, 3000.0}, {2, 1000.0}};
  const double expected = 2.0 * (gas * 6.0 + (gas + rain) * 3.0 + (gas + fog) * 1.0);
  std::cout << "10 km two-way at 94 GHz: " << table.two_way_loss_db(path) << " dB\n";
  EXPECT_NEAR(table.two_way_loss_db(path), expected, 1e-9 * expected);
  // Bad segments are counted and ignored.
  std::uint64_t rejected = 0;
  const PathSegment bad[] = {{7, 100.0}, {0, -5.0}, {0, std::nan("")}, {0, 1000.0}};
  EXPECT_NEAR(table.two_way_loss_db(bad, &rejected), 2.0 * gas, 1e-12);
  EXPECT_EQ(rejected, 3u);
  // Setup errors name the medium.
  const MediumSpec broken[] = {{"swamp", {1013.25, 288.15, -1.0}, 0.0, 0.0}};
  try {
    const PathAttenuation t(94e9, 0.0, broken);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("medium 'swamp'"), std::string::npos);
  }
}

TEST(Itu, RejectsOutOfRangeInput) {
  EXPECT_THROW((void)gaseous_specific_attenuation(0.5e9, {}), std::invalid_argument);
  EXPECT_THROW((void)gaseous_specific_attenuation(35e9, {-1.0, 288.15, 7.5}),
               std::invalid_argument);
  EXPECT_THROW((void)gaseous_specific_attenuation(35e9, {1013.25, 288.15, std::nan("")}),
               std::invalid_argument);
  EXPECT_THROW((void)rain_specific_attenuation_db_per_km(35e9, -1.0, 0, 0), std::invalid_argument);
  EXPECT_THROW((void)rain_coefficients(2e12, 0, 0), std::invalid_argument);
  EXPECT_THROW((void)cloud_fog_specific_attenuation_db_per_km(300e9, 0.05, 273.15),
               std::invalid_argument);
  EXPECT_THROW((void)cloud_fog_specific_attenuation_db_per_km(94e9, 0.05, 200.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace radar_emu::radar

namespace radar_emu::radar {
namespace {

TEST(ItuP833, WoodlandEquationAgainstTheRecommendationsTable) {
  // P.833-9/-10 Table 1 (measured gamma and A_m, one terminal in woodland), as transcribed in
  // docs/notes/clutter_data_sources.md sec. 1.1; eq. (1) A_ev = A_m [1 - exp(-d gamma / A_m)].
  // 949 MHz: gamma 0.17 dB/m, A_m 26.5 dB, d = 50 m -> 26.5 (1 - exp(-8.5/26.5)) = 7.27 dB.
  EXPECT_NEAR(woodland_excess_attenuation_db(0.17, 26.5, 50.0), 7.27, 0.005);
  // Limits of eq. (1): gamma d for a thin stand, A_m for a deep one.
  EXPECT_NEAR(woodland_excess_attenuation_db(0.30, 29.0, 0.01), 0.003, 1e-6);
  EXPECT_NEAR(woodland_excess_attenuation_db(0.30, 29.0, 1e5), 29.0, 1e-9);
  // A_m = 1.15 f_MHz^0.43 (Mulhouse) against the Table 1 values at 1852.2 and 2117.5 MHz (the
  // rows inside the Mulhouse campaign's band): 29.0 and 34.1 dB, within 10 %.
  EXPECT_NEAR(woodland_max_attenuation_db(1.8522e9) / 29.0, 1.0, 0.10);
  EXPECT_NEAR(woodland_max_attenuation_db(2.1175e9) / 34.1, 1.0, 0.10);
  // Figure 2 readings: about 0.2 dB/m at 1 GHz, 6 dB/m at 30 GHz (in leaf); out of leaf 1/1.2.
  EXPECT_NEAR(woodland_specific_attenuation_db_per_m(1e9, true), 0.2, 0.02);
  EXPECT_NEAR(woodland_specific_attenuation_db_per_m(30e9, true), 6.0, 0.3);
  EXPECT_NEAR(woodland_specific_attenuation_db_per_m(10e9, false) * 1.2,
              woodland_specific_attenuation_db_per_m(10e9, true), 1e-12);
  EXPECT_THROW((void)woodland_specific_attenuation_db_per_m(35e9, true), std::invalid_argument);
  EXPECT_THROW((void)woodland_excess_attenuation_db(0.2, 20.0, -1.0), std::invalid_argument);
}

TEST(PathAttenuation, WoodlandSaturatesOverTheDepthCrossed) {
  // 10 GHz: 200 m clear air, 30 m of forest, 100 m clear, 20 m of forest: the woodland loss is
  // eq. (1) over the 50 m crossed in all (not per stand), on top of the gases everywhere.
  const Atmosphere air{1013.25, 288.15, 7.5};
  MediumSpec forest{"forest", air, 0.0, 0.0};
  forest.woodland = true;
  const MediumSpec media[] = {{"clear", air, 0.0, 0.0}, forest};
  const PathAttenuation table(10e9, 0.0, media);
  const PathSegment path[] = {{0, 200.0}, {1, 30.0}, {0, 100.0}, {1, 20.0}};
  const double gas = gaseous_specific_attenuation(10e9, air).total_db_per_km() * 1e-3;
  const double gamma = woodland_specific_attenuation_db_per_m(10e9, true);
  const double a_m = woodland_max_attenuation_db(10e9);
  const double expected = 2.0 * (gas * 350.0 + woodland_excess_attenuation_db(gamma, a_m, 50.0));
  EXPECT_NEAR(table.two_way_loss_db(path), expected, 1e-9 * expected);
  EXPECT_LT(table.two_way_loss_db(path), 2.0 * (gas * 350.0 + gamma * 50.0));
  EXPECT_THROW(PathAttenuation(94e9, 0.0, media), std::invalid_argument);
}

}  // namespace
}  // namespace radar_emu::radar

TEST(PathAttenuation, TwoWayLossScalesEachReturnsAmplitudeByItsRange) {
  // gamma = 3 dB/km one way: a return at 500 m loses 2 x 0.5 x 3 = 3 dB of power, its amplitude
  // 10^(-3/20); at 0 m nothing. Diffuse returns are scaled the same way (their |A|^2 is power);
  // the phase is kept; a non-finite range is left alone.
  using radar_emu::radar::apply_two_way_loss;
  using radar_emu::radar::Contribution;
  std::vector<Contribution> c(4);
  c[0].amplitude = {2.0, -1.0};
  c[0].range_m = 500.0;
  c[1].amplitude = {0.5, 0.0};
  c[1].range_m = 0.0;
  c[2].amplitude = {0.0, 3.0};
  c[2].range_m = 2000.0;
  c[2].coherent = false;
  c[3].amplitude = {1.0, 1.0};
  c[3].range_m = std::nan("");
  apply_two_way_loss(c, 3e-3);
  EXPECT_NEAR(std::abs(c[0].amplitude), std::sqrt(5.0) * std::pow(10.0, -3.0 / 20.0), 1e-12);
  EXPECT_NEAR(std::arg(c[0].amplitude), std::atan2(-1.0, 2.0), 1e-12);
  EXPECT_DOUBLE_EQ(c[1].amplitude.real(), 0.5);
  EXPECT_NEAR(20.0 * std::log10(3.0 / std::abs(c[2].amplitude)), 12.0, 1e-9);  // 2 x 2 km x 3
  EXPECT_EQ(c[3].amplitude, std::complex<double>(1.0, 1.0));
  // No medium (gamma 0, negative or NaN): untouched.
  for (double g : {0.0, -1.0, std::nan("")}) {
    std::vector<Contribution> d(1);
    d[0].amplitude = {1.0, 0.0};
    d[0].range_m = 100.0;
    apply_two_way_loss(d, g);
    EXPECT_EQ(d[0].amplitude, std::complex<double>(1.0, 0.0));
  }
}
