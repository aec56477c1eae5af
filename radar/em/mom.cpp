#include "radar/em/mom.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <new>
#include <numeric>
#include <stdexcept>
#include <utility>

#include "radar/constants.hpp"
#include "scene/mesh/topology.hpp"

// LAPACK (OpenBLAS's build, Debian libopenblas-dev): LU factorisation and solve.
extern "C" {
void zgetrf_(const int* m, const int* n, std::complex<double>* a, const int* lda, int* ipiv,
             int* info);
void zgetrs_(const char* trans, const int* n, const int* nrhs, const std::complex<double>* a,
             const int* lda, const int* ipiv, std::complex<double>* b, const int* ldb, int* info,
             std::size_t trans_len);
}

namespace radar_emu::radar {
namespace {

using cd = std::complex<double>;

// A complex 3-vector as its real and imaginary parts (the geometry is real).
struct CplxVec {
  glm::dvec3 re{0.0}, im{0.0};
};
CplxVec& operator+=(CplxVec& a, const CplxVec& b) {
  a.re += b.re;
  a.im += b.im;
  return a;
}
cd dot(const glm::dvec3& a, const CplxVec& b) {
  return {glm::dot(a, b.re), glm::dot(a, b.im)};
}
CplxVec cross(const glm::dvec3& a, const CplxVec& b) {
  return {glm::cross(a, b.re), glm::cross(a, b.im)};
}
CplxVec scale(const glm::dvec3& a, cd s) {
  return {a * s.real(), a * s.imag()};
}
CplxVec minus(const CplxVec& a, const CplxVec& b) {
  return {a.re - b.re, a.im - b.im};
}

// Dunavant (1985) degree-4 rule: barycentric points and weights (summing to 1).
struct TriRule {
  std::array<std::array<double, 3>, 6> bary{};
  std::array<double, 6> weight{};
  std::size_t n = 0;
};
TriRule dunavant6() {
  TriRule r;
  const double a1 = 0.445948490915965, w1 = 0.223381589678011;
  const double a2 = 0.091576213509771, w2 = 0.109951743655322;
  r.bary = {{{a1, a1, 1.0 - 2.0 * a1},
             {a1, 1.0 - 2.0 * a1, a1},
             {1.0 - 2.0 * a1, a1, a1},
             {a2, a2, 1.0 - 2.0 * a2},
             {a2, 1.0 - 2.0 * a2, a2},
             {1.0 - 2.0 * a2, a2, a2}}};
  r.weight = {w1, w1, w1, w2, w2, w2};
  r.n = 6;
  return r;
}
// The 3-point degree-2 rule (Strang & Fix): points (2/3, 1/6, 1/6), weight 1/3 each.
TriRule strang3() {
  TriRule r;
  const double a = 1.0 / 6.0, b = 2.0 / 3.0;
  r.bary[0] = {b, a, a};
  r.bary[1] = {a, b, a};
  r.bary[2] = {a, a, b};
  r.weight[0] = r.weight[1] = r.weight[2] = 1.0 / 3.0;
  r.n = 3;
  return r;
}
const TriRule kRule6 = dunavant6();
const TriRule kRule3 = strang3();

// Gauss-Legendre 4 and 6 points on [0, 1] (Abramowitz & Stegun, table 25.4).
struct Line {
  std::vector<double> x, w;
};
void gauss_panel(const double* nodes, const double* weights, std::size_t half, double a, double b,
                 Line& out) {
  for (std::size_t i = 0; i < half; ++i) {
    for (double s : {-1.0, 1.0}) {
      out.x.push_back(a + (b - a) * 0.5 * (1.0 + s * nodes[i]));
      out.w.push_back((b - a) * 0.5 * weights[i]);
    }
  }
}
constexpr double kGl4x[2] = {0.3399810435848563, 0.8611363115940526};
constexpr double kGl4w[2] = {0.6521451548625461, 0.3478548451374538};
constexpr double kGl6x[3] = {0.2386191860831969, 0.6612093864662645, 0.9324695142031521};
constexpr double kGl6w[3] = {0.4679139345726910, 0.3607615730481386, 0.1713244923791704};
// Radial Duffy coordinate: 4-point panels graded toward the singular vertex (u = 0), where the
// observation point's height over a neighbour's plane makes the MFIE kernel peak.
Line duffy_radial() {
  Line l;
  const double edges[] = {0.0, 0.02, 0.1, 0.35, 1.0};
  for (std::size_t i = 0; i + 1 < std::size(edges); ++i)
    gauss_panel(kGl4x, kGl4w, 2, edges[i], edges[i + 1], l);
  return l;
}
Line duffy_angular() {
  Line l;
  gauss_panel(kGl6x, kGl6w, 3, 0.0, 1.0, l);
  return l;
}
const Line kDuffyU = duffy_radial();
const Line kDuffyV = duffy_angular();

// The inner integrals over a source triangle for one observation point r (weights include the
// source's area): sG = int G, vG = int G r', and for the MFIE sg = int g, vg = int g r', where
// G = e^{-jkR} / (4 pi R) and grad G = g (r - r'), g = -(1 + jkR) e^{-jkR} / (4 pi R^3).
struct Inner {
  cd sG{0.0, 0.0}, sg{0.0, 0.0};
  CplxVec vG, vg;
  void add(const glm::dvec3& r, const glm::dvec3& rp, double w, double k, bool mfie) {
    const double dist = glm::length(r - rp);
    const double c = std::cos(k * dist), s = std::sin(k * dist);
    const double wG = w / (4.0 * kPi * dist);
    const cd G(c * wG, -s * wG);
    sG += G;
    vG += scale(rp, G);
    if (mfie) {
      // -(1 + jkR) e^{-jkR} / (4 pi R^3), times w.
      const cd g = -cd(1.0, k * dist) * G / (dist * dist);
      sg += g;
      vg += scale(rp, g);
    }
  }
};

}  // namespace

const char* equation_name(MomEquation e) noexcept {
  switch (e) {
    case MomEquation::kEfie:
      return "EFIE";
    case MomEquation::kMfie:
      return "MFIE";
    case MomEquation::kCfie:
      return "CFIE";
  }
  return "?";
}

MomSolver::MomSolver(const scene::SceneDescription& description,
                     std::span<const SurfaceModel> surfaces, MomConfig config)
    : config_(config) {
  if (!(config.cfie_alpha > 0.0 && config.cfie_alpha < 1.0))
    throw std::invalid_argument("MoM: the CFIE weight alpha must be in (0, 1)");
  // World-frame triangles, every material PEC.
  std::vector<glm::dvec3> raw;
  std::vector<glm::uvec3> tris;
  for (const scene::ObjectDesc& o : description.objects) {
    if (o.motion || o.trajectory)
      throw std::invalid_argument("MoM: object '" + o.name +
                                  "' moves; the method of moments takes static targets");
    const glm::dmat4 m = o.world_from_body;
    const auto base = static_cast<std::uint32_t>(raw.size());
    for (const glm::vec3& p : o.mesh.positions_m) {
      const glm::dvec3 w(m * glm::dvec4(glm::dvec3(p), 1.0));
      if (!std::isfinite(w.x) || !std::isfinite(w.y) || !std::isfinite(w.z))
        throw std::invalid_argument("MoM: object '" + o.name + "' has a non-finite vertex");
      raw.push_back(w);
    }
    for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
      const glm::uvec3 tri = o.mesh.triangles[t];
      const std::size_t mat = t < o.mesh.triangle_material.size() ? o.mesh.triangle_material[t] : 0;
      if (mat >= surfaces.size())
        throw std::invalid_argument("MoM: object '" + o.name + "' names an unknown material");
      if (surfaces[mat].kind != SurfaceModel::Kind::kPec) {
        const std::string name =
            mat < description.materials.size() ? description.materials[mat].name : "?";
        throw std::invalid_argument("MoM: material '" + name + "' of object '" + o.name +
                                    "' is not a perfect conductor; the method of moments here "
                                    "models PEC surfaces only");
      }
      if (tri.x >= o.mesh.positions_m.size() || tri.y >= o.mesh.positions_m.size() ||
          tri.z >= o.mesh.positions_m.size())
        throw std::invalid_argument("MoM: object '" + o.name + "' has a vertex index out of range");
      tris.emplace_back(base + tri.x, base + tri.y, base + tri.z);
    }
  }
  if (tris.empty())
    throw std::invalid_argument("MoM: the target has no triangle");

  // Weld coincident vertices (meshes often repeat them per face) by the one rule of
  // scene/mesh/topology.hpp; each welded vertex sits at its first input vertex.
  glm::dvec3 lo(1e300), hi(-1e300);
  for (const glm::dvec3& p : raw)
    lo = glm::min(lo, p), hi = glm::max(hi, p);
  centre_m_ = 0.5 * (lo + hi);
  const double extent = std::max(glm::length(hi - lo), 1e-12);
  scene::VertexWeld weld = scene::weld_vertices(raw, tris);
  vertices_m_.reserve(weld.size());
  for (const std::uint32_t i : weld.first_input)
    vertices_m_.push_back(raw[i] - centre_m_);
  info_.vertices = vertices_m_.size();

  // Triangles with area; zero-area ones (after welding) are skipped and counted.
  std::vector<glm::uvec3> kept;
  for (const glm::uvec3& t0 : tris) {
    const std::array<std::uint32_t, 3> t = {weld.welded[t0.x], weld.welded[t0.y],
                                            weld.welded[t0.z]};
    const glm::dvec3 a = vertices_m_[t[0]], b = vertices_m_[t[1]], c = vertices_m_[t[2]];
    const glm::dvec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || len <= 1e-12 * extent * extent) {
      ++info_.degenerate_skipped;
      continue;
    }
    Triangle tri;
    tri.v = t;
    triangles_.push_back(tri);
    kept.push_back(t0);
  }
  if (triangles_.empty())
    throw std::invalid_argument("MoM: every triangle of the target is degenerate");

  // Edges, their triangles and the connected surfaces (triangle i of the topology is
  // triangles_[i]).
  const scene::MeshTopology topo = scene::build_topology(raw, std::move(weld), kept);
  const auto where = [&](std::uint32_t v) {
    const glm::dvec3 p = vertices_m_[v] + centre_m_;
    char buf[96];
    std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g) m", p.x, p.y, p.z);
    return std::string(buf);
  };
  for (const scene::MeshEdge& e : topo.edges) {
    if (e.non_manifold())
      throw std::invalid_argument("MoM: the edge from " + where(e.v0) + " to " + where(e.v1) +
                                  " is shared by " + std::to_string(e.count) +
                                  " triangles; RWG functions need at most two (no junctions)");
  }
  info_.boundary_edges = topo.boundary_edges;
  // Orient every connected surface consistently (breadth first across shared edges), then
  // closed ones outward (positive signed volume).
  const scene::Orientation orientation = scene::orient_parts(topo);
  if (orientation.conflict != scene::kNoIndex)
    throw std::invalid_argument("MoM: the surface through " +
                                where(triangles_[orientation.conflict].v[0]) +
                                " cannot be oriented (a Moebius-like strip)");
  std::vector<double> volume(topo.parts.size(), 0.0);
  for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
    if (orientation.flip[t])
      std::swap(triangles_[t].v[1], triangles_[t].v[2]);
    const auto& v = triangles_[t].v;
    volume[topo.triangle_part[t]] +=
        glm::dot(vertices_m_[v[0]], glm::cross(vertices_m_[v[1]], vertices_m_[v[2]])) / 6.0;
  }
  // Closed: no boundary edge (non-manifold ones were refused, mis-wound ones turned above).
  const auto closed = [&](std::size_t c) { return topo.parts[c].boundary_edges == 0; };
  info_.components = topo.parts.size();
  for (std::size_t c = 0; c < topo.parts.size(); ++c) {
    info_.closed_components += closed(c) ? 1u : 0u;
    if (closed(c) && volume[c] < 0.0)
      ++info_.flipped_components;
  }
  for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
    const std::size_t c = topo.triangle_part[t];
    if (closed(c) && volume[c] < 0.0)
      std::swap(triangles_[t].v[1], triangles_[t].v[2]);
    triangles_[t].closed = closed(c);
  }

  // Geometry of every triangle.
  double edge_sum = 0.0;
  std::size_t edge_count = 0;
  for (Triangle& t : triangles_) {
    const glm::dvec3 a = vertices_m_[t.v[0]], b = vertices_m_[t.v[1]], c = vertices_m_[t.v[2]];
    const glm::dvec3 n = glm::cross(b - a, c - a);
    t.area_m2 = 0.5 * glm::length(n);
    t.normal = glm::normalize(n);
    t.centroid = (a + b + c) / 3.0;
    t.size_m = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    t.basis = {-1, -1, -1};
    t.coefficient = {0.0, 0.0, 0.0};
    for (std::size_t q = 0; q < kRule6.n; ++q)
      t.points[q] = kRule6.bary[q][0] * a + kRule6.bary[q][1] * b + kRule6.bary[q][2] * c;
  }
  // RWG functions on interior edges (Rao, Wilton & Glisson 1982, eq. 1): f = l / (2 A+) (r - p+)
  // on T+, l / (2 A-) (p- - r) on T-; T+ is the first triangle listed with the edge.
  for (const scene::MeshEdge& e : topo.edges) {
    const double len = glm::length(vertices_m_[e.v0] - vertices_m_[e.v1]);
    edge_sum += len;
    ++edge_count;
    info_.max_edge_m = std::max(info_.max_edge_m, len);
    if (e.count != 2)
      continue;
    const auto n = static_cast<std::int64_t>(unknowns_++);
    const auto uses = topo.uses(e);
    for (std::size_t s = 0; s < 2; ++s) {
      Triangle& t = triangles_[uses[s].triangle];
      // The local index of the vertex opposite the edge, after any flip above.
      std::uint8_t local = 0;
      while (t.v[local] == e.v0 || t.v[local] == e.v1)
        ++local;
      t.basis[local] = n;
      t.coefficient[local] = (s == 0 ? 1.0 : -1.0) * len / (2.0 * t.area_m2);
    }
  }
  info_.triangles = triangles_.size();
  info_.unknowns = unknowns_;
  info_.mean_edge_m = edge_sum / static_cast<double>(std::max<std::size_t>(edge_count, 1));
  if (unknowns_ == 0)
    throw std::invalid_argument(
        "MoM: no two triangles share an edge, so there is no current "
        "to solve for");
  if (unknowns_ > config.max_unknowns)
    throw std::invalid_argument(
        "MoM: " + std::to_string(unknowns_) + " unknowns exceed the limit of " +
        std::to_string(config.max_unknowns) + " (the matrix would take " +
        std::to_string(static_cast<double>(unknowns_) * static_cast<double>(unknowns_) * 16e-9) +
        " GB); coarsen the mesh to about a tenth of a wavelength or use physical optics");

  equation_ = config.equation;
  if (equation_ == MomEquation::kMfie && info_.boundary_edges > 0)
    throw std::invalid_argument(
        "MoM: the MFIE holds on closed surfaces only, and this target "
        "has " +
        std::to_string(info_.boundary_edges) + " open edges");

  // Colour triangles so that no two sharing an edge (hence a basis function: a row and a column)
  // have the same colour.
  colour_.assign(triangles_.size(), 0);
  for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
    std::uint8_t used = 0;
    for (const std::uint32_t ei : topo.triangle_edges[t]) {
      const scene::MeshEdge& e = topo.edges[ei];
      if (e.count != 2)
        continue;
      const auto uses = topo.uses(e);
      const std::uint32_t u = uses[0].triangle == t ? uses[1].triangle : uses[0].triangle;
      if (u < t)
        used |= static_cast<std::uint8_t>(1u << colour_[u]);
    }
    std::uint8_t c = 0;
    while (used & (1u << c))
      ++c;
    colour_[t] = c;
  }
}

double MomSolver::efie_weight(const Triangle& t) const noexcept {
  if (!t.closed || equation_ == MomEquation::kEfie)
    return 1.0;
  return equation_ == MomEquation::kMfie ? 0.0 : config_.cfie_alpha;
}

MomFactorInfo MomSolver::factor(double frequency_hz) {
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz))
    throw std::invalid_argument("MoM: the frequency must be a positive finite number");
  MomFactorInfo fi;
  fi.frequency_hz = frequency_hz;
  const double k = 2.0 * kPi * frequency_hz / kSpeedOfLight_mps;
  k_rad_per_m_ = k;
  const std::size_t n = unknowns_;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    lu_.assign(n * n, cd(0.0, 0.0));
    pivots_.assign(n, 0);
  } catch (const std::bad_alloc&) {
    lu_.clear();
    throw std::runtime_error(
        "MoM: cannot allocate the " + std::to_string(n) + " x " + std::to_string(n) +
        " impedance matrix (" +
        std::to_string(16e-9 * static_cast<double>(n) * static_cast<double>(n)) +
        " GB); coarsen the mesh or lower --mom-max-unknowns");
  }

  std::uint8_t colours = 0;
  for (std::uint8_t c : colour_)
    colours = std::max<std::uint8_t>(colours, static_cast<std::uint8_t>(c + 1));
  // Column by column: the matrix is column-major (LAPACK) with a column per source basis
  // function, so a thread takes a source triangle and runs down its (at most three) columns over
  // every observation triangle, writing nearby rows. (Row by row, each of the 9 writes of a pair
  // landed n entries from the last: a cache miss each, most of the fill's time.) Source
  // triangles of one colour share no basis function, hence no column: they fill in parallel.
  std::vector<std::size_t> near_count(triangles_.size(), 0);
  const std::size_t nt = triangles_.size();
  for (std::uint8_t colour = 0; colour < colours; ++colour) {
    std::vector<std::uint32_t> sources;
    for (std::uint32_t t = 0; t < nt; ++t)
      if (colour_[t] == colour)
        sources.push_back(t);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, sources.size(), 1), [&](const auto& range) {
          std::array<Inner, 6> inner;
          for (std::size_t si = range.begin(); si != range.end(); ++si) {
            const std::uint32_t tn = sources[si];
            const Triangle& s = triangles_[tn];
            const bool has_basis = s.basis[0] >= 0 || s.basis[1] >= 0 || s.basis[2] >= 0;
            // The identity term of the MFIE, (1/2) <f_i, f_j> on triangle tn as observation
            // triangle: its entries lie in its own columns.
            const double alpha_s = efie_weight(s);
            if (alpha_s < 1.0) {
              for (std::size_t i = 0; i < 3; ++i) {
                if (s.basis[i] < 0)
                  continue;
                for (std::size_t j = 0; j < 3; ++j) {
                  if (s.basis[j] < 0)
                    continue;
                  double sum = 0.0;
                  for (std::size_t q = 0; q < kRule6.n; ++q)
                    sum += kRule6.weight[q] * glm::dot(s.points[q] - vertices_m_[s.v[i]],
                                                       s.points[q] - vertices_m_[s.v[j]]);
                  const double v = 0.5 * s.coefficient[i] * s.coefficient[j] * sum * s.area_m2;
                  lu_[static_cast<std::size_t>(s.basis[j]) * n +
                      static_cast<std::size_t>(s.basis[i])] += (1.0 - alpha_s) * v;
                }
              }
            }
            if (!has_basis)
              continue;
            const glm::dvec3 sa = vertices_m_[s.v[0]], sb = vertices_m_[s.v[1]],
                             sc = vertices_m_[s.v[2]];
            for (std::uint32_t tm = 0; tm < nt; ++tm) {
              const Triangle& m = triangles_[tm];
              const double dist = glm::length(m.centroid - s.centroid);
              const double scale_m = m.size_m + s.size_m;
              const bool near = dist < 0.75 * scale_m;
              if (near)
                ++near_count[tn];
              if (m.basis[0] < 0 && m.basis[1] < 0 && m.basis[2] < 0)
                continue;  // no row to fill
              const double alpha = efie_weight(m);
              const bool mfie = alpha < 1.0;
              const std::array<glm::dvec3, 6>& rq = m.points;
              for (auto& in : inner)
                in = Inner{};
              if (near) {
                // Duffy coordinates about the projection p of each observation point onto the
                // source plane: three sub-triangles (p, v_a, v_b), x = p + u (v_a - p) + u v (v_b -
                // v_a), dA = u ((v_a - p) x (v_b - v_a)) . n du dv (signed: p may lie outside).
                const std::array<glm::dvec3, 3> sv = {sa, sb, sc};
                for (std::size_t q = 0; q < kRule6.n; ++q) {
                  const glm::dvec3 p = rq[q] - s.normal * glm::dot(rq[q] - sa, s.normal);
                  for (std::size_t e = 0; e < 3; ++e) {
                    const glm::dvec3 va = sv[e], vb = sv[(e + 1) % 3];
                    const double jac = glm::dot(glm::cross(va - p, vb - va), s.normal);
                    if (std::abs(jac) <= 1e-14 * s.area_m2)
                      continue;
                    for (std::size_t iu = 0; iu < kDuffyU.x.size(); ++iu) {
                      const double u = kDuffyU.x[iu];
                      for (std::size_t iv = 0; iv < kDuffyV.x.size(); ++iv) {
                        const double v = kDuffyV.x[iv];
                        const glm::dvec3 x = p + u * (va - p) + u * v * (vb - va);
                        inner[q].add(rq[q], x, kDuffyU.w[iu] * kDuffyV.w[iv] * u * jac, k, mfie);
                      }
                    }
                  }
                }
              } else {
                const TriRule& rule = dist < 3.0 * scale_m ? kRule6 : kRule3;
                for (std::size_t j = 0; j < rule.n; ++j) {
                  const glm::dvec3 x =
                      rule.bary[j][0] * sa + rule.bary[j][1] * sb + rule.bary[j][2] * sc;
                  const double w = rule.weight[j] * s.area_m2;
                  for (std::size_t q = 0; q < kRule6.n; ++q)
                    inner[q].add(rq[q], x, w, k, mfie);
                }
              }
              // Moments over the observation triangle (weights times its area).
              cd i0(0.0, 0.0), irr(0.0, 0.0), m1(0.0, 0.0);
              CplxVec ir, irp, m2, m3, m4;
              for (std::size_t q = 0; q < kRule6.n; ++q) {
                const double w = kRule6.weight[q] * m.area_m2;
                const Inner& in = inner[q];
                i0 += w * in.sG;
                ir += scale(rq[q], w * in.sG);
                irp += CplxVec{in.vG.re * w, in.vG.im * w};
                irr += w * dot(rq[q], in.vG);
                if (mfie && tn != tm) {
                  const CplxVec d = minus(scale(rq[q], in.sg), in.vg);  // int g (r - r')
                  const glm::dvec3 rxn = glm::cross(rq[q], m.normal);
                  const CplxVec rxv = cross(rq[q], in.vg);
                  m1 += w * dot(rxn, rxv);
                  m2 += CplxVec{rxv.re * w, rxv.im * w};
                  const CplxVec rxnd = cross(rxn, d);
                  m3 += CplxVec{rxnd.re * w, rxnd.im * w};
                  m4 += CplxVec{d.re * w, d.im * w};
                }
              }
              for (std::size_t i = 0; i < 3; ++i) {
                if (m.basis[i] < 0)
                  continue;
                const glm::dvec3 pi = vertices_m_[m.v[i]];
                const glm::dvec3 bi = glm::cross(pi, m.normal);
                const std::size_t row = static_cast<std::size_t>(m.basis[i]);
                for (std::size_t j = 0; j < 3; ++j) {
                  if (s.basis[j] < 0)
                    continue;
                  const glm::dvec3 pj = vertices_m_[s.v[j]];
                  const double cc = m.coefficient[i] * s.coefficient[j];
                  // EFIE: jk [ int int f.f' G - (1/k^2) int int div f div' f' G ], div f = 2 c.
                  const cd ff = irr - dot(pj, ir) - dot(pi, irp) + glm::dot(pi, pj) * i0;
                  cd z = alpha * cd(0.0, k) * cc * (ff - 4.0 / (k * k) * i0);
                  if (mfie && tn != tm) {
                    // MFIE: - int f . (n x int grad G x f' dS') dS (derivation beside Inner).
                    const cd h = m1 - dot(bi, m2) - dot(pj, m3) + dot(pj, cross(bi, m4));
                    z += (1.0 - alpha) * (-cc * h);
                  }
                  lu_[static_cast<std::size_t>(s.basis[j]) * n + row] += z;
                }
              }
            }
          }
        });
  }
  fi.near_pairs = std::accumulate(near_count.begin(), near_count.end(), std::size_t{0});
  const auto t1 = std::chrono::steady_clock::now();
  fi.fill_s = std::chrono::duration<double>(t1 - t0).count();
  const int ni = static_cast<int>(n);
  int info = 0;
  zgetrf_(&ni, &ni, lu_.data(), &ni, pivots_.data(), &info);
  if (info != 0) {
    lu_.clear();
    throw std::runtime_error("MoM: the impedance matrix is singular at " +
                             std::to_string(frequency_hz) + " Hz (LAPACK zgetrf info " +
                             std::to_string(info) + ")");
  }
  fi.factor_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  return fi;
}

void MomSolver::scatter(std::span<const Direction> tx, std::span<const Direction> rx,
                        std::span<ScatteringMatrix> out) const {
  if (lu_.empty())
    throw std::logic_error("MoM: scatter() before factor()");
  if (tx.size() != rx.size() || out.size() != tx.size())
    throw std::invalid_argument("MoM: scatter() needs as many transmitters, receivers and outputs");
  const std::size_t n = unknowns_, nt = triangles_.size();
  const double k = k_rad_per_m_;
  // Directions in blocks: two right-hand sides (V, H transmit) each.
  constexpr std::size_t kBlock = 128;
  std::vector<cd> rhs;
  for (std::size_t first = 0; first < tx.size(); first += kBlock) {
    const std::size_t count = std::min(kBlock, tx.size() - first);
    rhs.assign(n * 2 * count, cd(0.0, 0.0));
    // <f_m, alpha E_i + (1 - alpha) n x (k_i x E_i)> (eta H_i = k_i x E_i), E_i = e
    // e^{-jk k_i . r}, k_i = -(direction of the transmitter).
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t d) {
      const Direction& dir = tx[first + d];
      const glm::dvec3 ki = -unit_vector(dir);
      const std::array<glm::dvec3, 2> pol = {theta_hat(dir), phi_hat(dir)};
      for (std::size_t t = 0; t < nt; ++t) {
        const Triangle& tri = triangles_[t];
        const double alpha = efie_weight(tri);
        for (std::size_t q = 0; q < kRule6.n; ++q) {
          const glm::dvec3& r = tri.points[q];
          const double phase = -k * glm::dot(ki, r + centre_m_);
          const cd e = kRule6.weight[q] * tri.area_m2 * cd(std::cos(phase), std::sin(phase));
          for (std::size_t p = 0; p < 2; ++p) {
            const glm::dvec3 field =
                alpha * pol[p] + (1.0 - alpha) * glm::cross(tri.normal, glm::cross(ki, pol[p]));
            for (std::size_t i = 0; i < 3; ++i) {
              if (tri.basis[i] < 0)
                continue;
              const double f = tri.coefficient[i] * glm::dot(r - vertices_m_[tri.v[i]], field);
              rhs[(2 * d + p) * n + static_cast<std::size_t>(tri.basis[i])] += f * e;
            }
          }
        }
      }
    });
    const int ni = static_cast<int>(n), nrhs = static_cast<int>(2 * count);
    int info = 0;
    const char trans = 'N';
    zgetrs_(&trans, &ni, &nrhs, lu_.data(), &ni, pivots_.data(), rhs.data(), &ni, &info, 1);
    if (info != 0)
      throw std::runtime_error("MoM: LAPACK zgetrs failed (info " + std::to_string(info) + ")");
    // S = -jk / sqrt(4 pi) p . int (eta J) e^{jk s . r'} dS' (unknowns are eta J).
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t d) {
      const Direction& dir = rx[first + d];
      const glm::dvec3 s = unit_vector(dir);
      std::array<CplxVec, 2> field{};  // the radiation integral for V and H transmit
      for (std::size_t t = 0; t < nt; ++t) {
        const Triangle& tri = triangles_[t];
        for (std::size_t q = 0; q < kRule6.n; ++q) {
          const glm::dvec3& r = tri.points[q];
          const double phase = k * glm::dot(s, r + centre_m_);
          const cd e = kRule6.weight[q] * tri.area_m2 * cd(std::cos(phase), std::sin(phase));
          for (std::size_t i = 0; i < 3; ++i) {
            if (tri.basis[i] < 0)
              continue;
            const glm::dvec3 f = tri.coefficient[i] * (r - vertices_m_[tri.v[i]]);
            for (std::size_t p = 0; p < 2; ++p)
              field[p] +=
                  scale(f, e * rhs[(2 * d + p) * n + static_cast<std::size_t>(tri.basis[i])]);
          }
        }
      }
      const cd factor = cd(0.0, -k) / std::sqrt(4.0 * kPi);
      const glm::dvec3 v = theta_hat(dir), h = phi_hat(dir);
      ScatteringMatrix& o = out[first + d];
      o.vv = factor * dot(v, field[0]);
      o.hv = factor * dot(h, field[0]);
      o.vh = factor * dot(v, field[1]);
      o.hh = factor * dot(h, field[1]);
    });
  }
}

}  // namespace radar_emu::radar
