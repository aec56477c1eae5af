// The measured-data sigma0 catalogue (radar/clutter/terrain.hpp, sigma0_catalogue.cpp) against
// the published points of its sources (tests/data/sigma0_catalogue_points.csv, one citation a
// point), its smoothness in angle and frequency, the contrasts the data give, and bad input.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "radar/clutter/terrain.hpp"

namespace radar_emu::radar::clutter {
namespace {

double deg(double d) {
  return common::radians(d);
}
double db(double linear) {
  return 10.0 * std::log10(linear);
}
Sigma0Pol pol_of(const std::string& p) {
  if (p == "HH")
    return Sigma0Pol::kHH;
  if (p == "VV")
    return Sigma0Pol::kVV;
  return Sigma0Pol::kHV;
}
double cat_db(const char* m, double f_hz, Sigma0Pol p, double theta_deg) {
  return db(sigma0(m, f_hz, p, deg(theta_deg)).linear);
}

struct Point {
  std::string material, pol, source;
  double freq_hz, theta_deg, sigma0_db, tol_db;
};

std::vector<Point> read_points() {
  const std::string path = std::string(RADAR_EMU_TEST_DATA_DIR) + "/sigma0_catalogue_points.csv";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::vector<Point> out;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell[7];
    for (auto& c : cell)
      std::getline(ss, c, ',');
    out.push_back({cell[0], cell[2], cell[6], std::stod(cell[1]), std::stod(cell[3]),
                   std::stod(cell[4]), std::stod(cell[5])});
  }
  return out;
}

// Every point of every cited source, within the tolerance the file states for it: Ulaby-Dobson
// rows 2 dB (UD at L/S/C; UDt, the trees X-band HH/VV rows; their regression scatter was not
// obtained; the rows are reproduced exactly at the anchor frequency), Billingsley near-grazing
// means 4 dB (measured at 1.23 / 3.24 / 9.2 GHz, compared at the 1.25 / 3.2 / 10 GHz anchors), the
// NRL equation 0.1 dB (the equation itself; its own fit to Nathanson's tables scatters 2.2-2.6 dB).
TEST(Catalogue, CurvesMatchTheirSourcesPoints) {
  const std::vector<Point> points = read_points();
  ASSERT_GT(points.size(), 400u);
  std::map<std::string, int> checked;
  std::map<std::string, double> worst;
  for (const Point& p : points) {
    double got = 0.0;
    if (p.material.rfind("sea_ss", 0) == 0) {
      const double ss = std::stod(p.material.substr(6));
      got = db(sea_sigma0(p.freq_hz, pol_of(p.pol), deg(p.theta_deg), ss).linear);
    } else {
      got = db(sigma0(p.material, p.freq_hz, pol_of(p.pol), deg(p.theta_deg)).linear);
    }
    EXPECT_NEAR(got, p.sigma0_db, p.tol_db)
        << p.material << " " << p.source << " " << p.freq_hz * 1e-9 << " GHz " << p.pol << " "
        << p.theta_deg << " deg";
    const std::string key = p.source + " " + p.material;
    ++checked[key];
    worst[key] = std::max(worst[key], std::abs(got - p.sigma0_db));
  }
  for (const auto& [key, n] : checked)
    std::cout << key << ": " << n << " points, worst " << worst[key] << " dB\n";
  // Each curve of the catalogue is compared with at least one source at 10 GHz or nearby.
  for (const char* m : {"grass", "crops", "tall_grass", "forest", "soil_dry", "gravel", "urban"})
    EXPECT_GT(checked[std::string("BL ") + m], 0) << m;
  EXPECT_GT(checked["NRL water"] + checked["NRL sea"], 0);
  EXPECT_GT(checked["UDt forest"], 0);  // the one handbook X-band row found (trees)
}

const std::vector<std::string>& land() {
  static const std::vector<std::string> k{"asphalt", "concrete", "grass",    "tall_grass",
                                          "crops",   "forest",   "soil_dry", "soil_wet",
                                          "gravel",  "snow",     "snow_wet", "urban"};
  return k;
}

// Over all materials, 1-100 GHz and HH/VV/HV: from one degree to the next no rise over 3 dB
// and no fall over 10 dB over 0-89 deg; no co-polarised land value under -45 dB from 10 to
// 88 deg (cross-pol: -60 dB); finite.
TEST(Catalogue, SmoothInAngleAndNoLandValueUnderMinus45dB) {
  std::vector<std::string> all = land();
  all.push_back("water");
  all.push_back("sea");
  const double freqs_ghz[] = {1.0,  1.25, 2.0,  3.2,  5.0,  6.0,  8.0,  9.2,
                              10.0, 15.0, 24.0, 35.0, 50.0, 77.0, 94.0, 100.0};
  double worst_up = 0.0, worst_down = 0.0, lowest_land = 0.0;
  std::string at_lowest;
  for (const std::string& m : all) {
    const bool is_land = m != "water" && m != "sea";
    for (double f : freqs_ghz) {
      for (Sigma0Pol p : {Sigma0Pol::kHH, Sigma0Pol::kVV, Sigma0Pol::kHV}) {
        // Per degree, sampled every 0.1 deg: max over windows of one degree.
        std::vector<double> v;
        for (int i = 0; i <= 890; ++i) {
          const double d = cat_db(m.c_str(), f * 1e9, p, i * 0.1);
          ASSERT_TRUE(std::isfinite(d)) << m << " " << f << " " << i * 0.1;
          v.push_back(d);
        }
        for (std::size_t i = 0; i + 10 < v.size(); ++i) {
          const double step = v[i + 10] - v[i];
          worst_up = std::max(worst_up, step);
          worst_down = std::max(worst_down, -step);
          EXPECT_LE(step, 3.0) << m << " " << f << " GHz pol " << static_cast<int>(p) << " at "
                               << static_cast<double>(i) * 0.1 << " deg";
          EXPECT_GE(step, -10.0) << m << " " << f << " GHz pol " << static_cast<int>(p) << " at "
                                 << static_cast<double>(i) * 0.1 << " deg";
        }
        // The -45 dB bound on co-polarised values (cross-pol of smooth surfaces near grazing
        // lies below it; its own bound: -60 dB).
        if (is_land && p != Sigma0Pol::kHV) {
          for (int i = 100; i <= 880; ++i) {
            if (v[static_cast<std::size_t>(i)] < lowest_land) {
              lowest_land = v[static_cast<std::size_t>(i)];
              at_lowest = m + " " + std::to_string(f) + " GHz, " + std::to_string(i * 0.1);
            }
          }
        }
      }
    }
  }
  std::cout << "per degree: worst rise " << worst_up << " dB, worst fall " << worst_down
            << " dB; lowest land value 10-88 deg " << lowest_land << " dB (" << at_lowest << ")\n";
  EXPECT_GE(lowest_land, -45.0) << at_lowest;
  for (const std::string& m : land())
    for (double f : freqs_ghz)
      for (double th = 10.0; th <= 88.0; th += 0.5)
        EXPECT_GE(cat_db(m.c_str(), f * 1e9, Sigma0Pol::kHV, th), -60.0)
            << m << " " << f << " " << th;
}

// Continuous in frequency: a 1 % frequency step changes no value by more than 0.3 dB.
TEST(Catalogue, ContinuousInFrequency) {
  double worst = 0.0;
  for (const std::string& m : land()) {
    for (double f = 1e9; f < 100e9; f *= 1.01) {
      for (double th : {5.0, 30.0, 60.0, 75.0, 85.0, 88.0}) {
        const double a = cat_db(m.c_str(), f, Sigma0Pol::kVV, th);
        const double b = cat_db(m.c_str(), f * 1.01, Sigma0Pol::kVV, th);
        worst = std::max(worst, std::abs(b - a));
        EXPECT_LT(std::abs(b - a), 0.3) << m << " " << f << " " << th;
      }
    }
  }
  std::cout << "worst change over a 1 % frequency step: " << worst << " dB\n";
  // The mm-wave bands differ from each other (the old models gave identical vegetation at 35
  // and 94 GHz).
  for (const char* m : {"grass", "crops", "forest"})
    EXPECT_GT(
        std::abs(cat_db(m, 94e9, Sigma0Pol::kVV, 85.0) - cat_db(m, 35e9, Sigma0Pol::kVV, 85.0)),
        1.0)
        << m;
}

// The contrasts. Measured: forest brighter than grass near grazing at X band (Billingsley,
// 2.75 deg depression: low-relief forest -25.1/-23.8 dB HH/VV vs grassland -39.1/-36.8 dB, so
// 14.0/13.0 dB, held within BL's 4 dB), and little from 40 to 70 deg at X band (the UD trees
// X rows against the UD grass C rows carried to X: forest -0.4 to +2.5 dB over grass); water far
// darker than land, finite, rising with sea state (NRL). Assumed (no 35 or 94 GHz land value
// was found; docs/validation.md): roads darker than mown grass near grazing at 94 GHz (10 dB
// asphalt / 9 dB concrete, as the issue reports 94 GHz landing imagery; asserted at >= 7 / 6 dB
// over 80-88 deg), and forest brighter than grass at 35 and 94 GHz.
TEST(Catalogue, ContrastsTheDataGive) {
  for (double th = 80.0; th <= 88.0; th += 1.0) {
    for (Sigma0Pol p : {Sigma0Pol::kHH, Sigma0Pol::kVV}) {
      const double grass = cat_db("grass", 94e9, p, th);
      EXPECT_GE(grass - cat_db("asphalt", 94e9, p, th), 7.0) << th;
      EXPECT_GE(grass - cat_db("concrete", 94e9, p, th), 6.0) << th;
    }
  }
  std::cout << "94 GHz, 85 deg, VV: grass " << cat_db("grass", 94e9, Sigma0Pol::kVV, 85.0)
            << " dB, asphalt " << cat_db("asphalt", 94e9, Sigma0Pol::kVV, 85.0) << " dB, concrete "
            << cat_db("concrete", 94e9, Sigma0Pol::kVV, 85.0) << " dB\n";
  // X band (measured): the BL contrast at its angle, forest brighter from 72 deg on, and
  // forest - grass in (-1, 3) dB from 40 to 70 deg.
  const double bl_hh =
      cat_db("forest", 10e9, Sigma0Pol::kHH, 87.25) - cat_db("grass", 10e9, Sigma0Pol::kHH, 87.25);
  const double bl_vv =
      cat_db("forest", 10e9, Sigma0Pol::kVV, 87.25) - cat_db("grass", 10e9, Sigma0Pol::kVV, 87.25);
  EXPECT_NEAR(bl_hh, -25.1 - -39.1, 4.0);
  EXPECT_NEAR(bl_vv, -23.8 - -36.8, 4.0);
  std::cout << "10 GHz, 87.25 deg: forest - grass " << bl_hh << " dB HH, " << bl_vv
            << " dB VV (Billingsley: 14.0 / 13.0 dB)\n";
  for (Sigma0Pol p : {Sigma0Pol::kHH, Sigma0Pol::kVV}) {
    for (double th = 72.0; th <= 88.0; th += 2.0)
      EXPECT_GT(cat_db("forest", 10e9, p, th), cat_db("grass", 10e9, p, th)) << th;
    for (double th = 40.0; th <= 70.0; th += 2.0) {
      const double d = cat_db("forest", 10e9, p, th) - cat_db("grass", 10e9, p, th);
      EXPECT_GT(d, -1.0) << th;
      EXPECT_LT(d, 3.0) << th;
    }
  }
  // 35 and 94 GHz (assumed).
  for (double f : {35e9, 94e9})
    for (double th = 40.0; th <= 88.0; th += 2.0)
      EXPECT_GT(cat_db("forest", f, Sigma0Pol::kVV, th), cat_db("grass", f, Sigma0Pol::kVV, th))
          << f << " " << th;
  // Water: the issue's case (35 GHz, 63 deg incidence) and the EV case (94 GHz, 85 deg).
  for (double f : {10e9, 35e9, 94e9}) {
    for (double th : {45.0, 63.0, 80.0, 85.0}) {
      double last = -1e9;
      for (int ss = 0; ss <= 6; ++ss) {
        const double w = db(sea_sigma0(f, Sigma0Pol::kHH, deg(th), ss).linear);
        EXPECT_TRUE(std::isfinite(w) && w > -80.0) << f << " " << th << " SS " << ss;
        EXPECT_GT(w, last) << f << " " << th << " SS " << ss;
        last = w;
      }
      EXPECT_LT(cat_db("water", f, Sigma0Pol::kHH, th),
                cat_db("grass", f, Sigma0Pol::kHH, th) - 10.0)
          << f << " " << th;
    }
  }
  const double issue_case = cat_db("water", 35e9, Sigma0Pol::kHH, 63.0);
  std::cout << "water (SS 1), 35 GHz, 63 deg, HH: " << issue_case << " dB\n";
  EXPECT_GT(issue_case, -40.0);
  EXPECT_LT(issue_case, -28.0);
}

TEST(Catalogue, FlagsSayWhatIsMeasured) {
  // The UD grass row at its anchor, 40 deg: measured.
  EXPECT_EQ(sigma0("grass", 3.2e9, Sigma0Pol::kVV, deg(40.0)).flags, 0u);
  // Billingsley's X-band point: measured; beyond it (89 deg): outside the measured range.
  EXPECT_EQ(sigma0("forest", 10e9, Sigma0Pol::kVV, deg(80.0)).flags & kOutsideMeasuredRange, 0u);
  EXPECT_NE(sigma0("forest", 10e9, Sigma0Pol::kVV, deg(89.0)).flags & kOutsideMeasuredRange, 0u);
  // The UD trees X rows: measured (HH, VV); the X cross-pol row is assumed.
  EXPECT_EQ(sigma0("forest", 10e9, Sigma0Pol::kHH, deg(40.0)).flags, 0u);
  EXPECT_EQ(sigma0("forest", 10e9, Sigma0Pol::kVV, deg(40.0)).flags, 0u);
  EXPECT_NE(sigma0("forest", 10e9, Sigma0Pol::kHV, deg(40.0)).flags & kAssumedValue, 0u);
  // Nothing published found at 94 GHz for land: assumed.
  for (const std::string& m : land())
    EXPECT_NE(sigma0(m, 94e9, Sigma0Pol::kVV, deg(85.0)).flags & kAssumedValue, 0u) << m;
  // NRL beyond 35 GHz: extrapolated.
  EXPECT_NE(sigma0("water", 94e9, Sigma0Pol::kHH, deg(80.0)).flags & kOutsideMeasuredRange, 0u);
  EXPECT_EQ(sigma0("water", 10e9, Sigma0Pol::kHH, deg(80.0)).flags, 0u);
  // The table keeps the flags for the images.
  const SurfaceSpec specs[] = {resolve_surface(terrain_material("asphalt"), 94e9),
                               resolve_surface(terrain_material("grass"), 3.2e9)};
  const Sigma0Table table(std::span<const SurfaceSpec>(specs, 1), Sigma0Model::kTotal, 94e9);
  EXPECT_NE(table.lookup_flags(0, Sigma0Table::kVV, std::cos(deg(85.0))) & kAssumedValue, 0u);
  EXPECT_NE(table.row_flags(0, Sigma0Table::kHH) & kAssumedValue, 0u);
  EXPECT_NEAR(db(table.lookup(0, Sigma0Table::kVV, std::cos(deg(85.0)))),
              cat_db("asphalt", 94e9, Sigma0Pol::kVV, 85.0), 0.05);
}

TEST(Catalogue, UnknownMaterialNamesTheKnownOnes) {
  try {
    (void)sigma0("lava", 10e9, Sigma0Pol::kVV, 0.5);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("unknown terrain material 'lava'"), std::string::npos) << what;
    EXPECT_NE(what.find("known: asphalt, concrete, grass"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  // The conductor has no diffuse term; bad numbers give 0, never NaN.
  EXPECT_EQ(sigma0("metal", 10e9, Sigma0Pol::kVV, 0.5).linear, 0.0);
  EXPECT_EQ(sigma0("grass", std::nan(""), Sigma0Pol::kVV, 0.5).linear, 0.0);
  EXPECT_EQ(sigma0("grass", 10e9, Sigma0Pol::kVV, std::nan("")).linear, 0.0);
}

}  // namespace
}  // namespace radar_emu::radar::clutter
