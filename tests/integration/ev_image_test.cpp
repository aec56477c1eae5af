// `radar-emu image` on the seed's 94 GHz enhanced-vision scenario (examples/ev_radar_94ghz.toml,
// the real 30 x 10 deg field of 0.15 deg pixels), 360 m short of the threshold (510 m from the
// first touchdown-zone stripes, the seed's "500 m from the touch down zone", figure 5):
//   - the N-look speckle over the grass has coefficient of variation 1/sqrt(N) within 10 %;
//   - the runway's edges and threshold, found independently in the radar image (its mean, no
//     speckle) and in the optical preview by the strongest gradient, register within a pixel;
//   - fog of 0.05 g/m^3 dims a trihedral 1 km ahead by the two-way ITU-R P.840-9 loss within
//     0.1 dB, the loss computed here from the Recommendation's formulas (not from radar/);
//   - every terrain cell read a sigma0 value the catalogue flags as assumed at 94 GHz, and the
//     image reports it per material (issue 28).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "radar/em/sbr.hpp"
#include "scene/scene.hpp"
#include "tools/image.hpp"

namespace loop = radar_emu::loop;
namespace tools = radar_emu::tools;

namespace {

namespace common = radar_emu::common;
constexpr double kTimeS = 52.0;  // ownship at (0, -360, 39.2) m
constexpr int kScale = 4;        // optical pixels per radar pixel

std::string example_text() {
  const char* root = std::getenv("RADAR_EMU_SOURCE_DIR");
  if (root == nullptr)
    return {};
  std::ifstream f(std::filesystem::path(root) / "examples" / "ev_radar_94ghz.toml");
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

double db(double v) {
  return 10.0 * std::log10(std::max(v, 1e-30));
}

// Optical luminance (Rec. 709 weights of the sRGB codes; only its gradients matter) of optical
// row y, column x.
double luma(const radar_emu::scene::PreviewImage& im, int x, int y) {
  const std::uint8_t* p =
      im.rgb.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(im.width_px) +
                       static_cast<std::size_t>(x)) *
                          3;
  return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

// The boundary (index b: between b - 1 and b) of the strongest |difference| of f over b in
// [lo, hi].
template <typename F>
int strongest_step(int lo, int hi, F f) {
  int best = lo;
  double best_step = -1.0;
  for (int b = lo; b <= hi; ++b) {
    const double step = std::abs(f(b) - f(b - 1));
    if (step > best_step) {
      best_step = step;
      best = b;
    }
  }
  return best;
}

// P.840-9 sec. 2 (eqs. 2-9), written out here: K_l = 0.819 f / (eps'' (1 + eta^2)) [(dB/km) /
// (g/m^3)], f in GHz, with the double-Debye permittivity of water at T [K].
double p840_kl(double f_ghz, double t_k) {
  const double theta = 300.0 / t_k;
  const double e0 = 77.66 + 103.3 * (theta - 1.0);
  const double e1 = 0.0671 * e0, e2 = 3.52;
  const double fp = 20.20 - 146.0 * (theta - 1.0) + 316.0 * (theta - 1.0) * (theta - 1.0);
  const double fs = 39.8 * fp;
  const double epp = f_ghz * (e0 - e1) / (fp * (1.0 + (f_ghz / fp) * (f_ghz / fp))) +
                     f_ghz * (e1 - e2) / (fs * (1.0 + (f_ghz / fs) * (f_ghz / fs)));
  const double ep = (e0 - e1) / (1.0 + (f_ghz / fp) * (f_ghz / fp)) +
                    (e1 - e2) / (1.0 + (f_ghz / fs) * (f_ghz / fs)) + e2;
  const double eta = (2.0 + ep) / epp;
  return 0.819 * f_ghz / (epp * (1.0 + eta * eta));
}

// The first boundary b, scanning from hi down to lo, whose |difference| is at least 30 % of the
// strongest in [lo, hi]: the near edge of what starts there (the threshold seen from short of
// it, before its painted stripes, whose white-on-asphalt steps are the strongest in the optical
// view but cut at a slant across its rows).
template <typename F>
int nearest_strong_step(int lo, int hi, F f) {
  double strongest = 0.0;
  for (int b = lo; b <= hi; ++b)
    strongest = std::max(strongest, std::abs(f(b) - f(b - 1)));
  for (int b = hi; b >= lo; --b) {
    if (std::abs(f(b) - f(b - 1)) >= 0.3 * strongest)
      return b;
  }
  return hi;
}

// Where a profile, scanned from outside an object (samples start, start + step, ...), first
// departs from its outside level (the first sample) by half the step to its inside level (three
// samples past the first sample that departs by 30 % of the largest departure), linearly
// interpolated between sample centres: the edge, in units of
// samples from the profile's index 0 (sample i spans [i, i + 1]). A radar pixel that the edge
// cuts holds a proportional mix of both powers, so the crossing places the edge within it.
template <typename F>
double edge_crossing(int start, int step, int count, F g) {
  const double out = g(start);
  double largest = 0.0;
  for (int k = 0; k < count; ++k)
    largest = std::max(largest, std::abs(g(start + k * step) - out));
  int first = 0;
  while (first < count - 1 && std::abs(g(start + first * step) - out) < 0.3 * largest)
    ++first;
  const double in = g(start + std::min(first + 3, count - 1) * step);
  // The first departure from the outside level by half the step to the inside level (a
  // painted stripe along the edge, brighter still, counts from its outer side).
  const double half = 0.5 * std::abs(in - out);
  for (int k = std::max(1, first - 1); k < count; ++k) {
    const double a = std::abs(g(start + (k - 1) * step) - out);
    const double b = std::abs(g(start + k * step) - out);
    if (a < half && b >= half) {
      const double t = (half - a) / (b - a);
      return start + (k - 1 + t) * step + 0.5;
    }
  }
  return start + first * step + 0.5;
}

class EvImageScenario : public ::testing::Test {
 protected:
  void SetUp() override {
    text_ = example_text();
    if (text_.empty())
      GTEST_SKIP() << "RADAR_EMU_SOURCE_DIR is not set (ctest sets it)";
  }
  std::string text_;
};

}  // namespace

TEST_F(EvImageScenario, SpeckleOverGrassHasCoefficientOfVariationOneOverRootLooks) {
  const loop::Scenario s = loop::parse_scenario(text_, "ev_radar_94ghz.toml");
  for (int looks : {1, 10}) {
    const tools::EvImageProduct p = tools::compute_ev_image(s, kTimeS, looks, 20261124, 0);
    const auto& im = p.image;
    ASSERT_EQ(im.columns, 200);
    ASSERT_EQ(im.rows, 66);
    // Grass right of the runway, short of the remote stand's link (x > 85 m at y < 688 m):
    // azimuth 9-14 deg, ranges 300-700 m. I / <I> there is Gamma(N, 1/N).
    double s1 = 0, s2 = 0, n = 0;
    for (int r = 0; r < im.rows; ++r) {
      const double* e = im.range_edges_m.data() + 160 * (im.rows + 1);
      if (!(e[r + 1] > 300.0 && e[r] < 700.0))
        continue;
      for (int c = 160; c < 193; ++c) {
        const std::size_t i = static_cast<std::size_t>(r * im.columns + c);
        ASSERT_GT(im.mean_m2[i], 0.0f) << r << " " << c;
        const double x = double(im.intensity_m2[i]) / double(im.mean_m2[i]);
        s1 += x;
        s2 += x * x;
        n += 1;
      }
    }
    ASSERT_GT(n, 300.0);
    const double mean = s1 / n, cv = std::sqrt(s2 / n - mean * mean) / mean;
    const double expected = 1.0 / std::sqrt(double(looks));
    EXPECT_NEAR(cv, expected, 0.1 * expected) << looks << " looks over " << n << " pixels";
  }
}

TEST_F(EvImageScenario, RunwayEdgesAndThresholdRegisterWithTheOpticalPreview) {
  const loop::Scenario s = loop::parse_scenario(text_, "ev_radar_94ghz.toml");
  const tools::EvImageProduct p = tools::compute_ev_image(s, kTimeS, 10, 20261124, kScale);
  const auto& im = p.image;
  const auto& opt = p.optical;
  ASSERT_EQ(opt.width_px, im.columns * kScale);
  ASSERT_EQ(opt.height_px, im.rows * kScale);
  const double az0 = p.config.azimuth_min_rad / common::kRadPerDeg,
               px = p.config.pixel_rad / common::kRadPerDeg;
  auto col_of = [&](double az_deg) { return static_cast<int>(std::lround((az_deg - az0) / px)); };
  auto mean_db = [&](int r, int c) {
    return db(im.mean_m2[static_cast<std::size_t>(r * im.columns + c)]);
  };
  // Runway edges, row by row, over ground 40-650 m past the threshold (between the taxiway
  // links at 0-23 m and 1000 m west, and the one at 688 m east): scanned in from the grass
  // at -5 and +5 deg toward the centreline (0.3 deg short of it).
  int rows_checked = 0;
  double worst_edge = 0.0;
  for (int r = 0; r < im.rows; ++r) {
    const double* e = im.range_edges_m.data() + 100 * (im.rows + 1);
    if (!(e[r + 1] > 400.0 && e[r] < 1000.0))
      continue;
    auto optical_row_mean = [&](int x) {
      double v = 0;
      for (int k = 0; k < kScale; ++k)
        v += luma(opt, x, r * kScale + k);
      return v;
    };
    auto mean_power = [&](int c) {
      return double(im.mean_m2[static_cast<std::size_t>(r * im.columns + c)]);
    };
    // Left edge, scanned rightwards from -5 deg; right edge, leftwards from +5 deg.
    for (const int side : {-1, 1}) {
      const int n = col_of(5.0) - col_of(0.3);
      const int start = side < 0 ? col_of(-5.0) : col_of(5.0) - 1;
      const double radar_edge = edge_crossing(start, -side, n, mean_power);
      const double optical_edge =
          edge_crossing(side < 0 ? start * kScale : (start + 1) * kScale - 1, -side, n * kScale,
                        optical_row_mean) /
          kScale;
      worst_edge = std::max(worst_edge, std::abs(radar_edge - optical_edge));
      EXPECT_LE(std::abs(radar_edge - optical_edge), 1.0)
          << "row " << r << (side < 0 ? " left" : " right") << " edge: radar " << radar_edge
          << ", optical " << optical_edge << " (pixels from the left)";
    }
    ++rows_checked;
  }
  EXPECT_GE(rows_checked, 8);
  // Threshold (y = 0), column by column across the runway (azimuth +-1 to +-3 deg, off the
  // approach lights on the centreline): the nearest strong step along elevation over the rows
  // that see 300-480 m (the painted stripes, 6-36 m past the threshold, are stronger still in
  // the optical view).
  const double* e = im.range_edges_m.data() + 100 * (im.rows + 1);
  int r_lo = im.rows, r_hi = 0;
  for (int r = 1; r < im.rows; ++r) {
    if (e[r + 1] > 300.0 && e[r] < 480.0) {
      r_lo = std::min(r_lo, r);
      r_hi = std::max(r_hi, r);
    }
  }
  ASSERT_LT(r_lo, r_hi);
  int cols_checked = 0;
  double worst_threshold = 0.0;
  for (int c = im.columns / 2 - 20; c <= im.columns / 2 + 20; ++c) {
    const double az = az0 + (c + 0.5) * px;
    if (std::abs(az) < 1.0 || std::abs(az) > 3.0)
      continue;
    const int radar_b = nearest_strong_step(r_lo + 1, r_hi, [&](int r) { return mean_db(r, c); });
    auto optical_col_mean = [&](int y) {
      double v = 0;
      for (int k = 0; k < kScale; ++k)
        v += luma(opt, c * kScale + k, y);
      return v;
    };
    const int optical_b = nearest_strong_step((r_lo + 1) * kScale, r_hi * kScale, optical_col_mean);
    EXPECT_LE(std::abs(radar_b - optical_b / double(kScale)), 1.0)
        << "column " << c << ": radar boundary " << radar_b << ", optical "
        << optical_b / double(kScale);
    worst_threshold = std::max(worst_threshold, std::abs(radar_b - optical_b / double(kScale)));
    ++cols_checked;
  }
  EXPECT_GE(cols_checked, 20);
  std::printf(
      "registration: runway edges over %d rows within %.2f pixel, threshold over %d "
      "columns within %.2f pixel\n",
      rows_checked, worst_edge, cols_checked, worst_threshold);
}

// The frame tracer's returns do not depend on how TBB splits its rays: one thread and all of
// them give the same contributions, in the same order, over the EV scene with a 0.5 m trihedral
// at 1 km. (When the rays' batches went to Embree as streams, the stream's packet intersectors
// rounded differently at triangle edges and the trihedral's multi-bounce returns changed with
// the partition: 39.6 to 41.9 dBsm from run to run in the image.)
TEST_F(EvImageScenario, TracerReturnsDoNotDependOnTheThreads) {
  const double y = -360.0 + std::sqrt(1000.0 * 1000.0 - 39.15 * 39.15);
  const loop::Scenario s =
      loop::parse_scenario(text_ +
                               "\n[[target]]\nname = \"trihedral\"\nbuiltin = \"trihedral-tri\"\n"
                               "size_m = 0.5\nheading_deg = 225.0\nposition_enu_m = [0.0, " +
                               std::to_string(y) + ", 0.05]\n",
                           "ev_radar_94ghz.toml + trihedral");
  radar_emu::scene::Scene scene(loop::scene_description(s));
  scene.set_time(kTimeS);
  // Both traces traced (the second would otherwise re-evaluate the first one's kept paths:
  // the same returns to rounding, tests/radar/sbr_reuse_test.cpp).
  radar_emu::radar::SbrConfig c = s.sbr;
  c.reuse_static_paths = false;
  radar_emu::radar::SbrTracer tracer(scene, c);
  const radar_emu::radar::RadarPose pose = loop::scripted_pose(s, kTimeS);
  auto run = [&](std::size_t threads) {
    std::optional<tbb::global_control> limit;
    if (threads > 0)
      limit.emplace(tbb::global_control::max_allowed_parallelism, threads);
    std::vector<radar_emu::radar::Contribution> out(tracer.max_contributions());
    radar_emu::radar::TraceStats ts;
    out.resize(tracer.trace(pose, out, ts));
    return out;
  };
  const auto one = run(1), all = run(0);
  ASSERT_EQ(one.size(), all.size());
  ASSERT_GT(one.size(), 1000u);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < one.size(); ++i)
    if (one[i].amplitude != all[i].amplitude || one[i].range_m != all[i].range_m ||
        one[i].azimuth_rad != all[i].azimuth_rad || one[i].bounces != all[i].bounces)
      ++differing;
  EXPECT_EQ(differing, 0u) << "of " << one.size() << " returns";
}

TEST_F(EvImageScenario, FogDimsATargetAt1KmByTheTwoWayP840Loss) {
  // A 0.5 m trihedral on the centreline 1 km from the antenna, its strongest axis toward the
  // radar (45 deg left of the nose: heading 225 deg points it south). Clear air (gases only)
  // against fog of 0.05 g/m^3 at 15 C: the pixel's dB difference is the fog's two-way loss.
  const double y = -360.0 + std::sqrt(1000.0 * 1000.0 - 39.15 * 39.15);  // ownship at 52 s
  const std::string target =
      "\n[[target]]\nname = \"trihedral\"\nbuiltin = \"trihedral-tri\"\n"
      "size_m = 0.5\nheading_deg = 225.0\nposition_enu_m = [0.0, " +
      std::to_string(y) + ", 0.05]\n";
  const loop::Scenario clear = loop::parse_scenario(
      text_ + target + "\n[weather]\ncondition = \"clear\"\n", "ev_radar_94ghz.toml + clear");
  const loop::Scenario fog =
      loop::parse_scenario(text_ + target +
                               "\n[weather]\ncondition = \"fog\"\nfog_water_gpm3 = 0.05\n"
                               "temperature_c = 15.0\n",
                           "ev_radar_94ghz.toml + fog");
  const tools::EvImageProduct a = tools::compute_ev_image(clear, kTimeS, 10, 20261124, 0);
  const tools::EvImageProduct b = tools::compute_ev_image(fog, kTimeS, 10, 20261124, 0);
  // The target's pixel: the brightest within a pixel of its direction (azimuth 0, the
  // boundary of columns 99 and 100; the row whose range gates hold 1 km).
  const auto& ia = a.image.intensity_m2;
  const int cols = a.image.columns;
  std::size_t k = 0;
  for (int r = 0; r < a.image.rows; ++r) {
    for (int c = cols / 2 - 2; c <= cols / 2 + 1; ++c) {
      const std::size_t i = static_cast<std::size_t>(r * cols + c);
      if (ia[i] > ia[k])
        k = i;
    }
  }
  const double range_m = std::sqrt((y + 360.0) * (y + 360.0) + (39.2 - 0.05) * (39.2 - 0.05));
  const double* e =
      a.image.range_edges_m.data() + static_cast<std::size_t>(static_cast<int>(k) % cols) *
                                         static_cast<std::size_t>(a.image.rows + 1);
  const int row = static_cast<int>(k) / cols;
  EXPECT_LE(e[row + 1], range_m) << "row " << row;
  EXPECT_GT(e[row], range_m) << "row " << row;
  ASSERT_GT(db(ia[k]), 25.0) << "the trihedral dominates its pixel";
  const double expected_db = 2.0 * p840_kl(94.0, 288.15) * 0.05 * range_m / 1000.0;
  const double measured_db = db(ia[k]) - db(b.image.intensity_m2[k]);
  EXPECT_NEAR(measured_db, expected_db, 0.1)
      << "pixel " << k << ", range " << range_m << " m; P.840 K_l " << p840_kl(94.0, 288.15);
  // The fog's loss is visible at all (0.36 dB two-way at 1 km) and the clear-air image is not
  // the same as the fog one elsewhere.
  EXPECT_GT(expected_db, 0.3);
  EXPECT_GT(measured_db, 0.3);
  std::printf(
      "fog 0.05 g/m^3, target at %.1f m: image dims it by %.4f dB, P.840-9 two-way %.4f dB\n",
      range_m, measured_db, expected_db);
}

// Terrain from the terrain engine: the runway's mean pixel under the grass beside it by the
// catalogue's contrast at each row's incidence (sigma0 of asphalt and grass read from the
// catalogue's table here, independently of the engine), within 1 dB; pixels whose four corners
// all fall on asphalt clear of the markings (x 1-8 m, y 150-1050 m: between the centreline and
// the touchdown-zone stripes, ICAO Annex 14, scene/airport_gen.hpp) or on the grass east of it
// (x 30-80 m, y 300-650 m); row by row (one range interval, one incidence), then averaged.
TEST_F(EvImageScenario, RunwayUnderGrassByTheCatalogueContrastAndApproachLightsAsPoints) {
  namespace rd = radar_emu::radar;
  const loop::Scenario s = loop::parse_scenario(text_, "ev_radar_94ghz.toml");
  const tools::EvImageProduct p = tools::compute_ev_image(s, kTimeS, 10, 20261124, 0);
  ASSERT_TRUE(p.terrain_engine);
  const auto& im = p.image;
  const std::vector<radar_emu::scene::Material> mats{{"asphalt", {}}, {"grass", {}}};
  const rd::SurfaceSet set = rd::resolve_surfaces(mats, {s.sbr.carrier_hz, s.sbr.polarisation, {}});
  const auto ch = rd::sigma0_channel(s.sbr.polarisation);
  const glm::dvec3 pos = p.pose.position_m;
  const double half = 0.5 * p.config.pixel_rad;
  // Ground point (the runway's level) of antenna direction (az, el); nullopt above the horizon.
  auto ground = [&](double az, double el) -> std::optional<glm::dvec2> {
    const glm::dvec3 w = p.pose.world_from_antenna * rd::direction_from_azel({az, el});
    if (w.z >= -1e-9)
      return std::nullopt;
    const double t = (pos.z - 0.05) / -w.z;
    return glm::dvec2(pos.x + t * w.x, pos.y + t * w.y);
  };
  auto inside = [&](int r, int c, double x0, double x1, double y0, double y1) {
    const double az = rd::ev_column_azimuth_rad(p.config, c);
    const double el = rd::ev_row_elevation_rad(p.config, r);
    for (double da : {-half, half})
      for (double de : {-half, half}) {
        const auto g = ground(az + da, el + de);
        if (!g || g->x < x0 || g->x > x1 || g->y < y0 || g->y > y1)
          return false;
      }
    return true;
  };
  double sum_diff = 0.0;
  int rows_used = 0;
  for (int r = 0; r < im.rows; ++r) {
    double run = 0.0, grass = 0.0;
    int nr = 0, ng = 0;
    for (int c = 0; c < im.columns; ++c) {
      const double v = static_cast<double>(im.at(r, c));
      if (inside(r, c, 1.0, 8.0, 150.0, 1050.0)) {
        run += v;
        ++nr;
      } else if (inside(r, c, 30.0, 80.0, 300.0, 650.0)) {
        grass += v;
        ++ng;
      }
    }
    if (nr < 1 || ng < 3)
      continue;
    const auto g = ground(0.0, rd::ev_row_elevation_rad(p.config, r));
    const double range = std::hypot(g->x - pos.x, g->y - pos.y, pos.z);
    const double cos_inc = pos.z / range;
    const double expected = db(double(set.sigma0_table.lookup(0, ch, cos_inc))) -
                            db(double(set.sigma0_table.lookup(1, ch, cos_inc)));
    const double measured = db((run / nr) / (grass / ng));
    std::printf("row %d, range %.0f m: runway - grass %.2f dB (catalogue %.2f dB)\n", r, range,
                measured, expected);
    sum_diff += measured - expected;
    ++rows_used;
  }
  ASSERT_GE(rows_used, 3);
  const double mean_diff = sum_diff / rows_used;
  std::printf("runway contrast against the catalogue: %.2f dB over %d rows\n", mean_diff,
              rows_used);
  EXPECT_LT(std::abs(mean_diff), 1.0);

  // Approach lights (metal masts and barrettes on the centreline, 30 m apart south of the
  // threshold): in the centre column, pixels brighter than the grass beside them by 10 dB.
  const int c0 =
      static_cast<int>(std::lround(-p.config.azimuth_min_rad / p.config.pixel_rad - 0.5));
  int points = 0;
  for (int r = 0; r < im.rows; ++r) {
    std::vector<double> side;
    for (int d = 6; d <= 12; ++d) {
      side.push_back(static_cast<double>(im.at(r, c0 - d)));
      side.push_back(static_cast<double>(im.at(r, c0 + d)));
    }
    std::sort(side.begin(), side.end());
    const double ref = side[side.size() / 2];
    const auto g = ground(0.0, rd::ev_row_elevation_rad(p.config, r));
    if (g && g->y < 0.0 && static_cast<double>(im.at(r, c0)) > 10.0 * ref) {
      std::printf("approach light row %d (ground y %.0f m): %.1f dB over the grass\n", r, g->y,
                  db(static_cast<double>(im.at(r, c0)) / ref));
      ++points;
    }
  }
  EXPECT_GE(points, 2);

  // Issue 28: at 94 GHz the catalogue's grass and asphalt are assumed at every incidence (its
  // own flags, clutter::sigma0 by name, checked here every degree), so every terrain cell of the
  // image read a flagged value, and the image says so per material.
  std::uint32_t catalogue = 0u;
  for (const char* m : {"grass", "asphalt"})
    for (int deg = 0; deg <= 89; ++deg) {
      const std::uint32_t f = rd::clutter::sigma0(m, s.sbr.carrier_hz, rd::clutter::Sigma0Pol::kVV,
                                                  common::radians(static_cast<double>(deg)))
                                  .flags;
      ASSERT_NE(f & rd::clutter::kAssumedValue, 0u) << m << " at " << deg << " deg";
      catalogue |= f;
    }
  EXPECT_NE(p.sigma0_flags & rd::clutter::kAssumedValue, 0u);
  EXPECT_EQ(p.sigma0_flags & ~catalogue, 0u);
  ASSERT_GT(p.terrain_cells, 0u);
  EXPECT_EQ(p.sigma0_flagged_cells, p.terrain_cells);
  ASSERT_FALSE(p.sigma0_lines.empty());
  for (const std::string& line : p.sigma0_lines) {
    std::printf("flagged: %s\n", line.c_str());
    EXPECT_NE(line.find(" at 94 GHz, "), std::string::npos) << line;
    EXPECT_NE(line.find("catalogue: assumed value"), std::string::npos) << line;
  }
}
