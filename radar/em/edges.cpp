#include "radar/em/edges.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {

using cplx = std::complex<double>;

// The wedge rule's bounds on q = psi h / lambda (edges.hpp).
constexpr double kWedgeSmoothQ = 0.5, kWedgeSharpQ = 1.0;

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

// The angles of a diffraction (edges.hpp): sin(beta) and the source's angle phi0 about `lit`
// for propagation direction d, the receiver's angle phi about `seen` toward s (its projection on
// the plane normal to the edge; within rounding of a face it is put on the face). `lit` and
// `seen` are the same edge for a single diffraction, parallel ones for a double. Returns why
// there is no term, or kNone.
EdgeSkip edge_angles(const WedgeEdge& lit, const WedgeEdge& seen, const glm::dvec3& d,
                     const glm::dvec3& s, double& sin_beta, double& phi0, double& phi) noexcept {
  sin_beta = glm::length(glm::cross(d, lit.t));
  const glm::dvec3 s_perp = s - glm::dot(s, seen.t) * seen.t;
  if (sin_beta < kEdgeMinSin || glm::length(s_perp) < kEdgeMinSin)
    return EdgeSkip::kAlongEdge;
  const glm::dvec3 u = normal_part(-d, lit.t), v = s_perp / glm::length(s_perp);
  phi0 = wrap_2pi(std::atan2(glm::dot(u, lit.y0), glm::dot(u, lit.x0)));
  if (phi0 > lit.alpha_rad)
    return EdgeSkip::kBackFace;
  phi = wrap_2pi(std::atan2(glm::dot(v, seen.y0), glm::dot(v, seen.x0)));
  if (phi > seen.alpha_rad) {
    // Within rounding of face 0 (wrapped to ~2 pi) or face 1: on the face; else inside.
    if (phi > 2.0 * kPi - 1e-9)
      phi = 0.0;
    else if (phi > seen.alpha_rad + 1e-9)
      return EdgeSkip::kInsideWedge;
    else
      phi = seen.alpha_rad;
  }
  return EdgeSkip::kNone;
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

double wedge_weight(const WedgeEdge& edge, double lambda_m, double full_turn_rad) noexcept {
  auto smoothstep = [](double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
  };
  const double psi = edge.alpha_rad - kPi;
  const double q = psi * edge.width_m / lambda_m;
  const double by_size = smoothstep((q - kWedgeSmoothQ) / (kWedgeSharpQ - kWedgeSmoothQ));
  const double by_turn =
      full_turn_rad > 0.0 ? smoothstep((psi - 0.5 * full_turn_rad) / (0.5 * full_turn_rad)) : 1.0;
  return std::max(by_size, by_turn);
}

std::vector<WedgeEdge> find_wedge_edges(std::span<const std::array<glm::dvec3, 3>> tris,
                                        const scene::MeshTopology& topology,
                                        std::span<const std::int8_t> outward,
                                        std::span<const std::uint8_t> pec, double min_turn_rad,
                                        EdgeCensus& census) {
  if (topology.use.size() != tris.size() || outward.size() != tris.size() ||
      pec.size() != tris.size())
    throw std::invalid_argument(
        "find_wedge_edges: one topology triangle, winding and PEC flag "
        "per triangle are needed");
  std::vector<WedgeEdge> out;
  for (const scene::MeshEdge& edge : topology.edges) {
    const std::span<const scene::HalfEdge> u = topology.uses(edge);
    const auto& t0 = tris[u[0].triangle];
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
    e.width_m = glm::dot(third0 - a, e.x0);
    const glm::dvec3 n0 = glm::normalize(glm::cross(t0[1] - t0[0], t0[2] - t0[0]));  // as wound
    if (u.size() > 2 || glm::length(e.x0) == 0.0) {
      ++census.unsupported;
      continue;
    }
    if (u.size() == 1) {  // boundary of an open sheet: a half-plane
      if (!pec[u[0].triangle]) {
        ++census.unsupported;
        continue;
      }
      e.y0 = n0;
      e.alpha_rad = 2.0 * kPi;
      ++census.half_planes;
      out.push_back(e);
      continue;
    }
    const auto& t1 = tris[u[1].triangle];
    if (edge.inconsistent() || !pec[u[0].triangle] || !pec[u[1].triangle]) {
      ++census.unsupported;  // inconsistent winding (no free-space side known), or non-PEC
      continue;
    }
    const glm::dvec3 third1 = t1[static_cast<std::size_t>((u[1].corner + 2) % 3)];
    const glm::dvec3 x1 = normal_part(third1 - a, e.t);
    e.width_m = 0.5 * (e.width_m + glm::dot(third1 - a, x1));
    const std::int8_t o = outward[u[0].triangle];
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

namespace {

// A face of an edge: the unit direction into it (normal to t) and the unit normal on its
// free-space side. Face 0 lies at angle 0, face 1 at alpha (for a half-plane, alpha = 2 pi: the
// same plane seen from its other side).
struct FaceFrame {
  glm::dvec3 into, normal;
  double phi_rad;
};
FaceFrame face_frame(const WedgeEdge& e, int face) noexcept {
  if (face == 0)
    return {e.x0, e.y0, 0.0};
  const double a = e.alpha_rad;
  return {std::cos(a) * e.x0 + std::sin(a) * e.y0, std::sin(a) * e.x0 - std::cos(a) * e.y0, a};
}

bool point_on_facet(const std::array<glm::dvec3, 3>& tri, const glm::dvec3& normal,
                    const glm::dvec3& p, double tolerance_m) noexcept {
  const glm::dvec3 n = glm::cross(tri[1] - tri[0], tri[2] - tri[0]);
  const double n2 = glm::dot(n, n);
  if (!(n2 > 0.0) || std::abs(glm::dot(n, normal)) < (1.0 - 1e-6) * std::sqrt(n2))
    return false;
  if (std::abs(glm::dot(p - tri[0], normal)) > tolerance_m)
    return false;
  // Barycentric signs: p is inside when it is on the inner side of all three edges.
  for (int c = 0; c < 3; ++c) {
    const glm::dvec3& a = tri[static_cast<std::size_t>(c)];
    const glm::dvec3& b = tri[static_cast<std::size_t>((c + 1) % 3)];
    if (glm::dot(glm::cross(b - a, p - a), n) < 0.0)
      return false;
  }
  return true;
}

}  // namespace

std::vector<EdgePair> find_edge_pairs(std::span<const WedgeEdge> edges,
                                      std::span<const std::array<glm::dvec3, 3>> tris,
                                      double tolerance_m) {
  // Bucket the edges by direction (sign-folded, rounded to 1e-6) so that only parallel edges
  // are compared.
  using Key = std::tuple<long long, long long, long long>;
  std::map<Key, std::vector<std::uint32_t>> buckets;
  for (std::uint32_t i = 0; i < edges.size(); ++i) {
    const glm::dvec3 t = sign_folded(edges[i].t);
    buckets[Key{std::llround(t.x * 1e6), std::llround(t.y * 1e6), std::llround(t.z * 1e6)}]
        .push_back(i);
  }
  std::vector<EdgePair> out;
  for (const auto& [key, ids] : buckets) {
    for (const std::uint32_t i : ids) {
      const WedgeEdge& ei = edges[i];
      for (const std::uint32_t j : ids) {
        if (i == j)
          continue;
        const WedgeEdge& ej = edges[j];
        if (std::abs(glm::dot(ei.t, ej.t)) < 1.0 - 1e-12)
          continue;
        for (int fi = 0; fi < 2; ++fi) {
          const FaceFrame a = face_frame(ei, fi);
          const glm::dvec3 ra = ej.a_m - ei.a_m, rb = ej.b_m - ei.a_m;
          if (std::abs(glm::dot(ra, a.normal)) > tolerance_m ||
              std::abs(glm::dot(rb, a.normal)) > tolerance_m)
            continue;
          const double w = glm::dot(ra, a.into);
          if (!(w > tolerance_m))
            continue;
          for (int fj = 0; fj < 2; ++fj) {
            const FaceFrame b = face_frame(ej, fj);
            if (glm::dot(b.into, a.into) > -1.0 + 1e-9 || glm::dot(b.normal, a.normal) < 1.0 - 1e-9)
              continue;
            EdgePair p;
            p.from = i;
            p.to = j;
            p.phi_launch_rad = a.phi_rad;
            p.phi_arrive_rad = b.phi_rad;
            p.width_m = w;
            p.to_lo_m = std::min(glm::dot(ra, ei.t), glm::dot(rb, ei.t));
            p.to_hi_m = std::max(glm::dot(ra, ei.t), glm::dot(rb, ei.t));
            const double lo = std::max(0.0, p.to_lo_m), hi = std::min(ei.length_m, p.to_hi_m);
            if (!(hi - lo > tolerance_m))
              continue;  // no overlap broadside
            // The face must be there between them: a facet of its plane under the strip's middle.
            const glm::dvec3 mid = ei.a_m + 0.5 * (lo + hi) * ei.t + 0.5 * w * a.into;
            bool on_face = false;
            for (const auto& tri : tris) {
              if (point_on_facet(tri, a.normal, mid, tolerance_m)) {
                on_face = true;
                break;
              }
            }
            if (on_face)
              out.push_back(p);
          }
        }
      }
    }
  }
  return out;
}

EdgeSkip double_edge_term(const EdgePair& pair, std::span<const WedgeEdge> edges,
                          const glm::dvec3& d, const glm::dvec3& s, const glm::dvec3& tx_h,
                          const glm::dvec3& tx_v, const glm::dvec3& rx_h, const glm::dvec3& rx_v,
                          DoubleEdgeTerm& term) noexcept {
  const WedgeEdge& e1 = edges[pair.from];
  const WedgeEdge& e2 = edges[pair.to];
  const glm::dvec3& t1 = e1.t;
  double sin_beta = 0.0, phi0 = 0.0, phi = 0.0;
  if (const EdgeSkip why = edge_angles(e1, e2, d, s, sin_beta, phi0, phi); why != EdgeSkip::kNone)
    return why;
  // Rays from Q1 in [0, L1] along t1 reach the second edge's line shifted by s (u . t1), with
  // s = w / sin(beta) and u . t1 = d . t1 (the Keller cone).
  const double w = pair.width_m;
  const double shift = w / sin_beta * glm::dot(d, t1);
  const double lo = std::max(shift, pair.to_lo_m), hi = std::min(e1.length_m + shift, pair.to_hi_m);
  if (!(hi > lo))
    return EdgeSkip::kAlongEdge;
  const glm::dvec3 into =
      std::cos(pair.phi_launch_rad) * e1.x0 + std::sin(pair.phi_launch_rad) * e1.y0;
  const glm::dvec3 centre = e1.a_m + 0.5 * (lo + hi) * t1 + w * into;
  const glm::dvec3& t2 = e2.t;
  const double pre = -glm::dot(t1, t2) / (std::sqrt(kPi) * sin_beta * sin_beta);
  const glm::dvec3 st2 = glm::cross(s, t2);
  auto amp = [&](const glm::dvec3& p, const glm::dvec3& e) {
    return pre * glm::dot(glm::cross(d, e), t1) * glm::dot(p, st2);
  };
  term.pol = {amp(rx_h, tx_h), amp(rx_h, tx_v), amp(rx_v, tx_h), amp(rx_v, tx_v)};
  term.alpha_from_rad = e1.alpha_rad;
  term.phi_launch_rad = pair.phi_launch_rad;
  term.phi0_rad = phi0;
  term.alpha_to_rad = e2.alpha_rad;
  term.phi_arrive_rad = pair.phi_arrive_rad;
  term.phi_rad = phi;
  term.l_m = w * sin_beta;
  term.length_m = hi - lo;
  term.centre_m = centre;
  term.taper_m = 0.5 * glm::dot(s - d, t2) * term.length_m;
  term.phase_m =
      glm::dot(s - d, centre) - w * sin_beta * (1.0 + std::cos(pair.phi_launch_rad - phi0));
  return EdgeSkip::kNone;
}

std::complex<double> double_edge_factor(const DoubleEdgeTerm& t, double k) noexcept {
  const double kl = k * t.l_m;
  const cplx g1 = utd_wedge_coefficient(t.alpha_from_rad, t.phi_launch_rad, t.phi0_rad, kl, true);
  const cplx g2 = utd_wedge_coefficient(t.alpha_to_rad, t.phi_rad, t.phi_arrive_rad, kl, true);
  const double x = k * t.taper_m;
  const double sinc = std::abs(x) < 1e-3 ? 1.0 - x * x / 6.0 : std::sin(x) / x;
  return std::polar(1.0 / std::sqrt(2.0 * kPi * kl), -0.25 * kPi) * g1 * (0.5 * g2) *
         std::polar(t.length_m * sinc, k * t.phase_m);
}

std::complex<double> utd_wedge_coefficient(double alpha_rad, double phi_rad, double phi0_rad,
                                           double kl, bool hard) noexcept {
  const double n = alpha_rad / kPi;
  // cot((pi +- x) / 2n) F(kL a+-(x)) [KP eqs. 25-27]; at a boundary cot -> inf and F -> 0: the
  // mean of the two one-sided limits, n sqrt(2 pi kL) e^{j pi/4} (+-1), is 0 (KP eq. 29).
  auto term = [&](double x) {
    cplx r = 0.0;
    for (const double sign : {1.0, -1.0}) {
      const double arg = (kPi + sign * x) / (2.0 * n);
      const double sa = std::sin(arg);
      if (std::abs(sa) < 1e-12)
        continue;
      const double big_n = std::round((x + sign * kPi) / (2.0 * kPi * n));
      const double c = std::cos(0.5 * (2.0 * kPi * n * big_n - x));
      r += (std::cos(arg) / sa) * utd_transition(kl * 2.0 * c * c);
    }
    return r;
  };
  return -(term(phi_rad - phi0_rad) + (hard ? 1.0 : -1.0) * term(phi_rad + phi0_rad)) / (2.0 * n);
}

std::complex<double> utd_transition(double x) noexcept {
  if (!(x > 0.0))
    return 0.0;
  const cplx j(0.0, 1.0);
  if (x > 16.0) {  // asymptotic: sum (-1)^m (2m - 1)!! / (2 j X)^m, stopped at its smallest term
    cplx sum = 1.0, t = 1.0;
    for (int m = 1; m <= 16; ++m) {
      const cplx next = t * (-(2.0 * m - 1.0) / (2.0 * j * x));
      if (std::abs(next) >= std::abs(t))
        break;
      t = next;
      sum += t;
    }
    return sum;
  }
  // int_0^a exp(-j tau^2) d tau = sum_n (-j)^n a^(2n+1) / (n! (2n + 1)), a = sqrt(X).
  const double a = std::sqrt(x);
  cplx p = a, series = a;
  for (int m = 1; m < 200; ++m) {
    p *= -j * x / static_cast<double>(m);
    const cplx add = p / (2.0 * m + 1.0);
    series += add;
    if (m > x && std::abs(add) < 1e-17 * std::abs(series))
      break;
  }
  const cplx tail = std::polar(0.5 * std::sqrt(kPi), -0.25 * kPi) - series;
  return 2.0 * j * a * std::polar(1.0, x) * tail;
}

glm::dvec3 sign_folded(const glm::dvec3& v) noexcept {
  const double big = std::abs(v.x) >= std::abs(v.y) && std::abs(v.x) >= std::abs(v.z)
                         ? v.x
                         : (std::abs(v.y) >= std::abs(v.z) ? v.y : v.z);
  return big < 0.0 ? -v : v;
}

glm::dvec3 edge_probe(const WedgeEdge& edge, double offset_m) noexcept {
  const double h = 0.5 * edge.alpha_rad;
  return 0.5 * (edge.a_m + edge.b_m) + offset_m * (std::cos(h) * edge.x0 + std::sin(h) * edge.y0);
}

EdgeSkip edge_term(const WedgeEdge& edge, const glm::dvec3& d, const glm::dvec3& s,
                   const glm::dvec3& tx_h, const glm::dvec3& tx_v, const glm::dvec3& rx_h,
                   const glm::dvec3& rx_v, EdgeCoefficient kind, EdgeTerm& term, bool& guarded,
                   double min_sin2_beta, double coefficient_bound) noexcept {
  guarded = false;
  const glm::dvec3& t = edge.t;
  double sin_beta = 0.0, phi0 = 0.0, phi = 0.0;
  if (const EdgeSkip why = edge_angles(edge, edge, d, s, sin_beta, phi0, phi);
      why != EdgeSkip::kNone)
    return why;
  WedgeCoefficients w = wedge_coefficients(edge.alpha_rad, phi, phi0, kind, guarded);
  w.f = std::clamp(w.f, -coefficient_bound, coefficient_bound);
  w.g = std::clamp(w.g, -coefficient_bound, coefficient_bound);
  // S = -(1 / (sqrt(pi) sin^2 beta)) [(e.t) f p.(s x (s x t)) + ((d x e).t) g p.(s x t)]
  // (edges.hpp), times the segment integral.
  // 1 / sin^2 beta, regularised (edges.hpp): unchanged down to sin^2 beta = m (min_sin2_beta),
  // then sin^2 beta / m^2, falling linearly to 0 end-on (where the skip at kEdgeMinSin would
  // otherwise make a step); continuous, never above 1 / m.
  const double sin2 = sin_beta * sin_beta;
  const double keller = sin2 >= min_sin2_beta ? 1.0 / sin2 : sin2 / (min_sin2_beta * min_sin2_beta);
  const double pre = -keller / std::sqrt(kPi);
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
