// The PEC sphere: our Mie series against its published limits and values, the PO closed form
// against its real-valued formula, and where PO fails against Mie (physics.md).
#include "radar/reference/mie.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <stdexcept>

#include "radar/constants.hpp"

namespace radar_emu::radar {
namespace {

double normalised_mie(double ka) {
  return mie_sphere_rcs_m2(1.0, ka) / kPi;  // radius 1 m: k = ka
}
double db(double x) {
  return 10.0 * std::log10(x);
}

TEST(Mie, RayleighLimit) {
  // sigma / (pi a^2) -> 9 (ka)^4 (physics.md; Knott et al. 2004, sec. 5.5). The next term of
  // the low-frequency series is O((ka)^2) relative: allow 2 (ka)^2.
  for (double ka : {0.01, 0.05}) {
    const double ratio = normalised_mie(ka) / (9.0 * std::pow(ka, 4));
    EXPECT_NEAR(ratio, 1.0, 2.0 * ka * ka) << "ka " << ka;
  }
}

TEST(Mie, ResonanceValueAtKaOne) {
  // 3.64 at ka = 1 (physics.md; the resonance peak of Ruck et al. 1970, fig. 3-5): three
  // published digits.
  const double v = normalised_mie(1.0);
  std::cout << "Mie sigma/(pi a^2) at ka = 1: " << v << "\n";
  EXPECT_NEAR(v, 3.64, 0.005);
}

TEST(Mie, OpticalLimit) {
  // Tends to 1; the creeping wave interferes with the specular return with an amplitude that
  // falls with ka: under 1 % (0.04 dB) from ka = 50.
  for (double ka : {50.0, 80.0, 120.0, 200.0, 300.0})
    EXPECT_NEAR(normalised_mie(ka), 1.0, 0.01) << "ka " << ka;
}

TEST(Mie, PhaseConventionMatchesPoSpecularTerm) {
  // Both amplitudes follow rcs.hpp's convention: at large ka they share the specular phase
  // (-sqrt(pi) a e^{j 2ka}); the creeping wave's relative amplitude (< 1 %) bounds the
  // difference to 0.02 rad.
  for (double ka = 50.0; ka <= 100.0; ka += 3.7) {
    const std::complex<double> m = mie_sphere_amplitude_m(1.0, ka);
    const std::complex<double> p = po_sphere_amplitude_m(1.0, ka);
    EXPECT_NEAR(std::arg(m / p), 0.0, 0.02) << "ka " << ka;
  }
}

TEST(Mie, PoClosedFormMatchesItsRealFormula) {
  for (double ka : {0.3, 1.0, 4.2, 17.0, 63.0}) {
    const double expected =
        1.0 - std::sin(2 * ka) / ka + std::sin(ka) * std::sin(ka) / (ka * ka);  // physics.md
    EXPECT_NEAR(po_sphere_rcs_m2(1.0, ka) / kPi, expected, 1e-12) << "ka " << ka;
    // Radius scaling: sigma scales with a^2 at fixed ka.
    EXPECT_NEAR(po_sphere_rcs_m2(0.25, ka / 0.25) / (kPi * 0.0625), expected, 1e-12);
  }
}

TEST(Mie, RecordsWherePoFails) {
  // Max |PO - Mie| in dB per band of ka (physics.md: about 1.4 / 0.6 / 0.2 dB at 5-10 / 10-20 /
  // 20-50). The 0.5 dB acceptance needs ka >= 20; below 10 PO fails (the CLI warns there).
  struct Band {
    double lo, hi, worst = 0.0;
  };
  Band bands[] = {{1.0, 5.0}, {5.0, 10.0}, {10.0, 20.0}, {20.0, 50.0}};
  for (Band& b : bands) {
    for (double ka = b.lo; ka <= b.hi; ka += 0.01) {
      const double err = db(po_sphere_rcs_m2(1.0, ka)) - db(mie_sphere_rcs_m2(1.0, ka));
      b.worst = std::max(b.worst, std::abs(err));
    }
    std::cout << "PO vs Mie, ka " << b.lo << "-" << b.hi << ": max |error| " << b.worst << " dB\n";
    ::testing::Test::RecordProperty("po_vs_mie_db_ka_" + std::to_string(static_cast<int>(b.lo)) +
                                        "_" + std::to_string(static_cast<int>(b.hi)),
                                    std::to_string(b.worst));
  }
  EXPECT_GT(bands[0].worst, 0.5);
  EXPECT_GT(bands[1].worst, 0.5);
  EXPECT_LT(bands[3].worst, 0.5);
}

TEST(Mie, RejectsBadArguments) {
  EXPECT_THROW((void)mie_sphere_rcs_m2(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW((void)mie_sphere_rcs_m2(1.0, -1.0), std::invalid_argument);
  EXPECT_THROW((void)po_sphere_rcs_m2(std::nan(""), 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace radar_emu::radar
