#include "radar/em/rcs.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>

#include "common/units.hpp"
#include "radar/constants.hpp"
#include "radar/em/facet_po.hpp"
#include "scene/mesh/topology.hpp"

namespace radar_emu::radar {

namespace {

using cplx = std::complex<double>;

void require(bool ok, const std::string& what) {
  if (!ok)
    throw std::invalid_argument("RCS: " + what);
}

// Terms of the sum over frequencies. S(k) = -j k / sqrt(pi) * sum_terms c * I_term(k).
struct FacetTerm {
  std::array<cplx, 4> c;  // hh, hv, vh, vv: (p . (eta J - s x M)) / 2
  double area_m2, b0_m, b1_m, b2_m;
};
struct PathTerm {
  std::array<cplx, 4> c;
  double area_m2;      // tube footprint on the last facet
  double phase_len_m;  // unfolded path to the exit point minus s . exit point (first tube)
  double taper_u_m;    // (s - d) . u_footprint / 2: the footprint integral is
  double taper_v_m;    // area sinc(k taper_u) sinc(k taper_v)
  // A run of `count` neighbouring tubes of one grid row that met the same facets in the same
  // order (hence the same field, footprint and tapers): their phase paths step by step_m from
  // tube to tube (planar facets: the path is affine in the tube's position), and their sum is
  // the footprint term times sum_i exp(-j k (L0 + i step)) = exp(-j k (L0 + (n - 1) step / 2))
  // sin(n k step / 2) / sin(k step / 2) (a geometric series): one term per run, not per tube.
  std::uint32_t count;
  double step_m;
};

// Per triangle: +1 / -1 where its part is closed (scene::closed_part_winding) or closed up to
// T-junctions, 0 elsewhere. Generated and exported meshes often meet a subdivided face with a
// coarser one (a prism's fanned cap against its subdivided sides): the vertices of the fine side
// lie on the coarse side's edge, so the topology (scene/mesh/topology.hpp: exact closure, no
// T-junction leniency) calls both parts open although together they bound a solid. Here the
// boundary edges of the parts that are open only through boundary edges (no non-manifold or
// inconsistent edge) are split at every boundary vertex lying on them (within kTJunctionRelative
// of the extent: 10 weld tolerances, a tenth of the engines' ray offset); parts whose split
// boundary segments all meet a segment of another such part running the opposite way are joined,
// and a group whose every segment is so matched is a closed solid, wound outward (+1) when its
// signed volume (the parts' volumes summed: the divergence theorem over the closed union) is
// positive. Only the bounce-1 lighting uses this (a facet of a solid facing away from the source
// is dark, which its samples would find at seven queries each); the edge finder keeps the exact
// closure.
constexpr double kTJunctionRelative = 1e-6;

std::vector<std::int8_t> solid_winding(const scene::MeshTopology& topo,
                                       std::span<const glm::vec3> positions_m) {
  std::vector<std::int8_t> out = scene::closed_part_winding(topo);
  const std::size_t n_parts = topo.parts.size();
  std::vector<std::uint8_t> candidate(n_parts, 0);
  bool any = false;
  for (std::size_t p = 0; p < n_parts; ++p) {
    const scene::MeshPart& part = topo.parts[p];
    candidate[p] =
        part.boundary_edges > 0 && part.non_manifold_edges == 0 && part.inconsistent_edges == 0 ? 1
                                                                                                : 0;
    any = any || candidate[p] != 0;
  }
  if (!any)
    return out;
  auto position = [&](std::uint32_t welded) {
    return glm::dvec3(positions_m[topo.weld.first_input[welded]]);
  };
  // The boundary edges of candidate parts, directed as their one triangle runs them.
  struct Segment {
    std::uint32_t from, to, part;
  };
  std::vector<Segment> segments;
  std::vector<std::uint32_t> boundary_vertices;
  for (const scene::MeshEdge& e : topo.edges) {
    if (!e.boundary())
      continue;
    const scene::HalfEdge& h = topo.uses(e)[0];
    const std::uint32_t part = topo.triangle_part[h.triangle];
    if (part == scene::kNoIndex || candidate[part] == 0)
      continue;
    const std::array<std::uint32_t, 3>& c = topo.corners[h.triangle];
    segments.push_back({c[h.corner], c[(h.corner + 1u) % 3u], part});
    boundary_vertices.push_back(e.v0);
    boundary_vertices.push_back(e.v1);
  }
  std::sort(boundary_vertices.begin(), boundary_vertices.end());
  boundary_vertices.erase(std::unique(boundary_vertices.begin(), boundary_vertices.end()),
                          boundary_vertices.end());
  const double tol_m = kTJunctionRelative * topo.weld.extent_m;
  // Split every segment at the boundary vertices on it; count the directed pieces.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> pieces;
  std::vector<std::pair<double, std::uint32_t>> on;
  for (const Segment& sg : segments) {
    const glm::dvec3 a = position(sg.from), b = position(sg.to), ab = b - a;
    const double len2 = glm::dot(ab, ab);
    on.clear();
    on.push_back({0.0, sg.from});
    on.push_back({1.0, sg.to});
    for (const std::uint32_t v : boundary_vertices) {
      if (v == sg.from || v == sg.to || !(len2 > 0.0))
        continue;
      const glm::dvec3 x = position(v);
      const double t = glm::dot(x - a, ab) / len2;
      if (t <= 0.0 || t >= 1.0 || glm::length(x - (a + t * ab)) > tol_m)
        continue;
      on.push_back({t, v});
    }
    std::sort(on.begin(), on.end());
    for (std::size_t k = 0; k + 1 < on.size(); ++k)
      pieces[{on[k].second, on[k + 1].second}].push_back(sg.part);
  }
  // Join the parts across matched pieces; a part with an unmatched piece is open.
  std::vector<std::uint32_t> root(n_parts);
  for (std::uint32_t p = 0; p < n_parts; ++p)
    root[p] = p;
  auto find = [&](std::uint32_t p) {
    while (root[p] != p)
      p = root[p] = root[root[p]];
    return p;
  };
  std::vector<std::uint8_t> open(n_parts, 0);
  for (const auto& [key, parts] : pieces) {
    const auto twin = pieces.find({key.second, key.first});
    if (parts.size() != 1 || twin == pieces.end() || twin->second.size() != 1) {
      for (const std::uint32_t p : parts)
        open[p] = 1;
      continue;
    }
    const std::uint32_t a = find(parts[0]), b = find(twin->second[0]);
    if (a != b)
      root[a] = b;
  }
  std::vector<double> volume_m3(n_parts, 0.0);
  std::vector<std::uint8_t> group_open(n_parts, 0);
  for (std::uint32_t p = 0; p < n_parts; ++p) {
    if (candidate[p] == 0)
      continue;
    volume_m3[find(p)] += topo.parts[p].volume_m3;
    group_open[find(p)] |= open[p];
  }
  for (std::size_t t = 0; t < out.size(); ++t) {
    const std::uint32_t p = topo.triangle_part[t];
    if (p == scene::kNoIndex || candidate[p] == 0)
      continue;
    const std::uint32_t g = find(p);
    if (group_open[g] == 0 && volume_m3[g] != 0.0)
      out[t] = volume_m3[g] > 0.0 ? 1 : -1;
  }
  return out;
}

// The Dirichlet kernel sin(n x / 2) / sin(x / 2) from its two sines and cosines (the limit
// n cos(n x / 2) / cos(x / 2) where sin(x / 2) vanishes).
double dirichlet(double sin_n, double cos_n, double sin_1, double cos_1, double n) noexcept {
  return std::abs(sin_1) > 1e-9 ? sin_n / sin_1 : n * cos_n / cos_1;
}

}  // namespace

glm::dvec3 unit_vector(const Direction& d) noexcept {
  const double st = std::sin(d.theta_rad);
  return {st * std::cos(d.phi_rad), st * std::sin(d.phi_rad), std::cos(d.theta_rad)};
}
glm::dvec3 theta_hat(const Direction& d) noexcept {
  const double ct = std::cos(d.theta_rad);
  return {ct * std::cos(d.phi_rad), ct * std::sin(d.phi_rad), -std::sin(d.theta_rad)};
}
glm::dvec3 phi_hat(const Direction& d) noexcept {
  return {-std::sin(d.phi_rad), std::cos(d.phi_rad), 0.0};
}

double dbsm(std::complex<double> a) noexcept {
  const double s = std::norm(a);
  return s > 0.0 ? common::db_from_power(s) : -400.0;
}

RcsEngine::RcsEngine(const scene::Scene& scene, std::vector<SurfaceModel> surfaces,
                     RcsConfig config)
    : scene_(&scene), surfaces_(std::move(surfaces)), config_(config) {
  require(surfaces_.size() == scene.materials().size(),
          "one surface model per scene material is needed (" + std::to_string(surfaces_.size()) +
              " given, " + std::to_string(scene.materials().size()) + " materials)");
  for (std::size_t i = 0; i < surfaces_.size(); ++i) {
    const SurfaceModel& s = surfaces_[i];
    const std::string name = "material '" + scene.materials()[i].name + "'";
    require(std::isfinite(s.relative_permittivity.real()) &&
                std::isfinite(s.relative_permittivity.imag()),
            name + ": permittivity must be finite");
    require(s.kind == SurfaceModel::Kind::kPec || s.relative_permittivity.real() >= 1.0,
            name + ": real part of the permittivity must be >= 1");
    require(s.kind == SurfaceModel::Kind::kPec || s.relative_permittivity.imag() <= 0.0,
            name + ": permittivity is eps' - j eps'' (imaginary part <= 0 for losses)");
    require(s.kind != SurfaceModel::Kind::kCoatedPec ||
                (std::isfinite(s.thickness_m) && s.thickness_m > 0.0),
            name + ": coating thickness must be > 0");
  }
  require(config_.max_bounces >= 1 && config_.max_bounces <= kMaxRcsBounces,
          "bounces must be in 1.." + std::to_string(kMaxRcsBounces));
  require(std::isfinite(config_.rays_per_wavelength) && config_.rays_per_wavelength > 0.0,
          "rays per wavelength must be > 0");
  require(std::isfinite(config_.coating_reference_hz) && config_.coating_reference_hz >= 0.0,
          "coating reference frequency must be >= 0");
  require(config_.max_rays >= 1, "max_rays must be >= 1");

  const auto& desc = scene.description();
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  std::vector<glm::dvec3> vertices_m;  // every vertex of the scene, world frame
  constexpr std::uint32_t kNoFacet = 0xFFFFFFFFu;
  std::vector<std::uint32_t> facet_of_triangle;  // facets_ index (kNoFacet: degenerate)
  for (std::uint32_t id = 0; id < desc.objects.size(); ++id) {
    const glm::dmat4 m = scene.world_from_body(id);
    const scene::Mesh& mesh = desc.objects[id].mesh;
    first_triangle_.push_back(facet_of_triangle.size());
    facet_of_triangle.resize(facet_of_triangle.size() + mesh.triangles.size(), kNoFacet);
    for (const glm::vec3& v : mesh.positions_m)
      vertices_m.push_back(glm::dvec3(m * glm::dvec4(v, 1.0)));
    const scene::MeshTopology topology = scene::build_topology(mesh.positions_m, mesh.triangles);
    const std::vector<std::int8_t> closed = scene::closed_part_winding(topology);
    const std::vector<std::int8_t> solid = solid_winding(topology, mesh.positions_m);
    const std::int8_t mirrored = glm::determinant(glm::dmat3(m)) < 0.0 ? -1 : 1;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const glm::uvec3 tri = mesh.triangles[t];
      auto world = [&](unsigned i) { return glm::dvec3(m * glm::dvec4(mesh.positions_m[i], 1.0)); };
      Facet f;
      f.v0 = world(tri.x);
      f.v1 = world(tri.y);
      f.v2 = world(tri.z);
      const glm::dvec3 nn = glm::cross(f.v1 - f.v0, f.v2 - f.v0);
      const double twice_area = glm::length(nn);
      const double longest =
          std::max({glm::length(f.v1 - f.v0), glm::length(f.v2 - f.v1), glm::length(f.v0 - f.v2)});
      if (!(twice_area > 1e-12 * longest * longest)) {
        ++degenerate_;
        continue;
      }
      f.normal = nn / twice_area;
      f.area_m2 = 0.5 * twice_area;
      f.centroid = (f.v0 + f.v1 + f.v2) / 3.0;
      f.longest_m = longest;
      f.surface = mesh.triangle_material[t];
      f.outward = static_cast<std::int8_t>(closed[t] * mirrored);
      f.solid = static_cast<std::int8_t>(solid[t] * mirrored);
      facet_of_triangle[first_triangle_.back() + t] = static_cast<std::uint32_t>(facets_.size());
      facets_.push_back(f);
      for (const glm::dvec3& v : {f.v0, f.v1, f.v2}) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
      }
    }
  }
  require(!facets_.empty(), "the target has no non-degenerate facet");
  for (const Facet& f : facets_) {
    for (const glm::dvec3& v : {f.v0, f.v1, f.v2})
      facet_vertices_m_.push_back(v);
  }
  std::sort(facet_vertices_m_.begin(), facet_vertices_m_.end(),
            [](const glm::dvec3& a, const glm::dvec3& b) {
              return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
            });
  facet_vertices_m_.erase(std::unique(facet_vertices_m_.begin(), facet_vertices_m_.end()),
                          facet_vertices_m_.end());
  centre_m_ = 0.5 * (lo + hi);
  for (const Facet& f : facets_) {
    for (const glm::dvec3& v : {f.v0, f.v1, f.v2})
      radius_m_ = std::max(radius_m_, glm::length(v - centre_m_));
  }
  // Hits are refit in double precision, but traversal is float: step off a surface by a few
  // float ulps of the target's coordinates (style.md: epsilons scale with the geometry).
  epsilon_m_ = 1e-5 * (radius_m_ + glm::length(centre_m_));
  // The hull flags hold for the geometry as it stands now: none where objects move.
  bool moving = false;
  for (const scene::ObjectDesc& o : desc.objects)
    moving = moving || o.motion.has_value() || o.trajectory.has_value();
  if (!moving)
    find_supporting_sides(vertices_m);
  triangle_empty_side_.assign(facet_of_triangle.size(), 0);
  for (std::size_t t = 0; t < facet_of_triangle.size(); ++t) {
    if (facet_of_triangle[t] != kNoFacet)
      triangle_empty_side_[t] = facets_[facet_of_triangle[t]].empty_side;
  }
  require(std::isfinite(config_.edge_min_turn_rad) && config_.edge_min_turn_rad >= 0.0 &&
              config_.edge_min_turn_rad < kPi,
          "edge threshold must be in [0, 180) deg");
  require(config_.edge_order == 1 || config_.edge_order == 2, "edge order must be 1 or 2");
  if (config_.edges) {
    std::vector<std::array<glm::dvec3, 3>> tris(facets_.size());
    std::vector<std::int8_t> outward(facets_.size());
    std::vector<std::uint8_t> pec(facets_.size());
    for (std::size_t i = 0; i < facets_.size(); ++i) {
      tris[i] = {facets_[i].v0, facets_[i].v1, facets_[i].v2};
      outward[i] = facets_[i].outward;
      pec[i] = surfaces_[facets_[i].surface].kind == SurfaceModel::Kind::kPec ? 1 : 0;
    }
    // Edges over the facets of all objects together, in the world frame (objects that meet at
    // coincident vertices share their edges there); closed parts above are per object.
    // Every joint that turns at all is a candidate; the wedge rule (edges.hpp, wedge_weight)
    // sorts wedges from joints of smooth surfaces per call, at its wavelength.
    edges_ = find_wedge_edges(tris, scene::build_topology(tris), outward, pec,
                              kWedgeCandidateTurnRad, census_);
    if (config_.edge_order >= 2) {
      // Double diffraction only between joints turning at least half the full turn (the ramp's
      // foot, edges.hpp): the surface wave a face carries from a wedge to a parallel one needs
      // real wedges at both ends, and the many parallel joints of a tessellated cylinder would
      // make the pair search quadratic.
      std::vector<WedgeEdge> sharp;
      std::vector<std::uint32_t> index;
      for (std::uint32_t i = 0; i < edges_.size(); ++i) {
        if (edges_[i].alpha_rad - kPi >= 0.5 * config_.edge_min_turn_rad) {
          sharp.push_back(edges_[i]);
          index.push_back(i);
        }
      }
      pairs_ = find_edge_pairs(sharp, tris, epsilon_m_);
      for (EdgePair& p : pairs_) {
        p.from = index[p.from];
        p.to = index[p.to];
      }
    }
    // Reflecting planes: the PEC facets grouped by plane (normal to 1e-6, offset to 100 ray
    // offsets), the largest kept.
    using Key = std::tuple<long long, long long, long long, long long>;
    std::map<Key, ReflectingPlane> by_plane;
    const double step_m = 100.0 * epsilon_m_;
    for (std::size_t i = 0; i < facets_.size(); ++i) {
      if (!pec[i])
        continue;
      const glm::dvec3 n = sign_folded(facets_[i].normal);
      const double offset = glm::dot(n, facets_[i].v0);
      ReflectingPlane& p = by_plane[Key{std::llround(n.x * 1e6), std::llround(n.y * 1e6),
                                        std::llround(n.z * 1e6), std::llround(offset / step_m)}];
      if (p.area_m2 == 0.0) {
        p.normal = n;
        p.offset_m = offset;
      }
      p.area_m2 += facets_[i].area_m2;
    }
    for (const auto& [key, p] : by_plane)
      planes_.push_back(p);
    std::sort(
        planes_.begin(), planes_.end(),
        [](const ReflectingPlane& a, const ReflectingPlane& b) { return a.area_m2 > b.area_m2; });
    if (planes_.size() > kMaxReflectingPlanes)
      planes_.resize(kMaxReflectingPlanes);
    if (!planes_.empty()) {
      const double floor_m2 = kReflectingPlaneShare * planes_.front().area_m2;
      std::erase_if(planes_, [floor_m2](const ReflectingPlane& p) { return p.area_m2 < floor_m2; });
    }
  }
}

// A facet whose plane has every vertex of the scene on one side (within kSupportTolerance ray
// offsets) lies on a supporting plane of the target (on its convex hull): the open half-space on
// the other side holds no geometry, so a ray leaving the facet into it, from a point lifted off
// the facet by the ray offset, meets nothing. Vertices are tried extreme ones first (each
// facet's test stops at the first vertex beyond its plane). The test costs up to facets x
// vertices dot products (a facet on the hull reads every vertex): above kSupportMaxWork it is
// not made and no facet is flagged (the flag only spares rays, so results do not change).
constexpr double kSupportTolerance = 0.1;
constexpr double kSupportMaxWork = 5e8;

void RcsEngine::find_supporting_sides(std::vector<glm::dvec3> vertices_m) {
  std::sort(vertices_m.begin(), vertices_m.end(), [](const glm::dvec3& a, const glm::dvec3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  vertices_m.erase(std::unique(vertices_m.begin(), vertices_m.end()), vertices_m.end());
  if (static_cast<double>(facets_.size()) * static_cast<double>(vertices_m.size()) >
      kSupportMaxWork)
    return;
  // The extreme vertices along the 13 directions of the cube's axes, face and body diagonals
  // first: most facets not on the hull find one of them beyond their plane.
  std::vector<std::size_t> first;
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        if (x == 0 && y == 0 && z == 0)
          continue;
        const glm::dvec3 dir(x, y, z);
        std::size_t best = 0;
        for (std::size_t i = 1; i < vertices_m.size(); ++i) {
          if (glm::dot(dir, vertices_m[i]) > glm::dot(dir, vertices_m[best]))
            best = i;
        }
        first.push_back(best);
      }
    }
  }
  std::sort(first.begin(), first.end());
  first.erase(std::unique(first.begin(), first.end()), first.end());
  std::vector<glm::dvec3> ordered;
  ordered.reserve(vertices_m.size());
  for (const std::size_t i : first)
    ordered.push_back(vertices_m[i]);
  for (std::size_t i = 0, k = 0; i < vertices_m.size(); ++i) {
    if (k < first.size() && first[k] == i) {
      ++k;
      continue;
    }
    ordered.push_back(vertices_m[i]);
  }
  const double tol_m = kSupportTolerance * epsilon_m_;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, facets_.size(), 64),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          Facet& f = facets_[i];
          const double offset = glm::dot(f.normal, f.v0);
          bool front = true, back = true;  // no vertex beyond the plane on the +n / -n side
          for (const glm::dvec3& v : ordered) {
            const double h = glm::dot(f.normal, v) - offset;
            front = front && h <= tol_m;
            back = back && h >= -tol_m;
            if (!front && !back)
              break;
          }
          f.empty_side = static_cast<std::uint8_t>((front ? 1u : 0u) | (back ? 2u : 0u));
        }
      });
}

RayGrid RcsEngine::ray_grid(const Direction& tx, double max_freq_hz) const {
  require(std::isfinite(max_freq_hz) && max_freq_hz > 0.0, "frequency must be > 0");
  const glm::dvec3 r_t = unit_vector(tx);
  const double spacing = kSpeedOfLight_mps / max_freq_hz / config_.rays_per_wavelength;
  // The grid covers the target's shadow on the wavefront plane (all vertices projected).
  // It is turned by atan(1 / golden ratio) from (V, H): a lattice whose rows line up with a
  // straight edge of the target counts whole rows in or out (error ~ spacing / size); at a badly
  // approximable slope the count along any straight edge is nearly exact (lattice-point
  // discrepancy; Kuipers & Niederreiter, Uniform Distribution of Sequences, 1974, ch. 2,
  // sec. 3), so aperture areas converge far faster with ray density.
  const double turn = std::atan(2.0 / (1.0 + std::sqrt(5.0)));
  const glm::dvec3 tx_v = theta_hat(tx), tx_h = phi_hat(tx);
  const glm::dvec3 axis_u = std::cos(turn) * tx_v + std::sin(turn) * tx_h;
  const glm::dvec3 axis_v = -std::sin(turn) * tx_v + std::cos(turn) * tx_h;
  double u_lo = std::numeric_limits<double>::max(), u_hi = -u_lo, v_lo = u_lo, v_hi = -u_lo;
  for (const glm::dvec3& p : facet_vertices_m_) {  // the facets' vertices, each once
    const double pu = glm::dot(p - centre_m_, axis_u), pv = glm::dot(p - centre_m_, axis_v);
    u_lo = std::min(u_lo, pu);
    u_hi = std::max(u_hi, pu);
    v_lo = std::min(v_lo, pv);
    v_hi = std::max(v_hi, pv);
  }
  RayGrid g;
  const double cols = std::ceil((u_hi - u_lo) / spacing) + 1.0;
  const double rows = std::ceil((v_hi - v_lo) / spacing) + 1.0;
  require(cols * rows <= static_cast<double>(config_.max_rays),
          "the ray grid needs " + std::to_string(static_cast<std::uint64_t>(cols * rows)) +
              " rays, over the limit of " + std::to_string(config_.max_rays) +
              " (lower rays-per-wavelength)");
  g.cols = static_cast<std::uint64_t>(cols);
  g.rows = static_cast<std::uint64_t>(rows);
  const double u0 = 0.5 * (u_lo + u_hi) - 0.5 * (cols - 1.0) * spacing;
  const double v0 = 0.5 * (v_lo + v_hi) - 0.5 * (rows - 1.0) * spacing;
  g.origin_m = centre_m_ + r_t * (radius_m_ + 10.0 * epsilon_m_) + u0 * axis_u + v0 * axis_v;
  g.du_m = axis_u * spacing;
  g.dv_m = axis_v * spacing;
  g.direction = -r_t;
  return g;
}

void RcsEngine::compute(const Direction& tx, const Direction& rx, std::span<const double> freqs_hz,
                        std::span<ScatteringMatrix> out, RcsStats& stats,
                        const std::function<void(const BounceEvent&)>* on_bounce) const {
  require(!freqs_hz.empty(), "no frequency given");
  require(out.size() == freqs_hz.size(), "output size differs from the number of frequencies");
  double f_lo = std::numeric_limits<double>::max(), f_hi = 0.0;
  for (double f : freqs_hz) {
    require(std::isfinite(f) && f > 0.0, "frequencies must be positive and finite");
    f_lo = std::min(f_lo, f);
    f_hi = std::max(f_hi, f);
  }
  require(std::isfinite(tx.theta_rad) && std::isfinite(tx.phi_rad) && std::isfinite(rx.theta_rad) &&
              std::isfinite(rx.phi_rad),
          "directions must be finite");
  const double f_ref =
      config_.coating_reference_hz > 0.0 ? config_.coating_reference_hz : 0.5 * (f_lo + f_hi);
  const double k_ref = 2.0 * kPi * f_ref / kSpeedOfLight_mps;

  const glm::dvec3 r_t = unit_vector(tx), r_r = unit_vector(rx);
  const glm::dvec3 d_i = -r_t, s = r_r, w = s - d_i;
  const glm::dvec3 tx_h = phi_hat(tx), tx_v = theta_hat(tx);
  const glm::dvec3 rx_h = phi_hat(rx), rx_v = theta_hat(rx);
  const bool shadowing = config_.shadowing;
  const double eps = epsilon_m_;

  auto coefficients = [&](const CVec& src_h, const CVec& src_v) {
    return std::array<cplx, 4>{0.5 * dot(rx_h, src_h), 0.5 * dot(rx_h, src_v),
                               0.5 * dot(rx_v, src_h), 0.5 * dot(rx_v, src_v)};
  };
  // Is the path from `from` toward the unit direction `toward` (the plane wave's source or the
  // receiver) free? Callers lift `from` off the surface along its lit normal.
  auto clear = [&](const glm::dvec3& from, const glm::dvec3& toward) {
    scene::Ray ray;
    ray.origin_m = from;
    ray.direction = toward;
    ray.t_near_m = 0.0;
    ray.t_far_m = std::numeric_limits<double>::infinity();
    return !scene_->occluded(ray);
  };

  // --- Bounce 1: classical PO over the lit surface (sbr_core.hpp, FacetLight). ----------------
  // Lit facets: the exact integral; partly lit facets: the exact integrals of their lit
  // sub-triangles; dark facets: nothing. No receiver-visibility cut: the lit currents radiate
  // toward the receiver wherever it is (forward scatter included).
  // Partly lit facets are resolved as finely as the tubes are spaced (sbr_core.hpp).
  const double resolution_m = kSpeedOfLight_mps / f_hi / config_.rays_per_wavelength;
  // The facets go in fixed blocks (results do not depend on the threading); in each, the
  // lighting samples of every facet that needs them are answered by one batched query (the
  // parallel rays toward the transmitter from neighbouring facets are coherent: Embree traces
  // them in packets), then the sub-triangles of the partly lit ones by a second. The rule and
  // its answers are facet_light's and for_each_lit_subtriangle's (sbr_core.hpp).
  constexpr std::size_t kFacetBlock = 256;
  const std::size_t n_blocks = (facets_.size() + kFacetBlock - 1) / kFacetBlock;
  std::vector<std::vector<FacetTerm>> block_terms(n_blocks);
  // At one frequency the facets' integrals are summed here, block by block (facet_sums[block],
  // added in block order below), instead of being kept as terms for the frequency sum.
  const bool one_frequency = freqs_hz.size() == 1;
  const double k_one = 2.0 * kPi * freqs_hz[0] / kSpeedOfLight_mps;
  std::vector<std::array<cplx, 4>> facet_sums(n_blocks, std::array<cplx, 4>{});
  std::atomic<std::uint64_t> lit{0}, partly{0}, shadowed{0}, edge_on{0}, occl{0}, subs{0};
  // Bounce 1 (the facets' lighting) and the rest (edges, ray tubes) are independent: they run
  // side by side (one join per call instead of one per stage, so neither stage's tail leaves a
  // thread idle); each writes only its own outputs, `stats` is written by the second alone.
  std::vector<FacetTerm> facet_list;
  std::vector<EdgeTerm> edge_terms;
  std::vector<DoubleEdgeTerm> double_terms;
  std::vector<PathTerm> path_terms;
  auto bounce1 = [&] {
    tbb::parallel_for(std::size_t{0}, n_blocks, [&](std::size_t bi) {
      const std::size_t begin = bi * kFacetBlock,
                        end = std::min(facets_.size(), begin + kFacetBlock);
      std::uint64_t n_lit = 0, n_partial = 0, n_shadow = 0, n_edge = 0, n_subs = 0;
      // Per facet of the block: how it is lit, its lit normal and the first of its sample rays
      // (7 in `rays`) and of its sub-triangle rays (m^2 in `sub_rays`).
      struct Lighting {
        FacetLight light = FacetLight::kDark;
        bool tested = false;
        int m = 0;
        glm::dvec3 n{0.0};
        double cos_i = 0.0;
        std::size_t first = 0, first_sub = 0;
      };
      std::array<Lighting, kFacetBlock> lighting{};
      // Where the rays toward the transmitter start: the samples, the sub-triangles' samples.
      std::vector<glm::dvec3> rays, sub_rays;
      std::vector<std::uint8_t> blocked, sub_blocked;
      for (std::size_t i = begin; i != end; ++i) {
        const Facet& f = facets_[i];
        Lighting& l = lighting[i - begin];
        glm::dvec3 n = f.normal;
        double cos_i = -glm::dot(n, d_i);
        if (cos_i < 0.0) {  // two-sided: the face the wave meets
          n = -n;
          cos_i = -cos_i;
        }
        l.n = n;
        l.cos_i = cos_i;
        if (cos_i <= kEdgeOnCos) {
          ++n_edge;
          l.light = FacetLight::kDark;
          continue;
        }
        // The inside of a closed part is never lit (sbr_core.hpp, closed parts), nor that of a
        // part closed up to T-junctions (solid_winding).
        const bool inside = f.solid != 0 && f.solid * glm::dot(f.normal, r_t) <= 0.0;
        if (!shadowing) {
          l.light = FacetLight::kLit;
        } else if (inside) {
          l.light = FacetLight::kDark;
          ++n_shadow;
        } else if ((f.empty_side & (glm::dot(n, f.normal) > 0.0 ? 1u : 2u)) != 0) {
          // On the convex hull, lit on its open side (find_supporting_sides): every sample's ray
          // toward the transmitter runs into the empty half-space, so all seven are clear.
          l.light = FacetLight::kLit;
        } else {
          l.tested = true;
          l.first = rays.size();
          for (const glm::dvec3& p : facet_samples(f.v0, f.v1, f.v2, n, eps))
            rays.push_back(p);
        }
      }
      blocked.resize(rays.size());
      scene_->occluded_along(r_t, rays, blocked);
      for (std::size_t i = begin; i != end; ++i) {
        Lighting& l = lighting[i - begin];
        if (!l.tested)
          continue;
        l.light = facet_light(
            std::span<const std::uint8_t, kFacetSamples>(blocked.data() + l.first, kFacetSamples));
        if (l.light == FacetLight::kDark) {
          ++n_shadow;
        } else if (l.light == FacetLight::kPartial) {
          // Partly lit facets are resolved as finely as the tubes are spaced (sbr_core.hpp).
          const Facet& f = facets_[i];
          l.m = facet_subdivisions(f.longest_m, resolution_m);
          l.first_sub = sub_rays.size();
          for_each_subtriangle(f.v0, f.v1, f.v2, l.m,
                               [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
                                 sub_rays.push_back(subtriangle_sample(a, b, c, l.n, eps));
                               });
        }
      }
      sub_blocked.resize(sub_rays.size());
      scene_->occluded_along(r_t, sub_rays, sub_blocked);
      occl.fetch_add(rays.size() + sub_rays.size(), std::memory_order_relaxed);
      std::vector<FacetTerm>& terms = block_terms[bi];
      for (std::size_t i = begin; i != end; ++i) {
        const Lighting& l = lighting[i - begin];
        if (l.light == FacetLight::kDark)
          continue;
        const Facet& f = facets_[i];
        const SurfaceModel& sm = surfaces_[f.surface];
        const bool pec = sm.kind == SurfaceModel::Kind::kPec;
        const ReflectionCoefficients rc = reflection_coefficients(sm, l.cos_i, k_ref);
        const CVec e_h{tx_h, glm::dvec3(0.0)}, e_v{tx_v, glm::dvec3(0.0)};
        const std::array<cplx, 4> c = coefficients(po_source(e_h, d_i, l.n, s, rc, pec),
                                                   po_source(e_v, d_i, l.n, s, rc, pec));
        if (one_frequency) {
          cplx integral;
          if (l.light == FacetLight::kLit) {
            ++n_lit;
            integral = triangle_phase_integral(f.area_m2, glm::dot(w, f.v0), glm::dot(w, f.v1),
                                               glm::dot(w, f.v2), k_one);
          } else {
            // The m x m congruent sub-triangles (for_each_subtriangle) are translates of two:
            // the "up" one (v0, v0 + e1, v0 + e2) and the "down" one (v0 + e1, v0 + e1 + e2,
            // v0 + e2), e1 = (v1 - v0) / m, e2 = (v2 - v0) / m, moved by i e1 + j e2. A
            // translation by t multiplies the integral of exp(j k w . r) by exp(j k w . t), so
            // the lit ones sum to I_up sum_up z1^i z2^j + I_down sum_down z1^i z2^j with
            // z1 = exp(j k w . e1), z2 = exp(j k w . e2): two closed forms per facet and one
            // complex rotation per sub-triangle instead of a sine and cosine each.
            ++n_partial;
            const double m = static_cast<double>(l.m);
            const glm::dvec3 e1 = (f.v1 - f.v0) / m, e2 = (f.v2 - f.v0) / m;
            const double b0 = glm::dot(w, f.v0), s1 = glm::dot(w, e1), s2 = glm::dot(w, e2);
            const double sub_area_m2 = f.area_m2 / (m * m);
            const cplx up = triangle_phase_integral(sub_area_m2, b0, b0 + s1, b0 + s2, k_one);
            const cplx down =
                triangle_phase_integral(sub_area_m2, b0 + s1, b0 + s1 + s2, b0 + s2, k_one);
            const cplx z1 = std::polar(1.0, k_one * s1), z2 = std::polar(1.0, k_one * s2);
            cplx sum_up{0.0, 0.0}, sum_down{0.0, 0.0}, row{1.0, 0.0};
            std::size_t q = l.first_sub;
            for (int a = 0; a < l.m; ++a) {
              cplx z = row;
              for (int b = 0; a + b < l.m; ++b) {
                if (sub_blocked[q++] == 0) {
                  ++n_subs;
                  sum_up += z;
                }
                if (a + b + 2 <= l.m && sub_blocked[q++] == 0) {
                  ++n_subs;
                  sum_down += z;
                }
                z *= z2;
              }
              row *= z1;
            }
            integral = up * sum_up + down * sum_down;
          }
          for (std::size_t p = 0; p < 4; ++p)
            facet_sums[bi][p] += c[p] * integral;
          continue;
        }
        auto add = [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& v) {
          FacetTerm t;
          t.c = c;
          t.area_m2 = 0.5 * glm::length(glm::cross(b - a, v - a));
          t.b0_m = glm::dot(w, a);
          t.b1_m = glm::dot(w, b);
          t.b2_m = glm::dot(w, v);
          terms.push_back(t);
        };
        if (l.light == FacetLight::kLit) {
          ++n_lit;
          add(f.v0, f.v1, f.v2);
          continue;
        }
        ++n_partial;
        std::size_t k = l.first_sub;
        for_each_subtriangle(f.v0, f.v1, f.v2, l.m,
                             [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& v) {
                               if (sub_blocked[k++] == 0) {
                                 ++n_subs;
                                 add(a, b, v);
                               }
                             });
      }
      lit += n_lit;
      partly += n_partial;
      shadowed += n_shadow;
      edge_on += n_edge;
      subs += n_subs;
    });
    {
      std::size_t total = 0;
      for (const auto& v : block_terms)
        total += v.size();
      facet_list.reserve(total);
      for (const auto& v : block_terms)
        facet_list.insert(facet_list.end(), v.begin(), v.end());
    }
  };
  auto later = [&] {
    // --- Edge diffraction: fringe equivalent edge currents (radar/em/edges.hpp). --------------
    // An edge radiates when a face of it is lit and the path from beside its midpoint (in the free
    // space) to the transmitter is clear (the same occlusion query as the facets').
    // Where an edge's occlusion test toward `toward` starts: beside its midpoint in the free space
    // (edge_probe), and for an open sheet's boundary (whose exterior bisector lies in the sheet's
    // own plane) also lifted off that plane on the side of `toward`, so that a wave travelling
    // exactly along the sheet is not blocked by the sheet's own facets seen edge-on (which made
    // the double-diffraction term vanish at exactly grazing incidence, a step in the pattern).
    auto probe_toward = [&](const WedgeEdge& e, const glm::dvec3& toward) {
      glm::dvec3 p = edge_probe(e, 10.0 * eps);
      if (e.alpha_rad > 2.0 * kPi - 1e-9)
        p += (glm::dot(e.y0, toward) >= 0.0 ? 10.0 : -10.0) * eps * e.y0;
      return p;
    };
    // The wedge rule at the call's shortest wavelength (edges.hpp): weight 0 for the joints of a
    // smooth surface, 1 for wedges, a smooth ramp between.
    std::vector<double> weight(edges_.size());
    const double lambda_min_m = kSpeedOfLight_mps / f_hi;
    {
      for (std::size_t i = 0; i < edges_.size(); ++i)
        weight[i] = wedge_weight(edges_[i], lambda_min_m, config_.edge_min_turn_rad);
    }
    if (!edges_.empty()) {
      std::vector<EdgeTerm> all(edges_.size());
      std::vector<std::uint8_t> state(edges_.size());  // 0 used, 1 shadowed, 2 skipped, 3 smooth
      std::atomic<std::uint64_t> guarded{0}, e_occl{0};
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, edges_.size(), 256),
          [&](const tbb::blocked_range<std::size_t>& range) {
            std::uint64_t n_guard = 0, n_occl = 0;
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
              if (weight[i] == 0.0) {
                state[i] = 3;
                continue;
              }
              bool g = false;
              if (edge_term(edges_[i], d_i, s, tx_h, tx_v, rx_h, rx_v, EdgeCoefficient::kFringe,
                            all[i], g, std::min(lambda_min_m / edges_[i].length_m, kMaxMinSin2Beta),
                            kMonostaticFringeBound) != EdgeSkip::kNone) {
                state[i] = 2;
                continue;
              }
              n_guard += g ? 1u : 0u;
              if (shadowing) {
                ++n_occl;
                if (!clear(probe_toward(edges_[i], r_t), r_t)) {
                  state[i] = 1;
                  continue;
                }
              }
              for (cplx& c : all[i].c)
                c *= weight[i];
              state[i] = 0;
            }
            guarded += n_guard;
            e_occl += n_occl;
          });
      for (std::size_t i = 0; i < edges_.size(); ++i) {
        if (state[i] == 0)
          edge_terms.push_back(all[i]);
        stats.edges_shadowed += state[i] == 1 ? 1u : 0u;
        stats.edges_skipped += state[i] == 2 ? 1u : 0u;
        stats.edges_smooth += state[i] == 3 ? 1u : 0u;
      }
      stats.edges_used += edge_terms.size();
      stats.edges_guarded += guarded;
      occl += e_occl;
    }
    // Reflection-diffraction (image theory): an edge lit by the transmitter's wave after one
    // reflection off a reflecting plane (RD), seen by the receiver after one (DR), or both (RDR).
    // A PEC plane reflects E into R(E) = 2 (n.E) n - E and a direction v into mirror(v, n); the
    // reflected plane wave's phase at x is -k (d_r . x + 2 (d . n) offset), and a current at x
    // radiating toward mirror(s, n) reaches the receiver with phase k (mirror(s, n) . x + 2 (s . n)
    // offset) (Balanis, Advanced Engineering Electromagnetics, 2nd ed., 2012, sec. 7.4: image
    // theory). The edge term is edges.hpp's with those directions, polarisations and phases. Paths:
    // from beside the edge's midpoint along -d_r (RD) or mirror(s, n) (DR), the first hit must be
    // a PEC facet of the plane, on the edge's side, and from there the transmitter (RD) or the
    // receiver (DR) must be in sight. An edge lying in the plane is not lit by it, and a plane
    // smaller than kReflectingPlaneMinWavelengths2 square wavelengths at the lowest frequency
    // lights nothing (image theory needs a plane large against the wavelength).
    if (!edges_.empty() && !planes_.empty()) {
      const double tol_m = 100.0 * eps;
      const double lambda_max_m = kSpeedOfLight_mps / f_lo;
      const double min_plane_m2 = kReflectingPlaneMinWavelengths2 * lambda_max_m * lambda_max_m;
      auto reflect_pol = [](const glm::dvec3& e, const glm::dvec3& n) {
        return 2.0 * glm::dot(n, e) * n - e;
      };
      // Per plane, once per direction pair: the mirrored directions, polarisations and phases.
      struct Image {
        const ReflectingPlane* plane;
        glm::dvec3 d_r, s_r, th, tv, rh, rv;
        double phase_rd, phase_dr;
      };
      std::vector<Image> images;
      for (const ReflectingPlane& plane : planes_) {
        if (plane.area_m2 < min_plane_m2)
          continue;  // too small to reflect a plane wave at the lowest frequency
        const glm::dvec3& n = plane.normal;
        images.push_back({&plane, mirror(d_i, n), mirror(s, n), reflect_pol(tx_h, n),
                          reflect_pol(tx_v, n), reflect_pol(rx_h, n), reflect_pol(rx_v, n),
                          -2.0 * glm::dot(d_i, n) * plane.offset_m,
                          2.0 * glm::dot(s, n) * plane.offset_m});
      }
      std::vector<std::vector<EdgeTerm>> found(edges_.size());
      std::atomic<std::uint64_t> r_occl{0};
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, edges_.size(), 64),
          [&](const tbb::blocked_range<std::size_t>& range) {
            std::uint64_t n_occl = 0;
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
              const WedgeEdge& edge = edges_[i];
              if (weight[i] == 0.0)
                continue;
              const glm::dvec3 probe = edge_probe(edge, 10.0 * eps);
              for (const Image& im : images) {
                const ReflectingPlane& plane = *im.plane;
                const glm::dvec3& n = plane.normal;
                const double side = glm::dot(n, probe) - plane.offset_m;
                if (std::abs(glm::dot(n, edge.a_m) - plane.offset_m) < tol_m &&
                    std::abs(glm::dot(n, edge.b_m) - plane.offset_m) < tol_m)
                  continue;  // the edge lies in the plane
                // Does the ray from the probe along `dir` meet the plane first, on a PEC facet,
                // and see `toward` from there?
                auto relayed = [&](const glm::dvec3& dir, const glm::dvec3& toward) {
                  if (side * glm::dot(n, toward) <= 0.0 || std::abs(glm::dot(n, dir)) < 1e-3)
                    return false;  // the plane faces away, or the path grazes it
                  scene::Ray ray;
                  ray.origin_m = probe;
                  ray.direction = dir;
                  ray.t_near_m = 0.0;
                  ray.t_far_m = std::numeric_limits<double>::infinity();
                  scene::Hit hit;
                  ++n_occl;
                  if (!scene_->intersect(ray, hit) ||
                      std::abs(glm::dot(hit.normal, n)) < 1.0 - 1e-6 ||
                      std::abs(glm::dot(n, hit.position_m) - plane.offset_m) > tol_m ||
                      surfaces_[hit.material_id].kind != SurfaceModel::Kind::kPec)
                    return false;
                  if (!shadowing)
                    return true;
                  ++n_occl;
                  const glm::dvec3 lift = (side > 0.0 ? eps : -eps) * n;
                  return clear(hit.position_m + lift, toward);
                };
                const bool rd = relayed(-im.d_r, r_t), dr = relayed(im.s_r, r_r);
                auto add = [&](const glm::dvec3& dd, const glm::dvec3& ss, const glm::dvec3& ah,
                               const glm::dvec3& av, const glm::dvec3& bh, const glm::dvec3& bv,
                               double phase_m) {
                  EdgeTerm t;
                  bool g = false;
                  if (edge_term(edge, dd, ss, ah, av, bh, bv, EdgeCoefficient::kFringe, t, g,
                                std::min(lambda_min_m / edge.length_m, kMaxMinSin2Beta),
                                kMonostaticFringeBound) != EdgeSkip::kNone)
                    return;
                  t.phase_m += phase_m;
                  for (cplx& c : t.c)
                    c *= weight[i];
                  found[i].push_back(t);
                };
                if (rd)
                  add(im.d_r, s, im.th, im.tv, rx_h, rx_v, im.phase_rd);
                if (dr)
                  add(d_i, im.s_r, tx_h, tx_v, im.rh, im.rv, im.phase_dr);
                if (rd && dr)
                  add(im.d_r, im.s_r, im.th, im.tv, im.rh, im.rv, im.phase_rd + im.phase_dr);
              }
            }
            r_occl += n_occl;
          });
      for (const auto& v : found) {
        edge_terms.insert(edge_terms.end(), v.begin(), v.end());
        stats.edges_reflected += v.size();
      }
      occl += r_occl;
    }
    // Double diffraction (edges.hpp): the launching edge's midpoint must see the transmitter and
    // the receiving edge's the receiver (tests memoised per edge and direction).
    if (!pairs_.empty()) {
      std::vector<std::int8_t> sees_tx(edges_.size(), -1), sees_rx(edges_.size(), -1);
      auto sees = [&](std::vector<std::int8_t>& memo, std::uint32_t i, const glm::dvec3& toward) {
        if (!shadowing)
          return true;
        if (memo[i] < 0) {
          ++occl;
          memo[i] = clear(probe_toward(edges_[i], toward), toward) ? 1 : 0;
        }
        return memo[i] == 1;
      };
      for (const EdgePair& pair : pairs_) {
        const double w_pair = weight[pair.from] * weight[pair.to];
        if (w_pair == 0.0)
          continue;
        DoubleEdgeTerm t;
        if (double_edge_term(pair, edges_, d_i, s, tx_h, tx_v, rx_h, rx_v, t) != EdgeSkip::kNone)
          continue;
        for (double& p : t.pol)
          p *= w_pair;
        if (sees(sees_tx, pair.from, r_t) && sees(sees_rx, pair.to, r_r))
          double_terms.push_back(t);
      }
      stats.edges_double += double_terms.size();
    }

    // --- Bounces 2..n: ray tubes over the incident wavefront. -----------------------------------
    if (config_.max_bounces >= 2) {
      const RayGrid grid = ray_grid(tx, f_hi);
      const std::uint64_t cols = grid.cols, n_rows = grid.rows;
      const glm::dvec3 tube_u0 = grid.du_m, tube_v0 = grid.dv_m;
      const auto rows = static_cast<std::size_t>(n_rows);
      // Per row, the columns whose rays can meet a facet at all: the union of the facets' projected
      // bounding boxes on the grid (its rows' column intervals), widened by the ray offset. A ray
      // outside every facet's projection meets nothing (its Embree query would miss), so tracing
      // only these columns changes no path; on the vehicle about half of the grid's rays miss.
      struct Spans {
        std::vector<std::int64_t> lo, hi;
      };
      const glm::dvec3 col_axis = grid.du_m / glm::dot(grid.du_m, grid.du_m);
      const glm::dvec3 row_axis = grid.dv_m / glm::dot(grid.dv_m, grid.dv_m);
      const double margin = eps / glm::length(grid.du_m);  // du and dv are equally long
      const auto last_col = static_cast<std::int64_t>(cols) - 1;
      const auto last_row = static_cast<std::int64_t>(n_rows) - 1;
      // floor and ceil of a grid coordinate (the grid covers every vertex: no overflow), inline.
      auto floor_index = [](double x) {
        const auto i = static_cast<std::int64_t>(x);
        return x < static_cast<double>(i) ? i - 1 : i;
      };
      auto ceil_index = [](double x) {
        const auto i = static_cast<std::int64_t>(x);
        return x > static_cast<double>(i) ? i + 1 : i;
      };
      tbb::enumerable_thread_specific<Spans> local_spans([&] {
        return Spans{std::vector<std::int64_t>(rows, last_col + 1),
                     std::vector<std::int64_t>(rows, -1)};
      });
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, facets_.size(), 1024),
          [&](const tbb::blocked_range<std::size_t>& range) {
            Spans& sp = local_spans.local();
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
              const Facet& f = facets_[i];
              double c_lo = std::numeric_limits<double>::max(), c_hi = -c_lo, r_lo = c_lo,
                     r_hi = -c_lo;
              for (const glm::dvec3& v : {f.v0, f.v1, f.v2}) {
                const glm::dvec3 x = v - grid.origin_m;
                const double c = glm::dot(x, col_axis), r = glm::dot(x, row_axis);
                c_lo = std::min(c_lo, c);
                c_hi = std::max(c_hi, c);
                r_lo = std::min(r_lo, r);
                r_hi = std::max(r_hi, r);
              }
              const std::int64_t r0 = std::max<std::int64_t>(0, ceil_index(r_lo - margin));
              const std::int64_t r1 = std::min(last_row, floor_index(r_hi + margin));
              const std::int64_t c0 = std::max<std::int64_t>(0, ceil_index(c_lo - margin));
              const std::int64_t c1 = std::min(last_col, floor_index(c_hi + margin));
              for (std::int64_t r = r0; r <= r1; ++r) {
                const auto ri = static_cast<std::size_t>(r);
                sp.lo[ri] = std::min(sp.lo[ri], c0);
                sp.hi[ri] = std::max(sp.hi[ri], c1);
              }
            }
          });
      Spans spans{std::vector<std::int64_t>(rows, last_col + 1),
                  std::vector<std::int64_t>(rows, -1)};
      for (const Spans& sp : local_spans) {
        for (std::size_t r = 0; r < rows; ++r) {
          spans.lo[r] = std::min(spans.lo[r], sp.lo[r]);
          spans.hi[r] = std::max(spans.hi[r], sp.hi[r]);
        }
      }
      std::vector<std::vector<PathTerm>> row_terms(rows);
      std::atomic<std::uint64_t> hits{0}, n_paths{0}, grazing{0}, segments{0}, cut{0};
      std::array<std::atomic<std::uint64_t>, kMaxRcsBounces + 1> by_bounce{};
      // Each row's tubes go in chunks of neighbouring columns, bounce by bounce: the chunk's rays
      // of one bounce are intersected by one batched query (Scene::intersect over spans: coherent
      // rays, traced by Embree in packets), then their exit tests by one batched occlusion query,
      // then the cap tests. What each tube does is what the tube-by-tube loop did; only the order
      // of the row's terms (chunk, bounce, column) differs.
      constexpr std::size_t kChunk = 64;
      // A tube in flight: where it is, its field and its footprint's edges.
      struct Tube {
        std::uint64_t col = 0;
        std::uint64_t seq_key = 0;  // the facets met so far, hashed
        glm::dvec3 d{0.0}, tube_u{0.0}, tube_v{0.0}, last_hit{0.0};
        CVec e_h, e_v;
        double path_m = 0.0;
      };
      // What a tube met at this bounce.
      struct Met {
        std::uint32_t tube = 0;
        glm::dvec3 n{0.0};
        ReflectionCoefficients rc;
        bool pec = true;
        bool radiate = false;
        // The facet is on the convex hull and n points to its empty side (Facet::empty_side): rays
        // from the hit into that side (the reflection, the exit toward the receiver, the cap
        // test) meet nothing, so they are not traced.
        bool open = false;
        std::uint32_t exit = 0;  // its exit test's index, when radiate, shadowing and not open
      };
      // Each thread's buffers for its rows, sized once per call.
      struct Scratch {
        std::vector<Tube> tubes = std::vector<Tube>(kChunk);
        std::vector<std::uint32_t> active = std::vector<std::uint32_t>(kChunk),
                                   next = std::vector<std::uint32_t>(kChunk);
        std::vector<scene::Ray> rays = std::vector<scene::Ray>(kChunk),
                                exits = std::vector<scene::Ray>(kChunk),
                                caps = std::vector<scene::Ray>(kChunk);
        std::vector<scene::Hit> met_hits = std::vector<scene::Hit>(kChunk);
        std::vector<std::uint8_t> found = std::vector<std::uint8_t>(kChunk),
                                  exit_blocked = std::vector<std::uint8_t>(kChunk),
                                  cap_blocked = std::vector<std::uint8_t>(kChunk);
        std::vector<Met> met = std::vector<Met>(kChunk);
      };
      tbb::enumerable_thread_specific<Scratch> row_scratch;
      tbb::parallel_for(std::size_t{0}, rows, [&](std::size_t row) {
        if (spans.lo[row] > spans.hi[row])
          return;  // no facet in this row
        const auto col_begin = static_cast<std::uint64_t>(spans.lo[row]);
        const auto col_end = static_cast<std::uint64_t>(spans.hi[row]) + 1;
        row_terms[row].reserve(static_cast<std::size_t>((col_end - col_begin) / 8));
        std::uint64_t l_hits = 0, l_paths = 0, l_grazing = 0, l_occl = 0, l_segments = 0, l_cut = 0;
        std::array<std::uint64_t, kMaxRcsBounces + 1> l_by{};
        const glm::dvec3 row_origin = grid.origin_m + static_cast<double>(row) * grid.dv_m;
        // The open run per bounce (PathTerm): its term's index, the facet sequence's key, the
        // last tube's column and phase path.
        struct Run {
          std::size_t term = 0;
          std::uint64_t key = 0, col = 0;
          double last_len_m = 0.0;
          bool open = false;
        };
        std::array<Run, kMaxRcsBounces + 1> runs{};
        const double run_tolerance_m = 1e-9 * glm::length(grid.du_m);
        Scratch& scratch = row_scratch.local();
        std::vector<Tube>& tubes = scratch.tubes;
        std::vector<std::uint32_t>&active = scratch.active, &next = scratch.next;
        std::vector<scene::Ray>&rays = scratch.rays, &exits = scratch.exits, &caps = scratch.caps;
        std::vector<scene::Hit>& met_hits = scratch.met_hits;
        std::vector<std::uint8_t>&found = scratch.found, &exit_blocked = scratch.exit_blocked,
        &cap_blocked = scratch.cap_blocked;
        std::vector<Met>& met = scratch.met;
        std::vector<PathTerm>& terms = row_terms[row];
        auto free_ray = [](const glm::dvec3& from, const glm::dvec3& dir) {
          scene::Ray ray;
          ray.origin_m = from;
          ray.direction = dir;
          ray.t_near_m = 0.0;
          ray.t_far_m = std::numeric_limits<double>::infinity();
          return ray;
        };
        for (std::uint64_t col0 = col_begin; col0 < col_end; col0 += kChunk) {
          const std::size_t n_chunk =
              static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, col_end - col0));
          std::size_t n_active = n_chunk;
          for (std::size_t j = 0; j < n_chunk; ++j) {
            Tube& tb = tubes[j];
            tb.col = col0 + j;
            tb.seq_key = 0x9e3779b97f4a7c15ull;
            tb.d = d_i;
            tb.tube_u = tube_u0;
            tb.tube_v = tube_v0;
            tb.e_h = CVec{tx_h, glm::dvec3(0.0)};
            tb.e_v = CVec{tx_v, glm::dvec3(0.0)};
            tb.last_hit = glm::dvec3(0.0);
            rays[j] = free_ray(row_origin + static_cast<double>(tb.col) * grid.du_m, d_i);
            tb.path_m = glm::dot(d_i, rays[j].origin_m);  // plane-wave phase path at the origin
            active[j] = static_cast<std::uint32_t>(j);
          }
          for (int bounce = 1; bounce <= config_.max_bounces && n_active > 0; ++bounce) {
            l_segments += n_active;
            scene_->intersect(std::span<const scene::Ray>(rays.data(), n_active),
                              std::span<scene::Hit>(met_hits.data(), n_active),
                              std::span<std::uint8_t>(found.data(), n_active));
            // The hits, in column order; exit tests of the footprints that may radiate.
            std::size_t n_met = 0, n_exits = 0;
            for (std::size_t a = 0; a < n_active; ++a) {
              if (found[a] == 0)
                continue;
              ++l_hits;
              Tube& tb = tubes[active[a]];
              scene::Hit& hit = met_hits[a];
              tb.seq_key =
                  (tb.seq_key ^ ((std::uint64_t{hit.object_id} << 32) | hit.primitive_id)) *
                  0x100000001b3ull;
              tb.seq_key ^= tb.seq_key >> 29;
              hit.position_m = extend_path(bounce == 1, hit.t_m, tb.last_hit, tb.d, hit.position_m,
                                           hit.normal, tb.path_m);
              tb.last_hit = hit.position_m;
              glm::dvec3 n = hit.normal;
              double cos_i = -glm::dot(n, tb.d);
              const bool back = cos_i < 0.0;
              if (back) {
                n = -n;
                cos_i = -cos_i;
              }
              if (cos_i < kGrazingCos) {
                ++l_grazing;
                continue;
              }
              Met& mt = met[n_met++];
              mt.tube = active[a];
              mt.n = n;
              const SurfaceModel& sm = surfaces_[hit.material_id];
              mt.pec = sm.kind == SurfaceModel::Kind::kPec;
              mt.rc = reflection_coefficients(sm, cos_i, k_ref);
              // Bounce 1 is the facets' (above). Later hits radiate when the receiver sees the lit
              // side of the hit (sbr_core.hpp, kGrazingCos) and nothing is in the way.
              mt.radiate = bounce >= 2 && glm::dot(n, s) >= kGrazingCos;
              mt.open = (triangle_empty_side_[first_triangle_[hit.object_id] + hit.primitive_id] &
                         (back ? 2u : 1u)) != 0;
              if (mt.radiate && shadowing && !mt.open) {
                mt.exit = static_cast<std::uint32_t>(n_exits);
                exits[n_exits++] = free_ray(hit.position_m + eps * n, s);
              }
            }
            if (n_exits > 0) {
              l_occl += n_exits;
              scene_->occluded(std::span<const scene::Ray>(exits.data(), n_exits),
                               std::span<std::uint8_t>(exit_blocked.data(), n_exits));
            }
            std::size_t n_next = 0, n_caps = 0;
            for (std::size_t q = 0; q < n_met; ++q) {
              const Met& mt = met[q];
              Tube& tb = tubes[mt.tube];
              const glm::dvec3& n = mt.n;
              const glm::dvec3& hit_m = tb.last_hit;
              if (mt.radiate && (!shadowing || mt.open || exit_blocked[mt.exit] == 0)) {
                ++l_paths;
                ++l_by[static_cast<std::size_t>(bounce)];
                // The tube's footprint on this facet: its edge vectors projected along d.
                const TubeFootprint fp = tube_footprint(tb.tube_u, tb.tube_v, tb.d, n, s);
                PathTerm t;
                t.c = coefficients(po_source(tb.e_h, tb.d, n, s, mt.rc, mt.pec),
                                   po_source(tb.e_v, tb.d, n, s, mt.rc, mt.pec));
                t.area_m2 = fp.area_m2;
                t.phase_len_m = tb.path_m - glm::dot(s, hit_m);
                t.taper_u_m = fp.taper_u_m;
                t.taper_v_m = fp.taper_v_m;
                t.count = 1;
                t.step_m = 0.0;
                Run& run = runs[static_cast<std::size_t>(bounce)];
                bool merged = false;
                if (run.open && run.key == tb.seq_key && run.col + 1 == tb.col) {
                  PathTerm& r = terms[run.term];
                  const double step = t.phase_len_m - run.last_len_m;
                  if (r.c == t.c && r.area_m2 == t.area_m2 && r.taper_u_m == t.taper_u_m &&
                      r.taper_v_m == t.taper_v_m &&
                      (r.count == 1 || std::abs(step - r.step_m) <= run_tolerance_m)) {
                    if (r.count == 1)
                      r.step_m = step;
                    ++r.count;
                    merged = true;
                  }
                }
                if (!merged) {
                  run.term = terms.size();
                  run.key = tb.seq_key;
                  run.open = true;
                  terms.push_back(t);
                }
                run.col = tb.col;
                run.last_len_m = t.phase_len_m;
              }
              // Specular reflection: direction, tube edges and field (law of reflection).
              const glm::dvec3 d_r = mirror(tb.d, n);
              if (bounce == config_.max_bounces) {
                // The cap: is this tube still bouncing (would its reflection meet the target)?
                if (!mt.open)
                  caps[n_caps++] = free_ray(hit_m + eps * n, d_r);
                continue;
              }
              const CVec e_v_r = reflect_field(tb.e_v, tb.d, d_r, n, mt.rc, mt.pec);
              const CVec e_h_r = reflect_field(tb.e_h, tb.d, d_r, n, mt.rc, mt.pec);
              if (on_bounce != nullptr) {
                BounceEvent ev;
                ev.bounce = bounce;
                ev.incident = tb.d;
                ev.normal = n;
                ev.reflected = d_r;
                ev.field_before = norm(tb.e_v);
                ev.field_after = norm(e_v_r);
                ev.field_h_before = norm(tb.e_h);
                ev.field_h_after = norm(e_h_r);
                ev.pec = mt.pec;
                (*on_bounce)(ev);
              }
              tb.e_h = e_h_r;
              tb.e_v = e_v_r;
              tb.tube_u = mirror(tb.tube_u, n);
              tb.tube_v = mirror(tb.tube_v, n);
              tb.d = d_r;
              if (mt.open)
                continue;  // the reflection leaves the target
              // Lifted to the lit side: no self-hit.
              rays[n_next] = free_ray(hit_m + eps * n, d_r);
              next[n_next++] = mt.tube;
            }
            if (n_caps > 0) {
              l_occl += n_caps;
              scene_->occluded(std::span<const scene::Ray>(caps.data(), n_caps),
                               std::span<std::uint8_t>(cap_blocked.data(), n_caps));
              for (std::size_t q = 0; q < n_caps; ++q)
                l_cut += cap_blocked[q] != 0 ? 1u : 0u;
            }
            std::swap(active, next);
            n_active = n_next;
          }
        }
        hits += l_hits;
        segments += l_segments;
        n_paths += l_paths;
        grazing += l_grazing;
        cut += l_cut;
        occl += l_occl;
        for (std::size_t b = 0; b < l_by.size(); ++b)
          by_bounce[b] += l_by[b];
      });
      std::size_t total = 0;
      for (const auto& r : row_terms)
        total += r.size();
      path_terms.reserve(total);
      for (const auto& r : row_terms)
        path_terms.insert(path_terms.end(), r.begin(), r.end());
      stats.rays += cols * n_rows;
      stats.ray_hits += hits;
      stats.segments += segments;
      stats.paths += n_paths;
      stats.grazing_stops += grazing;
      stats.tubes_cut_off += cut;
      for (std::size_t b = 0; b < by_bounce.size(); ++b)
        stats.paths_by_bounce[b] += by_bounce[b];
    }
  };
  tbb::parallel_invoke(bounce1, later);
  stats.facets_lit += lit;
  stats.facets_partial += partly;
  stats.lit_subfacets += subs;
  stats.facets_shadowed += shadowed;
  stats.facets_edge_on += edge_on;

  stats.occlusion_queries += occl;

  // --- Every frequency from the same terms. ---------------------------------------------------
  // Terms are split into a fixed number of chunks (a function of the sizes only), each summed in
  // order into its own per-frequency accumulator, and the chunks are added in order: the result
  // does not depend on the threading. On a uniform frequency grid the ray-path phasors and the
  // footprint tapers' sines advance by one complex rotation per frequency instead of three
  // trigonometric calls (rounding grows as n eps: 1e-13 after 1000 steps).
  const std::size_t nf = freqs_hz.size();
  const double df = nf > 1 ? (freqs_hz[nf - 1] - freqs_hz[0]) / static_cast<double>(nf - 1) : 0.0;
  bool uniform = nf >= 3;
  for (std::size_t i = 0; uniform && i < nf; ++i) {
    uniform = std::abs(freqs_hz[i] - (freqs_hz[0] + df * static_cast<double>(i))) <= 1e-9 * f_hi;
  }
  const double k_of_hz = 2.0 * kPi / kSpeedOfLight_mps;
  const std::size_t n_terms = facet_list.size() + path_terms.size();
  const std::size_t n_chunks = std::clamp<std::size_t>((n_terms + 1023) / 1024, 1, 64);
  const std::size_t chunk = (n_terms + n_chunks - 1) / n_chunks;
  std::vector<std::array<cplx, 4>> partial(n_chunks * nf, std::array<cplx, 4>{});
  tbb::parallel_for(std::size_t{0}, n_chunks, [&](std::size_t ci) {
    std::array<cplx, 4>* acc = partial.data() + ci * nf;
    const std::size_t begin = ci * chunk, end = std::min(n_terms, begin + chunk);
    for (std::size_t ti = begin; ti < end; ++ti) {
      if (ti < facet_list.size()) {
        const FacetTerm& t = facet_list[ti];
        // On a uniform grid, where the phase spread exceeds kSeriesSpreadRad at the lowest
        // frequency (so at all: it grows with k), the closed form of facet_po.cpp,
        //   I = -2 A [fd(k b1, k b2) - fd(k b0, k b1)] / (k (b2 - b0)),
        //   fd(x, y) = j exp(j (x + y) / 2) sinc((x - y) / 2), b0 <= b1 <= b2,
        // advances its four phasors by one rotation per frequency instead of sin and cos.
        double b[3] = {t.b0_m, t.b1_m, t.b2_m};
        std::sort(b, b + 3);
        if (uniform && k_of_hz * freqs_hz[0] * (b[2] - b[0]) >= kSeriesSpreadRad) {
          const double k0 = k_of_hz * freqs_hz[0], dk = k_of_hz * df;
          const double m12 = 0.5 * (b[1] + b[2]), h12 = 0.5 * (b[2] - b[1]);
          const double m01 = 0.5 * (b[0] + b[1]), h01 = 0.5 * (b[1] - b[0]);
          cplx e12 = std::polar(1.0, k0 * m12), de12 = std::polar(1.0, dk * m12);
          cplx e01 = std::polar(1.0, k0 * m01), de01 = std::polar(1.0, dk * m01);
          cplx s12 = std::polar(1.0, k0 * h12), ds12 = std::polar(1.0, dk * h12);
          cplx s01 = std::polar(1.0, k0 * h01), ds01 = std::polar(1.0, dk * h01);
          const double spread = b[2] - b[0];
          for (std::size_t fi = 0; fi < nf; ++fi) {
            const double k = k0 + dk * static_cast<double>(fi);
            const double x12 = k * h12, x01 = k * h01;
            const double c12 = std::abs(x12) < 1e-3 ? 1.0 - x12 * x12 / 6.0 : s12.imag() / x12;
            const double c01 = std::abs(x01) < 1e-3 ? 1.0 - x01 * x01 / 6.0 : s01.imag() / x01;
            // j (e12 c12 - e01 c01) * (-2 A) / (k spread)
            const cplx diff = e12 * c12 - e01 * c01;
            const cplx integral =
                cplx(-diff.imag(), diff.real()) * (-2.0 * t.area_m2 / (k * spread));
            for (std::size_t p = 0; p < 4; ++p)
              acc[fi][p] += t.c[p] * integral;
            e12 *= de12;
            e01 *= de01;
            s12 *= ds12;
            s01 *= ds01;
          }
          continue;
        }
        for (std::size_t fi = 0; fi < nf; ++fi) {
          const cplx integral =
              triangle_phase_integral(t.area_m2, t.b0_m, t.b1_m, t.b2_m, k_of_hz * freqs_hz[fi]);
          for (std::size_t p = 0; p < 4; ++p)
            acc[fi][p] += t.c[p] * integral;
        }
        continue;
      }
      const PathTerm& t = path_terms[ti - facet_list.size()];
      const double n_run = static_cast<double>(t.count);
      const double centre_len_m = t.phase_len_m + 0.5 * (n_run - 1.0) * t.step_m;
      if (!uniform) {
        for (std::size_t fi = 0; fi < nf; ++fi) {
          const double k = k_of_hz * freqs_hz[fi];
          double a = t.area_m2 * sinc(k * t.taper_u_m) * sinc(k * t.taper_v_m);
          if (t.count > 1) {
            const double h = 0.5 * k * t.step_m;
            a *= dirichlet(std::sin(n_run * h), std::cos(n_run * h), std::sin(h), std::cos(h),
                           n_run);
          }
          const cplx integral = std::polar(a, -k * centre_len_m);
          for (std::size_t p = 0; p < 4; ++p)
            acc[fi][p] += t.c[p] * integral;
        }
        continue;
      }
      const double k0 = k_of_hz * freqs_hz[0], dk = k_of_hz * df;
      cplx z = std::polar(1.0, -k0 * centre_len_m), dz = std::polar(1.0, -dk * centre_len_m);
      cplx pu = std::polar(1.0, k0 * t.taper_u_m), dpu = std::polar(1.0, dk * t.taper_u_m);
      cplx pv = std::polar(1.0, k0 * t.taper_v_m), dpv = std::polar(1.0, dk * t.taper_v_m);
      // The run's Dirichlet kernel: sin and cos of n k step / 2 and of k step / 2, rotated.
      const double h0 = 0.5 * k0 * t.step_m, dh = 0.5 * dk * t.step_m;
      cplx qn = std::polar(1.0, n_run * h0), dqn = std::polar(1.0, n_run * dh);
      cplx q1 = std::polar(1.0, h0), dq1 = std::polar(1.0, dh);
      for (std::size_t fi = 0; fi < nf; ++fi) {
        const double k = k0 + dk * static_cast<double>(fi);
        const double xu = k * t.taper_u_m, xv = k * t.taper_v_m;
        const double su = std::abs(xu) < 1e-3 ? 1.0 - xu * xu / 6.0 : pu.imag() / xu;
        const double sv = std::abs(xv) < 1e-3 ? 1.0 - xv * xv / 6.0 : pv.imag() / xv;
        double a = t.area_m2 * su * sv;
        if (t.count > 1) {
          a *= dirichlet(qn.imag(), qn.real(), q1.imag(), q1.real(), n_run);
          qn *= dqn;
          q1 *= dq1;
        }
        const cplx integral = a * z;
        for (std::size_t p = 0; p < 4; ++p)
          acc[fi][p] += t.c[p] * integral;
        z *= dz;
        pu *= dpu;
        pv *= dpv;
      }
    }
  });
  tbb::parallel_for(std::size_t{0}, nf, [&](std::size_t fi) {
    std::array<cplx, 4> sum{};
    for (std::size_t ci = 0; ci < n_chunks; ++ci) {
      for (std::size_t p = 0; p < 4; ++p)
        sum[p] += partial[ci * nf + fi][p];
    }
    if (one_frequency) {
      for (const std::array<cplx, 4>& b : facet_sums) {
        for (std::size_t p = 0; p < 4; ++p)
          sum[p] += b[p];
      }
    }
    const cplx pre(0.0, -k_of_hz * freqs_hz[fi] / std::sqrt(kPi));  // -j k / sqrt(pi)
    out[fi] = {pre * sum[0], pre * sum[1], pre * sum[2], pre * sum[3]};
    // Edge terms (edges.hpp): c L sinc(k taper) exp(j k phase), summed in order.
    const double k = k_of_hz * freqs_hz[fi];
    std::array<cplx, 4> e{};
    for (const EdgeTerm& t : edge_terms) {
      const cplx a = std::polar(t.length_m * sinc(k * t.taper_m), k * t.phase_m);
      for (std::size_t p = 0; p < 4; ++p)
        e[p] += t.c[p] * a;
    }
    for (const DoubleEdgeTerm& t : double_terms) {
      const cplx a = double_edge_factor(t, k);
      for (std::size_t p = 0; p < 4; ++p)
        e[p] += t.pol[p] * a;
    }
    out[fi].hh += e[0];
    out[fi].hv += e[1];
    out[fi].vh += e[2];
    out[fi].vv += e[3];
  });
}

}  // namespace radar_emu::radar
