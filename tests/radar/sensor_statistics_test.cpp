// The sensor's statistical noise cells against detection theory and against full synthesis:
// false alarms drawn for noise-only cells (Cfar2d::draw_false_alarms) have the design Pfa within
// its binomial confidence interval, and their amplitudes and noise estimates follow the same
// law as the crossings found in synthesised noise (two-sample Kolmogorov-Smirnov); the sensor's
// Pfa over more than 10^7 cells, and its Pd for Swerling 0 and 1 targets against the closed forms
// (Richards, Fundamentals of Radar Signal Processing, 2nd ed., 2014, secs. 6.3 and 6.5).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <vector>

#include "radar/sensor/cfar.hpp"
#include "radar/sensor/detection_theory.hpp"
#include "radar/sensor/noise.hpp"
#include "radar/sensor/sensor.hpp"

namespace rd = radar_emu::radar;

namespace {

constexpr double kPi = std::numbers::pi;

double from_db(double x) {
  return std::pow(10.0, x / 10.0);
}

// Two-sided 99.9 % interval of a binomial count (normal approximation, z = 3.29, plus one count
// of continuity): n p +- (3.29 sqrt(n p (1 - p)) + 1).
bool within_binomial(std::uint64_t count, double trials, double p) {
  const double mean = trials * p;
  return std::abs(static_cast<double>(count) - mean) <= 3.29 * std::sqrt(mean * (1.0 - p)) + 1.0;
}

// Two-sample Kolmogorov-Smirnov statistic D = sup |F_a - F_b|, and its 99.9 % critical value
// 1.95 sqrt((n + m) / (n m)) (Smirnov 1948; Massey, JASA 46(253), 1951, table 1).
double ks_statistic(std::vector<double> a, std::vector<double> b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  std::size_t i = 0, j = 0;
  double d = 0.0;
  while (i < a.size() && j < b.size()) {
    const double x = std::min(a[i], b[j]);
    while (i < a.size() && a[i] <= x)
      ++i;
    while (j < b.size() && b[j] <= x)
      ++j;
    d = std::max(d, std::abs(static_cast<double>(i) / static_cast<double>(a.size()) -
                             static_cast<double>(j) / static_cast<double>(b.size())));
  }
  return d;
}
double ks_critical(std::size_t n, std::size_t m) {
  const auto dn = static_cast<double>(n), dm = static_cast<double>(m);
  return 1.95 * std::sqrt((dn + dm) / (dn * dm));
}

struct Sample {
  std::uint64_t crossings = 0;
  double cells = 0.0;
  std::vector<double> peak_power, peak_noise;
};

// Crossings and local maxima (power above all 8 neighbours, velocity wrapping) of CFAR runs on
// synthesised unit exponential noise images: the reference.
Sample synthesised(rd::Cfar2d& cfar, std::size_t nr, std::size_t nv, int images,
                   std::uint64_t seed) {
  Sample s;
  rd::NoiseRng rng(seed);
  std::vector<double> power(nr * nv);
  std::vector<rd::CfarHit> hits(1 << 16);
  for (int im = 0; im < images; ++im) {
    for (double& p : power)
      p = -std::log(rng.uniform());
    std::uint64_t overflow = 0;
    const std::size_t n = cfar.detect(power, hits, overflow);
    EXPECT_EQ(overflow, 0u);
    s.crossings += n;
    s.cells += static_cast<double>(power.size());
    for (std::size_t h = 0; h < n; ++h) {
      const long l = hits[h].range_bin, j = hits[h].velocity_bin;
      bool peak = true;
      for (long dj = -1; dj <= 1; ++dj)
        for (long dl = -1; dl <= 1; ++dl) {
          const long jj = (j + dj + static_cast<long>(nv)) % static_cast<long>(nv), ll = l + dl;
          if ((dj || dl) && ll >= 0 && ll < static_cast<long>(nr) &&
              power[static_cast<std::size_t>(jj) * nr + static_cast<std::size_t>(ll)] >=
                  hits[h].power)
            peak = false;
        }
      if (peak) {
        s.peak_power.push_back(hits[h].power);
        s.peak_noise.push_back(hits[h].noise);
      }
    }
  }
  return s;
}

// The same image size with every cell drawn statistically (no cell under test on the image).
Sample drawn(rd::Cfar2d& cfar, std::size_t nr, std::size_t nv, int images, std::uint64_t seed) {
  Sample s;
  rd::NoiseRng rng(seed);
  const std::vector<rd::RowSpan> none(nv);
  std::vector<rd::FalseAlarm> alarms(4096);
  for (int im = 0; im < images; ++im) {
    std::uint64_t overflow = 0;
    const std::size_t n = cfar.draw_false_alarms(rng, none, alarms, s.crossings, overflow);
    EXPECT_EQ(overflow, 0u);
    s.cells += static_cast<double>(nr * nv);
    for (std::size_t i = 0; i < n; ++i) {
      s.peak_power.push_back(alarms[i].hit.power);
      s.peak_noise.push_back(alarms[i].hit.noise);
    }
  }
  return s;
}

}  // namespace

TEST(NoiseCells, DrawnFalseAlarmsFollowTheLawOfSynthesisedNoise) {
  const std::size_t nr = 1024, nv = 64;
  struct Case {
    const char* name;
    rd::CfarKind kind;
    int tr, gr, tv, gv;
  };
  const Case cases[] = {
      {"CA range-only (the default radar's)", rd::CfarKind::kCellAveraging, 12, 2, 0, 0},
      {"CA 2-D", rd::CfarKind::kCellAveraging, 8, 2, 4, 1},
      {"OS 2-D", rd::CfarKind::kOrderStatistic, 6, 1, 2, 1},
  };
  const std::uint64_t seed = 20261124;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  for (const Case& c : cases) {
    rd::CfarConfig cfg;
    cfg.kind = c.kind;
    cfg.pfa = 1e-4;
    cfg.range_training = c.tr;
    cfg.range_guard = c.gr;
    cfg.velocity_training = c.tv;
    cfg.velocity_guard = c.gv;
    rd::Cfar2d cfar(cfg, nr, nv);
    // >= 10^7 synthesised cells; 10^9 drawn ones (they cost a few draws an image).
    const Sample ref = synthesised(cfar, nr, nv, 160,
                                   rd::stream_key(seed, 1, c.kind == rd::CfarKind::kOrderStatistic,
                                                  static_cast<std::uint64_t>(c.tv)));
    const Sample st = drawn(cfar, nr, nv, 16000,
                            rd::stream_key(seed, 2, c.kind == rd::CfarKind::kOrderStatistic,
                                           static_cast<std::uint64_t>(c.tv)));
    // The design Pfa at every N (cells at the swath's ends have fewer training cells, and their
    // own threshold): the mean over the image's cells.
    double pfa_mean = 0.0;
    for (std::size_t l = 0; l < nr; ++l) {
      const long w = c.tr + c.gr;
      const long lo = std::max<long>(0, static_cast<long>(l) - w);
      const long hi = std::min<long>(static_cast<long>(nr) - 1, static_cast<long>(l) + w);
      const long glo = std::max<long>(0, static_cast<long>(l) - c.gr);
      const long ghi = std::min<long>(static_cast<long>(nr) - 1, static_cast<long>(l) + c.gr);
      const auto n = static_cast<std::size_t>((hi - lo + 1) * (2 * (c.tv + c.gv) + 1) -
                                              (ghi - glo + 1) * (2 * c.gv + 1));
      pfa_mean += cfar.pfa_of(n) / static_cast<double>(nr);
    }
    const double d_power = ks_statistic(ref.peak_power, st.peak_power);
    const double d_noise = ks_statistic(ref.peak_noise, st.peak_noise);
    const double crit = ks_critical(ref.peak_power.size(), st.peak_power.size());
    const double peak_ref =
        static_cast<double>(ref.peak_power.size()) / static_cast<double>(ref.crossings);
    const double peak_st =
        static_cast<double>(st.peak_power.size()) / static_cast<double>(st.crossings);
    std::printf(
        "%s: synthesised Pfa %.4g over %.3g cells, drawn %.4g over %.3g cells (design %.4g); "
        "local maxima %.3f / %.3f of crossings; KS D power %.4f, noise estimate %.4f "
        "(99.9 %% critical %.4f)\n",
        c.name, static_cast<double>(ref.crossings) / ref.cells, ref.cells,
        static_cast<double>(st.crossings) / st.cells, st.cells, pfa_mean, peak_ref, peak_st,
        d_power, d_noise, crit);
    EXPECT_GE(ref.cells, 1e7);
    EXPECT_TRUE(within_binomial(ref.crossings, ref.cells, pfa_mean)) << c.name;
    EXPECT_TRUE(within_binomial(st.crossings, st.cells, pfa_mean)) << c.name;
    EXPECT_LT(d_power, crit) << c.name;
    EXPECT_LT(d_noise, crit) << c.name;
    // The fraction of crossings that are local maxima: binomial over the reference's crossings.
    EXPECT_TRUE(within_binomial(ref.peak_power.size(), static_cast<double>(ref.crossings), peak_st))
        << c.name;
  }
}

namespace {

// One beam on boresight, range-only CA-CFAR as the default scenario's, 256 x 32 cells.
rd::SensorConfig one_beam(double pfa) {
  rd::SensorConfig c;
  rd::Waveform& w = c.processing.waveform;
  w.kind = rd::WaveformKind::kPulsedLfm;
  w.carrier_hz = 94e9;
  w.bandwidth_hz = 50e6;
  w.pulse_width_s = 2e-6;
  w.pri_s = 50e-6;
  w.pulses = 32;
  w.range_bins = 256;
  w.swath_start_m = 1000.0;
  c.processing.range_window.kind = rd::WindowKind::kHann;
  c.processing.doppler_window.kind = rd::WindowKind::kHann;
  c.antenna.beam_azimuth_rad = {0.0};
  c.antenna.azimuth = {rd::PatternKind::kGaussian, 0.0175, {}, {}};
  c.antenna.elevation = {rd::PatternKind::kGaussian, 0.14, {}, {}};
  c.antenna.peak_gain = 3000.0;
  c.antenna.monopulse = false;
  c.cfar.pfa = pfa;
  c.cfar.range_training = 12;
  c.cfar.range_guard = 2;
  c.cfar.velocity_training = 0;
  c.cfar.velocity_guard = 0;
  c.min_snr_db = -60.0;  // every CFAR peak: Pd and Pfa are the CFAR's
  c.max_detections = 256;
  return c;
}

}  // namespace

TEST(NoiseCells, SensorFalseAlarmRateOverTenMillionCellsWithAndWithoutSynthesis) {
  // Frames without returns: the sparse sensor draws every cell; the reference synthesises them.
  for (bool synthesise : {false, true}) {
    rd::SensorConfig c = one_beam(1e-4);
    c.synthesise_every_cell = synthesise;
    c.noise_seed = 777;
    rd::Sensor sensor(c);
    std::vector<rd::Detection> out(256);
    rd::SensorStats stats;
    std::uint64_t detections = 0;
    const int frames = 1300;  // 1300 x 8192 = 1.06e7 cells
    for (int f = 0; f < frames; ++f)
      detections += sensor.process({}, out, stats);
    const auto cells = static_cast<double>(stats.cells_touched);
    std::printf(
        "%s, seed %llu: %llu crossings in %.4g cells: Pfa %.4g (design 1e-4), %llu local "
        "maxima, %llu cells synthesised\n",
        synthesise ? "synthesised" : "drawn", static_cast<unsigned long long>(c.noise_seed),
        static_cast<unsigned long long>(stats.cfar_crossings), cells,
        static_cast<double>(stats.cfar_crossings) / cells,
        static_cast<unsigned long long>(detections),
        static_cast<unsigned long long>(stats.cells_synthesised));
    EXPECT_GE(cells, 1e7);
    // Mean Pfa over the image: cells within 14 bins of the swath's ends have fewer training
    // cells and their own exact threshold, so the design value holds for every cell (CA).
    EXPECT_TRUE(within_binomial(stats.cfar_crossings, cells, 1e-4));
    EXPECT_EQ(stats.cells_synthesised, synthesise ? stats.cells_touched : 0u);
  }
}

TEST(NoiseCells, SensorProbabilityOfDetectionFollowsSwerling0And1) {
  // An on-grid point target on boresight at a known image SNR, among drawn noise cells; Pd is
  // the fraction of frames with a detection in its cell, against the closed forms for CA-CFAR
  // with the window's N = 24 training cells.
  rd::SensorConfig c = one_beam(1e-6);
  c.noise_seed = 4243;
  rd::Sensor sensor(c);
  const rd::RangeDopplerProcessor& p = sensor.processor();
  const std::size_t n_train = 24;
  const double r = p.range_of_bin(128.0);
  std::vector<rd::Detection> out(256);
  rd::SensorStats stats;
  rd::NoiseRng fluct(rd::stream_key(4243, 1));
  std::printf("noise seed %llu, fluctuation seed 4243/1\n",
              static_cast<unsigned long long>(c.noise_seed));
  for (int swerling : {0, 1}) {
    const std::vector<double> snrs_db =
        swerling == 0 ? std::vector<double>{11, 12, 13, 14} : std::vector<double>{10, 15, 20};
    for (double snr_db : snrs_db) {
      const double snr = from_db(snr_db);
      const double sigma = snr / sensor.expected_snr(1.0, r);
      int hit = 0;
      const int frames = 1500;
      for (int f = 0; f < frames; ++f) {
        rd::Contribution t;
        t.range_m = r;
        t.object_id = 7;
        t.amplitude = swerling == 0 ? std::polar(std::sqrt(sigma), 2.0 * kPi * fluct.uniform())
                                    : fluct.complex_normal() * std::sqrt(sigma);
        const std::size_t n = sensor.process(std::span(&t, 1), out, stats);
        for (std::size_t i = 0; i < n; ++i)
          if (out[i].range_cell == 128 && out[i].doppler_cell == p.velocity_bins() / 2) {
            ++hit;
            EXPECT_EQ(out[i].object_id, 7u);
            break;
          }
      }
      const double pd = static_cast<double>(hit) / frames;
      const double theory = swerling == 0 ? rd::pd_swerling0_ca(snr, n_train, 1e-6)
                                          : rd::pd_swerling1_ca(snr, n_train, 1e-6);
      const double sd = std::sqrt(theory * (1.0 - theory) / frames);
      std::printf("Swerling %d, SNR %4.1f dB: Pd %.3f over %d frames, theory %.3f (sd %.3f)\n",
                  swerling, snr_db, pd, frames, theory, sd);
      // 4 standard deviations plus 0.02 for the Hann range sidelobes (-31 dB) in the training
      // cells and the interpolation of the direct path.
      EXPECT_NEAR(pd, theory, 4.0 * sd + 0.02) << "Swerling " << swerling << " SNR " << snr_db;
    }
  }
}

TEST(NoiseCells, DetectionsNameTheObjectThatDominatesTheirCell) {
  rd::SensorConfig c = one_beam(1e-6);
  rd::Sensor sensor(c);
  const rd::RangeDopplerProcessor& p = sensor.processor();
  std::vector<rd::Contribution> in;
  // Two rays of object 3 adding coherently at one cell, one weak ray of object 5 there too, and
  // object 9 alone 40 bins away.
  const double sigma = 100.0 / sensor.expected_snr(1.0, p.range_of_bin(60.0));
  for (std::uint32_t id : {3u, 3u, 5u}) {
    rd::Contribution t;
    t.range_m = p.range_of_bin(60.0);
    t.amplitude = std::sqrt(id == 5u ? 0.01 * sigma : sigma) * std::complex<double>{1.0, 0.0};
    t.object_id = id;
    in.push_back(t);
  }
  rd::Contribution far;
  far.range_m = p.range_of_bin(100.0);
  far.amplitude = std::sqrt(sigma);
  far.object_id = 9;
  in.push_back(far);
  std::vector<rd::Detection> out(16);
  rd::SensorStats stats;
  const std::size_t n = sensor.process(in, out, stats);
  ASSERT_GE(n, 2u);
  for (std::size_t i = 0; i < n; ++i) {
    if (out[i].range_cell == 60)
      EXPECT_EQ(out[i].object_id, 3u);
    else if (out[i].range_cell == 100)
      EXPECT_EQ(out[i].object_id, 9u);
    else
      EXPECT_EQ(out[i].object_id, rd::kNoObject);  // a false alarm: noise
  }
}

// The ziggurat's exponential variates (NoiseRng::exponential, used for the noise-only cells)
// against the unit exponential law: every layer of the table has the area v (Marsaglia and Tsang
// 2000, the method's definition); the mean and variance are 1; P(X > t) = exp(-t) at points
// inside the layers, at the base layer's edge r and in the tail beyond it (within 5 binomial
// standard deviations); and the one-sample Kolmogorov-Smirnov distance to 1 - exp(-x) is below
// its 1 % critical value 1.628 / sqrt(n) (Stephens 1970).
TEST(NoiseRng, ZigguratExponentialFollowsTheExponentialLaw) {
  const rd::ExponentialZiggurat z;
  constexpr double v = rd::ExponentialZiggurat::kV;
  EXPECT_NEAR(z.x[0] * z.f[1], v, 1e-9 * v);  // base layer: the rectangle plus the tail
  for (int i = 1; i < rd::ExponentialZiggurat::kLayers; ++i)
    EXPECT_NEAR(z.x[i] * (z.f[i + 1] - z.f[i]), v, 1e-9 * v) << "layer " << i;

  constexpr std::uint64_t seed = 20261128;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  rd::NoiseRng rng(seed);
  constexpr std::size_t n = 4'000'000;
  std::vector<double> x(n);
  double sum = 0.0, sum2 = 0.0;
  for (double& e : x) {
    e = rng.exponential(z);
    ASSERT_GE(e, 0.0);
    sum += e;
    sum2 += e * e;
  }
  const auto nd = static_cast<double>(n);
  const double mean = sum / nd, var = sum2 / nd - mean * mean;
  EXPECT_NEAR(mean, 1.0, 5.0 / std::sqrt(nd));       // sd of the mean 1 / sqrt(n)
  EXPECT_NEAR(var, 1.0, 5.0 * std::sqrt(8.0 / nd));  // mu4 - sigma^4 = 9 - 1
  std::sort(x.begin(), x.end());
  for (double t :
       {0.01, 0.1, 0.5, 1.0, 2.0, 4.0, 7.0, rd::ExponentialZiggurat::kR, 8.0, 10.0, 12.0}) {
    const double p = std::exp(-t);
    const double frac = static_cast<double>(x.end() - std::upper_bound(x.begin(), x.end(), t)) / nd;
    EXPECT_NEAR(frac, p, 5.0 * std::sqrt(p * (1.0 - p) / nd) + 1.0 / nd) << "P(X > " << t << ")";
  }
  double d = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double cdf = 1.0 - std::exp(-x[i]);
    d = std::max({d, static_cast<double>(i + 1) / nd - cdf, cdf - static_cast<double>(i) / nd});
  }
  std::printf("KS distance %.3g (1 %% critical %.3g)\n", d, 1.628 / std::sqrt(nd));
  EXPECT_LT(d, 1.628 / std::sqrt(nd));
}
