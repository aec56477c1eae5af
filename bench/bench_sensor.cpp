// The radar sensor's cost (issue 5): one 256 x 128 range-Doppler frame with CFAR on one core
// (goal: 5 ms or less), the exact data-cube path for comparison, and the CFAR variants alone.
// Run: build/bench/bench_sensor --benchmark_repetitions=3 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <complex>
#include <vector>

#include "radar/sensor/cfar.hpp"
#include "radar/sensor/noise.hpp"
#include "radar/sensor/range_doppler.hpp"
#include "radar/sensor/sensor.hpp"

namespace rd = radar_emu::radar;

namespace {

rd::SensorConfig frame_config(rd::CfarKind kind) {
  rd::SensorConfig c;
  rd::Waveform& w = c.processing.waveform;
  w.kind = rd::WaveformKind::kPulsedLfm;
  w.carrier_hz = 94e9;
  w.bandwidth_hz = 50e6;
  w.pulse_width_s = 2e-6;
  w.pri_s = 20e-6;
  w.pulses = 128;
  w.range_bins = 256;
  w.swath_start_m = 500.0;
  c.antenna.beam_azimuth_rad = {0.0};
  c.antenna.azimuth = {rd::PatternKind::kGaussian, 0.035, {}, {}};
  c.antenna.elevation = {rd::PatternKind::kGaussian, 0.14, {}, {}};
  c.antenna.peak_gain = 3000.0;
  c.tx_power_w = 100.0;
  c.cfar.kind = kind;
  return c;
}

// 20 point targets and 2000 clutter footprints spread over the swath, fixed seed.
std::vector<rd::Contribution> scene(const rd::Sensor& s) {
  std::vector<rd::Contribution> out;
  rd::NoiseRng rng(20261123);
  const auto& p = s.processor();
  for (int i = 0; i < 20; ++i) {
    rd::Contribution c;
    c.range_m = p.range_of_bin(10.0 + 236.0 * rng.uniform());
    c.amplitude = std::polar(std::sqrt(1.0 + 100.0 * rng.uniform()), 6.283 * rng.uniform());
    c.radial_velocity_mps = (rng.uniform() - 0.5) * 30.0;
    c.azimuth_rad = (rng.uniform() - 0.5) * 0.03;
    out.push_back(c);
  }
  for (int i = 0; i < 2000; ++i) {
    rd::Contribution c;
    c.coherent = false;
    c.range_m = p.range_of_bin(256.0 * rng.uniform());
    c.range_spread_m = 10.0 + 40.0 * rng.uniform();
    c.amplitude = {std::sqrt(0.01 * rng.uniform()), 0.0};
    c.radial_velocity_mps = -5.0 + rng.uniform();
    c.azimuth_rad = (rng.uniform() - 0.5) * 0.06;
    c.elevation_rad = -0.03;
    out.push_back(c);
  }
  return out;
}

void BM_RangeDopplerFrameWithCfar(benchmark::State& state) {
  tbb::global_control one_core(tbb::global_control::max_allowed_parallelism, 1);
  const auto kind =
      state.range(0) == 0 ? rd::CfarKind::kCellAveraging : rd::CfarKind::kOrderStatistic;
  rd::Sensor sensor(frame_config(kind));
  const std::vector<rd::Contribution> in = scene(sensor);
  std::vector<rd::Detection> out(64);
  rd::SensorStats stats;
  std::size_t n = 0;
  for (auto _ : state) {
    n = sensor.process(in, out, stats);
    benchmark::DoNotOptimize(n);
  }
  state.counters["cells"] = static_cast<double>(sensor.processor().image_cells());
  state.counters["contributions"] = static_cast<double>(in.size());
  state.counters["detections"] = static_cast<double>(n);
  state.SetLabel(kind == rd::CfarKind::kCellAveraging ? "direct synthesis, CA-CFAR, one core"
                                                      : "direct synthesis, OS-CFAR, one core");
}
BENCHMARK(BM_RangeDopplerFrameWithCfar)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_ExactCubeOneTarget(benchmark::State& state) {
  rd::RangeDopplerProcessor p(frame_config(rd::CfarKind::kCellAveraging).processing);
  std::vector<std::complex<double>> cube(p.cube_samples()), image(p.image_cells());
  const rd::PointScatterer t{{1.0, 0.0}, p.range_of_bin(100.3), 7.0};
  for (auto _ : state) {
    std::fill(cube.begin(), cube.end(), std::complex<double>{0.0, 0.0});
    p.synthesize_cube(std::span(&t, 1), cube);
    p.process_cube(cube, image);
    benchmark::DoNotOptimize(image.data());
  }
  state.SetLabel("synthesise 128 pulses x 355 samples, matched filter + Doppler FFT (FFTW)");
}
BENCHMARK(BM_ExactCubeOneTarget)->Unit(benchmark::kMillisecond);

void BM_ProcessCubeOnly(benchmark::State& state) {
  rd::RangeDopplerProcessor p(frame_config(rd::CfarKind::kCellAveraging).processing);
  std::vector<std::complex<double>> cube(p.cube_samples()), image(p.image_cells());
  rd::NoiseRng rng(1);
  for (auto& x : cube)
    x = rng.complex_normal();
  for (auto _ : state) {
    p.process_cube(cube, image);
    benchmark::DoNotOptimize(image.data());
  }
  state.SetLabel("range compression + Doppler FFT of a 256 x 128 image (FFTW)");
}
BENCHMARK(BM_ProcessCubeOnly)->Unit(benchmark::kMillisecond);

void BM_Cfar(benchmark::State& state) {
  rd::CfarConfig c;
  c.kind = state.range(0) == 0 ? rd::CfarKind::kCellAveraging : rd::CfarKind::kOrderStatistic;
  rd::Cfar2d cfar(c, 256, 128);
  std::vector<double> power(256 * 128);
  rd::NoiseRng rng(2);
  for (double& x : power)
    x = std::norm(rng.complex_normal());
  std::vector<rd::CfarHit> hits(4096);
  std::uint64_t overflow = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(cfar.detect(power, hits, overflow));
  state.counters["training_cells"] = static_cast<double>(cfar.training_cells());
  state.SetLabel(c.kind == rd::CfarKind::kCellAveraging ? "CA, summed-area table" : "OS, k = 3N/4");
}
BENCHMARK(BM_Cfar)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
