// First sensor against radar theory: cells, the radar equation (Skolnik eq. 2.1 form), 1/R^4,
// Doppler and folding, CA-CFAR on homogeneous clutter, peak grouping.

#include "radar/sensor/sensor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

namespace rd = radar_emu::radar;

namespace {
constexpr double kC = 299792458.0;
constexpr double kPi = std::numbers::pi;

rd::SensorConfig config() {
  rd::SensorConfig c;
  c.carrier_hz = 94e9;
  c.bandwidth_hz = 50e6;
  c.prf_hz = 100e3;
  c.pulses = 64;
  c.pulse_width_s = 10e-6;
  c.tx_power_w = 20.0;
  c.antenna_gain = std::pow(10.0, 4.5);
  c.noise_figure = std::pow(10.0, 0.5);
  c.system_losses = 2.0;
  c.azimuth_min_rad = -0.1;
  c.azimuth_max_rad = 0.1;
  c.azimuth_cell_rad = 0.02;
  c.max_range_m = 6000.0;
  return c;
}

rd::Contribution point(double sigma_m2, double range_m, double vr = 0.0, double az = 0.001) {
  rd::Contribution p;
  p.amplitude = {std::sqrt(sigma_m2), 0.0};
  p.range_m = range_m;
  p.radial_velocity_mps = vr;
  p.azimuth_rad = az;
  p.elevation_rad = -0.05;
  return p;
}

// The radar equation evaluated independently of the sensor's code.
double snr_expected(const rd::SensorConfig& c, double sigma, double r) {
  const double lambda = kC / c.carrier_hz;
  const double pr = c.tx_power_w * c.antenna_gain * c.antenna_gain * lambda * lambda * sigma /
                    (std::pow(4 * kPi, 3) * std::pow(r, 4) * c.system_losses);
  const double noise = 1.380649e-23 * 290.0 * c.noise_figure * c.bandwidth_hz;
  return pr * c.pulses * c.pulse_width_s * c.bandwidth_hz / noise;
}
double db(double x) {
  return 10 * std::log10(x);
}
}  // namespace

TEST(Sensor, CellSizesFromTheWaveform) {
  rd::Sensor s(config());
  EXPECT_NEAR(s.range_cell_m(), kC / (2 * 50e6), 1e-12);  // c / 2B = 2.998 m
  const double vua = (kC / 94e9) * 100e3 / 4.0;           // lambda PRF / 4 = 79.7 m/s
  EXPECT_NEAR(s.unambiguous_velocity_mps(), vua, 1e-9);
  EXPECT_NEAR(s.doppler_cell_mps(), 2 * vua / 64, 1e-12);
  EXPECT_EQ(s.azimuth_cells(), 10u);
  EXPECT_EQ(s.range_cells(), static_cast<std::size_t>(std::ceil(6000.0 / s.range_cell_m())));
}

TEST(Sensor, PointTargetSnrAndRcsFollowTheRadarEquation) {
  const rd::SensorConfig c = config();
  rd::Sensor s(c);
  std::vector<rd::Detection> out(8);
  for (double r : {1000.0, 2000.0, 4000.0}) {
    const double centre = (std::floor(r / s.range_cell_m()) + 0.5) * s.range_cell_m();
    const rd::Contribution p = point(10.0, centre);
    rd::SensorStats st;
    ASSERT_EQ(s.process(std::span(&p, 1), out, st), 1u) << r;
    EXPECT_NEAR(db(out[0].snr), db(snr_expected(c, 10.0, centre)), 0.1) << r;
    EXPECT_NEAR(db(out[0].rcs_m2), 10.0, 0.1) << r;
    EXPECT_EQ(out[0].range_cell, s.range_cell_of(r));
    EXPECT_NEAR(out[0].elevation_rad, -0.05, 1e-12);
  }
}

TEST(Sensor, ReceivedPowerFallsAsOneOverRToTheFourth) {
  rd::Sensor s(config());
  std::vector<rd::Detection> out(8);
  const double dr = s.range_cell_m();
  const double r1 = 400.5 * dr, r2 = 801.5 * dr;  // cell centres, r2 / r1 = 2.00125
  rd::SensorStats st;
  const rd::Contribution a = point(1.0, r1), b = point(1.0, r2);
  ASSERT_EQ(s.process(std::span(&a, 1), out, st), 1u);
  const double snr1 = out[0].snr;
  ASSERT_EQ(s.process(std::span(&b, 1), out, st), 1u);
  EXPECT_NEAR(db(snr1) - db(out[0].snr), 40.0 * std::log10(r2 / r1), 0.01);  // 12.05 dB
}

TEST(Sensor, DopplerCellOfAKnownSpeedAndFolding) {
  rd::Sensor s(config());
  const double dv = s.doppler_cell_mps(), vua = s.unambiguous_velocity_mps();
  std::vector<rd::Detection> out(8);
  for (double v : {-55.0, -70.0, 0.0, 12.3, 79.0}) {
    const rd::Contribution p = point(100.0, 1500.0, v);
    rd::SensorStats st;
    ASSERT_EQ(s.process(std::span(&p, 1), out, st), 1u);
    // Velocities are periodic in 2 v_ua: compare the wrapped difference (79 m/s sits in the
    // Nyquist cell, reported as -v_ua = -79.7 m/s, which is the same Doppler).
    const double diff = out[0].radial_velocity_mps - v;
    EXPECT_NEAR(diff - 2 * vua * std::round(diff / (2 * vua)), 0.0, dv / 2 + 1e-9) << v;
  }
  // Beyond v_ua the measured velocity folds by 2 v_ua: -85 m/s reads as -85 + 159.4 = 74.4.
  const rd::Contribution p = point(100.0, 1500.0, -85.0);
  rd::SensorStats st;
  ASSERT_EQ(s.process(std::span(&p, 1), out, st), 1u);
  EXPECT_NEAR(out[0].radial_velocity_mps, -85.0 + 2 * vua, dv / 2 + 1e-9);
}

TEST(Sensor, HomogeneousClutterGivesNoDetectionAndATargetAboveItIsFound) {
  rd::Sensor s(config());
  std::vector<rd::Contribution> in;
  for (int i = 100; i < 1500; ++i) {  // equal diffuse power in every range cell of one line
    rd::Contribution c = point(0.0, (i + 0.5) * s.range_cell_m(), -60.0);
    c.coherent = false;
    c.amplitude = {std::sqrt(5.0 * std::pow((i + 0.5) * s.range_cell_m() / 1000.0, 4)), 0.0};
    in.push_back(c);
  }
  std::vector<rd::Detection> out(16);
  rd::SensorStats st;
  EXPECT_EQ(s.process(in, out, st), 0u);
  // A point target 20 dB above the clutter cell at 2 km.
  const double r = (666 + 0.5) * s.range_cell_m();
  in.push_back(point(100.0 * 5.0 * std::pow(r / 1000.0, 4), r, -60.0));
  ASSERT_EQ(s.process(in, out, st), 1u);
  EXPECT_EQ(out[0].range_cell, 666u);
}

TEST(Sensor, PeakGroupingResolvesSeparatedTargetsAndMergesAdjacentOnes) {
  rd::Sensor s(config());
  const double dr = s.range_cell_m();
  std::vector<rd::Detection> out(16);
  rd::SensorStats st;
  const std::vector<rd::Contribution> apart = {point(50.0, 500.5 * dr), point(50.0, 503.5 * dr)};
  EXPECT_EQ(s.process(apart, out, st), 2u);
  const std::vector<rd::Contribution> adjacent = {point(50.0, 500.5 * dr), point(40.0, 501.5 * dr)};
  ASSERT_EQ(s.process(adjacent, out, st), 1u);
  EXPECT_EQ(out[0].range_cell, 500u);  // the stronger one
}

TEST(Sensor, ContributionsOutsideTheGridAreCountedNotDetected) {
  rd::Sensor s(config());
  std::vector<rd::Detection> out(8);
  rd::SensorStats st;
  const std::vector<rd::Contribution> in = {point(100.0, 7000.0), point(100.0, 1000.0, 0.0, 0.2),
                                            point(100.0, -5.0)};
  EXPECT_EQ(s.process(in, out, st), 0u);
  EXPECT_EQ(st.out_of_grid, 3u);
}

TEST(Sensor, InvalidConfigurationNamesTheField) {
  rd::SensorConfig c = config();
  c.bandwidth_hz = 0.0;
  try {
    rd::Sensor s(c);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bandwidth_hz"), std::string::npos);
  }
}
