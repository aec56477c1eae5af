// WGS84 geodesy against closed forms and published reference values.

#include "scene/geo.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>
#include <random>

namespace w = radar_emu::scene::wgs84;
constexpr double kDeg = std::numbers::pi / 180.0;

namespace {
// Independent constants (NIMA TR8350.2, 3rd ed., 2000, table 3.1), not the library's.
constexpr double kA = 6378137.0;
constexpr double kF = 1.0 / 298.257223563;
constexpr double kE2 = kF * (2.0 - kF);
}  // namespace

TEST(Wgs84, EquatorAndPoleAreTheEllipsoidAxes) {
  const glm::dvec3 e = w::ecef_from_geodetic({0.0, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(e.x, 6378137.0);
  EXPECT_NEAR(e.y, 0.0, 1e-9);
  EXPECT_NEAR(e.z, 0.0, 1e-9);
  // Semi-minor axis b = a (1 - f) = 6356752.3142 m (NIMA TR8350.2, table 3.3).
  const glm::dvec3 p = w::ecef_from_geodetic({90.0 * kDeg, 0.0, 0.0});
  EXPECT_NEAR(p.z, 6356752.314245, 1e-6);
  EXPECT_NEAR(std::hypot(p.x, p.y), 0.0, 1e-6);
  const glm::dvec3 s = w::ecef_from_geodetic({-90.0 * kDeg, 0.0, 1000.0});
  EXPECT_NEAR(s.z, -6357752.314245, 1e-6);
  // lon 90 deg puts the equator point on +y.
  const glm::dvec3 y = w::ecef_from_geodetic({0.0, 90.0 * kDeg, 10.0});
  EXPECT_NEAR(y.y, 6378147.0, 1e-6);
  EXPECT_NEAR(y.x, 0.0, 1e-6);
}

TEST(Wgs84, GeographicLibCartConvertExamples) {
  // Published worked examples of GeographicLib's CartConvert(1) man page, section EXAMPLES
  // (C. F. F. Karney, https://geographiclib.sourceforge.io/C++/doc/CartConvert.1.html):
  //   echo 33.3 44.4 6000 | CartConvert               => 3816209.60 3737108.55 3485109.57
  //   echo 33.3 44.4 6000 | CartConvert -l 33 44 20   => 37288.97 33374.29 5783.64
  // (WGS84; -l gives local cartesian x east, y north, z up.) Printed to 1 cm. Evaluated with
  // 40-digit arithmetic the local point is (37288.9732, 33374.2949, 5783.6466): the page's z is
  // 6.6 mm below that (its last digit looks truncated, not rounded), so compare to 1 cm.
  const w::Geodetic g{33.3 * kDeg, 44.4 * kDeg, 6000.0};
  const glm::dvec3 e = w::ecef_from_geodetic(g);
  EXPECT_NEAR(e.x, 3816209.60, 0.0051);
  EXPECT_NEAR(e.y, 3737108.55, 0.0051);
  EXPECT_NEAR(e.z, 3485109.57, 0.0051);
  const w::EnuFrame local(w::Geodetic{33.0 * kDeg, 44.0 * kDeg, 20.0});
  const glm::dvec3 enu = local.enu_from_geodetic(g);
  EXPECT_NEAR(enu.x, 37288.97, 0.01);
  EXPECT_NEAR(enu.y, 33374.29, 0.01);
  EXPECT_NEAR(enu.z, 5783.64, 0.01);
  // The inverse of the published (cm-rounded) points: 1 cm is about 1e-7 deg on the Earth.
  const w::Geodetic back = w::geodetic_from_ecef({3816209.60, 3737108.55, 3485109.57});
  EXPECT_NEAR(back.latitude_rad / kDeg, 33.3, 1e-7);
  EXPECT_NEAR(back.longitude_rad / kDeg, 44.4, 1e-7);
  EXPECT_NEAR(back.height_m, 6000.0, 0.01);
  const w::Geodetic back_local = local.geodetic_from_enu({37288.97, 33374.29, 5783.64});
  EXPECT_NEAR(back_local.latitude_rad / kDeg, 33.3, 1e-7);
  EXPECT_NEAR(back_local.longitude_rad / kDeg, 44.4, 1e-7);
  EXPECT_NEAR(back_local.height_m, 6000.0, 0.01);
}

TEST(Wgs84, ClosedFormAtFortyFiveDegrees) {
  // lat 45, lon 45, h 0: N = a / sqrt(1 - e^2/2); x = y = N cos^2 45 = N/2,
  // z = N (1 - e^2) sin 45 (TR8350.2 eq. 4-14, 4-15), evaluated here from the constants.
  const double n = kA / std::sqrt(1.0 - kE2 / 2.0);
  EXPECT_NEAR(n, 6388838.2901, 1e-4);
  const glm::dvec3 x = w::ecef_from_geodetic({45.0 * kDeg, 45.0 * kDeg, 0.0});
  EXPECT_NEAR(x.x, n / 2.0, 1e-6);
  EXPECT_NEAR(x.y, n / 2.0, 1e-6);
  EXPECT_NEAR(x.z, n * (1.0 - kE2) * std::sqrt(0.5), 1e-6);
}

TEST(Wgs84, InverseIsExactToATenthOfAMillimetreWorldwide) {
  const std::uint32_t seed = 3;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> lat(-90.0, 90.0), lon(-180.0, 180.0),
      h(-10000.0, 100000.0);
  double worst_m = 0.0;
  auto check = [&](const w::Geodetic& g) {
    const w::Geodetic r = w::geodetic_from_ecef(w::ecef_from_geodetic(g));
    // Errors as distances: latitude along the meridian, longitude along the parallel.
    const double dlon = std::remainder(r.longitude_rad - g.longitude_rad, 2.0 * std::numbers::pi);
    const double e = std::max({std::abs(r.latitude_rad - g.latitude_rad) * kA,
                               std::abs(dlon) * kA * std::cos(g.latitude_rad),
                               std::abs(r.height_m - g.height_m)});
    worst_m = std::max(worst_m, e);
    EXPECT_LT(e, 1e-4) << g.latitude_rad / kDeg << " " << g.longitude_rad / kDeg << " "
                       << g.height_m;
  };
  for (int i = 0; i < 20000; ++i)
    check({lat(rng) * kDeg, lon(rng) * kDeg, h(rng)});
  for (double la : {-90.0, -89.9999, -45.0, 0.0, 1e-9, 45.0, 89.9999, 90.0}) {
    for (double height : {-10000.0, 0.0, 150.0, 100000.0})
      check({la * kDeg, 10.0 * kDeg, height});
  }
  std::cout << "worst inverse error " << worst_m * 1e3 << " mm\n";
}

TEST(Wgs84, EnuRoundTripWithinOneMillimetreOverFiftyKilometres) {
  const std::uint32_t seed = 11;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  const w::EnuFrame enu(w::Geodetic{43.6 * kDeg, 1.4 * kDeg, 150.0});
  std::uniform_real_distribution<double> horizontal(-50e3, 50e3), height(-100.0, 10000.0);
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    glm::dvec3 p(horizontal(rng), horizontal(rng), height(rng));
    if (glm::length(glm::dvec2(p)) > 50e3)
      p = glm::dvec3(glm::normalize(glm::dvec2(p)) * 50e3, p.z);
    const glm::dvec3 q = enu.enu_from_geodetic(enu.geodetic_from_enu(p));
    worst = std::max(worst, glm::length(q - p));
  }
  EXPECT_LT(worst, 1e-3);
  EXPECT_LT(worst, 1e-6);  // in fact double rounding
  std::cout << "worst round-trip error " << worst * 1e3 << " mm\n";
}

TEST(Wgs84, EnuAxesAtTheAnchor) {
  const w::Geodetic anchor{43.6 * kDeg, 1.4 * kDeg, 150.0};
  const w::EnuFrame enu(anchor);
  EXPECT_NEAR(glm::length(enu.enu_from_geodetic(anchor)), 0.0, 1e-6);
  // 1 m up along the ellipsoid normal is (0, 0, 1).
  const glm::dvec3 up = enu.enu_from_geodetic({anchor.latitude_rad, anchor.longitude_rad, 151.0});
  EXPECT_NEAR(up.z, 1.0, 1e-6);
  EXPECT_NEAR(std::hypot(up.x, up.y), 0.0, 1e-6);
  // A small step north in latitude moves along +y by the meridian radius of curvature
  // M = a (1 - e^2) / (1 - e^2 sin^2 phi)^1.5 per radian (plus the height).
  const double s = std::sin(anchor.latitude_rad);
  const double m = kA * (1 - kE2) / std::pow(1 - kE2 * s * s, 1.5);
  const double dlat = 1e-6;
  const glm::dvec3 n =
      enu.enu_from_geodetic({anchor.latitude_rad + dlat, anchor.longitude_rad, 150.0});
  EXPECT_NEAR(n.y, (m + 150.0) * dlat, 1e-6);
  EXPECT_NEAR(n.x, 0.0, 1e-9);
  // A small step east in longitude moves along +x by (N + h) cos(phi) per radian.
  const double nn = kA / std::sqrt(1 - kE2 * s * s);
  const double dlon = 1e-6;
  const glm::dvec3 e =
      enu.enu_from_geodetic({anchor.latitude_rad, anchor.longitude_rad + dlon, 150.0});
  EXPECT_NEAR(e.x, (nn + 150.0) * std::cos(anchor.latitude_rad) * dlon, 1e-6);
  // The parallel is a small circle: it bends north of the east axis by x^2 tan(phi) / (2 N).
  EXPECT_NEAR(e.y, e.x * e.x * std::tan(anchor.latitude_rad) / (2.0 * nn), 1e-8);
  // The GeoAnchor constructor is the same frame.
  const w::EnuFrame from_anchor(
      radar_emu::scene::GeoAnchor{anchor.latitude_rad, anchor.longitude_rad, 150.0});
  EXPECT_NEAR(glm::length(from_anchor.enu_from_geodetic(anchor)), 0.0, 1e-9);
  const glm::dvec3 p(1234.5, -678.9, 42.0);
  EXPECT_LT(glm::length(from_anchor.enu_from_ecef(enu.ecef_from_enu(p)) - p), 1e-8);
}
