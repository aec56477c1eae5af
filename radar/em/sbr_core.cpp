#include "radar/em/sbr_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include "radar/constants.hpp"
#include "radar/em/facet_po.hpp"

namespace radar_emu::radar {

using cplx = std::complex<double>;

ReflectionCoefficients reflection_coefficients(const SurfaceModel& surface, double cos_incidence,
                                               double k) noexcept {
  if (surface.kind == SurfaceModel::Kind::kPec)
    return {};
  const double c = std::clamp(cos_incidence, 0.0, 1.0);
  const double sin2 = 1.0 - c * c;
  const cplx eps = surface.relative_permittivity;
  const cplx root = std::sqrt(eps - sin2);  // principal branch: Im <= 0 for lossy eps
  ReflectionCoefficients r;
  r.perp = (c - root) / (c + root);
  r.par = (eps * c - root) / (eps * c + root);
  if (surface.kind == SurfaceModel::Kind::kCoatedPec) {
    const cplx beta = k * root;
    const cplx delay = std::exp(cplx(0.0, -2.0) * beta * surface.thickness_m);
    r.perp = (r.perp - delay) / (1.0 - r.perp * delay);  // r12 = -1
    r.par = (r.par + delay) / (1.0 + r.par * delay);     // r12 = +1
  }
  return r;
}

CVec reflect_field(const CVec& e, const glm::dvec3& d, const glm::dvec3& d_r, const glm::dvec3& n,
                   const ReflectionCoefficients& r, bool pec) noexcept {
  if (pec)  // tangential E flips, normal E stays: E_r = -E + 2 (n.E) n
    return {2.0 * glm::dot(n, e.re) * n - e.re, 2.0 * glm::dot(n, e.im) * n - e.im};
  glm::dvec3 e_perp = glm::cross(d, n);
  double len = glm::length(e_perp);
  if (len < 1e-12) {  // normal incidence: any tangential direction (take one from the field)
    e_perp = e.re - glm::dot(e.re, d) * d;
    if (glm::length(e_perp) < 1e-12 * (norm(e) + 1e-300))
      e_perp = e.im - glm::dot(e.im, d) * d;
    len = glm::length(e_perp);
    if (len == 0.0)
      return {};
  }
  e_perp /= len;
  const glm::dvec3 e_par_i = glm::cross(e_perp, d), e_par_r = glm::cross(e_perp, d_r);
  return scale(r.perp * dot(e_perp, e), e_perp) + scale(r.par * dot(e_par_i, e), e_par_r);
}

CVec po_source(const CVec& e, const glm::dvec3& d, const glm::dvec3& n, const glm::dvec3& s,
               const ReflectionCoefficients& r, bool pec) noexcept {
  if (pec)  // eta J = 2 n x (d x E), M = 0
    return {2.0 * glm::cross(n, glm::cross(d, e.re)), 2.0 * glm::cross(n, glm::cross(d, e.im))};
  const glm::dvec3 d_r = mirror(d, n);
  const CVec e_r = reflect_field(e, d, d_r, n, r, false);
  const CVec eta_j = cross(n, cross(d, e) + cross(d_r, e_r));
  const CVec m = cross(e + e_r, n);
  return eta_j - cross(s, m);
}

TubeFootprint tube_footprint(const glm::dvec3& tube_u_m, const glm::dvec3& tube_v_m,
                             const glm::dvec3& d, const glm::dvec3& n,
                             const glm::dvec3& s) noexcept {
  const double n_d = glm::dot(n, d);
  TubeFootprint f;
  f.u_m = tube_u_m - d * (glm::dot(n, tube_u_m) / n_d);
  f.v_m = tube_v_m - d * (glm::dot(n, tube_v_m) / n_d);
  f.area_m2 = glm::length(glm::cross(f.u_m, f.v_m));
  f.taper_u_m = 0.5 * glm::dot(s - d, f.u_m);
  f.taper_v_m = 0.5 * glm::dot(s - d, f.v_m);
  return f;
}

double footprint_integral(const TubeFootprint& f, double k) noexcept {
  return f.area_m2 * sinc(k * f.taper_u_m) * sinc(k * f.taper_v_m);
}

cplx po_amplitude_m(double k, const glm::dvec3& p, const CVec& source,
                    double integral_m2) noexcept {
  return cplx(0.0, -k / std::sqrt(kPi)) * (0.5 * dot(p, source)) * integral_m2;
}

std::array<glm::dvec3, kFacetSamples> facet_samples(const glm::dvec3& v0, const glm::dvec3& v1,
                                                    const glm::dvec3& v2,
                                                    const glm::dvec3& lit_normal,
                                                    double offset_m) noexcept {
  const glm::dvec3 c = (v0 + v1 + v2) / 3.0, lift = offset_m * lit_normal;
  auto inset = [&](const glm::dvec3& p) { return p + kFacetSampleInset * (c - p) + lift; };
  return {c + lift,
          inset(v0),
          inset(v1),
          inset(v2),
          inset(0.5 * (v0 + v1)),
          inset(0.5 * (v1 + v2)),
          inset(0.5 * (v2 + v0))};
}

int facet_subdivisions(double longest_edge_m, double resolution_m) noexcept {
  const double m = std::ceil(longest_edge_m / resolution_m);
  if (!(m < kMaxFacetSubdivisions))  // also NaN
    return kMaxFacetSubdivisions;
  return std::max(1, static_cast<int>(m));
}

std::vector<std::int8_t> closed_part_winding(std::span<const glm::vec3> positions,
                                             std::span<const glm::uvec3> triangles) {
  const std::size_t nt = triangles.size();
  std::vector<std::int8_t> out(nt, 0);
  // Weld vertices by exact position (meshes often repeat a vertex per face).
  auto key = [&](unsigned i) {
    const glm::vec3 p = positions[i] + glm::vec3(0.0f);  // -0 -> +0: equal positions, equal keys
    std::uint32_t b[3];
    std::memcpy(b, &p, sizeof b);
    return (static_cast<std::uint64_t>(b[0]) * 0x9E3779B97F4A7C15ull) ^
           (static_cast<std::uint64_t>(b[1]) * 0xC2B2AE3D27D4EB4Full) ^
           (static_cast<std::uint64_t>(b[2]) * 0x165667B19E3779F9ull);
  };
  std::unordered_multimap<std::uint64_t, std::uint32_t> by_key;
  std::vector<std::uint32_t> weld(positions.size());
  for (std::uint32_t i = 0; i < positions.size(); ++i) {
    std::uint32_t id = i;
    const auto range = by_key.equal_range(key(i));
    for (auto it = range.first; it != range.second; ++it) {
      if (positions[it->second] == positions[i]) {
        id = weld[it->second];
        break;
      }
    }
    weld[i] = id;
    if (id == i)
      by_key.emplace(key(i), i);
  }
  // Parts: union-find over triangles sharing an (undirected) edge; an edge is closed when it is
  // met exactly twice, in opposite directions.
  std::vector<std::uint32_t> parent(nt);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x)
      x = parent[x] = parent[parent[x]];
    return x;
  };
  struct EdgeUse {
    std::uint32_t triangle;
    int forward = 0, backward = 0;
  };
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(3 * nt);
  std::vector<std::uint8_t> open(nt, 0);
  for (std::uint32_t t = 0; t < nt; ++t) {
    const std::uint32_t v[3] = {weld[triangles[t].x], weld[triangles[t].y], weld[triangles[t].z]};
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
      open[t] = 1;
      continue;
    }
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = v[e], b = v[(e + 1) % 3];
      const std::uint64_t k = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
      auto [it, fresh] = edges.try_emplace(k, EdgeUse{t});
      (a < b ? it->second.forward : it->second.backward) += 1;
      if (!fresh) {
        const std::uint32_t ra = find(it->second.triangle), rb = find(t);
        parent[ra] = rb;
      }
    }
  }
  // A part is open if any of its triangles is degenerate or any of its edges is not closed.
  std::vector<std::uint8_t> part_open(nt, 0);
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (open[t])
      part_open[find(t)] = 1;
  }
  for (const auto& [k, use] : edges) {
    if (use.forward != 1 || use.backward != 1)
      part_open[find(use.triangle)] = 1;
  }
  // Orientation of each closed part: the sign of its volume, sum of v0 . (v1 x v2) / 6 (the
  // divergence theorem over the part's triangles, counter-clockwise seen from outside).
  std::vector<double> volume(nt, 0.0);
  for (std::uint32_t t = 0; t < nt; ++t) {
    const glm::dvec3 a(positions[triangles[t].x]), b(positions[triangles[t].y]),
        c(positions[triangles[t].z]);
    volume[find(t)] += glm::dot(a, glm::cross(b, c));
  }
  for (std::uint32_t t = 0; t < nt; ++t) {
    const std::uint32_t r = find(t);
    if (!part_open[r] && volume[r] != 0.0)
      out[t] = volume[r] > 0.0 ? 1 : -1;
  }
  return out;
}

bool facet_in_far_field(double rho_m, double range_m, double k) noexcept {
  return k * rho_m * rho_m <= 0.125 * kPi * range_m;
}

}  // namespace radar_emu::radar
