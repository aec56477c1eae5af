// The sensor's frame path must not allocate (style.md: nothing in the frame path allocates):
// count every operator new over 300 frames of targets, clutter, noise, CFAR and monopulse, in
// both CFAR kinds and both waveforms. Its own executable: tests/alloc_counter.cpp replaces the
// global operator new.

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "radar/sensor/noise.hpp"
#include "radar/sensor/sensor.hpp"
#include "tests/alloc_counter.hpp"

namespace rd = radar_emu::radar;

TEST(SensorAllocation, NoHeapAllocationOverManyFrames) {
  for (rd::WaveformKind wk : {rd::WaveformKind::kPulsedLfm, rd::WaveformKind::kFmcw}) {
    for (rd::CfarKind ck : {rd::CfarKind::kCellAveraging, rd::CfarKind::kOrderStatistic}) {
      rd::SensorConfig c;
      rd::Waveform& w = c.processing.waveform;
      w.kind = wk;
      w.pulses = 32;
      w.range_bins = 128;
      if (wk == rd::WaveformKind::kFmcw) {
        w.carrier_hz = 77e9;
        w.bandwidth_hz = 100e6;
        w.pulse_width_s = 12.8e-6;
        w.pri_s = 15e-6;
      } else {
        w.swath_start_m = 400.0;
      }
      c.cfar.kind = ck;
      c.antenna.beam_azimuth_rad = {-0.02, 0.0, 0.02};
      c.antenna.azimuth = {rd::PatternKind::kGaussian, 0.02, {}, {}};
      c.max_contributions = 4096;
      rd::Sensor sensor(c);
      std::vector<rd::Contribution> in;
      rd::NoiseRng rng(11);
      const auto& p = sensor.processor();
      for (int i = 0; i < 300; ++i) {
        rd::Contribution x;
        x.coherent = i % 3 == 0;
        x.range_m = p.range_of_bin(120.0 * rng.uniform());
        x.range_spread_m = x.coherent ? 0.0 : 5.0 + 20.0 * rng.uniform();
        const double power = 1e-3 + rng.uniform();
        x.amplitude = std::polar(std::sqrt(power), 6.283 * rng.uniform());
        x.radial_velocity_mps = (rng.uniform() - 0.5) * 10.0;
        x.azimuth_rad = (rng.uniform() - 0.5) * 0.06;
        in.push_back(x);
      }
      std::vector<rd::Detection> out(64);
      rd::SensorStats stats;
      for (int f = 0; f < 5; ++f)  // warm-up: TBB's worker threads start on first use
        (void)sensor.process(in, out, stats);
      radar_emu::test::start_counting_allocations();
      std::size_t detections = 0;
      for (int f = 0; f < 300; ++f)
        detections += sensor.process(in, out, stats);
      EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u)
          << rd::waveform_name(wk) << (ck == rd::CfarKind::kCellAveraging ? " CA" : " OS");
      EXPECT_GT(detections, 0u);
    }
  }
}

// A captured frame (`run --cube`): the frame path's copies and the writer's completion of both
// cubes allocate nothing either (their storage and workspace are made at setup).
TEST(SensorAllocation, CaptureAndItsCompletionDoNotAllocate) {
  rd::SensorConfig c;
  c.processing.waveform.pulses = 32;
  c.processing.waveform.range_bins = 128;
  c.processing.waveform.swath_start_m = 400.0;
  c.antenna.beam_azimuth_rad = {-0.02, 0.0, 0.02};
  c.antenna.azimuth = {rd::PatternKind::kGaussian, 0.02, {}, {}};
  c.max_contributions = 4096;
  rd::Sensor sensor(c);
  const rd::CaptureShape shape = sensor.capture_shape();
  std::vector<std::complex<float>> image(shape.image_values()), raw(shape.raw_values());
  std::vector<float> power(shape.image_values());
  std::vector<rd::RowSpan> synthesised(shape.beams * shape.velocity_bins);
  std::vector<rd::FalseAlarm> alarms(shape.beams * 64);
  std::vector<std::uint32_t> alarm_count(shape.beams);
  std::vector<rd::CapturedReturn> returns(4096);
  rd::SensorCapture capture{image, power, synthesised, alarms, alarm_count, returns};
  const auto workspace = sensor.make_raw_workspace();
  std::vector<rd::Contribution> in;
  rd::NoiseRng rng(12);
  for (int i = 0; i < 300; ++i) {
    rd::Contribution x;
    x.coherent = i % 3 == 0;
    x.range_m = sensor.processor().range_of_bin(120.0 * rng.uniform());
    x.range_spread_m = x.coherent ? 0.0 : 5.0 + 20.0 * rng.uniform();
    x.amplitude = std::polar(1.0, 6.283 * rng.uniform());
    x.radial_velocity_mps = (rng.uniform() - 0.5) * 10.0;
    x.azimuth_rad = (rng.uniform() - 0.5) * 0.06;
    in.push_back(x);
  }
  std::vector<rd::Detection> out(64);
  rd::SensorStats stats;
  for (int f = 0; f < 3; ++f) {  // warm-up: TBB's worker threads start on first use
    sensor.capture_next(&capture);
    (void)sensor.process(in, out, stats);
    sensor.complete_image(capture);
    sensor.synthesise_raw(capture, raw, *workspace);
  }
  radar_emu::test::start_counting_allocations();
  for (int f = 0; f < 20; ++f) {
    sensor.capture_next(&capture);
    (void)sensor.process(in, out, stats);
    sensor.complete_image(capture);
    sensor.synthesise_raw(capture, raw, *workspace);
  }
  EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u);
  EXPECT_TRUE(capture.filled);
  EXPECT_GT(capture.return_count, 0u);
}
