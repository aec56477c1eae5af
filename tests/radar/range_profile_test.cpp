// Range profiles and ISAR images of synthesised point scatterers (closed form: the model in
// radar/products/range_profile.hpp) and the windows' published peak sidelobe levels.
#include "radar/products/range_profile.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "radar/constants.hpp"

namespace radar_emu::radar {
namespace {

struct Point {
  double a, range_m, cross_m;
};

const FrequencyGrid kGrid{9.5e9, 10e6, 128};  // B = 1.28 GHz: 0.117 m; window 15 m

std::vector<std::complex<double>> synth(const std::vector<Point>& pts, const FrequencyGrid& g,
                                        double dtheta = 0.0) {
  std::vector<std::complex<double>> s(g.count);
  for (std::size_t n = 0; n < g.count; ++n) {
    const double k =
        2.0 * kPi * (g.start_hz + g.step_hz * static_cast<double>(n)) / kSpeedOfLight_mps;
    for (const Point& p : pts)
      s[n] += p.a * std::polar(1.0, -2.0 * k * p.range_m + 2.0 * k * dtheta * p.cross_m);
  }
  return s;
}

std::size_t argmax(const std::vector<std::complex<double>>& v) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (std::abs(v[i]) > std::abs(v[best]))
      best = i;
  }
  return best;
}

double db20(double x) {
  return 20.0 * std::log10(x);
}

TEST(RangeProfile, ResolutionAndAxes) {
  const RangeProfile p = range_profile(synth({{1.0, 0.0, 0.0}}, kGrid), kGrid, Window::kHann, 4);
  EXPECT_NEAR(p.resolution_m, kSpeedOfLight_mps / (2.0 * 1.28e9), 1e-12);
  EXPECT_NEAR(p.bin_m, p.resolution_m / 4.0, 1e-12);
  EXPECT_NEAR(p.unambiguous_m, kSpeedOfLight_mps / (2.0 * 10e6), 1e-9);
  ASSERT_EQ(p.range_m.size(), 512u);
  EXPECT_NEAR(p.range_m.front(), -p.unambiguous_m / 2.0, 1e-9);
  EXPECT_NEAR(p.range_m[256], 0.0, 1e-12);
}

TEST(RangeProfile, PointScatterersAtTheirRangesForEveryWindow) {
  for (Window w : {Window::kRectangular, Window::kHann, Window::kHamming, Window::kTaylor}) {
    for (double r : {-5.0, -0.3, 0.0, 1.234, 6.9}) {
      const RangeProfile p = range_profile(synth({{0.7, r, 0.0}}, kGrid), kGrid, w, 4);
      const std::size_t i = argmax(p.amplitude_m);
      EXPECT_NEAR(p.range_m[i], r, p.bin_m) << "window " << static_cast<int>(w) << " R " << r;
      // Peak within the window's worst scalloping loss at a quarter-resolution sampling
      // (under 0.25 dB for these windows: Harris 1978, table 1, at half a bin; here a quarter).
      EXPECT_NEAR(std::abs(p.amplitude_m[i]), 0.7, 0.7 * 0.03);
    }
  }
  // Exactly on a sample with the rectangular window: |a| to 1e-12, and its phase is kept.
  const double r0 = 40.0 * kSpeedOfLight_mps / (2.0 * 10e6 * 512.0);
  const RangeProfile p =
      range_profile(synth({{0.7, r0, 0.0}}, kGrid), kGrid, Window::kRectangular, 4);
  const std::size_t i = argmax(p.amplitude_m);
  EXPECT_NEAR(std::abs(p.amplitude_m[i] - 0.7), 0.0, 1e-9);
}

TEST(RangeProfile, TwoScatterersThreeResolutionsApartAreResolved) {
  // Hann widens the main lobe 1.6x (Harris 1978, table 1: 6-dB width 2.00 bins vs 1.21):
  // three resolution cells apart the dip between equal scatterers is several dB.
  const double res = kSpeedOfLight_mps / (2.0 * 1.28e9);
  const RangeProfile p = range_profile(synth({{1.0, 0.0, 0.0}, {1.0, 3.0 * res, 0.0}}, kGrid),
                                       kGrid, Window::kHann, 8);
  auto at = [&](double r) {
    std::size_t best = 0;
    for (std::size_t i = 0; i < p.range_m.size(); ++i) {
      if (std::abs(p.range_m[i] - r) < std::abs(p.range_m[best] - r))
        best = i;
    }
    return std::abs(p.amplitude_m[best]);
  };
  const double dip_db = db20(at(0.0)) - db20(at(1.5 * res));
  std::cout << "dip between two Hann peaks 3 resolutions apart: " << dip_db << " dB\n";
  EXPECT_GT(dip_db, 3.0);
}

TEST(RangeProfile, PeakSidelobesMatchTheWindows) {
  // Published peak sidelobe levels (Harris, Proc. IEEE 66(1), 1978, table 1): rectangular
  // -13.3 dB, Hann -31.5 dB, Hamming -42.7 dB; Taylor designed for -35 dB. Finite N and the
  // symmetric (N-1) definition move them by a few tenths: 1 dB tolerance.
  struct Case {
    Window w;
    double psl_db;
  };
  for (const Case c : {Case{Window::kRectangular, -13.26}, Case{Window::kHann, -31.47},
                       Case{Window::kHamming, -42.7}, Case{Window::kTaylor, -35.0}}) {
    const RangeProfile p = range_profile(synth({{1.0, 0.0, 0.0}}, kGrid), kGrid, c.w, 16);
    const std::size_t peak = argmax(p.amplitude_m);
    // Walk down the main lobe to its first null on the right, then take the largest value.
    std::size_t i = peak;
    while (i + 1 < p.amplitude_m.size() &&
           std::abs(p.amplitude_m[i + 1]) < std::abs(p.amplitude_m[i]))
      ++i;
    double side = 0.0;
    for (std::size_t j = i; j < p.amplitude_m.size(); ++j)
      side = std::max(side, std::abs(p.amplitude_m[j]));
    const double psl = db20(side / std::abs(p.amplitude_m[peak]));
    std::cout << "window " << static_cast<int>(c.w) << ": peak sidelobe " << psl << " dB\n";
    EXPECT_NEAR(psl, c.psl_db, 1.0);
  }
}

TEST(Isar, ScatterersAtTheirRangeAndCrossRange) {
  const std::size_t na = 64;
  const double step = 0.1 * kPi / 180.0;  // 6.4 deg aperture
  const std::vector<Point> pts{{1.0, 0.0, 0.0}, {0.8, 2.0, 1.5}, {0.6, -3.0, -2.5}};
  std::vector<std::complex<double>> samples;
  for (std::size_t m = 0; m < na; ++m) {
    const double dtheta = (static_cast<double>(m) - 0.5 * static_cast<double>(na - 1)) * step;
    const auto row = synth(pts, kGrid, dtheta);
    samples.insert(samples.end(), row.begin(), row.end());
  }
  const IsarImage img = isar_image(samples, kGrid, step, na, Window::kHann, 2);
  const double f_c = kGrid.start_hz + 0.5 * kGrid.step_hz * 127.0;
  EXPECT_NEAR(img.cross_range_resolution_m, kSpeedOfLight_mps / f_c / (2.0 * step * na), 1e-12);
  EXPECT_NEAR(img.range_resolution_m, kSpeedOfLight_mps / (2.0 * 1.28e9), 1e-12);
  const double bin_r = img.range_m[1] - img.range_m[0];
  const double bin_y = img.cross_range_m[1] - img.cross_range_m[0];
  for (const Point& p : pts) {
    // Brightest pixel within 3 cells of the expected position, and it is where expected.
    double best = 0.0;
    std::size_t br = 0, bc = 0;
    for (std::size_t r = 0; r < img.cross_range_m.size(); ++r) {
      for (std::size_t c = 0; c < img.range_m.size(); ++c) {
        if (std::abs(img.range_m[c] - p.range_m) > 3 * bin_r ||
            std::abs(img.cross_range_m[r] - p.cross_m) > 3 * bin_y)
          continue;
        const double v = std::abs(img.pixels_m[r * img.range_m.size() + c]);
        if (v > best) {
          best = v;
          br = r;
          bc = c;
        }
      }
    }
    EXPECT_NEAR(img.range_m[bc], p.range_m, bin_r) << p.range_m;
    EXPECT_NEAR(img.cross_range_m[br], p.cross_m, bin_y) << p.cross_m;
    // Range migration blurs a little at 6.4 deg: within 15 % of |a|.
    EXPECT_NEAR(best, p.a, 0.15 * p.a) << p.range_m;
  }
}

TEST(RangeProfile, RejectsBadInput) {
  const auto s = synth({{1.0, 0.0, 0.0}}, kGrid);
  EXPECT_THROW((void)range_profile(s, {9.5e9, 10e6, 64}, Window::kHann), std::invalid_argument);
  EXPECT_THROW((void)range_profile(s, {9.5e9, -1.0, 128}, Window::kHann), std::invalid_argument);
  EXPECT_THROW((void)range_profile(s, kGrid, Window::kHann, 0), std::invalid_argument);
  std::vector<std::complex<double>> bad = s;
  bad[3] = {std::nan(""), 0.0};
  EXPECT_THROW((void)range_profile(bad, kGrid, Window::kHann), std::invalid_argument);
  EXPECT_THROW((void)isar_image(s, kGrid, 0.01, 1, Window::kHann), std::invalid_argument);
  EXPECT_FALSE(parse_window_kind("kaiser").has_value());
  EXPECT_EQ(parse_window_kind("taylor"), Window::kTaylor);
}

}  // namespace
}  // namespace radar_emu::radar
