// The enhanced-vision image (radar/products/ev_image.hpp) on synthetic returns: the range-gate
// to elevation mapping against the flat-earth closed form R = h / sin(psi), the N-look speckle
// statistics against Gamma(N, 1/N) (coefficient of variation 1/sqrt(N)), coherent targets kept
// as they are, and the counts of returns outside the field.
#include "radar/products/ev_image.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/units.hpp"

namespace radar = radar_emu::radar;

namespace {

namespace common = radar_emu::common;

// A level antenna at height h looking north: antenna x (boresight) = north, y (right) = east,
// z (down) = -up.
radar::RadarPose level_pose(double height_m) {
  radar::RadarPose p;
  p.position_m = {0.0, 0.0, height_m};
  p.world_from_antenna = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1));
  return p;
}

// The seed's 30 x 10 deg field of 0.15 deg pixels (ev_radar_94ghz.toml), looking down.
radar::EvImageConfig seed_grid() {
  radar::EvImageConfig c;
  c.azimuth_min_rad = common::radians(-15.0);
  c.azimuth_max_rad = common::radians(15.0);
  c.elevation_min_rad = common::radians(-12.0);
  c.elevation_max_rad = common::radians(-2.0);
  c.pixel_rad = common::radians(0.15);
  return c;
}

// `m` diffuse returns of unit power at the centre of every cell (range midway between the
// row's edges; the edges from the closed form, not from the code).
std::vector<radar::Contribution> homogeneous(const radar::EvImageConfig& c, double height_m,
                                             int m) {
  std::vector<radar::Contribution> out;
  const int cols = radar::ev_image_columns(c), rows = radar::ev_image_rows(c);
  for (int r = 0; r < rows; ++r) {
    const double psi_far = -(c.elevation_max_rad - r * c.pixel_rad);
    const double psi_near = -(c.elevation_max_rad - (r + 1) * c.pixel_rad);
    const double range = 0.5 * (height_m / std::sin(psi_far) + height_m / std::sin(psi_near));
    for (int col = 0; col < cols; ++col) {
      for (int k = 0; k < m; ++k) {
        radar::Contribution q;
        q.coherent = false;
        q.amplitude = {1.0, 0.0};
        q.range_m = range;
        q.azimuth_rad = radar::ev_column_azimuth_rad(c, col);
        out.push_back(q);
      }
    }
  }
  return out;
}

double cv(const std::vector<float>& v) {
  double s = 0, s2 = 0;
  for (const double x : v) {
    s += x;
    s2 += x * x;
  }
  const double n = double(v.size()), mean = s / n;
  return std::sqrt(s2 / n - mean * mean) / mean;
}

}  // namespace

TEST(EvImage, TheSeedsFieldIs200By66SquarePixels) {
  radar::EvImageConfig c = seed_grid();
  c.elevation_min_rad = common::radians(-5.0);
  c.elevation_max_rad = common::radians(5.0);
  EXPECT_EQ(radar::ev_image_columns(c), 200);
  EXPECT_EQ(radar::ev_image_rows(c), 66);  // 10 / 0.15 = 66.7: whole pixels from the top edge
  c.pixel_rad = 0.0;
  EXPECT_THROW((void)radar::ev_image_rows(c), std::invalid_argument);
}

TEST(EvImage, RowEdgesAreTheFlatEarthRangesOfTheirDepression) {
  // Level antenna at 50 m: the row edge at elevation el meets the ground at R = h / sin(-el)
  // in every column (Skolnik, Radar Handbook, 3rd ed., sec. 16.2).
  const radar::EvImageConfig c = seed_grid();
  const double h = 50.0;
  const radar::EvImage im = radar::form_ev_image({}, level_pose(h), c);
  ASSERT_EQ(im.rows, 66);
  for (int col : {0, 57, 199}) {
    for (int k = 0; k <= im.rows; ++k) {
      const double psi = -(c.elevation_max_rad - k * c.pixel_rad);
      EXPECT_NEAR(im.range_edges_m[static_cast<std::size_t>(col * (im.rows + 1) + k)],
                  h / std::sin(psi), 1e-9 * h / std::sin(psi));
    }
  }
  // 2 deg of depression: 1432.7 m; the bottom edge, 66 rows of 0.15 deg lower (11.9 deg): 242.5 m.
  EXPECT_NEAR(im.range_edges_m[0], 1432.7, 0.1);
  EXPECT_NEAR(im.range_edges_m[66], 242.5, 0.1);
}

TEST(EvImage, ReturnsLandInTheRowOfTheirRangeAndColumnOfTheirAzimuth) {
  const radar::EvImageConfig c = seed_grid();
  const double h = 50.0;
  // A point on the ground 400 m north and 30 m east: depression atan(50 / 400.0), azimuth
  // atan(30 / 400) (level antenna).
  radar::Contribution q;
  q.coherent = true;
  q.amplitude = {3.0, 4.0};  // 25 m^2
  q.range_m = std::sqrt(400.0 * 400.0 + 30.0 * 30.0 + h * h);
  q.azimuth_rad = std::atan2(30.0, 400.0);
  const radar::EvImage im = radar::form_ev_image(std::span(&q, 1), level_pose(h), c);
  const double psi = std::asin(h / q.range_m);
  const int row = static_cast<int>(std::floor((c.elevation_max_rad + psi) / c.pixel_rad));
  const int col = static_cast<int>(std::floor((q.azimuth_rad - c.azimuth_min_rad) / c.pixel_rad));
  EXPECT_EQ(im.contributions_used, 1u);
  EXPECT_FLOAT_EQ(im.at(row, col), 25.0f);  // a target alone keeps |A|^2 in every look
  EXPECT_FLOAT_EQ(im.mean_m2[static_cast<std::size_t>(row * im.columns + col)], 25.0f);
  double total = 0;
  for (const double v : im.intensity_m2)
    total += v;
  EXPECT_FLOAT_EQ(static_cast<float>(total), 25.0f);
}

TEST(EvImage, ReturnsOutsideTheFieldAreCountedNotPlaced) {
  const radar::EvImageConfig c = seed_grid();
  std::vector<radar::Contribution> q(3);
  q[0].range_m = 500.0;
  q[0].azimuth_rad = common::radians(20.0);  // right of the field
  q[1].range_m = 100.0;                      // nearer than 12 deg of depression at 50 m (240 m)
  q[2].range_m = 5000.0;                     // beyond 2 deg (1433 m)
  const radar::EvImage im = radar::form_ev_image(q, level_pose(50.0), c);
  EXPECT_EQ(im.outside_columns, 1u);
  EXPECT_EQ(im.nearer_than_field, 1u);
  EXPECT_EQ(im.farther_than_field, 1u);
  EXPECT_EQ(im.contributions_used, 0u);
}

TEST(EvImage, NLooksOfHomogeneousClutterHaveCoefficientOfVariationOneOverRootN) {
  // Oliver & Quegan (2004) eq. 4.8: N-look intensity ~ Gamma(N, <I>/N), CV = 1/sqrt(N), whatever
  // the number of returns summed per cell (each is complex Gaussian). 200 x 66 cells.
  radar::EvImageConfig c = seed_grid();
  const double h = 50.0;
  for (int m : {1, 5}) {
    const std::vector<radar::Contribution> q = homogeneous(c, h, m);
    for (int looks : {1, 4, 10}) {
      c.looks = looks;
      const radar::EvImage im = radar::form_ev_image(q, level_pose(h), c);
      ASSERT_EQ(im.contributions_used, q.size());
      const double expected = 1.0 / std::sqrt(double(looks));
      EXPECT_NEAR(cv(im.intensity_m2), expected, 0.1 * expected)
          << m << " returns a cell, " << looks << " looks";
      EXPECT_FLOAT_EQ(im.mean_m2[1234], static_cast<float>(m));
      // The looks are uncorrelated: the mean over the image is the mean power within 3 sigma.
      double s = 0;
      for (const double v : im.intensity_m2)
        s += v;
      const double n = double(im.intensity_m2.size());
      EXPECT_NEAR(s / n, m, 3.0 * m * expected / std::sqrt(n));
    }
  }
  // Without speckle the image is the mean image.
  c.speckle = false;
  const radar::EvImage im = radar::form_ev_image(homogeneous(c, h, 3), level_pose(h), c);
  EXPECT_EQ(cv(im.intensity_m2), 0.0);
}
