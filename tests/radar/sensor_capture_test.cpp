// The sensor's capture of a frame (SensorCapture, `run --cube`, docs/cube.md): the raw samples
// against the exact sample-by-sample synthesis and against the sensor's own image, receiver
// noise at its closed-form power in both cubes, and a capture that changes no detection.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "radar/sensor/capture_storage.hpp"
#include "radar/sensor/noise.hpp"
#include "radar/sensor/range_doppler.hpp"
#include "radar/sensor/sensor.hpp"
#include "radar/sensor/waveform.hpp"

namespace rd = radar_emu::radar;

namespace {

constexpr double kC = 299792458.0;
using cd = std::complex<double>;

rd::Waveform pulsed() {
  rd::Waveform w;
  w.kind = rd::WaveformKind::kPulsedLfm;
  w.carrier_hz = 94e9;
  w.bandwidth_hz = 50e6;
  w.pulse_width_s = 2e-6;
  w.pri_s = 50e-6;
  w.pulses = 16;
  w.range_bins = 128;
  w.swath_start_m = 1000.0;
  return w;
}

// Storage for one captured frame, as loop/outputs/cube_writer.cpp allocates a slot.
struct Storage : rd::CaptureStorage {
  explicit Storage(const rd::Sensor& sensor)
      : rd::CaptureStorage(sensor.capture_shape(), 64, 4096),
        shape(sensor.capture_shape()),
        raw(shape.raw_values()),
        workspace(sensor.make_raw_workspace()) {}
  rd::CaptureShape shape;
  std::vector<std::complex<float>> raw;
  std::unique_ptr<rd::Sensor::RawWorkspace> workspace;
};

rd::SensorConfig three_beams() {
  rd::SensorConfig c;
  c.processing.waveform = pulsed();
  c.antenna.beam_azimuth_rad = {-0.02, 0.0, 0.02};
  c.antenna.azimuth = {rd::PatternKind::kGaussian, 0.02, {}, {}};
  c.max_contributions = 4096;
  return c;
}

}  // namespace

// Delays on the synthesiser's grid (1/8 of a sample, no Doppler): it reproduces the exact
// sample-by-sample synthesis (RangeDopplerProcessor::synthesize_cube) to float precision.
TEST(RawSynthesiser, OnItsDelayGridEqualsTheExactSynthesis) {
  rd::ProcessingConfig cfg;
  cfg.waveform = pulsed();
  rd::RangeDopplerProcessor p(cfg);
  const double fs = rd::fast_sample_rate_hz(cfg.waveform);
  const double t0 = 2.0 * cfg.waveform.swath_start_m / kC;
  std::vector<rd::PointScatterer> s;
  for (int i = 0; i < 5; ++i) {
    const double samples = 10.0 + 23.0 * i + 0.125 * i;  // 1/8-sample steps
    s.push_back({std::polar(1.0 + i, 0.7 * i), 0.5 * kC * (t0 + samples / fs), 0.0});
  }
  std::vector<cd> exact(p.cube_samples());
  p.synthesize_cube(s, exact);
  rd::RangeDopplerProcessor::RawSynthesiser synth(p, 1);
  std::vector<std::complex<float>> raw(p.cube_samples());
  const double gain = 1.0;
  for (const auto& x : s)
    synth.add(x, std::span(&gain, 1));
  synth.render(raw);
  double worst = 0.0, peak = 0.0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    worst = std::max(worst, std::abs(cd(raw[i]) - exact[i]));
    peak = std::max(peak, std::abs(exact[i]));
  }
  std::printf("on the grid: worst difference %.2e of the peak sample\n", worst / peak);
  EXPECT_LT(worst / peak, 1e-5);
}

// Anywhere (random delays and velocities, seed printed): after processing, the synthesiser's
// echoes match the exact ones around each peak within what a delay rounded by at most 1/16 of a
// sample changes (0.06 of the peak on the response's steepest slope), on the same peak cell.
TEST(RawSynthesiser, AnywhereMatchesTheExactSynthesisAfterProcessing) {
  std::mt19937_64 rng(20261127);
  std::printf("seed 20261127\n");
  std::uniform_real_distribution<double> u(0.0, 1.0);
  rd::ProcessingConfig cfg;
  cfg.waveform = pulsed();
  rd::RangeDopplerProcessor p(cfg);
  rd::RangeDopplerProcessor::RawSynthesiser synth(p, 1);
  const double v_ua = rd::unambiguous_velocity_mps(cfg.waveform);
  double worst = 0.0;
  for (int i = 0; i < 8; ++i) {
    // Slow (0.02 v_ua): the exact synthesis has range walk, the synthesiser does not.
    const rd::PointScatterer s{std::polar(1.0, 6.283 * u(rng)),
                               p.range_of_bin(20.0 + 80.0 * u(rng)), (u(rng) - 0.5) * 0.04 * v_ua};
    std::vector<cd> cube(p.cube_samples()), exact(p.image_cells()), mine(p.image_cells());
    p.synthesize_cube(std::span(&s, 1), cube);
    p.process_cube(cube, exact);
    std::vector<std::complex<float>> raw(p.cube_samples());
    const double gain = 1.0;
    synth.clear();
    synth.add(s, std::span(&gain, 1));
    synth.render(raw);
    std::vector<cd> raw_d(raw.begin(), raw.end());
    p.process_cube(raw_d, mine);
    auto argmax = [](const std::vector<cd>& v) {
      return static_cast<std::size_t>(
          std::max_element(v.begin(), v.end(),
                           [](const cd& a, const cd& b) { return std::abs(a) < std::abs(b); }) -
          v.begin());
    };
    const std::size_t k = argmax(exact);
    EXPECT_EQ(argmax(mine), k) << "scatterer " << i;
    const double peak = std::abs(exact[k]);
    for (std::size_t c = 0; c < exact.size(); ++c)
      worst = std::max(worst, std::abs(mine[c] - exact[c]) / peak);
  }
  std::printf("anywhere: worst difference after processing %.3f of the peak\n", worst);
  EXPECT_LT(worst, 0.06);
}

// A strong point on a beam's boresight, receiver noise off: the raw Sigma samples processed as
// the sensor processes a cube (RangeDopplerProcessor::process_cube) peak on the captured
// image's peak cell at the same power (the image is the sensor's direct path: two independent
// routes to one cell).
TEST(SensorCapture, RawSamplesProcessedGiveTheCapturedImage) {
  rd::SensorConfig c = three_beams();
  c.thermal_noise = false;
  rd::Sensor sensor(c);
  Storage st(sensor);
  rd::Contribution x;
  x.amplitude = {3e3, 0.0};
  x.range_m = sensor.processor().range_of_bin(61.3);
  x.radial_velocity_mps = 1.7;
  x.azimuth_rad = 0.0;
  std::vector<rd::Detection> out(8);
  rd::SensorStats stats;
  sensor.capture_next(&st.capture);
  const std::size_t n = sensor.process(std::span(&x, 1), out, stats);
  ASSERT_TRUE(st.capture.filled);
  ASSERT_GE(n, 1u);
  sensor.complete_image(st.capture);
  sensor.synthesise_raw(st.capture, st.raw, *st.workspace);
  const rd::CaptureShape& sh = st.shape;
  const std::size_t beam = 1, per_beam = sh.channels * sh.pulses * sh.fast_samples;
  std::vector<cd> sigma(
      st.raw.begin() + static_cast<long>(beam * per_beam),
      st.raw.begin() + static_cast<long>(beam * per_beam + sh.pulses * sh.fast_samples));
  rd::RangeDopplerProcessor p(c.processing);
  std::vector<cd> processed(p.image_cells());
  p.process_cube(sigma, processed);
  const std::size_t cells = sh.velocity_bins * sh.range_bins;
  std::size_t k_img = 0, k_raw = 0;
  for (std::size_t k = 0; k < cells; ++k) {
    if (std::norm(st.image[beam * cells + k]) > std::norm(st.image[beam * cells + k_img]))
      k_img = k;
    if (std::norm(processed[k]) > std::norm(processed[k_raw]))
      k_raw = k;
  }
  EXPECT_EQ(k_raw, k_img);
  EXPECT_EQ(k_img, out[0].doppler_cell * sh.range_bins + out[0].range_cell);
  const double ratio_db = 10.0 * std::log10(std::norm(processed[k_raw]) /
                                            std::norm(cd(st.image[beam * cells + k_img])));
  std::printf("raw processed against the image at the peak: %+.3f dB\n", ratio_db);
  EXPECT_LT(std::abs(ratio_db), 0.5);
}

// An empty frame: every cell of both cubes is receiver noise, mean power 1 (the image's
// normalisation; one sample's variance in the raw samples), within 4 standard errors.
TEST(SensorCapture, NoiseHasUnitPowerInBothCubes) {
  rd::Sensor sensor(three_beams());
  Storage st(sensor);
  std::vector<rd::Detection> out(64);
  rd::SensorStats stats;
  sensor.capture_next(&st.capture);
  (void)sensor.process({}, out, stats);
  ASSERT_TRUE(st.capture.filled);
  sensor.complete_image(st.capture);
  sensor.synthesise_raw(st.capture, st.raw, *st.workspace);
  auto mean_power = [](const std::vector<std::complex<float>>& v) {
    double s = 0.0;
    for (const auto& x : v)
      s += std::norm(cd(x));
    return s / static_cast<double>(v.size());
  };
  const double image = mean_power(st.image), raw = mean_power(st.raw);
  std::printf("mean power: image %.4f (%zu cells), raw %.4f (%zu samples)\n", image,
              st.image.size(), raw, st.raw.size());
  EXPECT_NEAR(image, 1.0, 4.0 / std::sqrt(static_cast<double>(st.image.size())));
  EXPECT_NEAR(raw, 1.0, 4.0 / std::sqrt(static_cast<double>(st.raw.size())));
}

// Capturing changes nothing the sensor reports: the same frames with and without a capture
// armed give the same detections, bit for bit.
TEST(SensorCapture, ChangesNoDetection) {
  const rd::SensorConfig c = three_beams();
  rd::Sensor plain(c), capturing(c);
  Storage st(capturing);
  rd::NoiseRng rng(5);
  std::vector<rd::Contribution> in;
  for (int i = 0; i < 200; ++i) {
    rd::Contribution x;
    x.coherent = i % 4 == 0;
    x.range_m = plain.processor().range_of_bin(120.0 * rng.uniform());
    x.range_spread_m = x.coherent ? 0.0 : 10.0 * rng.uniform();
    x.amplitude = std::polar(x.coherent ? 300.0 : 30.0, 6.283 * rng.uniform());
    x.radial_velocity_mps = (rng.uniform() - 0.5) * 10.0;
    x.azimuth_rad = (rng.uniform() - 0.5) * 0.06;
    in.push_back(x);
  }
  std::vector<rd::Detection> a(64), b(64);
  rd::SensorStats sa, sb;
  for (int f = 0; f < 4; ++f) {
    capturing.capture_next(&st.capture);
    const std::size_t na = plain.process(in, a, sa), nb = capturing.process(in, b, sb);
    ASSERT_TRUE(st.capture.filled);
    ASSERT_EQ(na, nb) << "frame " << f;
    EXPECT_GT(na, 0u);
    for (std::size_t i = 0; i < na; ++i) {
      EXPECT_EQ(a[i].range_m, b[i].range_m);
      EXPECT_EQ(a[i].radial_velocity_mps, b[i].radial_velocity_mps);
      EXPECT_EQ(a[i].azimuth_rad, b[i].azimuth_rad);
      EXPECT_EQ(a[i].snr, b[i].snr);
    }
  }
}

// A Gaussian azimuth pattern on evenly spaced beams (the sensor takes each return's gains across
// beams by a recurrence): the captured peak power of an on-grid point target in each of nine
// beams, relative to the beam nearest it, equals the closed-form two-way pattern ratio
// (Sensor::two_way_gain, the antenna's direct formula), with and without monopulse, to the
// float image's precision.
TEST(SensorCapture, GaussianGainsAcrossEvenlySpacedBeamsFollowTheDirectPattern) {
  for (const bool monopulse : {true, false}) {
    rd::SensorConfig c = three_beams();
    c.antenna.monopulse = monopulse;
    c.antenna.beam_azimuth_rad.clear();
    for (int b = 0; b < 9; ++b)
      c.antenna.beam_azimuth_rad.push_back(-0.04 + 0.01 * b);
    c.thermal_noise = false;
    rd::Sensor sensor(c);
    Storage st(sensor);
    rd::Contribution x;
    x.amplitude = {3e3, 0.0};
    x.range_m = sensor.processor().range_of_bin(61.0);
    x.azimuth_rad = 0.0137;
    std::vector<rd::Detection> out(8);
    rd::SensorStats stats;
    sensor.capture_next(&st.capture);
    ASSERT_GE(sensor.process(std::span(&x, 1), out, stats), 1u);
    ASSERT_TRUE(st.capture.filled);
    const rd::CaptureShape& sh = st.shape;
    const std::size_t cells = sh.velocity_bins * sh.range_bins, ref = 5;  // beam at 0.01 rad
    std::size_t k = 0;
    for (std::size_t i = 0; i < cells; ++i)
      if (st.capture.power[ref * cells + i] > st.capture.power[ref * cells + k])
        k = i;
    const std::size_t j = k / sh.range_bins, l = k % sh.range_bins;
    EXPECT_EQ(l, 61u);
    const double g_ref = sensor.two_way_gain(x.azimuth_rad - c.antenna.beam_azimuth_rad[ref], 0.0);
    int checked = 0;
    for (std::size_t b = 0; b < 9; ++b) {
      const rd::RowSpan sp = st.capture.synthesised[b * sh.velocity_bins + j];
      if (sp.empty() || l < sp.begin || l >= sp.end)
        continue;
      const double ratio = static_cast<double>(st.capture.power[b * cells + k]) /
                           static_cast<double>(st.capture.power[ref * cells + k]);
      const double expected =
          sensor.two_way_gain(x.azimuth_rad - c.antenna.beam_azimuth_rad[b], 0.0) / g_ref;
      EXPECT_NEAR(ratio, expected, 1e-5 * expected) << "beam " << b << " monopulse " << monopulse;
      ++checked;
    }
    std::printf("monopulse %d: %d beams checked against the direct pattern\n", monopulse ? 1 : 0,
                checked);
    EXPECT_GE(checked, 5);
  }
}
