// The closed-form triangle integral (radar/em/facet_po.hpp) against brute-force quadrature in
// every regime of its removable singularities: normal incidence (all vertex phases equal),
// oblique, near edge-on, one edge inside the first-difference series threshold and the other
// outside, and whole spreads just under and just over the second-difference series switch.
#include "radar/em/facet_po.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <iostream>
#include <random>
#include <vector>

namespace radar_emu::radar {
namespace {

// Gauss-Legendre nodes and weights on [0, 1] (Newton on P_n; Press et al., Numerical Recipes
// 3rd ed., sec. 4.6.1).
struct Rule {
  std::vector<double> x, w;
};
Rule gauss_legendre(int n) {
  Rule r;
  r.x.resize(static_cast<std::size_t>(n));
  r.w.resize(static_cast<std::size_t>(n));
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < n; ++i) {
    double z = std::cos(pi * (i + 0.75) / (n + 0.5)), pp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p1 = 1.0, p2 = 0.0;
      for (int j = 0; j < n; ++j) {
        const double p3 = p2;
        p2 = p1;
        p1 = ((2.0 * j + 1.0) * z * p2 - j * p3) / (j + 1.0);
      }
      pp = n * (z * p1 - p2) / (z * z - 1.0);
      const double dz = p1 / pp;
      z -= dz;
      if (std::abs(dz) < 1e-15)
        break;
    }
    r.x[static_cast<std::size_t>(i)] = 0.5 * (1.0 - z);
    r.w[static_cast<std::size_t>(i)] = 1.0 / ((1.0 - z * z) * pp * pp);
  }
  return r;
}

// Brute force: Duffy map of the triangle to the unit square, s = u, t = (1 - u) v, with a
// tensor Gauss-Legendre rule (exact to machine precision for these entire integrands once the
// rule resolves the oscillation: 240 nodes cover phase spreads of a few hundred radians).
std::complex<double> quadrature(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2,
                                const glm::dvec3& g) {
  static const Rule rule = gauss_legendre(240);
  const glm::dvec3 e1 = v1 - v0, e2 = v2 - v0;
  const double two_area = glm::length(glm::cross(e1, e2));
  std::complex<double> sum{0.0, 0.0};
  for (std::size_t i = 0; i < rule.x.size(); ++i) {
    const double u = rule.x[i];
    for (std::size_t j = 0; j < rule.x.size(); ++j) {
      const double v = rule.x[j];
      const glm::dvec3 r = v0 + u * e1 + (1.0 - u) * v * e2;
      const double phase = glm::dot(g, r);
      sum += rule.w[i] * rule.w[j] * (1.0 - u) *
             std::complex<double>(std::cos(phase), std::sin(phase));
    }
  }
  return two_area * sum;
}

// A triangle in the plane z = z0 whose vertex phases under g = (1, 0, gz) are p0, p1, p2 plus
// the common gz z0: x-coordinates carry the phases.
struct Case {
  const char* name;
  double p0, p1, p2, gz, z0;
};

constexpr double kRelTol = 1e-6;  // acceptance criterion of issue 3

void check(const Case& c) {
  const glm::dvec3 v0(c.p0, 0.0, c.z0), v1(c.p1, 1.0, c.z0), v2(c.p2, -0.6, c.z0);
  const glm::dvec3 g(1.0, 0.0, c.gz);
  const std::complex<double> closed = triangle_phase_integral(v0, v1, v2, g);
  const std::complex<double> brute = quadrature(v0, v1, v2, g);
  const double rel = std::abs(closed - brute) / std::abs(brute);
  std::cout << c.name << ": |I| = " << std::abs(brute) << ", relative error " << rel << "\n";
  EXPECT_LT(rel, kRelTol) << c.name;
  EXPECT_TRUE(std::isfinite(closed.real()) && std::isfinite(closed.imag())) << c.name;
}

TEST(FacetPo, NormalIncidenceAllPhasesEqual) {
  // g along the normal: every vertex has the same phase, I = A e^{j g.v0} exactly.
  const glm::dvec3 v0(0, 0, 0.7), v1(0, 1, 0.7), v2(0.5, -0.6, 0.7), g(0.0, 0.0, 3.0);
  const std::complex<double> i = triangle_phase_integral(v0, v1, v2, g);
  const double area = 0.5 * glm::length(glm::cross(v1 - v0, v2 - v0));
  EXPECT_NEAR(std::abs(i - area * std::polar(1.0, 2.1)), 0.0, 1e-14);
  const std::complex<double> brute = quadrature(v0, v1, v2, g);
  EXPECT_LT(std::abs(i - brute) / std::abs(brute), kRelTol);
}

TEST(FacetPo, ObliqueIncidence) {
  check({"oblique", 0.0, 2.3, -1.7, 5.0, 0.3});
  check({"oblique-large-offset", 4000.0, 4003.1, 3998.2, 1.0, 0.0});
}

TEST(FacetPo, NearEdgeOn) {
  // Large in-plane gradient: phase spreads of tens to a hundred radians over the facet.
  check({"near-edge-on", 0.0, 47.0, -31.0, 1e-3, 0.0});
  check({"edge-on-spread-100", -50.0, 50.0, 13.0, 0.0, 0.0});
}

TEST(FacetPo, OneEdgeInsideSeriesThresholdOtherOutside) {
  // Edge v0-v1 has a vanishing phase difference (first-difference Taylor branch), the others
  // do not; with the spread above the second-difference switch and below it.
  check({"edge-inside-spread-3", 0.0, 1e-4, 3.0, 0.0, 0.0});
  check({"edge-inside-spread-0.5", 0.0, 2e-4, 0.5, 0.0, 0.0});
  check({"edge-at-sinc-switch", 0.0, 2e-3 - 1e-12, 2.0, 0.0, 0.0});
  check({"edge-past-sinc-switch", 0.0, 2e-3 + 1e-12, 2.0, 0.0, 0.0});
}

TEST(FacetPo, SpreadJustUnderAndOverSeriesSwitch) {
  check({"spread-just-under", 0.0, 0.4, kSeriesSpreadRad * (1.0 - 1e-12), 0.0, 0.0});
  check({"spread-just-over", 0.0, 0.4, kSeriesSpreadRad * (1.0 + 1e-12), 0.0, 0.0});
  check({"spread-under-two-close", 0.0, 1e-9, kSeriesSpreadRad * (1.0 - 1e-9), 0.0, 0.0});
  check({"spread-over-two-close", 0.0, 1e-9, kSeriesSpreadRad * (1.0 + 1e-9), 0.0, 0.0});
  // Continuity across the switch: the two branches agree to near machine precision.
  const std::complex<double> below = exp_divided_difference2(0.0, 0.3, kSeriesSpreadRad - 1e-13);
  const std::complex<double> above = exp_divided_difference2(0.0, 0.3, kSeriesSpreadRad + 1e-13);
  EXPECT_LT(std::abs(below - above) / std::abs(below), 1e-12);
}

TEST(FacetPo, RandomTrianglesAllRegimes) {
  const std::uint64_t seed = 20261122;
  std::cout << "seed " << seed << "\n";
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), log_scale(-8.0, 2.0);
  double worst = 0.0;
  for (int trial = 0; trial < 300; ++trial) {
    const glm::dvec3 v0{unit(rng), unit(rng), unit(rng)};
    const glm::dvec3 v1 = v0 + glm::dvec3{unit(rng), unit(rng), unit(rng)};
    const glm::dvec3 v2 = v0 + glm::dvec3{unit(rng), unit(rng), unit(rng)};
    // Phase gradient magnitudes from 1e-8 to 100 rad/m: every branch.
    const glm::dvec3 dir = glm::normalize(glm::dvec3{unit(rng), unit(rng), unit(rng)});
    const glm::dvec3 g = dir * std::pow(10.0, log_scale(rng));
    const std::complex<double> brute = quadrature(v0, v1, v2, g);
    const double rel = std::abs(triangle_phase_integral(v0, v1, v2, g) - brute) / std::abs(brute);
    worst = std::max(worst, rel);
    ASSERT_LT(rel, kRelTol) << "trial " << trial;
  }
  std::cout << "worst relative error over 300 random triangles: " << worst << "\n";
}

TEST(FacetPo, NeverNanForExtremeInputs) {
  const glm::dvec3 v0(0, 0, 0), v1(1, 0, 0), v2(0, 1, 0);
  for (double s : {0.0, 1e-300, 1e-20, 1e-8, 1.0, 1e6, 1e12}) {
    const std::complex<double> i = triangle_phase_integral(v0, v1, v2, {s, -0.5 * s, s});
    EXPECT_TRUE(std::isfinite(i.real()) && std::isfinite(i.imag())) << s;
    EXPECT_LE(std::abs(i), 0.5 + 1e-12) << s;  // |I| <= area
  }
  // Degenerate triangle: zero, not NaN.
  EXPECT_EQ(triangle_phase_integral(v0, v1, 2.0 * v1, {1, 2, 3}), std::complex<double>(0.0, 0.0));
}

}  // namespace
}  // namespace radar_emu::radar
