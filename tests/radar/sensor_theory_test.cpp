// Closed forms of the sensor model against published numbers and independent computations:
// detection theory (Marcum Q, Swerling 0/1, CA/OS-CFAR factors), CFAR false-alarm rate and
// probability of detection by Monte Carlo at fixed seeds, the ambiguity function, and antenna
// patterns (line-source beamwidths and sidelobes, Gaussian monopulse ratio, gain).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "radar/antenna/antenna.hpp"
#include "radar/sensor/cfar.hpp"
#include "radar/sensor/detection_theory.hpp"
#include "radar/sensor/noise.hpp"
#include "radar/sensor/range_doppler.hpp"
#include "radar/sensor/waveform.hpp"
#include "radar/sensor/window.hpp"

namespace rd = radar_emu::radar;

namespace {
constexpr double kPi = std::numbers::pi;
double from_db(double x) {
  return std::pow(10.0, x / 10.0);
}
}  // namespace

// Reference numbers computed with mpmath (50-bit) from the closed forms, and the book example of
// Richards 2014, sec. 6.5.6 (docs/notes/sensor_theory_reference.md, tables in secs. 3-4).
TEST(DetectionTheory, MatchesIndependentlyComputedTables) {
  EXPECT_NEAR(rd::ca_cfar_alpha(16, 1e-6), 21.942, 1e-3);
  EXPECT_NEAR(rd::ca_cfar_alpha(32, 1e-6), 17.278, 1e-3);
  EXPECT_NEAR(rd::os_cfar_pfa(20, 15, 6.857), 9.987e-4, 2e-6);  // Richards' example: 1e-3
  EXPECT_NEAR(rd::os_cfar_alpha(16, 12, 1e-6), 20.954, 2e-3);
  EXPECT_NEAR(rd::os_cfar_alpha(32, 24, 1e-6), 14.399, 2e-3);
  const struct {
    double snr_db, sw0, sw1;
  } table[] = {
      {10, 0.2480, 0.2848}, {12, 0.6794, 0.4404}, {13, 0.8744, 0.5172}, {14, 0.9721, 0.5892}};
  for (const auto& t : table) {
    EXPECT_NEAR(rd::pd_swerling0(from_db(t.snr_db), 1e-6), t.sw0, 1e-4) << t.snr_db;
    EXPECT_NEAR(rd::pd_swerling1(from_db(t.snr_db), 1e-6), t.sw1, 1e-4) << t.snr_db;
  }
  // Swerling 1 with CA-CFAR: SNR for Pd 0.9 at N = 16 is 23.15 dB (table, sec. 3.1).
  EXPECT_NEAR(rd::pd_swerling1_ca(from_db(23.15), 16, 1e-6), 0.9, 2e-3);
  // Marcum Q limits: Q1(0, b) = exp(-b^2 / 2).
  EXPECT_NEAR(rd::marcum_q1(0.0, 3.0), std::exp(-4.5), 1e-12);
  // CA-CFAR loss vanishes as N grows: SW0 with N = 4096 approaches the known-noise Pd.
  EXPECT_NEAR(rd::pd_swerling0_ca(from_db(13), 4096, 1e-6), rd::pd_swerling0(from_db(13), 1e-6),
              0.01);
}

namespace {
// Noise-only power image of unit mean (independent cells).
void noise_image(rd::NoiseRng& rng, std::vector<double>& power) {
  for (double& p : power)
    p = std::norm(rng.complex_normal());
}
}  // namespace

TEST(Cfar, FalseAlarmRateWithinFactorTwoOfDesignOverMillionsOfCells) {
  const std::uint64_t seed = 20261123;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const std::size_t nr = 1024, nv = 64;
  struct Case {
    rd::CfarKind kind;
    double pfa;
    int images;
    int tr, gr, tv, gv;
  };
  const Case cases[] = {
      {rd::CfarKind::kCellAveraging, 1e-4, 16, 8, 2, 4, 1},   // 1.05e6 cells, 105 expected
      {rd::CfarKind::kCellAveraging, 1e-5, 64, 8, 2, 4, 1},   // 4.2e6 cells, 42 expected
      {rd::CfarKind::kOrderStatistic, 1e-4, 16, 6, 1, 2, 1},  // 1.05e6 cells, 105 expected
  };
  for (const Case& c : cases) {
    rd::CfarConfig cfg;
    cfg.kind = c.kind;
    cfg.pfa = c.pfa;
    cfg.range_training = c.tr;
    cfg.range_guard = c.gr;
    cfg.velocity_training = c.tv;
    cfg.velocity_guard = c.gv;
    rd::Cfar2d cfar(cfg, nr, nv);
    rd::NoiseRng rng(rd::stream_key(seed, static_cast<std::uint64_t>(c.kind),
                                    static_cast<std::uint64_t>(c.images)));
    std::vector<double> power(nr * nv);
    std::vector<rd::CfarHit> hits(4096);
    std::uint64_t alarms = 0, overflow = 0, cells = 0;
    for (int i = 0; i < c.images; ++i) {
      noise_image(rng, power);
      alarms += cfar.detect(power, hits, overflow);
      cells += power.size();
    }
    const double rate = static_cast<double>(alarms + overflow) / static_cast<double>(cells);
    std::printf("%s-CFAR, N = %zu: %llu alarms in %llu cells: Pfa %.3g (design %.0e)\n",
                c.kind == rd::CfarKind::kCellAveraging ? "CA" : "OS", cfar.training_cells(),
                static_cast<unsigned long long>(alarms + overflow),
                static_cast<unsigned long long>(cells), rate, c.pfa);
    EXPECT_GE(cells, 1'000'000u);
    EXPECT_LT(rate, 2.0 * c.pfa);
    EXPECT_GT(rate, 0.5 * c.pfa);
  }
}

TEST(Cfar, WindowedDataCubeNoiseKeepsTheFalseAlarmRate) {
  // Receiver noise through the whole exact chain (Hann range and Doppler tapers make adjacent
  // cells correlated; guard cells keep the training cells nearly independent of the CUT).
  rd::ProcessingConfig pc;
  pc.waveform.kind = rd::WaveformKind::kFmcw;
  pc.waveform.carrier_hz = 77e9;
  pc.waveform.bandwidth_hz = 200e6;
  pc.waveform.pulse_width_s = 51.2e-6;
  pc.waveform.pri_s = 60e-6;
  pc.waveform.pulses = 64;
  pc.waveform.range_bins = 512;
  rd::RangeDopplerProcessor p(pc);
  rd::CfarConfig cfg;
  cfg.pfa = 1e-4;
  rd::Cfar2d cfar(cfg, p.range_bins(), p.velocity_bins());
  rd::NoiseRng rng(rd::stream_key(20261123, 99));
  std::vector<std::complex<double>> cube(p.cube_samples()), image(p.image_cells());
  std::vector<double> power(p.image_cells());
  std::vector<rd::CfarHit> hits(4096);
  std::uint64_t alarms = 0, overflow = 0, cells = 0;
  for (int i = 0; i < 32; ++i) {
    for (auto& x : cube)
      x = rng.complex_normal();
    p.process_cube(cube, image);
    for (std::size_t k = 0; k < image.size(); ++k)
      power[k] = std::norm(image[k]);
    alarms += cfar.detect(power, hits, overflow);
    cells += power.size();
  }
  const double rate = static_cast<double>(alarms + overflow) / static_cast<double>(cells);
  std::printf("FMCW cube, Hann x Hann, CA N = %zu: Pfa %.3g over %llu cells (design 1e-4)\n",
              cfar.training_cells(), rate, static_cast<unsigned long long>(cells));
  EXPECT_LT(rate, 2e-4);
  EXPECT_GT(rate, 0.5e-4);
}

namespace {
// Monte-Carlo Pd: 40 images of unit complex noise with targets of one SNR on a grid (steps
// step_l x step_j, so that no target is in another's training window); the fraction of targets
// whose own cell the CFAR reports. Swerling 0: fixed amplitude, random phase; 1: Rayleigh.
struct PdEstimate {
  double pd = 0.0;
  int trials = 0;
};
PdEstimate monte_carlo_pd(rd::Cfar2d& cfar, std::size_t nr, std::size_t nv, std::size_t step_l,
                          std::size_t step_j, int swerling, double snr, rd::NoiseRng& rng) {
  std::vector<double> power(nr * nv);
  std::vector<rd::CfarHit> hits(4096);
  int detected = 0, trials = 0;
  for (int image = 0; image < 40; ++image) {
    std::vector<std::complex<double>> field(nr * nv);
    for (auto& x : field)
      x = rng.complex_normal();
    std::vector<std::size_t> targets;
    for (std::size_t j = step_j / 2; j < nv; j += step_j)
      for (std::size_t l = step_l / 2; l + step_l / 2 < nr; l += step_l) {
        field[j * nr + l] += swerling == 0 ? std::polar(std::sqrt(snr), 2 * kPi * rng.uniform())
                                           : rng.complex_normal() * std::sqrt(snr);
        targets.push_back(j * nr + l);
      }
    for (std::size_t k = 0; k < field.size(); ++k)
      power[k] = std::norm(field[k]);
    std::uint64_t overflow = 0;
    const std::size_t h = cfar.detect(power, hits, overflow);
    for (std::size_t t : targets) {
      ++trials;
      for (std::size_t i = 0; i < h; ++i)
        if (hits[i].velocity_bin * nr + hits[i].range_bin == t) {
          ++detected;
          break;
        }
    }
  }
  return {static_cast<double>(detected) / trials, trials};
}
}  // namespace

TEST(Cfar, ProbabilityOfDetectionFollowsSwerling0And1AtPfa1e6) {
  // Targets of known SNR on a grid of independent cells; CA-CFAR at Pfa 1e-6; Pd against the
  // closed forms with the same number of training cells.
  const std::size_t nr = 256, nv = 64;
  rd::CfarConfig cfg;
  cfg.pfa = 1e-6;
  rd::Cfar2d cfar(cfg, nr, nv);
  const std::size_t n = cfar.training_cells();
  const std::uint64_t seed = 4242;
  std::printf("seed %llu, CA-CFAR N = %zu\n", static_cast<unsigned long long>(seed), n);
  for (int swerling : {0, 1}) {
    const std::vector<double> snrs_db = swerling == 0 ? std::vector<double>{10, 11, 12, 13, 14}
                                                      : std::vector<double>{10, 15, 20, 25};
    for (double snr_db : snrs_db) {
      rd::NoiseRng rng(rd::stream_key(seed, static_cast<std::uint64_t>(swerling),
                                      static_cast<std::uint64_t>(snr_db * 10)));
      const double snr = from_db(snr_db);
      const auto [pd, trials] = monte_carlo_pd(cfar, nr, nv, 24, 12, swerling, snr, rng);
      const double theory =
          swerling == 0 ? rd::pd_swerling0_ca(snr, n, 1e-6) : rd::pd_swerling1_ca(snr, n, 1e-6);
      std::printf("Swerling %d, SNR %4.1f dB: Pd %.3f over %d trials, theory %.3f\n", swerling,
                  snr_db, pd, trials, theory);
      EXPECT_NEAR(pd, theory, 0.05) << "Swerling " << swerling << " SNR " << snr_db;
    }
  }
}

TEST(Cfar, OrderStatisticProbabilityOfDetectionFollowsSwerling1) {
  const std::size_t nr = 256, nv = 64;
  rd::CfarConfig cfg;
  cfg.kind = rd::CfarKind::kOrderStatistic;
  cfg.pfa = 1e-6;
  cfg.range_training = 6;
  cfg.range_guard = 1;
  cfg.velocity_training = 2;
  cfg.velocity_guard = 1;
  rd::Cfar2d cfar(cfg, nr, nv);
  const std::size_t n = cfar.training_cells();
  const auto k = static_cast<std::size_t>(std::lround(0.75 * static_cast<double>(n)));
  std::printf("seed 515, OS-CFAR N = %zu, k = %zu\n", n, k);
  for (double snr_db : {15.0, 20.0, 25.0}) {
    rd::NoiseRng rng(rd::stream_key(515, static_cast<std::uint64_t>(snr_db)));
    const auto [pd, trials] = monte_carlo_pd(cfar, nr, nv, 16, 8, 1, from_db(snr_db), rng);
    const double theory = rd::pd_swerling1_os(from_db(snr_db), n, k, 1e-6);
    std::printf("OS, Swerling 1, SNR %4.1f dB: Pd %.3f over %d trials, theory %.3f\n", snr_db, pd,
                trials, theory);
    EXPECT_NEAR(pd, theory, 0.05) << snr_db;
  }
}

TEST(Ambiguity, NumericalMatchesTheLinearFmClosedFormAndItsRidge) {
  rd::Waveform w;
  w.bandwidth_hz = 20e6;
  w.pulse_width_s = 1e-6;  // B T = 20
  const double k = rd::chirp_rate_hz_per_s(w);
  std::vector<double> delays, dopplers;
  for (int i = -40; i <= 40; ++i)
    delays.push_back(i * w.pulse_width_s / 40.0);
  for (int i = -20; i <= 20; ++i)
    dopplers.push_back(i * 0.5 / w.pulse_width_s);
  std::vector<double> af(delays.size() * dopplers.size());
  rd::ambiguity_numerical(w, delays, dopplers, af, 16);
  double worst = 0.0;
  for (std::size_t j = 0; j < dopplers.size(); ++j)
    for (std::size_t i = 0; i < delays.size(); ++i)
      worst =
          std::max(worst, std::abs(af[j * delays.size() + i] -
                                   rd::lfm_ambiguity(delays[i], dopplers[j], w.pulse_width_s, k)));
  std::printf("LFM ambiguity, BT 20: numerical vs closed form worst %.4f\n", worst);
  EXPECT_LT(worst, 0.01);
  // Range-Doppler coupling: at Doppler f_d the peak sits at tau = -f_d / k (Richards eq. 4.106).
  for (double fd : {-3e6, 1.5e6, 4e6}) {
    std::vector<double> fine;
    for (int i = -400; i <= 400; ++i)
      fine.push_back(i * w.pulse_width_s / 800.0);
    std::vector<double> cut(fine.size());
    rd::ambiguity_numerical(w, fine, std::span(&fd, 1), cut, 16);
    const auto ip = std::max_element(cut.begin(), cut.end()) - cut.begin();
    std::printf("f_d %.1f MHz: ridge at %.4f us, -f_d/k = %.4f us\n", fd / 1e6,
                fine[static_cast<std::size_t>(ip)] * 1e6, -fd / k * 1e6);
    EXPECT_NEAR(fine[static_cast<std::size_t>(ip)], -fd / k, 2.0 * w.pulse_width_s / 800.0);
  }
}

TEST(Ambiguity, PulseTrainClosedFormMatchesTheNumericalTrain) {
  rd::Waveform w;
  w.bandwidth_hz = 10e6;
  w.pulse_width_s = 1e-6;
  w.pri_s = 4e-6;
  w.pulses = 4;
  const double k = rd::chirp_rate_hz_per_s(w);
  std::vector<double> delays, dopplers;
  for (int i = -60; i <= 60; ++i)
    delays.push_back(i * 0.1e-6);  // +-6 us: the p = 0, +-1 pulse pairs
  for (int i = -12; i <= 12; ++i)
    dopplers.push_back(i * 0.25 / w.pri_s);  // +-3/PRI: the Doppler ambiguities at n / PRI
  std::vector<double> af(delays.size() * dopplers.size());
  rd::ambiguity_numerical(w, delays, dopplers, af, 8, true);
  double worst = 0.0;
  for (std::size_t j = 0; j < dopplers.size(); ++j)
    for (std::size_t i = 0; i < delays.size(); ++i)
      worst = std::max(worst, std::abs(af[j * delays.size() + i] -
                                       rd::lfm_train_ambiguity(delays[i], dopplers[j],
                                                               w.pulse_width_s, k, w.pri_s, 4)));
  std::printf("train of 4: numerical vs closed form worst %.4f\n", worst);
  EXPECT_LT(worst, 0.02);
  // Doppler ambiguity at f_d = 1/PRI: the ridge again, at tau = -f_d/k, with the single pulse's
  // (1 - |tau|/T) there.
  const double tau = -(1.0 / w.pri_s) / k;
  EXPECT_NEAR(rd::lfm_train_ambiguity(tau, 1.0 / w.pri_s, w.pulse_width_s, k, w.pri_s, 4),
              1.0 - std::abs(tau) / w.pulse_width_s, 1e-9);
}

TEST(Antenna, LineSourcePatternsHaveTheirTextbookWidthsAndSidelobes) {
  // Uniform illumination: 3-dB width 0.886 lambda/L, first null at lambda/L, first sidelobe
  // -13.26 dB; cosine: 1.19 lambda/L, null at 1.5 lambda/L, -23.0 dB (Skolnik 2001, sec. 9.4).
  struct Case {
    rd::PatternKind kind;
    double null_over_half_width, sidelobe_db;
  };
  for (const Case c : {Case{rd::PatternKind::kUniform, 1.0 / 0.443, -13.26},
                       Case{rd::PatternKind::kCosine, 1.5 / 0.5945, -23.0}}) {
    rd::AntennaConfig cfg;
    cfg.azimuth = {c.kind, 2.0 * kPi / 180.0, {}, {}};
    cfg.monopulse = false;
    rd::Antenna a(cfg);
    double null = 0.0, side = 0.0;
    double prev = 1.0;
    for (double t = 1e-5; t < 0.3; t += 1e-5) {
      const double v = std::abs(a.component_az(t));
      if (null == 0.0 && v > prev)
        null = t;
      if (null > 0.0)
        side = std::max(side, v);
      prev = v;
    }
    const double half = 1.0 * kPi / 180.0;
    std::printf("%s: first null %.4f deg (%.3f half-widths), first sidelobe %.2f dB\n",
                rd::pattern_name(c.kind), null * 180 / kPi, null / half, 20 * std::log10(side));
    EXPECT_NEAR(null / half, c.null_over_half_width, 0.01 * c.null_over_half_width);
    EXPECT_NEAR(20 * std::log10(side), c.sidelobe_db, 0.1);
    EXPECT_NEAR(20 * std::log10(a.component_az(half)), -3.0103, 1e-3);
  }
}

TEST(Antenna, GaussianMonopulseRatioIsTheClosedForm) {
  rd::AntennaConfig cfg;
  const double bw = 1.5 * kPi / 180.0;
  cfg.azimuth = {rd::PatternKind::kGaussian, bw, {}, {}};
  cfg.squint_fraction = 0.35;
  rd::Antenna a(cfg);
  const double d = 0.35 * bw;
  for (double t : {-0.6, -0.3, 0.0, 0.1, 0.3, 0.7}) {
    const double theta = t * bw;
    const double ratio = a.delta_az(theta) / a.sum_az(theta);
    // D/S = tanh(4 ln 2 d theta / theta3^2) (docs/notes/sensor_theory_reference.md sec. 5).
    EXPECT_NEAR(ratio, std::tanh(4 * std::log(2.0) * d * theta / (bw * bw)), 1e-12) << t;
    EXPECT_NEAR(a.offset_from_ratio_az(ratio), theta, 1e-4 * bw) << t;
  }
  EXPECT_NEAR(a.monopulse_slope_az(), 4 * std::log(2.0) * 0.35, 1e-6);
  EXPECT_NEAR(a.sum_az(0.0), 1.0, 1e-15);
}

TEST(Antenna, GainFromBeamwidthAndApertureAndTablePatterns) {
  // 4 pi / (1 deg)^2 = 41 253 (the classic 41 253 / (theta_az theta_el) in degrees).
  EXPECT_NEAR(rd::gain_from_beamwidths(kPi / 180, kPi / 180, 1.0), 41253.0, 1.0);
  EXPECT_NEAR(rd::gain_from_aperture(1.0, 0.6, 0.03), 0.6 * 4 * kPi / 0.0009, 1e-6);
  rd::AntennaConfig cfg;
  cfg.monopulse = false;
  cfg.azimuth.kind = rd::PatternKind::kTable;
  cfg.azimuth.table_angle_rad = {-0.1, -0.02, 0.0, 0.02, 0.1};
  cfg.azimuth.table_gain_db = {-30, -6, 0, -6, -30};
  rd::Antenna a(cfg);
  EXPECT_NEAR(a.component_az(0.01), std::pow(10.0, -3.0 / 20.0), 1e-12);  // linear in dB
  EXPECT_NEAR(a.sum_beamwidth_az_rad(), 0.02, 1e-4);                      // -3 dB at +-0.01
  cfg.azimuth.table_angle_rad = {0.0, -0.1};
  cfg.azimuth.table_gain_db = {0.0, -3.0};
  EXPECT_THROW(rd::Antenna b(cfg), std::invalid_argument);
}
