#include "radar/em/edges.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {

using cplx = std::complex<double>;

double wrap_2pi(double a) noexcept {
  a = std::fmod(a, 2.0 * kPi);
  return a < 0.0 ? a + 2.0 * kPi : a;
}

// Unit component of v normal to unit t (zero vector when v is along t).
glm::dvec3 normal_part(const glm::dvec3& v, const glm::dvec3& t) noexcept {
  const glm::dvec3 u = v - glm::dot(v, t) * t;
  const double l = glm::length(u);
  return l > 0.0 ? u / l : glm::dvec3(0.0);
}

struct Coeffs {
  double f, g;
  double min_den;  // smallest |denominator| met (boundary singularities)
};

// Exact and PO wedge coefficients (edges.hpp) at one observation angle.
Coeffs evaluate(double alpha, double phi, double phi0, EdgeCoefficient kind) noexcept {
  double f = 0.0, g = 0.0, min_den = 1e300;
  if (kind != EdgeCoefficient::kPhysicalOptics) {
    // Sommerfeld/Keller wedge coefficients [U, ch. 2]: n = alpha / pi.
    const double n = alpha / kPi;
    const double sn = std::sin(kPi / n) / n, cn = std::cos(kPi / n);
    const double d1 = cn - std::cos((phi - phi0) / n), d2 = cn - std::cos((phi + phi0) / n);
    min_den = std::min({min_den, std::abs(d1), std::abs(d2)});
    f += sn * (1.0 / d1 - 1.0 / d2);
    g += sn * (1.0 / d1 + 1.0 / d2);
  }
  if (kind != EdgeCoefficient::kExact) {
    // Minus the PO of the lit faces [U, ch. 2]: f0 = sin phi0 / (cos phi + cos phi0),
    // g0 = -sin phi / (cos phi + cos phi0), and the same about face 1 (angles from alpha).
    const double sign = kind == EdgeCoefficient::kFringe ? -1.0 : 1.0;
    if (phi0 < kPi) {
      const double den = std::cos(phi) + std::cos(phi0);
      min_den = std::min(min_den, std::abs(den));
      f += sign * std::sin(phi0) / den;
      g -= sign * std::sin(phi) / den;
    }
    if (phi0 > alpha - kPi) {
      const double den = std::cos(alpha - phi) + std::cos(alpha - phi0);
      min_den = std::min(min_den, std::abs(den));
      f += sign * std::sin(alpha - phi0) / den;
      g -= sign * std::sin(alpha - phi) / den;
    }
  }
  return {f, g, min_den};
}

}  // namespace

WedgeCoefficients wedge_coefficients(double alpha_rad, double phi_rad, double phi0_rad,
                                     EdgeCoefficient kind, bool& guarded) noexcept {
  // Near a shadow or reflection boundary (or the specular direction of a face) the exact and PO
  // parts are each singular and their difference is finite and smooth: step delta to either
  // side and average (error O(delta^2); the cancellation loses ~ 1/min_den of 1e-16).
  constexpr double kSingular = 1e-4, kDelta = 1e-3;
  const Coeffs c = evaluate(alpha_rad, phi_rad, phi0_rad, kind);
  guarded = false;
  if (c.min_den >= kSingular && std::isfinite(c.f) && std::isfinite(c.g))
    return {c.f, c.g};
  guarded = true;
  const Coeffs lo = evaluate(alpha_rad, phi_rad - kDelta, phi0_rad, kind);
  const Coeffs hi = evaluate(alpha_rad, phi_rad + kDelta, phi0_rad, kind);
  return {0.5 * (lo.f + hi.f), 0.5 * (lo.g + hi.g)};
}

std::vector<WedgeEdge> find_wedge_edges(std::span<const std::array<glm::dvec3, 3>> tris,
                                        std::span<const std::int8_t> outward,
                                        std::span<const std::uint8_t> pec, double min_turn_rad,
                                        EdgeCensus& census) {
  // Weld vertices by exact position.
  using Key = std::tuple<double, double, double>;
  std::map<Key, std::uint32_t> ids;
  auto id_of = [&](const glm::dvec3& p) {
    const auto [it, inserted] =
        ids.emplace(Key{p.x, p.y, p.z}, static_cast<std::uint32_t>(ids.size()));
    return it->second;
  };
  struct Use {
    std::uint32_t tri;
    int corner;    // the edge runs from corner to corner + 1 (mod 3)
    bool forward;  // wound from the lower vertex id to the higher
  };
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<Use>> uses;
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    std::array<std::uint32_t, 3> v{id_of(tris[t][0]), id_of(tris[t][1]), id_of(tris[t][2])};
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = v[static_cast<std::size_t>(c)],
                          b = v[static_cast<std::size_t>((c + 1) % 3)];
      if (a == b)
        continue;
      uses[{std::min(a, b), std::max(a, b)}].push_back({t, c, a < b});
    }
  }
  std::vector<WedgeEdge> out;
  for (const auto& [key, u] : uses) {
    const auto& t0 = tris[u[0].tri];
    const glm::dvec3 a = t0[static_cast<std::size_t>(u[0].corner)];
    const glm::dvec3 b = t0[static_cast<std::size_t>((u[0].corner + 1) % 3)];
    const glm::dvec3 third0 = t0[static_cast<std::size_t>((u[0].corner + 2) % 3)];
    WedgeEdge e;
    e.a_m = a;
    e.b_m = b;
    e.length_m = glm::length(b - a);
    if (!(e.length_m > 0.0))
      continue;
    e.t = (b - a) / e.length_m;
    e.x0 = normal_part(third0 - a, e.t);
    const glm::dvec3 n0 = glm::normalize(glm::cross(t0[1] - t0[0], t0[2] - t0[0]));  // as wound
    if (u.size() > 2 || glm::length(e.x0) == 0.0) {
      ++census.unsupported;
      continue;
    }
    if (u.size() == 1) {  // boundary of an open sheet: a half-plane
      if (!pec[u[0].tri]) {
        ++census.unsupported;
        continue;
      }
      e.y0 = n0;
      e.alpha_rad = 2.0 * kPi;
      ++census.half_planes;
      out.push_back(e);
      continue;
    }
    const auto& t1 = tris[u[1].tri];
    if (u[0].forward == u[1].forward || !pec[u[0].tri] || !pec[u[1].tri]) {
      ++census.unsupported;  // inconsistent winding (no free-space side known), or non-PEC
      continue;
    }
    const glm::dvec3 third1 = t1[static_cast<std::size_t>((u[1].corner + 2) % 3)];
    const glm::dvec3 x1 = normal_part(third1 - a, e.t);
    const std::int8_t o = outward[u[0].tri];
    e.y0 = o < 0 ? -n0 : n0;
    double alpha = wrap_2pi(std::atan2(glm::dot(x1, e.y0), glm::dot(x1, e.x0)));
    if (o == 0 && alpha < kPi) {  // open part: take the convex side
      e.y0 = -e.y0;
      alpha = 2.0 * kPi - alpha;
    }
    if (alpha - kPi <= min_turn_rad) {
      ++(alpha < kPi - min_turn_rad ? census.unsupported : census.smooth);  // concave or smooth
      continue;
    }
    e.alpha_rad = alpha;
    ++census.wedges;
    out.push_back(e);
  }
  return out;
}

glm::dvec3 edge_probe(const WedgeEdge& edge, double offset_m) noexcept {
  const double h = 0.5 * edge.alpha_rad;
  return 0.5 * (edge.a_m + edge.b_m) + offset_m * (std::cos(h) * edge.x0 + std::sin(h) * edge.y0);
}

EdgeSkip edge_term(const WedgeEdge& edge, const glm::dvec3& d, const glm::dvec3& s,
                   const glm::dvec3& tx_h, const glm::dvec3& tx_v, const glm::dvec3& rx_h,
                   const glm::dvec3& rx_v, EdgeCoefficient kind, EdgeTerm& term,
                   bool& guarded) noexcept {
  guarded = false;
  const glm::dvec3& t = edge.t;
  const double sin_beta = glm::length(glm::cross(d, t));
  const glm::dvec3 s_perp = s - glm::dot(s, t) * t;
  if (sin_beta < kEdgeMinSin || glm::length(s_perp) < kEdgeMinSin)
    return EdgeSkip::kAlongEdge;
  const glm::dvec3 u = normal_part(-d, t), v = s_perp / glm::length(s_perp);
  const double phi0 = wrap_2pi(std::atan2(glm::dot(u, edge.y0), glm::dot(u, edge.x0)));
  if (phi0 > edge.alpha_rad)
    return EdgeSkip::kBackFace;
  double phi = wrap_2pi(std::atan2(glm::dot(v, edge.y0), glm::dot(v, edge.x0)));
  if (phi > edge.alpha_rad) {
    // Within rounding of face 0 (wrapped to ~2 pi) or face 1: on the face; else inside.
    if (phi > 2.0 * kPi - 1e-9)
      phi = 0.0;
    else if (phi > edge.alpha_rad + 1e-9)
      return EdgeSkip::kInsideWedge;
    else
      phi = edge.alpha_rad;
  }
  const WedgeCoefficients w = wedge_coefficients(edge.alpha_rad, phi, phi0, kind, guarded);
  // S = -(1 / (sqrt(pi) sin^2 beta)) [(e.t) f p.(s x (s x t)) + ((d x e).t) g p.(s x t)]
  // (edges.hpp), times the segment integral.
  const double pre = -1.0 / (std::sqrt(kPi) * sin_beta * sin_beta);
  const glm::dvec3 sst = glm::cross(s, glm::cross(s, t)), st = glm::cross(s, t);
  auto amp = [&](const glm::dvec3& p, const glm::dvec3& e) {
    const double soft = glm::dot(e, t) * w.f, hard = glm::dot(glm::cross(d, e), t) * w.g;
    return cplx(pre * (soft * glm::dot(p, sst) + hard * glm::dot(p, st)), 0.0);
  };
  term.c = {amp(rx_h, tx_h), amp(rx_h, tx_v), amp(rx_v, tx_h), amp(rx_v, tx_v)};
  term.length_m = edge.length_m;
  term.taper_m = 0.5 * glm::dot(s - d, t) * edge.length_m;
  term.phase_m = glm::dot(s - d, 0.5 * (edge.a_m + edge.b_m));
  return EdgeSkip::kNone;
}

}  // namespace radar_emu::radar
