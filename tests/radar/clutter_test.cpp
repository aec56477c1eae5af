// Clutter physics against closed forms and limits: speckle statistics (exponential, L looks, K),
// roughness spectra against numerical Hankel transforms, IEM -> SPM for small roughness, the
// geometrical-optics closed form, the coherent loss exp(-(2ks cos)^2), energy in the specular
// lobe, the Rayleigh-layer volume term, and finiteness and flags over the whole input grid.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "radar/clutter/speckle.hpp"
#include "radar/clutter/surface.hpp"
#include "radar/constants.hpp"

namespace radar_emu::radar::clutter {
namespace {

double deg(double d) {
  return d * kPi / 180.0;
}
double db(double x) {
  return 10.0 * std::log10(x);
}
double wavenumber(double f_hz) {
  return 2.0 * kPi * f_hz / kSpeedOfLight_mps;
}

// ---------------------------------------------------------------------------------- speckle

std::vector<double> intensities(const SpeckleSpec& spec, std::size_t n) {
  std::vector<SpeckleSample> pattern(n);
  fill_speckle_pattern(spec, 0, pattern);
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = pattern[i].intensity;
  return out;
}

TEST(Speckle, SingleLookIsExponentialWithUniformPhase) {
  SpeckleSpec spec;
  spec.model = SpeckleModel::kExponential;
  spec.seed = 20261122;
  std::cout << "speckle seed " << spec.seed << "\n";
  constexpr std::size_t kN = 1000000;
  std::vector<SpeckleSample> pattern(kN);
  fill_speckle_pattern(spec, 0, pattern);
  std::vector<double> x(kN), phase(kN);
  double mean_db = 0.0;
  for (std::size_t i = 0; i < kN; ++i) {
    x[i] = pattern[i].intensity;
    phase[i] = pattern[i].phase_rad;
    mean_db += db(x[i]);
  }
  mean_db /= kN;
  double var_db = 0.0;
  for (double v : x)
    var_db += (db(v) - mean_db) * (db(v) - mean_db);
  const double std_db = std::sqrt(var_db / (kN - 1));
  // Kolmogorov-Smirnov against F(x) = 1 - exp(-x) and the phase against U(0, 2 pi): the 1 %
  // critical value of D is 1.628 / sqrt(N) (Massey 1951, Table 1 asymptote).
  auto ks_stat = [](std::vector<double> v, auto cdf) {
    std::sort(v.begin(), v.end());
    double d = 0.0;
    const double n = static_cast<double>(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      const double f = cdf(v[i]);
      d = std::max({d, f - static_cast<double>(i) / n, static_cast<double>(i + 1) / n - f});
    }
    return d;
  };
  const double crit = 1.628 / std::sqrt(static_cast<double>(kN));
  const double d_int = ks_stat(x, [](double v) { return 1.0 - std::exp(-v); });
  const double d_phase = ks_stat(phase, [](double v) { return v / (2.0 * kPi); });
  // Closed forms: mean of dB values = -10 gamma_E / ln 10 = -2.507 dB; their standard deviation
  // = (10 / ln 10) pi / sqrt 6 = 5.57 dB (Oliver & Quegan 2004, sec. 4.3).
  std::cout << "KS D intensity " << d_int << ", phase " << d_phase << " (1 % critical " << crit
            << "); mean of dB " << mean_db << " dB, std of dB " << std_db << " dB\n";
  EXPECT_LT(d_int, crit);
  EXPECT_LT(d_phase, crit);
  EXPECT_NEAR(mean_db, -2.507, 0.03);
  EXPECT_NEAR(std_db, 5.57, 0.03);
}

TEST(Speckle, LooksGiveCoefficientOfVariationOneOverSqrtL) {
  for (int looks : {1, 4, 10, 30}) {
    SpeckleSpec spec;
    spec.model = SpeckleModel::kLooks;
    spec.looks = looks;
    spec.seed = 7 + static_cast<std::uint64_t>(looks);
    const std::vector<double> x = intensities(spec, 100000);
    double m = 0.0, m2 = 0.0;
    for (double v : x) {
      m += v;
      m2 += v * v;
    }
    m /= static_cast<double>(x.size());
    const double cv = std::sqrt(m2 / static_cast<double>(x.size()) - m * m) / m;
    std::cout << "L = " << looks << " (seed " << spec.seed << "): mean " << m << ", CV " << cv
              << " vs " << 1.0 / std::sqrt(looks) << "\n";
    EXPECT_NEAR(m, 1.0, 0.01);
    EXPECT_NEAR(cv * std::sqrt(looks), 1.0, 0.02);
  }
}

TEST(Speckle, KDistributionSecondMoment) {
  // <I^2>/<I>^2 = (1 + 1/L)(1 + 1/nu) (Ward, Tough & Watts 2006, sec. 4.6).
  for (double nu : {0.5, 2.0, 10.0}) {
    SpeckleSpec spec;
    spec.model = SpeckleModel::kK;
    spec.looks = 2;
    spec.k_order_nu = nu;
    spec.seed = 99;
    const std::vector<double> x = intensities(spec, 400000);
    double m = 0.0, m2 = 0.0;
    for (double v : x) {
      m += v;
      m2 += v * v;
    }
    m /= static_cast<double>(x.size());
    m2 /= static_cast<double>(x.size());
    const double expected = (1.0 + 0.5) * (1.0 + 1.0 / nu);
    std::cout << "K nu " << nu << ": <I^2>/<I>^2 " << m2 / (m * m) << " vs " << expected << "\n";
    EXPECT_NEAR(m2 / (m * m) / expected, 1.0, 0.04);
  }
}

TEST(Speckle, PatternIsAFunctionOfSeedAndPolygonOnly) {
  SpeckleSpec spec;
  spec.seed = 42;
  std::vector<SpeckleSample> a(100), b(10);
  fill_speckle_pattern(spec, 0, a);
  fill_speckle_pattern(spec, 50, b);  // a window, filled on its own
  for (std::size_t i = 0; i < b.size(); ++i) {
    EXPECT_EQ(a[50 + i].intensity, b[i].intensity);
    EXPECT_EQ(a[50 + i].phase_rad, b[i].phase_rad);
  }
  spec.seed = 43;
  EXPECT_NE(speckle_sample(spec, 3).intensity, a[3].intensity);
  SpeckleSpec bad;
  bad.model = SpeckleModel::kK;
  bad.k_order_nu = -1.0;
  EXPECT_THROW(validate(bad), std::invalid_argument);
}

// ---------------------------------------------------------------------------- rough surfaces

TEST(RoughSurface, SpectraMatchNumericalHankelTransforms) {
  // W^(n)(K) = int_0^inf rho^n(r) J0(K r) r dr, by composite Simpson on a fine grid.
  const double l = 0.01;
  for (Correlation c : {Correlation::kGaussian, Correlation::kExponential, Correlation::kXPower}) {
    const Roughness r{0.001, l, c, 1.5};
    for (int n : {1, 2, 5}) {
      for (double kl : {0.0, 0.7, 3.0}) {
        const double big_k = kl / l;
        auto rho = [&](double x) {
          switch (c) {
            case Correlation::kGaussian:
              return std::exp(-x * x / (l * l));
            case Correlation::kExponential:
              return std::exp(-x / l);
            case Correlation::kXPower:
              return std::pow(1.0 + x * x / (l * l), -1.5);
          }
          return 0.0;
        };
        const double r_max = (c == Correlation::kXPower ? 2000.0 : 40.0) * l;
        const int steps = c == Correlation::kXPower ? 400000 : 20000;
        const double h = r_max / steps;
        double sum = 0.0;
        for (int i = 0; i <= steps; ++i) {
          const double x = i * h;
          const double wgt = (i == 0 || i == steps) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
          sum += wgt * std::pow(rho(x), n) * std::cyl_bessel_j(0.0, big_k * x) * x;
        }
        const double numeric = sum * h / 3.0;
        const double closed = roughness_spectrum(r, n, big_k);
        EXPECT_NEAR(closed / numeric, 1.0, 2e-3)
            << "correlation " << static_cast<int>(c) << " n " << n << " kl " << kl;
      }
    }
  }
}

SurfaceParams surface(std::complex<double> eps, double ks, double kl, Correlation c, double f_hz) {
  const double k = wavenumber(f_hz);
  return {eps, {ks / k, kl / k, c, 1.5}};
}

TEST(RoughSurface, IemReducesToSpmForSmallRoughness) {
  // Acceptance: IEM within 1 dB of SPM for ks <= 0.2 (kl <= 3, SPM's own domain), backscatter
  // and bistatic, both spectra, two permittivities. SPM is the first-order term of the spectral
  // series; where the second-order term is more than 10% of it (Gaussian spectra far into their
  // tail, (ks (cos + cos_s))^2 / 2 W2(K) / W1(K) > 0.1) the IEM rightly parts from SPM and the
  // case is counted, not compared. At ks = 0.2 and 60 deg incidence the I2EM's complementary
  // terms of order two reach 1-2 dB, as in the published code (IemMatchesThePublishedI2em
  // shows it there): that edge is held to 2.5 dB and printed.
  double worst = 0.0, worst_edge = 0.0;
  int compared = 0, beyond_first_order = 0;
  for (std::complex<double> eps : {std::complex<double>(4.0, -0.1), {15.0, -3.0}}) {
    for (Correlation c : {Correlation::kGaussian, Correlation::kExponential}) {
      for (double ks : {0.05, 0.1, 0.2}) {
        for (double th : {10.0, 30.0, 50.0, 60.0}) {
          for (Geometry g :
               {Geometry::backscatter(deg(th)), Geometry{deg(th), deg(25.0), deg(60.0)},
                Geometry{deg(th), deg(45.0), deg(160.0)}}) {
            const SurfaceParams p = surface(eps, ks, 2.5, c, 35e9);
            const double k = wavenumber(35e9);
            const double kx =
                std::sin(g.theta_s_rad) * std::cos(g.phi_s_rad) - std::sin(g.theta_i_rad);
            const double ky = std::sin(g.theta_s_rad) * std::sin(g.phi_s_rad);
            const double big_k = k * std::hypot(kx, ky);
            const double lambda =
                std::pow(ks * (std::cos(g.theta_i_rad) + std::cos(g.theta_s_rad)), 2);
            if (0.5 * lambda * roughness_spectrum(p.roughness, 2, big_k) >
                0.1 * roughness_spectrum(p.roughness, 1, big_k)) {
              ++beyond_first_order;
              continue;
            }
            ++compared;
            const SurfaceScatter a = iem(p, 35e9, g), b = spm(p, 35e9, g);
            for (auto [x, y] : {std::pair{a.incoherent.hh, b.incoherent.hh},
                                std::pair{a.incoherent.vv, b.incoherent.vv}}) {
              const double d = std::abs(db(x) - db(y));
              const bool edge = ks > 0.15 && th > 55.0;
              (edge ? worst_edge : worst) = std::max(edge ? worst_edge : worst, d);
              EXPECT_LT(d, edge ? 2.5 : 1.0)
                  << "eps " << eps << " ks " << ks << " theta " << th << " corr "
                  << static_cast<int>(c) << " theta_s " << g.theta_s_rad << " phi_s " << g.phi_s_rad
                  << " iem " << db(x) << " spm " << db(y);
            }
          }
        }
      }
    }
  }
  std::cout << "IEM vs SPM, ks <= 0.2: worst co-pol difference " << worst << " dB (" << worst_edge
            << " dB at ks 0.2, 60 deg) over " << compared << " cases (" << beyond_first_order
            << " where the second-order term exceeds 10% of the first)\n";
  EXPECT_GT(compared, 4 * beyond_first_order);
}

TEST(RoughSurface, BistaticIemMeetsBackscatterContinuously) {
  // Backscatter uses the closed forms that match the published I2EM; the bistatic directions
  // next to it must give the same sigma0 (the first-order anchor vanishes in backscatter), for
  // smooth and rough surfaces alike.
  for (Correlation c : {Correlation::kGaussian, Correlation::kExponential}) {
    for (double ks : {0.1, 0.5, 1.5}) {
      for (double th : {10.0, 35.0, 55.0}) {
        const SurfaceParams p = surface({6.0, -0.8}, ks, 6.0, c, 10e9);
        const SurfaceScatter back = iem(p, 10e9, Geometry::backscatter(deg(th)));
        const SurfaceScatter near = iem(p, 10e9, Geometry{deg(th), deg(th) + 1e-6, kPi - 1e-6});
        EXPECT_NEAR(db(near.incoherent.hh), db(back.incoherent.hh), 0.01) << ks << " " << th;
        EXPECT_NEAR(db(near.incoherent.vv), db(back.incoherent.vv), 0.01) << ks << " " << th;
      }
    }
  }
}

struct ReferenceRow {
  double freq_hz, eps_re, eps_im, ks, kl, theta_deg, vv_db, hh_db, hv_db;
  Correlation correlation;
};

std::vector<ReferenceRow> read_iem_reference() {
  const std::string path = std::string(RADAR_EMU_TEST_DATA_DIR) + "/iem_reference.csv";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot read " << path;
  std::vector<ReferenceRow> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string f[10];
    for (auto& x : f)
      std::getline(fields, x, ',');
    rows.push_back({std::stod(f[0]), std::stod(f[1]), std::stod(f[2]), std::stod(f[3]),
                    std::stod(f[4]), std::stod(f[6]), std::stod(f[7]), std::stod(f[8]),
                    std::stod(f[9]),
                    f[5] == "gaussian" ? Correlation::kGaussian : Correlation::kExponential});
  }
  return rows;
}

TEST(RoughSurface, IemMatchesThePublishedI2em) {
  // Independent implementation: Ulaby & Long (2014) I2EM (co-pol, Code 10.3) and IEMX
  // (cross-pol) MATLAB codes, run under GNU Octave at exact angles (tests/data/iem_reference.md):
  // 720 rows, eps 4-j0.1 and 15-j3, ks 0.1-2, kl 5 and 10, Gaussian and exponential, 10-60 deg,
  // 10/35/94 GHz (s = ks/k at each frequency). Acceptance: within 1 dB. With that code's own
  // conventions (IemConventions::kUlabyLongCode: sin instead of sin^2 in the transition
  // function, its weight unclamped, q = sqrt(1.0001 - u^2) in the cross-polarised integral) the
  // two must agree to the quadrature's accuracy: the same model, term by term.
  const std::vector<ReferenceRow> rows = read_iem_reference();
  ASSERT_EQ(rows.size(), 720u);
  double worst[2][3] = {};  // [conventions][vv, hh, hv]
  for (const ReferenceRow& r : rows) {
    const SurfaceParams p = surface({r.eps_re, -r.eps_im}, r.ks, r.kl, r.correlation, r.freq_hz);
    for (int c = 0; c < 2; ++c) {
      const SurfaceScatter s =
          iem(p, r.freq_hz, Geometry::backscatter(deg(r.theta_deg)),
              c == 0 ? IemConventions::kPublishedEquations : IemConventions::kUlabyLongCode);
      const double d[3] = {db(s.incoherent.vv) - r.vv_db, db(s.incoherent.hh) - r.hh_db,
                           db(s.incoherent.hv) - r.hv_db};
      for (int q = 0; q < 3; ++q) {
        worst[c][q] = std::max(worst[c][q], std::abs(d[q]));
        EXPECT_LT(std::abs(d[q]), c == 0 ? 1.0 : (q == 2 ? 0.1 : 0.01))
            << "pol " << q << " conventions " << c << " f " << r.freq_hz << " ks " << r.ks << " kl "
            << r.kl << " theta " << r.theta_deg;
      }
      EXPECT_DOUBLE_EQ(s.incoherent.hv, s.incoherent.vh);  // reciprocity
    }
  }
  std::cout << "IEM vs published I2EM/IEMX (720 rows), worst |difference| VV/HH/HV: " << worst[0][0]
            << " / " << worst[0][1] << " / " << worst[0][2] << " dB; with the code's conventions "
            << worst[1][0] << " / " << worst[1][1] << " / " << worst[1][2] << " dB\n";
  // The published I2EM itself leaves SPM at ks 0.2, 60 deg (exponential, kl 5, eps 15-j3): the
  // second-order complementary terms (IemReducesToSpmForSmallRoughness's edge).
  for (const ReferenceRow& r : rows) {
    if (r.freq_hz == 10e9 && r.ks == 0.2 && r.theta_deg == 60.0 && r.eps_re == 15.0 &&
        r.correlation == Correlation::kExponential) {
      const SurfaceParams p = surface({r.eps_re, -r.eps_im}, r.ks, r.kl, r.correlation, 10e9);
      const double d = r.hh_db - db(spm(p, 10e9, Geometry::backscatter(deg(60.0))).incoherent.hh);
      std::cout << "published I2EM minus SPM, HH, ks 0.2, 60 deg: " << d << " dB\n";
      EXPECT_GT(d, 1.0);
    }
  }
}

TEST(RoughSurface, GeometricalOpticsClosedForm) {
  // Backscatter, stationary phase: sigma0 = |R(0)|^2 exp(-tan^2 t / 2 m^2) / (2 m^2 cos^4 t),
  // m^2 = 2 s^2 / l^2 for a Gaussian correlation (Ulaby & Long 2014, sec. 10-4).
  const std::complex<double> eps{5.0, -0.5};
  const double f = 94e9, k = wavenumber(f);
  const SurfaceParams p{eps, {3.0 / k, 30.0 / k, Correlation::kGaussian, 1.5}};
  const double m2 = 2.0 * std::pow(3.0 / 30.0, 2);
  const std::complex<double> r0 = (std::sqrt(eps) - 1.0) / (std::sqrt(eps) + 1.0);
  for (double th : {0.0, 10.0, 20.0, 30.0}) {
    const double t = deg(th);
    const double closed = std::norm(r0) * std::exp(-std::tan(t) * std::tan(t) / (2.0 * m2)) /
                          (2.0 * m2 * std::pow(std::cos(t), 4));
    const SurfaceScatter ka = kirchhoff(p, f, Geometry::backscatter(t));
    EXPECT_NEAR(ka.incoherent.vv / closed, 1.0, 1e-9) << th;
    EXPECT_NEAR(ka.incoherent.hh / closed, 1.0, 1e-9) << th;
    EXPECT_LT(ka.incoherent.hv, 1e-12 * closed);
  }
}

TEST(RoughSurface, PhysicalOpticsSeriesJoinsGeometricalOptics) {
  // The Kirchhoff series and its stationary-phase limit describe the same field: for a Gaussian
  // spectrum they agree on each side of the switch at (k s (cos t + cos t_s))^2 = 10 within
  // 1 dB near the specular peak (the series, 10-30 terms there, is not yet at its asymptote;
  // far down the GO tail, 20 deg here, the two differ by tens of dB and neither is trusted).
  const double f = 35e9, k = wavenumber(f);
  for (double th : {0.0, 5.0, 10.0}) {
    const double c = std::cos(deg(th));
    const double ks_below = std::sqrt(9.9) / (2.0 * c), ks_above = std::sqrt(10.1) / (2.0 * c);
    const SurfaceParams below{{5.0, -0.5}, {ks_below / k, 40.0 / k, Correlation::kGaussian, 1.5}};
    const SurfaceParams above{{5.0, -0.5}, {ks_above / k, 40.0 / k, Correlation::kGaussian, 1.5}};
    const double a = kirchhoff(below, f, Geometry::backscatter(deg(th))).incoherent.vv;
    const double b = kirchhoff(above, f, Geometry::backscatter(deg(th))).incoherent.vv;
    EXPECT_NEAR(db(a), db(b), 1.0) << th;
  }
}

TEST(RoughSurface, CoherentPartFallsAsExpOfRoughnessWhileIncoherentRises) {
  // Seed (Bistatic IEM/RT paper, Fig. 4): asphalt at 94 GHz, incidence 40 deg. Coherent
  // reflectivity |R|^2 exp(-(2 k s cos t)^2) exactly; the incoherent power, integrated over the
  // upper hemisphere (bistatic albedo (1 / 4 pi cos t) int sigma0 dOmega), rises from nothing.
  const double f = 94e9, k = wavenumber(f), t = deg(40.0);
  const std::complex<double> eps{3.18, -0.1};
  const std::complex<double> root = std::sqrt(eps - std::sin(t) * std::sin(t));
  const double rh2 = std::norm((std::cos(t) - root) / (std::cos(t) + root));
  double previous_albedo = -1.0;
  for (double ks : {0.02, 0.1, 0.3, 0.6}) {
    const SurfaceParams p{eps, {ks / k, 8.0 / k, Correlation::kExponential, 1.5}};
    const SurfaceScatter spec = iem(p, f, Geometry{t, t, 0.0});
    EXPECT_NEAR(spec.coherent_hh / (rh2 * std::exp(-std::pow(2.0 * ks * std::cos(t), 2))), 1.0,
                1e-12);
    double albedo = 0.0;
    const int nt = 60, np = 72;
    for (int i = 0; i < nt; ++i) {
      const double ts = (i + 0.5) * (kPi / 2.0) / nt;
      for (int j = 0; j < np; ++j) {
        const double ps = (j + 0.5) * 2.0 * kPi / np;
        const SurfaceScatter s = iem(p, f, Geometry{t, ts, ps});
        albedo += (s.incoherent.hh + s.incoherent.vh) * std::sin(ts) * (kPi / 2.0 / nt) *
                  (2.0 * kPi / np);
      }
    }
    albedo /= 4.0 * kPi * std::cos(t);
    std::cout << "ks " << ks << ": coherent HH " << spec.coherent_hh << ", incoherent albedo H "
              << albedo << ", sum " << spec.coherent_hh + albedo << " (|R_h|^2 = " << rh2 << ")\n";
    EXPECT_GT(albedo, previous_albedo);
    previous_albedo = albedo;
    if (ks <= 0.02) {
      EXPECT_LT(albedo, 0.01 * spec.coherent_hh);  // a smooth surface: power in the specular lobe
    }
    EXPECT_LT(spec.coherent_hh + albedo, 1.0);  // no power from nowhere
  }
}

TEST(RoughSurface, VolumeTermClosedFormAndLimits) {
  // Rayleigh layer in air (no ground): backscatter co-pol (3/4) a cos t (1 - Y^2),
  // Y^2 = exp(-2 kappa_e d sec t) (Ulaby & Long 2014, eq. 11.23, first volume term).
  VolumeLayer layer{VolumeLayer::Placement::kCanopyAboveGround, 0.5, 2.0, 0.1};
  const SurfaceParams ground{{10.0, -2.0}, {0.002, 0.02, Correlation::kExponential, 1.5}};
  for (double th : {10.0, 40.0, 75.0}) {
    const double t = deg(th);
    std::uint32_t flags = 0;
    const Sigma0 v = rt_volume(layer, ground, 35e9, Geometry::backscatter(t), &flags);
    const double y2 = std::exp(-2.0 * 2.0 * 0.5 / std::cos(t));
    const double closed = 0.75 * 0.1 * std::cos(t) * (1.0 - y2);
    EXPECT_NEAR(v.vv / closed, 1.0, 1e-12);
    EXPECT_NEAR(v.hh / closed, 1.0, 1e-12);
  }
  // Vanishes as the layer thins.
  double previous = 1.0;
  for (double d : {1.0, 0.1, 0.01, 0.0}) {
    layer.thickness_m = d;
    const Sigma0 v = rt_volume(layer, ground, 35e9, Geometry::backscatter(deg(30.0)), nullptr);
    EXPECT_LT(v.vv, previous);
    previous = v.vv;
  }
  EXPECT_EQ(previous, 0.0);
}

TEST(RoughSurface, VolumeDominatesFarFromSpecularAndTotalIsTheSum) {
  // Seed (Bistatic IEM/RT paper, Fig. 6): asphalt HH at 94 GHz, incidence 40 deg: surface +
  // volume; the volume term is the larger far from the specular direction, the surface near it.
  const double f = 94e9;
  const SurfaceParams asphalt{{3.18, -0.1}, {0.0003, 0.003, Correlation::kExponential, 1.5}};
  const VolumeLayer inclusions{VolumeLayer::Placement::kInsideGround, 0.05, 20.0, 0.1};
  const double t = deg(40.0);
  auto parts = [&](const Geometry& g) {
    std::uint32_t flags = 0;
    return std::pair{iem(asphalt, f, g).incoherent.hh,
                     rt_volume(inclusions, asphalt, f, g, &flags).hh};
  };
  const auto [surf_spec, vol_spec] = parts(Geometry{t, t, 0.0});
  const auto [surf_far, vol_far] = parts(Geometry{t, deg(60.0), deg(180.0)});
  std::cout << "specular: surface " << db(surf_spec) << " dB, volume " << db(vol_spec)
            << " dB; far (60 deg, back side): surface " << db(surf_far) << " dB, volume "
            << db(vol_far) << " dB\n";
  EXPECT_GT(surf_spec, vol_spec);
  EXPECT_GT(vol_far, surf_far);
  const Geometry g{t, deg(20.0), deg(90.0)};
  const auto [s, v] = parts(g);
  EXPECT_NEAR(rt_total(inclusions, asphalt, f, g).incoherent.hh / (s + v), 1.0, 1e-12);
}

TEST(RoughSurface, FiniteEverywhereAndFlaggedAtGrazing) {
  // No NaN or infinity anywhere on the grid the CLI accepts (ks up to 1000, kl 0.5-100, 0-89.9 deg,
  // every spectrum and model); beyond 70 deg every model says it has left its domain.
  int checked = 0;
  for (Correlation c : {Correlation::kGaussian, Correlation::kExponential, Correlation::kXPower}) {
    for (double ks : {0.0, 0.01, 0.3, 1.0, 3.0, 8.0, 20.0, 100.0, 1000.0}) {
      for (double kl : {0.5, 3.0, 12.0, 100.0}) {
        const SurfaceParams p = surface({3.0, -0.2}, ks, kl, c, 94e9);
        for (double th : {0.0, 5.0, 30.0, 60.0, 70.0, 75.0, 80.0, 85.0, 88.0, 89.9}) {
          for (Geometry g : {Geometry::backscatter(deg(th)), Geometry{deg(th), deg(th), 0.0},
                             Geometry{deg(40.0), deg(th), deg(90.0)}}) {
            for (const SurfaceScatter& s :
                 {spm(p, 94e9, g), kirchhoff(p, 94e9, g), iem(p, 94e9, g)}) {
              for (double x : {s.incoherent.hh, s.incoherent.vv, s.incoherent.hv, s.incoherent.vh,
                               s.coherent_hh, s.coherent_vv}) {
                ASSERT_TRUE(std::isfinite(x) && x >= 0.0)
                    << "ks " << ks << " kl " << kl << " theta " << th;
              }
              if (th > 70.0) {
                EXPECT_NE(s.invalid & kGrazing, 0u);
              }
              ++checked;
            }
          }
        }
      }
    }
  }
  std::cout << checked << " evaluations finite\n";
  EXPECT_THROW(validate(surface({3.0, -0.2}, -0.1, 3.0, Correlation::kGaussian, 94e9), 94e9),
               std::invalid_argument);
  EXPECT_THROW(validate(surface({3.0, 0.2}, 0.1, 3.0, Correlation::kGaussian, 94e9), 94e9),
               std::invalid_argument);
  EXPECT_THROW(validate(surface({3.0, -0.2}, 1500.0, 3.0, Correlation::kGaussian, 94e9), 94e9),
               std::invalid_argument);
}

}  // namespace
}  // namespace radar_emu::radar::clutter

#include "radar/clutter/terrain.hpp"

namespace radar_emu::radar::clutter {
namespace {

TEST(Terrain, EmpiricalCurvesMatchAnIndependentEvaluation) {
  // Ulaby & Dobson (1989) regression evaluated independently (docs/notes/
  // clutter_data_sources.md sec. 2.1, "sanity evaluation", 0.1 dB rounding) at 0/20/40/60/70 deg.
  struct Case {
    EmpiricalClass cls;
    int pol;
    double db[5];
  };
  const Case cases[] = {
      {EmpiricalClass::kGrass, 0, {3.7, -8.0, -13.8, -14.1, -13.6}},
      {EmpiricalClass::kGrass, 1, {3.9, -7.3, -12.6, -13.6, -14.1}},
      {EmpiricalClass::kShortVegetation, 0, {1.1, -7.6, -12.2, -14.5, -15.5}},
      {EmpiricalClass::kShortVegetation, 1, {0.8, -7.6, -11.6, -13.7, -15.0}},
      {EmpiricalClass::kShrubs, 0, {0.1, -7.3, -11.5, -14.3, -15.9}},
  };
  const double angles[] = {0.0, 20.0, 40.0, 60.0, 70.0};
  for (const Case& c : cases) {
    const auto row = empirical_row(c.cls, 5.3e9, c.pol);
    ASSERT_TRUE(row.has_value());
    for (int i = 0; i < 5; ++i)
      EXPECT_NEAR(empirical_sigma0_db(*row, deg(angles[i])), c.db[i], 0.051)
          << static_cast<int>(c.cls) << " pol " << c.pol << " at " << angles[i];
  }
  // No row where none was published (X band and above, trees, roads) or where the public
  // transcription is wrong (soil L HH refit, shrubs S).
  EXPECT_FALSE(empirical_row(EmpiricalClass::kGrass, 10e9, 0).has_value());
  EXPECT_FALSE(empirical_row(EmpiricalClass::kSoil, 1.5e9, 0).has_value());
  EXPECT_TRUE(empirical_row(EmpiricalClass::kSoil, 1.5e9, 1).has_value());
  EXPECT_FALSE(empirical_row(EmpiricalClass::kShrubs, 3e9, 1).has_value());
}

TEST(Terrain, EveryMaterialResolvesAndStaysFiniteAtRadarBands) {
  for (const TerrainMaterial& m : terrain_catalogue()) {
    for (double f : {10e9, 35e9, 94e9}) {
      const SurfaceSpec spec = resolve_surface(m, f);
      if (spec.conductor)
        continue;
      EXPECT_GE(spec.surface.relative_permittivity.real(), 1.0) << m.name;
      EXPECT_LE(spec.surface.relative_permittivity.imag(), 0.0) << m.name;
      for (double th = 0.0; th < 90.0; th += 0.5) {
        const SurfaceScatter s =
            evaluate_sigma0(spec, Sigma0Model::kTotal, f, Geometry::backscatter(deg(th)));
        ASSERT_TRUE(std::isfinite(s.incoherent.hh) && std::isfinite(s.incoherent.vv))
            << m.name << " " << f << " " << th;
      }
    }
  }
  // Dobson soil: wetter soil has the larger permittivity and loss (monotone in m_v).
  const std::complex<double> dry = permittivity(*find_terrain_material("soil_dry"), 10e9);
  const std::complex<double> wet = permittivity(*find_terrain_material("soil_wet"), 10e9);
  EXPECT_GT(wet.real(), dry.real());
  EXPECT_LT(wet.imag(), dry.imag());
}

TEST(Terrain, Sigma0TableInterpolatesTheModels) {
  std::vector<SurfaceSpec> specs;
  for (const char* name : {"asphalt", "grass", "metal"})
    specs.push_back(resolve_surface(*find_terrain_material(name), 94e9));
  const Sigma0Table table(specs, Sigma0Model::kTotal, 94e9);
  ASSERT_EQ(table.materials(), 3u);
  double worst = 0.0, worst_hv = 0.0;
  for (std::size_t m = 0; m < 2; ++m) {
    for (double th = 0.013; th < 85.0; th += 1.37) {
      const SurfaceScatter s =
          evaluate_sigma0(specs[m], Sigma0Model::kTotal, 94e9, Geometry::backscatter(deg(th)));
      const double got = table.lookup(m, Sigma0Table::kVV, std::cos(deg(th)));
      worst = std::max(worst, std::abs(db(got) - db(s.incoherent.vv)));
      // HV is sampled every 0.5 deg and interpolated in dB (its double integral is costly).
      const double got_hv = table.lookup(m, Sigma0Table::kHV, std::cos(deg(th)));
      if (s.incoherent.hv > 0.0)
        worst_hv = std::max(worst_hv, std::abs(db(got_hv) - db(s.incoherent.hv)));
      else
        EXPECT_EQ(got_hv, 0.0f) << th;
      EXPECT_EQ(table.lookup(m, Sigma0Table::kVH, std::cos(deg(th))), static_cast<float>(got_hv));
    }
  }
  std::cout << "table vs direct evaluation: worst " << worst << " dB (VV), " << worst_hv
            << " dB (HV)\n";
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(worst_hv, 0.05);
  EXPECT_EQ(table.lookup(2, Sigma0Table::kHH, 0.5), 0.0f);  // the conductor: no diffuse term
  EXPECT_EQ(table.lookup(7, Sigma0Table::kHH, 0.5), 0.0f);  // unknown material
  EXPECT_EQ(table.lookup(0, Sigma0Table::kHH, std::nan("")), 0.0f);
  EXPECT_EQ(table.lookup(0, Sigma0Table::kHH, 1.5), 0.0f);
}

}  // namespace
}  // namespace radar_emu::radar::clutter
