// common/: closed-form checks of the units, sinc, require and the polarisation channel.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "common/polarisation.hpp"
#include "common/require.hpp"
#include "common/sinc.hpp"
#include "common/units.hpp"

namespace cm = radar_emu::common;

namespace {

std::string what_of(std::string_view name) {
  try {
    (void)cm::parse_polarisation(name);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace

TEST(Units, PiAndSpeedOfLight) {
  EXPECT_EQ(cm::kPi, std::numbers::pi);
  EXPECT_EQ(cm::kC, 299792458.0);
  EXPECT_EQ(cm::kRadPerDeg, std::numbers::pi / 180.0);
}

TEST(Units, RadiansAndDegrees) {
  EXPECT_EQ(cm::radians(180.0), cm::kPi);
  EXPECT_EQ(cm::radians(90.0), cm::kPi / 2.0);
  EXPECT_EQ(cm::radians(0.0), 0.0);
  EXPECT_EQ(cm::degrees(cm::kPi), 180.0);
  EXPECT_EQ(cm::degrees(-cm::kPi / 2.0), -90.0);
  // The exact expressions the call sites computed before (bit for bit).
  for (double x : {0.1, 1.0, 33.3, -17.25, 89.0, 359.9}) {
    EXPECT_EQ(cm::radians(x), x * (std::numbers::pi / 180.0)) << x;
    EXPECT_EQ(cm::degrees(x), x * (180.0 / std::numbers::pi)) << x;
    EXPECT_NEAR(cm::degrees(cm::radians(x)), x, 1e-13 * std::abs(x)) << x;
  }
  static_assert(cm::radians(180.0) == cm::kPi);
}

TEST(Units, Decibels) {
  EXPECT_NEAR(cm::db_from_power(2.0), 3.0103, 5e-5);
  EXPECT_DOUBLE_EQ(cm::db_from_power(2.0), 10.0 * std::log10(2.0));
  EXPECT_EQ(cm::db_from_power(1.0), 0.0);
  EXPECT_EQ(cm::db_from_power(1000.0), 30.0);
  EXPECT_EQ(cm::power_from_db(0.0), 1.0);
  EXPECT_EQ(cm::power_from_db(-20.0), 0.01);
  EXPECT_NEAR(cm::power_from_db(3.0103), 2.0, 1e-5);
  for (double p : {1e-12, 0.5, 2.0, 7.0, 1e9})
    EXPECT_NEAR(cm::power_from_db(cm::db_from_power(p)), p, 1e-14 * p) << p;
}

TEST(Sinc, ZeroAndZeros) {
  EXPECT_EQ(cm::sinc(0.0), 1.0);
  EXPECT_NEAR(cm::sinc(1e-4), 1.0 - 1e-8 / 6.0, 1e-16);
  for (int n = 1; n <= 5; ++n) {
    EXPECT_NEAR(cm::sinc(n * cm::kPi), 0.0, 1e-15) << n;
    EXPECT_NEAR(cm::sinc(-n * cm::kPi), 0.0, 1e-15) << n;
  }
  EXPECT_NEAR(cm::sinc(cm::kPi / 2.0), 2.0 / cm::kPi, 1e-15);
  // Both branches meet at |x| = 1e-3.
  EXPECT_NEAR(cm::sinc(0.999999e-3), std::sin(1e-3) / 1e-3, 1e-12);
}

TEST(Require, MessageNamesModuleFieldAndRule) {
  EXPECT_NO_THROW(cm::require(true, "cfar", "pfa", "must be in (0, 1)"));
  try {
    cm::require(false, "cfar", "pfa", "must be in (0, 1)");
    FAIL() << "not refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "cfar: pfa must be in (0, 1)");
  }
}

TEST(Polarisation, NameParseRoundTrip) {
  for (cm::Polarisation p : {cm::Polarisation::kHH, cm::Polarisation::kHV, cm::Polarisation::kVH,
                             cm::Polarisation::kVV}) {
    EXPECT_EQ(cm::parse_polarisation(cm::polarisation_name(p)), p);
    std::string lower(cm::polarisation_name(p));
    for (char& c : lower)
      c = c == 'H' ? 'h' : 'v';
    EXPECT_EQ(cm::parse_polarisation(lower), p) << lower;
  }
  // Receive letter first.
  EXPECT_EQ(cm::polarisation_name(cm::Polarisation::kHV), "HV");
  EXPECT_EQ(cm::parse_polarisation("hV"), cm::Polarisation::kHV);
  EXPECT_EQ(cm::parse_polarisation("Vh"), cm::Polarisation::kVH);
}

TEST(Polarisation, BadNamesRefusedWithTheMessage) {
  EXPECT_EQ(what_of("XX"), "'XX' is not one of HH, HV, VH, VV");
  EXPECT_EQ(what_of("RHC"), "'RHC' is not one of HH, HV, VH, VV");
  EXPECT_EQ(what_of(""), "'' is not one of HH, HV, VH, VV");
  EXPECT_EQ(what_of("H"), "'H' is not one of HH, HV, VH, VV");
  EXPECT_EQ(what_of("HHV"), "'HHV' is not one of HH, HV, VH, VV");
  EXPECT_EQ(what_of(" HH"), "' HH' is not one of HH, HV, VH, VV");
}
