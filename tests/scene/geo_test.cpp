// WGS84 geodesy against closed forms and published reference values.

#include "scene/geo.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace w = radar_emu::scene::wgs84;
constexpr double kDeg = std::numbers::pi / 180.0;

TEST(Wgs84, EquatorAndPoleAreTheEllipsoidAxes) {
  const glm::dvec3 e = w::ecef_from_geodetic({0.0, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(e.x, 6378137.0);
  EXPECT_NEAR(e.y, 0.0, 1e-9);
  // Semi-minor axis b = a (1 - f) = 6356752.314245 m (NIMA TR8350.2, table 3.3).
  const glm::dvec3 p = w::ecef_from_geodetic({90.0 * kDeg, 0.0, 0.0});
  EXPECT_NEAR(p.z, 6356752.314245, 1e-6);
  EXPECT_NEAR(std::hypot(p.x, p.y), 0.0, 1e-6);
}

TEST(Wgs84, PublishedReferencePoint) {
  // Closed form at lat 45 deg, lon 45 deg, h 0: N = a / sqrt(1 - e^2/2) = 6388838.2901 m, so
  // x = y = N cos^2(45) = N/2 = 3194419.1451 m and z = N (1 - e^2) sin 45 = 4487348.4088 m.
  // The same values are tabulated in many geodesy course notes (e.g. the ECEF example of
  // Hofmann-Wellenhof et al., GNSS, 2008, recomputed here from the closed form above).
  const double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2.0 - f);
  const double n = a / std::sqrt(1.0 - e2 / 2.0);
  EXPECT_NEAR(n, 6388838.2901, 1e-4);
  const glm::dvec3 x = w::ecef_from_geodetic({45.0 * kDeg, 45.0 * kDeg, 0.0});
  EXPECT_NEAR(x.x, 3194419.1451, 1e-3);
  EXPECT_NEAR(x.y, 3194419.1451, 1e-3);
  EXPECT_NEAR(x.z, 4487348.4088, 1e-3);
}

TEST(Wgs84, RoundTripWithinOneMillimetreOverFiftyKilometres) {
  const std::uint32_t seed = 11;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  const w::EnuFrame enu(w::Geodetic{43.6 * kDeg, 1.4 * kDeg, 150.0});
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const glm::dvec3 p(std::uniform_real_distribution<double>(-50e3, 50e3)(rng),
                       std::uniform_real_distribution<double>(-50e3, 50e3)(rng),
                       std::uniform_real_distribution<double>(-100.0, 10000.0)(rng));
    const glm::dvec3 q = enu.enu_from_geodetic(enu.geodetic_from_enu(p));
    worst = std::max(worst, glm::length(q - p));
  }
  EXPECT_LT(worst, 1e-3);
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
  const double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2.0 - f);
  const double s = std::sin(anchor.latitude_rad);
  const double m = a * (1 - e2) / std::pow(1 - e2 * s * s, 1.5);
  const double dlat = 1e-6;
  const glm::dvec3 n =
      enu.enu_from_geodetic({anchor.latitude_rad + dlat, anchor.longitude_rad, 150.0});
  EXPECT_NEAR(n.y, (m + 150.0) * dlat, 1e-6);
  EXPECT_NEAR(n.x, 0.0, 1e-9);
}
