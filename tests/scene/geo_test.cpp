// WGS84 geodesy against closed forms and published reference values.

#include "scene/geo.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <random>

#include "common/units.hpp"

namespace w = radar_emu::scene::wgs84;
namespace common = radar_emu::common;

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
  const glm::dvec3 p = w::ecef_from_geodetic({common::radians(90.0), 0.0, 0.0});
  EXPECT_NEAR(p.z, 6356752.314245, 1e-6);
  EXPECT_NEAR(std::hypot(p.x, p.y), 0.0, 1e-6);
  const glm::dvec3 s = w::ecef_from_geodetic({common::radians(-90.0), 0.0, 1000.0});
  EXPECT_NEAR(s.z, -6357752.314245, 1e-6);
  // lon 90 deg puts the equator point on +y.
  const glm::dvec3 y = w::ecef_from_geodetic({0.0, common::radians(90.0), 10.0});
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
  const w::Geodetic g{common::radians(33.3), common::radians(44.4), 6000.0};
  const glm::dvec3 e = w::ecef_from_geodetic(g);
  EXPECT_NEAR(e.x, 3816209.60, 0.0051);
  EXPECT_NEAR(e.y, 3737108.55, 0.0051);
  EXPECT_NEAR(e.z, 3485109.57, 0.0051);
  const w::EnuFrame local(w::Geodetic{common::radians(33.0), common::radians(44.0), 20.0});
  const glm::dvec3 enu = local.enu_from_geodetic(g);
  EXPECT_NEAR(enu.x, 37288.97, 0.01);
  EXPECT_NEAR(enu.y, 33374.29, 0.01);
  EXPECT_NEAR(enu.z, 5783.64, 0.01);
  // The inverse of the published (cm-rounded) points: 1 cm is about 1e-7 deg on the Earth.
  const w::Geodetic back = w::geodetic_from_ecef({3816209.60, 3737108.55, 3485109.57});
  EXPECT_NEAR(back.latitude_rad / common::kRadPerDeg, 33.3, 1e-7);
  EXPECT_NEAR(back.longitude_rad / common::kRadPerDeg, 44.4, 1e-7);
  EXPECT_NEAR(back.height_m, 6000.0, 0.01);
  const w::Geodetic back_local = local.geodetic_from_enu({37288.97, 33374.29, 5783.64});
  EXPECT_NEAR(back_local.latitude_rad / common::kRadPerDeg, 33.3, 1e-7);
  EXPECT_NEAR(back_local.longitude_rad / common::kRadPerDeg, 44.4, 1e-7);
  EXPECT_NEAR(back_local.height_m, 6000.0, 0.01);
}

TEST(Wgs84, EpsgGuidanceNoteWorkedExamples) {
  // IOGP Publication 373-7-2 (EPSG Guidance Note 7-2), "Coordinate Conversions and
  // Transformations including Formulas": worked examples of the WGS 84 geographic/geocentric
  // conversion (EPSG method 9602) and geocentric/topocentric conversion (method 9836),
  // transcribed at https://epsg.io/9602-method and https://epsg.io/9836-method.
  // 9602: 53 deg 48' 33.820" N, 2 deg 07' 46.380" E, h = 73.000 m
  //   => X = 3771793.968 m, Y = 140253.342 m, Z = 5124304.349 m (printed to 1 mm).
  const double lat = common::radians(53.0 + 48.0 / 60.0 + 33.820 / 3600.0);
  const double lon = common::radians(2.0 + 7.0 / 60.0 + 46.380 / 3600.0);
  const glm::dvec3 point(3771793.968, 140253.342, 5124304.349);
  const glm::dvec3 x = w::ecef_from_geodetic({lat, lon, 73.0});
  EXPECT_NEAR(x.x, point.x, 0.001);
  EXPECT_NEAR(x.y, point.y, 0.001);
  EXPECT_NEAR(x.z, point.z, 0.001);
  const w::Geodetic g = w::geodetic_from_ecef(point);
  EXPECT_NEAR(g.latitude_rad, lat, 3e-10);  // 1 mm is 1.6e-10 rad on the Earth
  EXPECT_NEAR(g.longitude_rad, lon, 3e-10);
  EXPECT_NEAR(g.height_m, 73.0, 0.0015);
  // 9836: topocentric origin Xo = 3652755.3058, Yo = 319574.6799, Zo = 5201547.3536 m, whose
  // ellipsoidal coordinates the example derives as Po = 0.9599310885 rad (55 deg N),
  // Lo = 0.0872664625 rad (5 deg E) (height 200 m, which the 0.1 mm agreement below confirms);
  // the 9602 point above has U = -189013.869, V = -128642.040, W = -4220.171 m (east, north,
  // up, printed to 1 mm).
  const w::Geodetic origin{common::radians(55.0), common::radians(5.0), 200.0};
  const glm::dvec3 o = w::ecef_from_geodetic(origin);
  EXPECT_NEAR(o.x, 3652755.3058, 1e-4);
  EXPECT_NEAR(o.y, 319574.6799, 1e-4);
  EXPECT_NEAR(o.z, 5201547.3536, 1e-4);
  // The example's Po and Lo are 55 and 5 deg to their 10 printed decimals (within 1.1e-10
  // rad); from the 0.1 mm origin the inverse gives the exact angles to 1.6e-11 rad.
  const w::Geodetic og = w::geodetic_from_ecef({3652755.3058, 319574.6799, 5201547.3536});
  EXPECT_NEAR(og.latitude_rad, common::radians(55.0), 2e-11);
  EXPECT_NEAR(og.longitude_rad, common::radians(5.0), 2e-11);
  EXPECT_NEAR(og.latitude_rad, 0.9599310885, 1.1e-10);
  EXPECT_NEAR(og.longitude_rad, 0.0872664625, 1.1e-10);
  EXPECT_NEAR(og.height_m, 200.0, 1e-4);
  const w::EnuFrame topo(origin);
  const glm::dvec3 uvw = topo.enu_from_ecef(point);
  EXPECT_NEAR(uvw.x, -189013.869, 0.001);
  EXPECT_NEAR(uvw.y, -128642.040, 0.001);
  EXPECT_NEAR(uvw.z, -4220.171, 0.001);
  const glm::dvec3 back = topo.ecef_from_enu({-189013.869, -128642.040, -4220.171});
  EXPECT_LT(glm::length(back - point), 0.002);
  // The same point through geodetic -> topocentric directly (EPSG method 9837 composes the two).
  EXPECT_LT(glm::length(topo.enu_from_geodetic({lat, lon, 73.0}) - uvw), 0.002);
}

TEST(Wgs84, EnuRoundTripOnAGridAtAnchorsWorldwide) {
  // Every point of a 5 km grid up to 50 km from the anchor, heights -100 m .. 10 km, at anchors
  // from the equator to near the pole and across the date line: ENU -> WGS84 -> ENU and
  // WGS84 -> ENU -> WGS84 within 1 mm.
  const w::Geodetic anchors[] = {{0.0, 0.0, 0.0},
                                 {common::radians(43.6), common::radians(1.4), 150.0},
                                 {common::radians(-33.95), common::radians(151.18), 6.0},
                                 {common::radians(69.68), common::radians(18.92), 9.0},
                                 {common::radians(89.5), common::radians(-45.0), 2800.0},
                                 {common::radians(-12.0), common::radians(179.95), -30.0}};
  double worst_enu = 0.0, worst_geo = 0.0;
  int points = 0;
  for (const w::Geodetic& a : anchors) {
    const w::EnuFrame enu(a);
    for (int i = -10; i <= 10; ++i) {
      for (int j = -10; j <= 10; ++j) {
        const double e = 5000.0 * i, n = 5000.0 * j;
        if (std::hypot(e, n) > 50000.0)
          continue;
        for (double h : {-100.0, 0.0, 1500.0, 10000.0}) {
          const glm::dvec3 p(e, n, h);
          worst_enu =
              std::max(worst_enu, glm::length(enu.enu_from_geodetic(enu.geodetic_from_enu(p)) - p));
          const w::Geodetic g = enu.geodetic_from_enu(p);
          const w::Geodetic r = enu.geodetic_from_enu(enu.enu_from_geodetic(g));
          const double dlon =
              std::remainder(r.longitude_rad - g.longitude_rad, 2.0 * std::numbers::pi);
          worst_geo = std::max({worst_geo, std::abs(r.latitude_rad - g.latitude_rad) * kA,
                                std::abs(dlon) * kA * std::cos(g.latitude_rad),
                                std::abs(r.height_m - g.height_m)});
          ++points;
        }
      }
    }
  }
  std::cout << points << " grid points, worst ENU round trip " << worst_enu * 1e3
            << " mm, worst geodetic round trip " << worst_geo * 1e3 << " mm\n";
  EXPECT_LT(worst_enu, 1e-3);
  EXPECT_LT(worst_geo, 1e-3);
}

TEST(Wgs84, ClosedFormAtFortyFiveDegrees) {
  // lat 45, lon 45, h 0: N = a / sqrt(1 - e^2/2); x = y = N cos^2 45 = N/2,
  // z = N (1 - e^2) sin 45 (TR8350.2 eq. 4-14, 4-15), evaluated here from the constants.
  const double n = kA / std::sqrt(1.0 - kE2 / 2.0);
  EXPECT_NEAR(n, 6388838.2901, 1e-4);
  const glm::dvec3 x = w::ecef_from_geodetic({common::radians(45.0), common::radians(45.0), 0.0});
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
    EXPECT_LT(e, 1e-4) << g.latitude_rad / common::kRadPerDeg << " "
                       << g.longitude_rad / common::kRadPerDeg << " " << g.height_m;
  };
  for (int i = 0; i < 20000; ++i)
    check({common::radians(lat(rng)), common::radians(lon(rng)), h(rng)});
  for (double la : {-90.0, -89.9999, -45.0, 0.0, 1e-9, 45.0, 89.9999, 90.0}) {
    for (double height : {-10000.0, 0.0, 150.0, 100000.0})
      check({common::radians(la), common::radians(10.0), height});
  }
  std::cout << "worst inverse error " << worst_m * 1e3 << " mm\n";
}

TEST(Wgs84, EnuRoundTripWithinOneMillimetreOverFiftyKilometres) {
  const std::uint32_t seed = 11;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  const w::EnuFrame enu(w::Geodetic{common::radians(43.6), common::radians(1.4), 150.0});
  std::uniform_real_distribution<double> horizontal(-50e3, 50e3), height(-100.0, 10000.0);
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    glm::dvec3 p{horizontal(rng), horizontal(rng), height(rng)};
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
  const w::Geodetic anchor{common::radians(43.6), common::radians(1.4), 150.0};
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
