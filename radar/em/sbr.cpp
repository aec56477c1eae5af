#include "radar/em/sbr.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "radar/constants.hpp"
#include "radar/em/facet_po.hpp"
#include "scene/mesh/topology.hpp"

#if defined(RADAR_EMU_HAVE_MVEC)
#include <emmintrin.h>
// glibc's libmvec: atan2 on two lanes (atan2_pair below).
extern "C" __m128d _ZGVbN2vv_atan2(__m128d y, __m128d x);
#endif

namespace radar_emu::radar {

namespace {

void require(bool ok, const char* field, const char* what) {
  if (!ok)
    throw std::invalid_argument(std::string("SBR config: ") + field + " " + what);
}

// Vertical polarisation for a wave along `d`: antenna "up" projected perpendicular to d.
inline glm::dvec3 v_pol(const glm::dvec3& up, const glm::dvec3& boresight, const glm::dvec3& d) {
  glm::dvec3 v = up - glm::dot(up, d) * d;
  double n2 = glm::dot(v, v);
  if (n2 < 1e-18) {  // looking along "up" (|v| < 1e-9): fall back to the boresight's projection
    v = boresight - glm::dot(boresight, d) * d;
    n2 = glm::dot(v, v);
  }
  return v * (1.0 / std::sqrt(n2));
}

// The antenna's polarisation vector of channel `h` (H: true, V: false) for a wave along `d`
// (from the radar): V as above, H = V x d (SbrConfig::polarisation), a unit vector to rounding
// as it is (V is a unit vector perpendicular to the unit d).
inline glm::dvec3 pol_vector(bool h, const glm::dvec3& up, const glm::dvec3& boresight,
                             const glm::dvec3& d) {
  const glm::dvec3 v = v_pol(up, boresight, d);
  return h ? glm::cross(v, d) : v;
}

// pol_vector(h, up, boresight, d) for a return arriving along d (from the radar, world), given
// d in the antenna frame, `a` (x boresight, y right, z down), and h = sqrt(a_x^2 + a_y^2), the
// cosine of its elevation. There V = unit(up_a - (up_a . a) a) with up_a = (0, 0, -1) is
// (a_z a_x, a_z a_y, a_z^2 - 1) / |.| = (a_z a_x / h, a_z a_y / h, -h) for a unit a (a_z^2 - 1 =
// -h^2, |.| = h): the antenna's up rotated toward d by the elevation, free of the cancellation of
// up - (up . d) d near the vertical and of its square root. Within 1e-8 of the vertical (h <
// 1e-8) it is pol_vector itself, which falls back on the boresight where V is undefined.
inline glm::dvec3 receive_pol(bool h, const glm::dmat3& world_from_antenna, const glm::dvec3& up,
                              const glm::dvec3& boresight, const glm::dvec3& d, const glm::dvec3& a,
                              double cos_el) {
  if (!(cos_el >= 1e-8))
    return pol_vector(h, up, boresight, d);
  const double inv = 1.0 / cos_el;
  const glm::dvec3 v = world_from_antenna * glm::dvec3(a.z * a.x * inv, a.z * a.y * inv, -cos_el);
  return h ? glm::cross(v, d) : v;
}

// The product of two finite complex numbers: the real products and sums that std::complex's
// multiplication forms, without its NaN recovery (libgcc's __muldc3).
inline std::complex<double> times(std::complex<double> x, std::complex<double> y) noexcept {
  return {x.real() * y.real() - x.imag() * y.imag(), x.real() * y.imag() + x.imag() * y.real()};
}

// std::polar(1.0, phase_rad), by sin_cos (sbr_core.hpp).
inline std::complex<double> unit_phasor(double phase_rad) noexcept {
  const SinCos sc = sin_cos(phase_rad);
  return {sc.cos, sc.sin};
}

// atan2(y0, x0) and atan2(y1, x1) together: with glibc's vector math library (libmvec, glibc
// >= 2.35) its two-lane atan2, by its name in the x86-64 vector function ABI (SSE2 variant:
// `b`, 2 lanes, two vector arguments; glibc's manual, "Known Maximum Errors in Math Functions":
// within 4 ulp); else two calls.
inline AzEl atan2_pair(double y0, double x0, double y1, double x1) noexcept {
#if defined(RADAR_EMU_HAVE_MVEC)
  const __m128d r = _ZGVbN2vv_atan2(_mm_set_pd(y1, y0), _mm_set_pd(x1, x0));
  return {_mm_cvtsd_f64(r), _mm_cvtsd_f64(_mm_unpackhi_pd(r, r))};
#else
  return {std::atan2(y0, x0), std::atan2(y1, x1)};
#endif
}

#if defined(RADAR_EMU_HAVE_MVEC)
// Two doubles in the lanes of an SSE2 register, with double's arithmetic lane by lane (each an
// IEEE operation, so each lane gets what the same expression in double gives): for evaluating
// two kept paths at once with the scalar code's operations in the scalar code's order.
struct D2 {
  __m128d v;
};
inline D2 d2(double x) noexcept {
  return {_mm_set1_pd(x)};
}
inline D2 d2(double lane0, double lane1) noexcept {
  return {_mm_set_pd(lane1, lane0)};
}
inline D2 operator+(D2 a, D2 b) noexcept {
  return {_mm_add_pd(a.v, b.v)};
}
inline D2 operator-(D2 a, D2 b) noexcept {
  return {_mm_sub_pd(a.v, b.v)};
}
inline D2 operator*(D2 a, D2 b) noexcept {
  return {_mm_mul_pd(a.v, b.v)};
}
inline D2 operator/(D2 a, D2 b) noexcept {
  return {_mm_div_pd(a.v, b.v)};
}
inline D2 operator+(D2 a, double b) noexcept {
  return a + d2(b);
}
inline D2 operator+(double a, D2 b) noexcept {
  return d2(a) + b;
}
inline D2 operator-(D2 a, double b) noexcept {
  return a - d2(b);
}
inline D2 operator-(double a, D2 b) noexcept {
  return d2(a) - b;
}
inline D2 operator*(D2 a, double b) noexcept {
  return a * d2(b);
}
inline D2 operator*(double a, D2 b) noexcept {
  return d2(a) * b;
}
inline D2 operator-(D2 a) noexcept {  // the sign flipped, as double's unary minus
  return {_mm_xor_pd(a.v, _mm_set1_pd(-0.0))};
}
inline D2 sqrt(D2 a) noexcept {
  return {_mm_sqrt_pd(a.v)};
}
inline double lane0(D2 a) noexcept {
  return _mm_cvtsd_f64(a.v);
}
inline double lane1(D2 a) noexcept {
  return _mm_cvtsd_f64(_mm_unpackhi_pd(a.v, a.v));
}
#endif

// azel_from_direction for a return's direction of arrival (an output, no decision rests on
// it): sqrt(x^2 + y^2) for hypot(x, y), whose overflow guard a unit vector does not need; both
// angles from one atan2_pair.
inline AzEl arrival_azel(const glm::dvec3& d, double horizontal) noexcept {
  return atan2_pair(d.y, d.x, -d.z, horizontal);
}
inline AzEl arrival_azel(const glm::dvec3& d) noexcept {
  return arrival_azel(d, std::sqrt(d.x * d.x + d.y * d.y));
}

}  // namespace

AzEl azel_from_direction(const glm::dvec3& d) noexcept {
  return {std::atan2(d.y, d.x), std::atan2(-d.z, std::hypot(d.x, d.y))};
}

glm::dvec3 direction_from_azel(const AzEl& a) noexcept {
  const double ce = std::cos(a.elevation_rad);
  return {ce * std::cos(a.azimuth_rad), ce * std::sin(a.azimuth_rad), -std::sin(a.elevation_rad)};
}

namespace {
// The column table (SbrTracer::column_cos_): columns held per target, and a bundle without any.
constexpr std::size_t kColumnsPerTarget = 4096;
constexpr std::size_t kNoColumns = static_cast<std::size_t>(-1);
// A target without a region of kept paths (SbrTracer::kept_region_).
constexpr std::size_t kNoRegion = static_cast<std::size_t>(-1);
}  // namespace

SbrTracer::SbrTracer(const scene::Scene& scene, const SbrConfig& config)
    : scene_(&scene), config_(config) {
  const SbrConfig& c = config;
  require(std::isfinite(c.carrier_hz) && c.carrier_hz > 0, "carrier_hz", "must be > 0");
  require(c.azimuth_min_rad < c.azimuth_max_rad && c.azimuth_min_rad > -kPi / 2 &&
              c.azimuth_max_rad < kPi / 2,
          "azimuth_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  require(c.elevation_min_rad < c.elevation_max_rad && c.elevation_min_rad > -kPi / 2 &&
              c.elevation_max_rad < kPi / 2,
          "elevation_min/max_rad", "must satisfy -pi/2 < min < max < pi/2");
  fov_tan_ = {std::tan(c.azimuth_min_rad), std::tan(c.azimuth_max_rad),
              std::tan(c.elevation_min_rad), std::tan(c.elevation_max_rad)};
  require(c.terrain_ray_spacing_rad > 0, "terrain_ray_spacing_rad", "must be > 0");
  require(c.target_ray_spacing_m > 0, "target_ray_spacing_m", "must be > 0");
  require(c.max_rays_per_target >= 1, "max_rays_per_target", "must be >= 1");
  require(c.max_range_m > 0, "max_range_m", "must be > 0");
  require(c.max_bounces >= 1 && c.max_bounces <= 16, "max_bounces", "must be in 1..16");
  n_az_ = static_cast<std::size_t>(
      std::ceil((c.azimuth_max_rad - c.azimuth_min_rad) / c.terrain_ray_spacing_rad - 1e-9));
  n_el_ = static_cast<std::size_t>(
      std::ceil((c.elevation_max_rad - c.elevation_min_rad) / c.terrain_ray_spacing_rad - 1e-9));
  require(n_az_ * n_el_ <= 50'000'000, "terrain_ray_spacing_rad", "gives more than 5e7 rays");

  // Each scene material at the carrier, once: specular model, sigma0 row, conductor flag.
  surfaces_ = resolve_surfaces(scene.materials(), {c.carrier_hz, c.polarisation, {}});

  const auto& desc = scene.description();
  is_target_.assign(desc.objects.size(), 0);
  bundled_.assign(desc.objects.size(), 0);
  for (std::size_t i = 0; i < desc.objects.size(); ++i) {
    for (std::uint16_t m : desc.objects[i].mesh.triangle_material) {
      if (surfaces_.surfaces[m].conductor) {
        is_target_[i] = 1;
        break;
      }
    }
    n_targets_ += is_target_[i];
  }
  bundles_.reserve(n_targets_);
  unbundled_in_range_.reserve(n_targets_);
  counts_.assign(n_az_ * n_el_ + n_targets_ * c.max_rays_per_target, 0);
  facet_first_.assign(desc.objects.size() + 1, 0);
  for (std::size_t i = 0; i < desc.objects.size(); ++i) {
    facet_first_[i + 1] =
        facet_first_[i] + (is_target_[i] ? desc.objects[i].mesh.triangles.size() : 0);
  }
  // Each target's triangles (body frame, in double) and their one topology (scene/mesh/
  // topology.hpp), built from the triangles as a soup: its edges then come in the order the
  // triangles first reach their vertices. Closed parts and edges both come from it.
  std::vector<std::vector<std::array<glm::dvec3, 3>>> target_tris(desc.objects.size());
  std::vector<scene::MeshTopology> topology(desc.objects.size());
  facet_outward_.assign(facet_first_.back(), 0);
  for (std::size_t i = 0; i < desc.objects.size(); ++i) {
    if (!is_target_[i])
      continue;
    const scene::Mesh& mesh = desc.objects[i].mesh;
    std::vector<std::array<glm::dvec3, 3>>& tris = target_tris[i];
    tris.resize(mesh.triangles.size());
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const glm::uvec3 tri = mesh.triangles[t];
      tris[t] = {glm::dvec3(mesh.positions_m[tri.x]), glm::dvec3(mesh.positions_m[tri.y]),
                 glm::dvec3(mesh.positions_m[tri.z])};
    }
    topology[i] = scene::build_topology(tris);
    const std::vector<std::int8_t> closed = scene::closed_part_winding(topology[i]);
    std::copy(closed.begin(), closed.end(),
              facet_outward_.begin() + static_cast<std::ptrdiff_t>(facet_first_[i]));
  }
  edge_first_.assign(desc.objects.size() + 1, 0);
  pair_first_.assign(desc.objects.size() + 1, 0);
  require(c.edge_order == 1 || c.edge_order == 2, "edge_order", "must be 1 or 2");
  if (c.edges) {
    require(std::isfinite(c.edge_min_turn_rad) && c.edge_min_turn_rad >= 0.0 &&
                c.edge_min_turn_rad < kPi,
            "edge_min_turn_rad", "must be in [0, pi)");
    for (std::size_t i = 0; i < desc.objects.size(); ++i) {
      edge_first_[i + 1] = edge_first_[i];
      pair_first_[i + 1] = pair_first_[i];
      if (!is_target_[i])
        continue;
      const scene::Mesh& mesh = desc.objects[i].mesh;
      const std::size_t nt = mesh.triangles.size();
      const std::vector<std::array<glm::dvec3, 3>>& tris = target_tris[i];
      std::vector<std::uint8_t> pec(nt);
      for (std::size_t t = 0; t < nt; ++t) {
        const std::uint16_t m = mesh.triangle_material[t];
        pec[t] = surfaces_.surfaces[m].specular.kind == SurfaceModel::Kind::kPec ? 1 : 0;
      }
      EdgeCensus census;
      const std::vector<WedgeEdge> found = find_wedge_edges(
          tris, topology[i],
          std::span<const std::int8_t>(facet_outward_).subspan(facet_first_[i], nt), pec,
          c.edge_min_turn_rad, census);
      edges_body_.insert(edges_body_.end(), found.begin(), found.end());
      edge_first_[i + 1] = edges_body_.size();
      if (c.edge_order < 2)
        continue;
      // Pairs in the body frame (a rigid placement keeps them); indices made global.
      double extent_m = 0.0;
      for (const auto& t : tris)
        extent_m = std::max({extent_m, glm::length(t[0]), glm::length(t[1]), glm::length(t[2])});
      for (EdgePair p : find_edge_pairs(found, tris, 1e-5 * extent_m)) {
        p.from += static_cast<std::uint32_t>(edge_first_[i]);
        p.to += static_cast<std::uint32_t>(edge_first_[i]);
        pairs_.push_back(p);
      }
      pair_first_[i + 1] = pairs_.size();
    }
  }
  pair_used_.assign(pairs_.size(), 0);
  pair_out_.assign(pairs_.size(), Contribution{});
  edge_state_.assign(edges_body_.size(), 2);
  edge_out_.assign(edges_body_.size(), Contribution{});
  facet_light_.assign(facet_first_.back(), kLightByRays);
  facet_out_.assign(facet_first_.back(), Contribution{});
  frame_world_from_body_.assign(desc.objects.size(), glm::dmat4(1.0));
  frame_box_.assign(desc.objects.size(), scene::PaddedBox{});
  // Columns: the terrain grid's (knobs only coarsen it) and up to kColumnsPerTarget per target
  // (a wider bundle takes its cos and sin per ray).
  column_cos_.assign(n_az_ + n_targets_ * std::min(kColumnsPerTarget, c.max_rays_per_target), 0.0);
  column_sin_.assign(column_cos_.size(), 0.0);
  plan_bundles_.reserve(n_targets_);
  // Masks (SbrConfig::mask_target_rays): rows of the bundles of a frame, up to 1024 a target on
  // average; a bundle past the capacity shoots its whole box.
  if (c.mask_target_rays)
    row_spans_.assign(n_targets_ * 1025, RowSpan{});
  // Each target's facets in up to kMaskParts parts (SbrConfig::mask_target_rays): split at the
  // median of their centroids along the longest side, recursively; each part's box holds its
  // facets' corners.
  part_first_.assign(desc.objects.size() + 1, 0);
  ground_planes_.assign(desc.objects.size(), GroundPlanes{});
  for (std::uint32_t i = 0; i < desc.objects.size(); ++i) {
    if (c.mask_target_rays && is_target_[i])
      split_parts(desc.objects[i].mesh);
    part_first_[i + 1] = part_boxes_.size();
  }
  // Static path reuse: a region of kept paths per target that does not move.
  kept_.assign(desc.objects.size(), Kept{});
  kept_region_.assign(desc.objects.size(), kNoRegion);
  met_mover_ = std::make_unique<std::atomic<std::uint8_t>[]>(desc.objects.size());
  for (std::uint32_t i = 0; i < desc.objects.size(); ++i) {
    if (scene.objects()[i].moving)
      movers_.push_back(i);
  }
  if (c.reuse_static_paths) {
    require(std::isfinite(c.reuse_max_phase_rad) && c.reuse_max_phase_rad > 0.0,
            "reuse_max_phase_rad", "must be > 0");
    require(c.reuse_refresh_frames >= 1, "reuse_refresh_frames", "must be >= 1");
    require(c.reuse_refresh_slices >= 1 && c.reuse_refresh_slices <= SbrConfig::kMaxKeptSlices,
            "reuse_refresh_slices", "must be 1..8");
    // A region per slice, each with a slot per ray and bounce (the rays of a slice write their
    // paths at their slots, then the slice's are compacted to its front); pages touched as used.
    const std::size_t per_target = c.max_rays_per_target * static_cast<std::size_t>(c.max_bounces);
    std::size_t n_slots = 0;
    for (std::uint32_t i = 0; i < desc.objects.size(); ++i) {
      if (is_target_[i] && !scene.objects()[i].moving) {
        kept_region_[i] = n_slots;
        n_slots += per_target * static_cast<std::size_t>(c.reuse_refresh_slices);
      }
    }
    kept_runs_.reserve(n_targets_ * static_cast<std::size_t>(c.reuse_refresh_slices));
    static_assert(std::is_trivially_default_constructible_v<KeptPath>);
    kept_paths_ = std::make_unique_for_overwrite<KeptPath[]>(n_slots);
    kept_facet_by_rays_.assign(facet_first_.back(), 0);
    static_assert(FacetMemo::kBits >=
                  kFacetSamples + kMaxFacetSubdivisions * kMaxFacetSubdivisions);
    facet_memo_.assign(facet_first_.back(), FacetMemo{});
    facet_self_memo_.assign(facet_first_.back(), 0);
    memo_state_.assign(desc.objects.size(), MemoState{});
    // Movers' facets keep their answers too, in groups asked again in turn (mover_memo_).
    memo_groups_ = std::min(static_cast<std::size_t>(c.reuse_refresh_frames), kMaxMemoGroups);
    mover_memo_first_.assign(desc.objects.size(), kNoRegion);
    std::size_t n_states = 0;
    for (const std::uint32_t m : movers_) {
      if (is_target_[m]) {
        mover_memo_first_[m] = n_states;
        n_states += memo_groups_;
      }
    }
    mover_memo_.assign(n_states, MemoState{});
  }
}

bool SbrTracer::intersect(const scene::Ray& ray, scene::Hit& hit) const noexcept {
  if (query_log_ != nullptr) {
    const std::size_t i = query_log_->n_intersects.fetch_add(1, std::memory_order_relaxed);
    if (i < query_log_->intersects.size())
      query_log_->intersects[i] = ray;
  }
  return scene_->intersect(ray, hit);
}

void SbrTracer::intersect(std::span<const scene::Ray> rays, std::span<scene::Hit> hits,
                          std::span<std::uint8_t> found) const noexcept {
  if (query_log_ != nullptr) {
    for (const scene::Ray& ray : rays) {
      const std::size_t i = query_log_->n_intersects.fetch_add(1, std::memory_order_relaxed);
      if (i < query_log_->intersects.size())
        query_log_->intersects[i] = ray;
    }
  }
  // One query per ray, not the scene's stream (rtcIntersect1M): Embree's stream intersectors
  // group the rays into packets whose triangle tests round differently at edges from the single
  // ray's, so a ray's hit would depend on its neighbours in the batch, and the batches on the
  // threads' partition of the frame (a 0.5 m trihedral at 1 km in the EV image came out 1-3 dB
  // low and different from run to run).
  for (std::size_t i = 0; i < rays.size() && i < hits.size() && i < found.size(); ++i)
    found[i] = scene_->intersect(rays[i], hits[i]) ? 1 : 0;
}

void SbrTracer::log_occlusions(std::span<const scene::Ray> rays) const noexcept {
  if (query_log_ == nullptr)
    return;
  for (const scene::Ray& ray : rays) {
    const std::size_t i = query_log_->n_occlusions.fetch_add(1, std::memory_order_relaxed);
    if (i < query_log_->occlusions.size())
      query_log_->occlusions[i] = ray;
  }
}

void SbrTracer::occluded(std::span<const scene::Ray> rays,
                         std::span<std::uint8_t> blocked) const noexcept {
  log_occlusions(rays);
  // One query per ray, as intersect() above.
  for (std::size_t i = 0; i < rays.size() && i < blocked.size(); ++i)
    blocked[i] = scene_->occluded(rays[i]) ? 1 : 0;
}

void SbrTracer::occluded_coherent(std::span<const scene::Ray> rays,
                                  std::span<std::uint8_t> blocked) const noexcept {
  log_occlusions(rays);
  scene_->occluded(rays, blocked);
}

void SbrTracer::occluded_split(std::span<const scene::Ray> rays,
                               std::span<const std::uint32_t> mover, scene::MoverSplit split,
                               std::span<std::uint8_t> blocked) const noexcept {
  // The query log holds whole queries: a ray asked split is logged with its rest of the scene
  // (kRest), the part that a raw query of the same ray would traverse the most of.
  if (split == scene::MoverSplit::kRest)
    log_occlusions(rays);
  scene_->occluded(rays, mover, split, blocked);
}

bool SbrTracer::occluded(const scene::Ray& ray) const noexcept {
  log_occlusions(std::span<const scene::Ray>(&ray, 1));
  return scene_->occluded(ray);
}

std::size_t SbrTracer::max_contributions() const noexcept {
  return counts_.size() * static_cast<std::size_t>(config_.max_bounces) + facet_out_.size() +
         edge_out_.size() + pair_out_.size();
}

namespace {
// How far a ray leaving a surface at `p` starts off it, along the lit normal [m]: about ten float
// ulps of the coordinates (traversal is float), so the ray cannot meet the surface it leaves
// however grazing; small enough (1 um near the origin, 2 mm at 2 km) that the lifted ray
// misses no edge that the unlifted one meets (onto_ray puts its hit back on the unlifted ray).
double surface_offset_m(const glm::dvec3& p) noexcept {
  return 1e-6 * (1.0 + glm::length(p));
}

// The occlusion query of a bounce-1 sample at `p`: the segment from p to the radar at
// `radar_m` (facet_sample_rays, facet_finish: the same ray either way).
scene::Ray ray_toward(const glm::dvec3& p, const glm::dvec3& radar_m) noexcept {
  scene::Ray ray;
  const glm::dvec3 to = radar_m - p;
  ray.t_far_m = glm::length(to);
  ray.origin_m = p;
  ray.direction = to / ray.t_far_m;
  ray.t_near_m = 0.0;
  return ray;
}

// facet_batch: a facet decided without a query.
constexpr std::size_t kNoSlot = std::numeric_limits<std::size_t>::max();
// facet_batch's answer of a sample that the mover's own body blocked when recorded (its self
// memo), not asked this frame: blocked (non-zero), and no query counted (facet_finish).
constexpr std::uint8_t kAnswerKnown = 2;

// Whether a direction `a` from the radar (antenna frame, unit) is inside the field of view:
// ahead of the antenna (a.x > 0) and within its azimuth and elevation limits, by their tangents
// (`fov_tan`: az min, az max, el min, el max; the limits are within +-pi/2, where tan is
// increasing): az = atan2(a.y, a.x) in [lo, hi] iff a.x tan lo <= a.y <= a.x tan hi, and
// el = atan2(-a.z, h) likewise with h = |(a.x, a.y)|. No atan2: the angles are needed only for
// what radiates.
bool in_field_of_view(const std::array<double, 4>& fov_tan, const glm::dvec3& a) noexcept {
  if (!(a.x > 0.0) || a.y < a.x * fov_tan[0] || a.y > a.x * fov_tan[1])
    return false;
  const double h = std::sqrt(a.x * a.x + a.y * a.y);
  return -a.z >= h * fov_tan[2] && -a.z <= h * fov_tan[3];
}

// The bundled targets' items of one kind (facets, edges or edge pairs: object id's are
// object_first[id] .. object_first[id + 1]) laid end to end for one parallel loop: sets each
// bundle's start in that run (member `first`) and returns the run's length.
template <typename B>
std::size_t lay_out_run(std::vector<B>& bundles, std::size_t B::*first,
                        const std::vector<std::size_t>& object_first) noexcept {
  std::size_t n = 0;
  for (B& bd : bundles) {
    bd.*first = n;
    n += object_first[bd.object_id + 1] - object_first[bd.object_id];
  }
  return n;
}

// Item i of such a run: moves `b` (a chunk's cursor, walking i upward from 0) to its bundle and
// returns the item's index within its object.
template <typename B>
std::size_t run_item(const std::vector<B>& bundles, std::size_t B::*first, std::size_t i,
                     std::size_t& b) noexcept {
  while (b + 1 < bundles.size() && i >= bundles[b + 1].*first)
    ++b;
  return i - bundles[b].*first;
}

// A bounce-1 return of target `id` (a facet's or an edge's): coherent, radiated by its owner.
Contribution bounce1_return(std::complex<double> amplitude, double range_m,
                            double radial_velocity_mps, const AzEl& ae, std::uint32_t id) noexcept {
  Contribution out;
  out.amplitude = amplitude;
  out.range_m = range_m;
  out.range_spread_m = 0.0;
  out.radial_velocity_mps = radial_velocity_mps;
  out.azimuth_rad = ae.azimuth_rad;
  out.elevation_rad = ae.elevation_rad;
  out.object_id = id;
  out.radiated_by_owner = true;
  out.bounces = 1;
  out.coherent = true;
  return out;
}
}  // namespace

std::uint8_t SbrTracer::facet_geometry(const RadarPose& pose, std::uint32_t id, std::size_t t,
                                       double resolution_m, FacetGeometry& g) const noexcept {
  const SbrConfig& c = config_;
  const scene::Mesh& mesh = scene_->description().objects[id].mesh;
  const glm::uvec3 tri = mesh.triangles[t];
  const auto dark = static_cast<std::uint8_t>(FacetLight::kDark);
  const glm::dmat4& xf = frame_world_from_body_[id];
  auto world = [&](unsigned i) { return glm::dvec3(xf * glm::dvec4(mesh.positions_m[i], 1.0)); };
  const glm::dvec3 v0 = world(tri.x), v1 = world(tri.y), v2 = world(tri.z);
  const glm::dvec3 nn = glm::cross(v1 - v0, v2 - v0);
  const double twice_area = glm::length(nn);
  const double longest =
      std::max({glm::length(v1 - v0), glm::length(v2 - v1), glm::length(v0 - v2)});
  if (!(twice_area > 1e-12 * longest * longest))
    return dark;  // degenerate: rays do not meet it
  const glm::dvec3 centroid = (v0 + v1 + v2) / 3.0;
  const glm::dvec3 to_radar = pose.position_m - centroid;
  const double range_m = glm::length(to_radar);
  const glm::dvec3 s = to_radar / range_m, d = -s;
  glm::dvec3 n = nn / twice_area;
  double cos_i = glm::dot(n, s);
  // The inside of a closed part is never lit (sbr_core.hpp, closed parts); a mirroring
  // placement turns the winding over.
  const int outward =
      facet_outward_[facet_first_[id] + t] * (glm::determinant(glm::dmat3(xf)) < 0.0 ? -1 : 1);
  if (outward != 0 && outward * cos_i <= 0.0)
    return dark;
  if (cos_i < 0.0) {  // two-sided: the face the wave meets
    n = -n;
    cos_i = -cos_i;
  }
  if (cos_i <= kEdgeOnCos)
    return dark;
  const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  const glm::dvec3 arrival = antenna_from_world * d;
  // Outside the view or the range, or too near for a plane wave over it: the rays sample it.
  const double rho_m = std::max(
      {glm::length(v0 - centroid), glm::length(v1 - centroid), glm::length(v2 - centroid)});
  const bool in_view = in_field_of_view(fov_tan_, arrival);
  if (!in_view || range_m > c.max_range_m || !facet_in_far_field(rho_m, range_m, k))
    return kLightByRays;
  g.v0_m = v0;
  g.v1_m = v1;
  g.v2_m = v2;
  g.centroid_m = centroid;
  g.n = n;
  g.s = s;
  g.arrival = arrival;
  g.range_m = range_m;
  g.cos_i = cos_i;
  g.offset_m = surface_offset_m(centroid);
  g.m = facet_subdivisions(longest, resolution_m);
  g.id = id;
  g.material = mesh.triangle_material[t];
  return kFacetNeedsLight;
}

std::size_t SbrTracer::facet_sample_rays(const RadarPose& pose, const FacetGeometry& g,
                                         bool centroid_only, std::size_t replayed,
                                         std::span<scene::Ray> rays) const noexcept {
  // facet_finish's first queries, in its order.
  if (centroid_only || g.m == 1) {
    if (replayed < 1)
      rays[0] = ray_toward(g.centroid_m + g.offset_m * g.n, pose.position_m);
    return 1;
  }
  if (replayed >= kFacetSamples)
    return kFacetSamples;  // every sample's answer read back: no ray to make
  const std::array<glm::dvec3, kFacetSamples> samples =
      facet_samples(g.v0_m, g.v1_m, g.v2_m, g.n, g.offset_m);
  for (std::size_t q = replayed; q < kFacetSamples; ++q)
    rays[q - replayed] = ray_toward(samples[q], pose.position_m);
  return kFacetSamples;
}

std::uint8_t SbrTracer::facet_finish(const RadarPose& pose, const FacetGeometry& g,
                                     bool centroid_only, Contribution& out, std::uint64_t& queries,
                                     FacetMemo* record, const FacetMemo* replay,
                                     std::span<const std::uint8_t> answered,
                                     std::size_t first_answered) const noexcept {
  const SbrConfig& c = config_;
  const auto dark = static_cast<std::uint8_t>(FacetLight::kDark);
  const glm::dvec3 v0 = g.v0_m, v1 = g.v1_m, v2 = g.v2_m, centroid = g.centroid_m, n = g.n, s = g.s,
                   d = -g.s;
  const double offset_m = g.offset_m;
  const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
  std::size_t asked = 0;  // this facet's queries so far (FacetMemo: answers in this order)
  auto blocked = [&](const glm::dvec3& p) {
    const std::size_t q = asked++;
    if (replay != nullptr && q < replay->count)
      return ((replay->blocked[q / 64] >> (q % 64)) & 1u) != 0;
    // Query q's answer asked beforehand (facet_batch; kAnswerKnown: blocked by the mover's own
    // body as recorded, not asked), or asked now.
    bool answer = false;
    if (q >= first_answered && q - first_answered < answered.size()) {
      const std::uint8_t a = answered[q - first_answered];
      queries += a == kAnswerKnown ? 0u : 1u;
      answer = a != 0;
    } else {
      ++queries;
      answer = occluded(ray_toward(p, pose.position_m));
    }
    if (record != nullptr && q < FacetMemo::kBits) {
      record->blocked[q / 64] |= static_cast<std::uint64_t>(answer ? 1 : 0) << (q % 64);
      record->count = static_cast<std::uint16_t>(q + 1);
    }
    return answer;
  };
  // TraceKnobs::facet_centroid_only: the centroid's sample alone decides, lit or dark whole. So
  // it does for a facet no longer than the spacing: the rule (facet_light) would cut it, were it
  // partly lit, into m = 1 sub-triangle, the facet itself, lit by its centroid's sample, which
  // is the first of its seven; all seven clear or all blocked, the centroid's says the same. The
  // other six samples could not change the outcome, so they are not asked. (facet_sample_rays
  // makes the same choice.)
  const int m = g.m;
  const FacetLight light =
      centroid_only || m == 1
          ? (blocked(centroid + offset_m * n) ? FacetLight::kDark : FacetLight::kLit)
          : facet_light(facet_samples(v0, v1, v2, n, offset_m), blocked);
  if (light == FacetLight::kDark)
    return dark;
  // The answers asked beforehand were the samples' (facet_light may have stopped before the
  // last): none is a sub-triangle's.
  answered = {};
  // The exact PO integral (facet_po.hpp) over the facet, or over its lit sub-triangles, in the
  // local plane wave of the centroid direction, phase referred to the centroid:
  // integral exp(j k (s - d).(r' - c)) dS' times exp(-j k 2 R) of the centroid's two-way path
  // (sbr_core.hpp's footprint integral, over whole triangles).
  const glm::dvec3 gk = k * (s - d);
  std::complex<double> integral{0.0, 0.0};
  if (light == FacetLight::kLit) {
    integral = triangle_phase_integral(v0 - centroid, v1 - centroid, v2 - centroid, gk);
  } else {
    // A partly lit facet asks every one of its m^2 sub-triangles' samples
    // (for_each_lit_subtriangle), queries asked .. asked + m^2 - 1: those a replay memo does not
    // hold go as one coherent batch, consumed by `blocked` in the same order.
    std::array<scene::Ray, kMaxFacetSubdivisions * kMaxFacetSubdivisions> sub_rays;
    std::array<std::uint8_t, kMaxFacetSubdivisions * kMaxFacetSubdivisions> sub_answers;
    std::size_t q = asked, n_sub = 0;
    first_answered = std::max<std::size_t>(asked, replay != nullptr ? replay->count : 0);
    for_each_subtriangle(
        v0, v1, v2, m, [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& e) {
          if (q++ >= first_answered) {
            sub_rays[n_sub++] =
                ray_toward(subtriangle_sample(a, b, e, n, offset_m), pose.position_m);
          }
        });
    occluded_coherent(std::span<const scene::Ray>(sub_rays.data(), n_sub),
                      std::span<std::uint8_t>(sub_answers.data(), n_sub));
    answered = std::span<const std::uint8_t>(sub_answers.data(), n_sub);
    (void)for_each_lit_subtriangle(
        v0, v1, v2, n, offset_m, m, blocked,
        [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& e) {
          integral += triangle_phase_integral(a - centroid, b - centroid, e - centroid, gk);
        });
    if (integral == std::complex<double>(0.0, 0.0))
      return dark;  // no lit sub-triangle
  }
  const SurfaceModel& sm = surfaces_.surfaces[g.material].specular;
  const bool pec = sm.kind == SurfaceModel::Kind::kPec;
  const ReflectionCoefficients rc = reflection_coefficients(sm, g.cos_i, k);
  const glm::dvec3 boresight = pose.world_from_antenna[0], up = -pose.world_from_antenna[2];
  const bool tx_h = c.polarisation == Polarisation::kHH || c.polarisation == Polarisation::kVH;
  const bool rx_h = c.polarisation == Polarisation::kHH || c.polarisation == Polarisation::kHV;
  const CVec e{pol_vector(tx_h, up, boresight, d), glm::dvec3(0.0)};
  const glm::dvec3 p = pol_vector(rx_h, up, boresight, d);
  const glm::dvec3 v_obj = scene_->objects()[g.id].velocity_mps;
  out = bounce1_return(po_amplitude_m(k, p, po_source(e, d, n, s, rc, pec), 1.0) * integral *
                           std::polar(1.0, -2.0 * k * g.range_m),
                       g.range_m, glm::dot(v_obj - pose.velocity_mps, d), arrival_azel(g.arrival),
                       g.id);
  return static_cast<std::uint8_t>(light);
}

void SbrTracer::facet_batch(const RadarPose& pose, const TraceKnobs& knobs, std::size_t begin,
                            std::size_t end, std::size_t& b, std::uint64_t& queries) noexcept {
  // Per facet of the batch: its geometry, slot, memo pointers and where its up-front answers
  // start in `answers` (count: how many it has there). On the stack: no allocation.
  std::array<FacetGeometry, kFacetBatch> geometry;
  std::array<std::size_t, kFacetBatch> slot;
  std::array<FacetMemo*, kFacetBatch> record;
  std::array<const FacetMemo*, kFacetBatch> replay;
  std::array<std::uint16_t, kFacetBatch> first_ray, ray_count, first_query;
  // A mover's facet (kMemoRolling) whose group records asks its own body and the rest of the
  // scene apart (split_record: its own answers are its self memo); one whose group reads its
  // own shadows back asks only the rest, for the samples its body did not block.
  std::array<std::uint8_t, kFacetBatch> split_record;
  std::array<std::uint8_t, kFacetBatch * kFacetSamples> answers;
  // The rays asked, in facet and sample order: the answer slot each fills, its facet in the
  // batch, and the mover it leaves out (scene::kNoMover: the whole scene).
  std::array<scene::Ray, kFacetBatch * kFacetSamples> rays;
  std::array<std::uint16_t, kFacetBatch * kFacetSamples> ask_slot;
  std::array<std::uint8_t, kFacetBatch * kFacetSamples> ask_facet;
  std::array<std::uint32_t, kFacetBatch * kFacetSamples> ask_mover;
  static_assert(kFacetBatch <= 256, "ask_facet holds a facet's index in a byte");
  std::size_t n_answers = 0, n_ask = 0;
  bool any_split = false;
  for (std::size_t i = begin; i != end; ++i) {
    const std::size_t j = i - begin;
    const std::size_t t = run_item(bundles_, &Bundle::first_facet, i, b);
    const Bundle& bd = bundles_[b];
    slot[j] = facet_first_[bd.object_id] + t;
    record[j] = memo_record(bd, slot[j], t);
    replay[j] = memo_replay(bd, slot[j], t);
    const bool rolling = bd.memo == kMemoRolling;
    split_record[j] = rolling && record[j] != nullptr ? 1 : 0;
    // Its own shadows read back (its group's, recorded with its samples' answers).
    const bool self_replay = rolling && ((bd.memo_self_groups >> (t % memo_groups_)) & 1u) != 0 &&
                             (facet_self_memo_[slot[j]] & kSelfRecorded) != 0;
    if (record[j] != nullptr)
      *record[j] = FacetMemo{};
    if (split_record[j] != 0)
      facet_self_memo_[slot[j]] = 0;
    ray_count[j] = 0;
    first_ray[j] = static_cast<std::uint16_t>(n_answers);
    first_query[j] = 0;
    const std::uint8_t decided = facet_geometry(pose, bd.object_id, t, bd.spacing_m, geometry[j]);
    if (decided != kFacetNeedsLight) {
      facet_light_[slot[j]] = decided;
      slot[j] = kNoSlot;
      continue;
    }
    const std::size_t replayed = replay[j] != nullptr ? replay[j]->count : 0;
    const std::size_t samples =
        facet_sample_rays(pose, geometry[j], knobs.facet_centroid_only, replayed,
                          std::span<scene::Ray>(rays).subspan(n_ask, kFacetSamples));
    if (replayed >= samples)
      continue;
    first_query[j] = static_cast<std::uint16_t>(replayed);
    ray_count[j] = static_cast<std::uint16_t>(samples - replayed);
    const std::uint32_t leave_out =
        split_record[j] != 0 || self_replay ? bd.object_id : scene::kNoMover;
    any_split = any_split || leave_out != scene::kNoMover;
    const std::size_t first_ask = n_ask;
    for (std::size_t q = replayed; q < samples; ++q) {
      const std::size_t a = n_answers + (q - replayed);
      if (self_replay && ((facet_self_memo_[slot[j]] >> q) & 1u) != 0) {
        answers[a] = kAnswerKnown;  // its own body blocked it: nothing else to ask
        continue;
      }
      rays[n_ask] = rays[first_ask + (q - replayed)];  // compacted (n_ask <= that index)
      ask_slot[n_ask] = static_cast<std::uint16_t>(a);
      ask_facet[n_ask] = static_cast<std::uint8_t>(j);
      ask_mover[n_ask++] = leave_out;
    }
    n_answers += samples - replayed;
  }
  std::array<std::uint8_t, kFacetBatch * kFacetSamples> asked;
  if (!any_split) {  // no mover's facet: the whole scene for each (as ever)
    occluded_coherent(std::span<const scene::Ray>(rays.data(), n_ask),
                      std::span<std::uint8_t>(asked.data(), n_ask));
  } else {
    occluded_split(std::span<const scene::Ray>(rays.data(), n_ask),
                   std::span<const std::uint32_t>(ask_mover.data(), n_ask),
                   scene::MoverSplit::kRest, std::span<std::uint8_t>(asked.data(), n_ask));
  }
  for (std::size_t k = 0; k < n_ask; ++k)
    answers[ask_slot[k]] = asked[k];
  if (any_split) {
    // The recording facets' own answers: their rays again, each against its own mover alone.
    std::array<scene::Ray, kFacetBatch * kFacetSamples> own_rays;
    std::array<std::uint32_t, kFacetBatch * kFacetSamples> own_mover;
    std::array<std::uint16_t, kFacetBatch * kFacetSamples> own_ask;  // its index among the asked
    std::array<std::uint8_t, kFacetBatch * kFacetSamples> own;
    std::size_t n_own = 0;
    for (std::size_t k = 0; k < n_ask; ++k) {
      if (split_record[ask_facet[k]] == 0)
        continue;
      own_rays[n_own] = rays[k];
      own_mover[n_own] = ask_mover[k];
      own_ask[n_own++] = static_cast<std::uint16_t>(k);
    }
    occluded_split(std::span<const scene::Ray>(own_rays.data(), n_own),
                   std::span<const std::uint32_t>(own_mover.data(), n_own), scene::MoverSplit::kOwn,
                   std::span<std::uint8_t>(own.data(), n_own));
    for (std::size_t k = 0; k < n_own; ++k) {
      const std::size_t a = ask_slot[own_ask[k]], j = ask_facet[own_ask[k]];
      answers[a] |= own[k];  // the whole scene's answer: its body's or the rest's
      const std::size_t q = std::size_t{first_query[j]} + a - first_ray[j];
      facet_self_memo_[slot[j]] |=
          static_cast<std::uint8_t>(kSelfRecorded | (own[k] != 0 ? 1u << q : 0u));
    }
  }
  for (std::size_t j = 0; j < end - begin; ++j) {
    if (slot[j] == kNoSlot)
      continue;
    facet_light_[slot[j]] = facet_finish(
        pose, geometry[j], knobs.facet_centroid_only, facet_out_[slot[j]], queries, record[j],
        replay[j], std::span<const std::uint8_t>(answers.data() + first_ray[j], ray_count[j]),
        first_query[j]);
  }
}

WedgeEdge SbrTracer::world_edge(std::uint32_t id, std::size_t e) const noexcept {
  const glm::dmat4& xf = frame_world_from_body_[id];
  const glm::dmat3 r(xf);
  const WedgeEdge& body = edges_body_[e];
  WedgeEdge w = body;
  w.a_m = glm::dvec3(xf * glm::dvec4(body.a_m, 1.0));
  w.b_m = glm::dvec3(xf * glm::dvec4(body.b_m, 1.0));
  w.t = r * body.t;
  w.x0 = r * body.x0;
  w.y0 = r * body.y0;
  return w;
}

bool SbrTracer::pair_pass(const RadarPose& pose, std::uint32_t id, std::size_t p,
                          Contribution& out) const noexcept {
  const SbrConfig& c = config_;
  const EdgePair& body = pairs_[p];
  // Both edges radiate this frame: lit, clear to the radar, in view, range and far field.
  if (edge_state_[body.from] != 0 || edge_state_[body.to] != 0)
    return false;
  const std::array<WedgeEdge, 2> w{world_edge(id, body.from), world_edge(id, body.to)};
  EdgePair local = body;
  local.from = 0;
  local.to = 1;
  // The plane wave of the radar at the receiving edge's midpoint (as edge_pass takes it).
  const glm::dvec3 to_radar = pose.position_m - 0.5 * (w[1].a_m + w[1].b_m);
  const double mid_range_m = glm::length(to_radar);
  if (!(mid_range_m > 0.0))
    return false;
  const glm::dvec3 s = to_radar / mid_range_m, d = -s;
  const glm::dvec3 boresight = pose.world_from_antenna[0], up = -pose.world_from_antenna[2];
  const glm::dvec3 h = pol_vector(true, up, boresight, d), v = pol_vector(false, up, boresight, d);
  DoubleEdgeTerm term;
  if (double_edge_term(local, w, d, s, h, v, h, v, term) != EdgeSkip::kNone)
    return false;
  // edges.hpp: pol * factor, with the plane-wave phase (s - d) . centre replaced by the
  // spherical wave's two-way path to the middle of the receiving segment.
  const double range_m = glm::length(pose.position_m - term.centre_m);
  term.phase_m -= glm::dot(s - d, term.centre_m);
  const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
  const std::size_t channel = static_cast<std::size_t>(c.polarisation);  // hh, hv, vh, vv
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  const AzEl ae = azel_from_direction(antenna_from_world * d);
  const glm::dvec3 v_obj = scene_->objects()[id].velocity_mps;
  out = bounce1_return(
      term.pol[channel] * double_edge_factor(term, k) * std::polar(1.0, -2.0 * k * range_m),
      range_m, glm::dot(v_obj - pose.velocity_mps, d), ae, id);
  return true;
}

std::uint8_t SbrTracer::edge_pass(const RadarPose& pose, std::uint32_t id, std::size_t e,
                                  Contribution& out, std::uint64_t& queries) const noexcept {
  const SbrConfig& c = config_;
  constexpr std::uint8_t kUsed = 0, kShadowed = 1, kNoTerm = 2;
  // The edge in the world now (a rigid placement: points by the transform, directions by its
  // rotation).
  const WedgeEdge w = world_edge(id, e);
  const glm::dvec3 centre = 0.5 * (w.a_m + w.b_m);
  const glm::dvec3 to_radar = pose.position_m - centre;
  const double range_m = glm::length(to_radar);
  if (!(range_m > 0.0) || range_m > c.max_range_m)
    return kNoTerm;
  const glm::dvec3 s = to_radar / range_m, d = -s;
  const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  const glm::dvec3 arrival = antenna_from_world * d;
  const bool in_view = in_field_of_view(fov_tan_, arrival);
  // A plane wave along the edge: its own far field, as for a facet (facet_in_far_field).
  if (!in_view || !facet_in_far_field(0.5 * w.length_m, range_m, k))
    return kNoTerm;
  const glm::dvec3 boresight = pose.world_from_antenna[0], up = -pose.world_from_antenna[2];
  // The antenna's H and V along d (SbrConfig::polarisation: S_pq as the RCS engine's).
  const glm::dvec3 h = pol_vector(true, up, boresight, d), v = pol_vector(false, up, boresight, d);
  EdgeTerm term;
  bool guarded = false;
  // The RCS engine's bounds (edges.hpp, edge_term): 1 / sin^2 beta regularised at lambda / L,
  // coefficients limited to the monostatic bound.
  if (edge_term(w, d, s, h, v, h, v, EdgeCoefficient::kFringe, term, guarded,
                std::min(2.0 * kPi / (k * w.length_m), kMaxMinSin2Beta),
                kMonostaticFringeBound) != EdgeSkip::kNone)
    return kNoTerm;
  ++queries;
  scene::Ray ray;
  ray.origin_m = edge_probe(w, 10.0 * surface_offset_m(centre));
  const glm::dvec3 to = pose.position_m - ray.origin_m;
  ray.t_far_m = glm::length(to);
  ray.direction = to / ray.t_far_m;
  ray.t_near_m = 0.0;
  if (occluded(ray))
    return kShadowed;
  // edges.hpp: S = c L sinc(k taper) exp(j k (s - d).centre); here the phase is the spherical
  // wave's two-way path to the midpoint, as a facet's is to its centroid.
  const std::size_t channel = static_cast<std::size_t>(c.polarisation);  // hh, hv, vh, vv
  const glm::dvec3 v_obj = scene_->objects()[id].velocity_mps;
  out = bounce1_return(term.c[channel] * (term.length_m * sinc(k * term.taper_m)) *
                           std::polar(1.0, -2.0 * k * range_m),
                       range_m, glm::dot(v_obj - pose.velocity_mps, d), arrival_azel(arrival), id);
  return kUsed;
}

SbrTracer::Frame SbrTracer::frame_for(const TraceKnobs& knobs, TraceStats* stats) const noexcept {
  const SbrConfig& c = config_;
  Frame f;
  double scale = knobs.terrain_spacing_scale;
  if (!(std::isfinite(scale) && scale >= 1.0)) {
    scale = 1.0;
    if (stats != nullptr)
      ++stats->knob_fallbacks;
  }
  const double spacing = c.terrain_ray_spacing_rad * scale;
  if (scale == 1.0) {
    f.terrain_n_az = n_az_;
    f.terrain_n_el = n_el_;
  } else {
    f.terrain_n_az = std::max<std::size_t>(
        1, static_cast<std::size_t>(
               std::ceil((c.azimuth_max_rad - c.azimuth_min_rad) / spacing - 1e-9)));
    f.terrain_n_el = std::max<std::size_t>(
        1, static_cast<std::size_t>(
               std::ceil((c.elevation_max_rad - c.elevation_min_rad) / spacing - 1e-9)));
  }
  f.terrain_daz_rad = (c.azimuth_max_rad - c.azimuth_min_rad) / static_cast<double>(f.terrain_n_az);
  f.terrain_del_rad =
      (c.elevation_max_rad - c.elevation_min_rad) / static_cast<double>(f.terrain_n_el);
  if (!c.terrain_rays) {  // terrain from the engine: no grid this frame
    f.terrain_n_az = 0;
    f.terrain_n_el = 0;
  }
  f.max_bounces = c.max_bounces;
  if (knobs.max_bounces != 0) {
    if (knobs.max_bounces >= 1 && knobs.max_bounces <= c.max_bounces)
      f.max_bounces = knobs.max_bounces;
    else if (stats != nullptr)
      ++stats->knob_fallbacks;
  }
  return f;
}

double SbrTracer::target_spacing(const TraceKnobs& knobs, std::uint32_t id,
                                 TraceStats* stats) const noexcept {
  if (id >= knobs.target_ray_spacing_m.size())
    return config_.target_ray_spacing_m;
  const double s = knobs.target_ray_spacing_m[id];
  if (s == 0.0)
    return config_.target_ray_spacing_m;
  if (!(std::isfinite(s) && s > 0.0)) {
    if (stats != nullptr)
      ++stats->knob_fallbacks;
    return config_.target_ray_spacing_m;
  }
  return s;
}

bool SbrTracer::bundle_for(const RadarPose& pose, std::uint32_t id, double spacing_m, Bundle& b,
                           bool& coarsened) const noexcept {
  const SbrConfig& c = config_;
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  const scene::ObjectState& o = scene_->objects()[id];
  const glm::dvec3 nearest = glm::clamp(pose.position_m, o.bounds_min_m, o.bounds_max_m);
  const double range = glm::length(nearest - pose.position_m);
  coarsened = false;
  if (range > c.max_range_m || range < 1e-6)
    return false;
  double az_lo = 1e9, az_hi = -1e9, el_lo = 1e9, el_hi = -1e9;
  bool behind = false;
  // The box's corners and, with target_ground_image, those of its mirror image in the horizontal
  // plane of its base: a ray aimed at the image of a target point meets the ground and then that
  // point (image method), so the ground-first double bounces start there.
  const double z_image = 2.0 * o.bounds_min_m.z - o.bounds_max_m.z;
  const int corners = c.target_ground_image ? 12 : 8;
  for (int corner = 0; corner < corners; ++corner) {
    const glm::dvec3 p((corner & 1) ? o.bounds_max_m.x : o.bounds_min_m.x,
                       (corner & 2) ? o.bounds_max_m.y : o.bounds_min_m.y,
                       corner >= 8    ? z_image
                       : (corner & 4) ? o.bounds_max_m.z
                                      : o.bounds_min_m.z);
    const glm::dvec3 a = antenna_from_world * (p - pose.position_m);
    if (a.x <= 0.0)
      behind = true;
    const AzEl ae = azel_from_direction(a);
    az_lo = std::min(az_lo, ae.azimuth_rad);
    az_hi = std::max(az_hi, ae.azimuth_rad);
    el_lo = std::min(el_lo, ae.elevation_rad);
    el_hi = std::max(el_hi, ae.elevation_rad);
  }
  if (behind) {  // straddles the antenna plane: cover the whole field of view
    az_lo = c.azimuth_min_rad;
    az_hi = c.azimuth_max_rad;
    el_lo = c.elevation_min_rad;
    el_hi = c.elevation_max_rad;
  }
  b.clipped = behind || az_lo < c.azimuth_min_rad || az_hi > c.azimuth_max_rad ||
              el_lo < c.elevation_min_rad || el_hi > c.elevation_max_rad;
  b.behind = behind;
  // The share of the box in view along each angle (ViewShare), before the cut.
  const double box_az_rad = az_hi - az_lo, box_el_rad = el_hi - el_lo;
  auto share = [](double lo, double width, double min, double max, double& s0, double& s1) {
    s0 = width > 0.0 ? std::clamp((min - lo) / width, 0.0, 1.0) : 0.0;
    s1 = width > 0.0 ? std::clamp((max - lo) / width, 0.0, 1.0) : 1.0;
  };
  share(az_lo, box_az_rad, c.azimuth_min_rad, c.azimuth_max_rad, b.view.az0, b.view.az1);
  share(el_lo, box_el_rad, c.elevation_min_rad, c.elevation_max_rad, b.view.el0, b.view.el1);
  const double box_el_lo = el_lo;
  az_lo = std::max(az_lo, c.azimuth_min_rad);
  az_hi = std::min(az_hi, c.azimuth_max_rad);
  el_lo = std::max(el_lo, c.elevation_min_rad);
  el_hi = std::min(el_hi, c.elevation_max_rad);
  if (!(az_lo < az_hi) || !(el_lo < el_hi))
    return false;
  double spacing = spacing_m / range;
  auto cells = [&](double span) {
    return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(span / spacing)));
  };
  // Static path reuse: a target whose paths are kept and that the view cuts takes the grid of
  // its whole box (its spacing, under the ray cap, and its rows over the box's whole elevation
  // extent), of which it shoots the rows whose centres are in view and the columns that cover
  // the view. So its rows, hence its slices (choose_reuse), do not move as the cut does.
  const bool whole_box =
      c.reuse_static_paths && kept_region_[id] != kNoRegion && b.clipped && !behind;
  const double grid_az_rad = whole_box ? box_az_rad : az_hi - az_lo;
  const double grid_el_rad = whole_box ? box_el_rad : el_hi - el_lo;
  std::size_t n_az = cells(grid_az_rad), n_el = cells(grid_el_rad);
  if (n_az * n_el > c.max_rays_per_target) {
    coarsened = true;
    spacing *=
        std::sqrt(static_cast<double>(n_az * n_el) / static_cast<double>(c.max_rays_per_target));
    do {
      n_az = cells(grid_az_rad);
      n_el = cells(grid_el_rad);
      spacing *= 1.01;
    } while (n_az * n_el > c.max_rays_per_target);
  }
  // Static path reuse: a target whose paths are kept keeps the rows they were traced with while
  // the grid asks for nearly as many (within kKeptRowsSlack of them, or one row), so that its
  // slices stay a partition of its rows and are traced again one at a time (choose_reuse). Its
  // elevation step then differs from the one its spacing asks for by at most that fraction.
  if (c.reuse_static_paths && kept_region_[id] != kNoRegion) {
    const Kept& kp = kept_[id];
    const std::size_t d = kp.n_el > n_el ? kp.n_el - n_el : n_el - kp.n_el;
    if (kp.valid && kp.spacing_m == spacing_m && d != 0 &&
        (d <= 1 || static_cast<double>(d) <= kKeptRowsSlack * static_cast<double>(kp.n_el))) {
      n_el = kp.n_el;
      n_az = std::min(n_az, std::max<std::size_t>(1, c.max_rays_per_target / n_el));
    }
  }
  b.object_id = id;
  b.n_el_full = n_el;
  b.row_offset = 0;
  if (whole_box) {
    // The box's rows whose centres lie in view, and columns over the view at the box's spacing.
    const double del = box_el_rad / static_cast<double>(n_el);
    const double first = std::ceil((el_lo - box_el_lo) / del - 0.5);
    const double end = std::floor((el_hi - box_el_lo) / del - 0.5) + 1.0;
    const double rows = static_cast<double>(n_el);
    const auto r_lo = static_cast<std::size_t>(std::clamp(first, 0.0, rows));
    const auto r_hi = static_cast<std::size_t>(std::clamp(end, 0.0, rows));
    if (r_lo >= r_hi)
      return false;
    b.row_offset = r_lo;
    b.n_el = r_hi - r_lo;
    b.del_rad = del;
    b.el0_rad = box_el_lo + static_cast<double>(r_lo) * del;
    // The columns at the box grid's own step.
    const double daz = grid_az_rad / static_cast<double>(n_az);
    b.n_az = std::clamp<std::size_t>(
        static_cast<std::size_t>(std::ceil((az_hi - az_lo) / daz - 1e-9)), 1, n_az);
  } else {
    b.n_el = n_el;
    b.del_rad = (el_hi - el_lo) / static_cast<double>(n_el);
    b.el0_rad = el_lo;
    b.n_az = n_az;
  }
  b.trace_whole();
  b.mask = kNoMask;
  b.daz_rad = (az_hi - az_lo) / static_cast<double>(b.n_az);
  b.az0_rad = az_lo;
  b.half_tube_az = box_az_rad > 0.0 ? 0.5 * b.daz_rad / box_az_rad : 0.0;
  b.half_tube_el = box_el_rad > 0.0 ? 0.5 * b.del_rad / box_el_rad : 0.0;
  if (c.mask_target_rays)
    mask_rows(pose, id, b);
  return true;
}

bool SbrTracer::may_reach_owner(const scene::Ray& ray, const Frame& frame, std::uint32_t owner,
                                bool terrain) const noexcept {
  if (!terrain)
    return scene::ray_crosses_box(ray, frame_box_[owner]);
  for (const std::uint32_t id : frame.unbundled_in_range) {
    if (scene::ray_crosses_box(ray, frame_box_[id]))
      return true;
  }
  return false;
}

namespace {
// A static target's box with its ground image (SbrConfig::target_ground_image): where its
// bundle's paths run.
void target_region(const scene::ObjectState& o, bool ground_image, glm::dvec3& lo,
                   glm::dvec3& hi) noexcept {
  lo = o.bounds_min_m;
  hi = o.bounds_max_m;
  if (ground_image)
    lo.z = 2.0 * o.bounds_min_m.z - o.bounds_max_m.z;
}
}  // namespace

bool SbrTracer::mover_near(const RadarPose& pose, std::uint32_t id) const noexcept {
  const auto objects = scene_->objects();
  glm::dvec3 lo, hi;
  target_region(objects[id], config_.target_ground_image, lo, hi);
  const glm::dvec3 centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  scene::Ray sight;  // the target's centre to the radar
  sight.origin_m = centre;
  const glm::dvec3 to = pose.position_m - centre;
  sight.t_far_m = glm::length(to);
  sight.direction = sight.t_far_m > 0.0 ? to / sight.t_far_m : glm::dvec3(0.0, 0.0, 1.0);
  sight.t_near_m = 0.0;
  for (const std::uint32_t m : movers_) {
    if (m == id)
      continue;  // a mover's own motion is the memo's rule (mover_memo_fraction), not this one
    const scene::ObjectState& o = objects[m];
    // Within the target's region, or across the line of sight (the mover's box grown by the
    // region's half extent: any line from the region to the radar).
    if (glm::all(glm::lessThanEqual(o.bounds_min_m, hi)) &&
        glm::all(glm::lessThanEqual(lo, o.bounds_max_m)))
      return true;
    if (scene::ray_crosses_box(sight, o.bounds_min_m - half, o.bounds_max_m + half))
      return true;
  }
  return false;
}

void SbrTracer::choose_reuse(const RadarPose& pose, int max_bounces, std::span<Bundle> bundles,
                             double& credit, bool defer_refresh) const noexcept {
  const SbrConfig& c = config_;
  for (Bundle& b : bundles) {
    b.trace_whole();
    b.keep = false;
    b.still = false;
    b.refreshed = false;
  }
  if (!c.reuse_static_paths)
    return;
  const int n_slices = c.reuse_refresh_slices;
  const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
  const auto objects = scene_->objects();
  std::size_t forced_rays = 0, kept_rays = 0;  // static bundles traced / kept this frame
  for (Bundle& b : bundles) {
    const std::uint32_t id = b.object_id;
    const std::size_t rays = all_rays(b);
    b.still = kept_region_[id] != kNoRegion && !objects[id].moving && !mover_near(pose, id);
    b.keep = b.still && !b.behind;
    if (!b.keep)
      continue;
    const Kept& kp = kept_[id];
    bool reuse = kp.valid && kp.spacing_m == b.spacing_m && kp.max_bounces == max_bounces;
    b.slice_fraction.fill(0.0);
    if (reuse) {
      // The aspect change since each slice was traced, against its limit
      // (SbrConfig::reuse_static_paths), and the antenna's turn (its polarisation basis: the
      // largest change of its axes).
      for (int s = 0; s < n_slices; ++s) {
        const KeptSlice& ks = kp.slices[static_cast<std::size_t>(s)];
        double dtheta = 0.0, limit = 0.0, extent_m = 0.0;
        aspect_change(pose, b, ks.radar_m, dtheta, limit, extent_m);
        limit = std::min(limit, std::sqrt(c.reuse_max_phase_rad / (k * extent_m)));
        double turn = 0.0;
        for (int a = 0; a < 3; ++a)
          turn = std::max(turn, glm::length(pose.world_from_antenna[a] - ks.world_from_antenna[a]));
        b.slice_fraction[static_cast<std::size_t>(s)] = std::max(dtheta, turn) / limit;
      }
      // A target cut by the field of view: its paths cover the part of it that was in view when
      // they were traced. They serve while the part in view now lies within that part, to half
      // a ray tube (a trace samples the view's edge no closer); the paths whose first hit has
      // left the view are then left out (prune_outside_view). A target coming into view is
      // traced.
      for (int s = 0; s < n_slices && reuse; ++s) {
        const ViewShare& then = kp.slices[static_cast<std::size_t>(s)].view;
        reuse = b.view.az0 >= then.az0 - b.half_tube_az &&
                b.view.az1 <= then.az1 + b.half_tube_az &&
                b.view.el0 >= then.el0 - b.half_tube_el && b.view.el1 <= then.el1 + b.half_tube_el;
      }
    }
    // The aspect rule holds per slice: a slice past its limit is traced again. Of a bundle with
    // the rows its slices were kept with (as for the refresh), the slices from the first past
    // it to the last are traced (rows in one run), the others kept; else the whole bundle is.
    int first_over = n_slices, end_over = 0;
    for (int s = 0; s < n_slices && reuse; ++s) {
      if (b.slice_fraction[static_cast<std::size_t>(s)] > 1.0) {
        first_over = std::min(first_over, s);
        end_over = s + 1;
      }
    }
    if (reuse && end_over == 0) {
      b.trace = false;
      b.kept_fraction =
          *std::max_element(b.slice_fraction.begin(), b.slice_fraction.begin() + n_slices);
      kept_rays += rays;
    } else if (reuse && slices_apart(b) && end_over - first_over < n_slices) {
      b.trace_slices(first_over, end_over, n_slices);
      const std::size_t traced = traced_rays(b);
      b.kept_fraction = 0.0;  // of the slices kept
      for (int s = 0; s < n_slices; ++s) {
        if (!b.traces_slice(s))
          b.kept_fraction =
              std::max(b.kept_fraction, b.slice_fraction[static_cast<std::size_t>(s)]);
      }
      kept_rays += rays - traced;
      forced_rays += traced;
    } else {
      forced_rays += rays;
    }
  }
  // The refresh: a credit of 1 / reuse_refresh_frames of the kept rays a frame, less the rays
  // of static bundles traced anyway, pays for tracing again the longest kept bundle (then the
  // lowest id) once it covers its rays, so each is traced about every reuse_refresh_frames.
  // TraceKnobs::defer_refresh: none this frame, and the credit waits as it is; but not past
  // twice the refresh's period (the oldest kept bundle's age), so the paths stay about as fresh
  // as the refresh keeps them.
  if (defer_refresh) {
    std::uint64_t oldest = 0;
    for (const Bundle& b : bundles) {
      if (!b.trace)
        oldest = std::max(oldest, frame_count_ - oldest_kept_at(b.object_id));
    }
    if (oldest < 2 * static_cast<std::uint64_t>(c.reuse_refresh_frames))
      return;
  }
  credit += static_cast<double>(kept_rays) / static_cast<double>(c.reuse_refresh_frames);
  credit = std::max(0.0, credit - static_cast<double>(forced_rays));
  // A slice at a time: the most urgent kept slice, the larger of its age over
  // reuse_refresh_frames and its aspect change over its limit (so that a slice is refreshed
  // before the aspect rule forces it), of a bundle that has the rows its slices were kept with,
  // or the whole of one that has not (SbrConfig::reuse_refresh_slices).
  const auto period = static_cast<double>(c.reuse_refresh_frames);
  for (;;) {
    Bundle* pick = nullptr;
    std::uint8_t pick_slice = kAllSlices;
    double pick_urgency = 0.0;
    for (Bundle& b : bundles) {
      if (b.trace)
        continue;
      const Kept& kp = kept_[b.object_id];
      // Of a target cut by the view, the rows in view (its box's grid: bundle_for).
      const bool by_slice = slices_apart(b);
      for (int s = 0; s < n_slices; ++s) {
        const auto i = static_cast<std::size_t>(s);
        const double urgency =
            std::max(static_cast<double>(frame_count_ - kp.slices[i].traced_at) / period,
                     b.slice_fraction[i]);
        if (pick == nullptr || urgency > pick_urgency) {
          pick = &b;
          pick_slice = by_slice ? static_cast<std::uint8_t>(s) : kAllSlices;
          pick_urgency = urgency;
        }
      }
    }
    if (pick == nullptr)
      break;
    std::size_t lo = 0, hi = pick->n_el;
    if (pick_slice != kAllSlices)
      pick->grid_slice_rows(n_slices, pick_slice, lo, hi);
    const std::size_t rays = rays_in_rows(*pick, lo, hi);
    if (credit < static_cast<double>(rays))
      break;
    if (pick_slice != kAllSlices)
      pick->trace_slices(pick_slice, pick_slice + 1, n_slices);
    else
      pick->trace_whole();
    pick->refreshed = true;
    credit -= static_cast<double>(rays);
  }
}

void SbrTracer::slice_rows(std::size_t n_el, int slices, int s, std::size_t& lo,
                           std::size_t& hi) noexcept {
  // Row ie is in slice floor((2 ie + 1) slices / (2 n_el)); the first row of slice s is the
  // least ie with (2 ie + 1) slices >= 2 s n_el.
  const auto n = static_cast<std::size_t>(slices);
  auto first = [&](std::size_t t) { return (2 * t * n_el + n - 1) / (2 * n); };
  lo = first(static_cast<std::size_t>(s));
  hi = first(static_cast<std::size_t>(s) + 1);
}

void SbrTracer::split_parts(const scene::Mesh& mesh) {
  std::vector<std::uint32_t> tris(mesh.triangles.size());
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    tris[t] = t;
  auto centroid = [&](std::uint32_t t) {
    const glm::uvec3 v = mesh.triangles[t];
    return (glm::dvec3(mesh.positions_m[v[0]]) + glm::dvec3(mesh.positions_m[v[1]]) +
            glm::dvec3(mesh.positions_m[v[2]])) /
           3.0;
  };
  auto split = [&](auto&& self, std::size_t lo, std::size_t hi, std::size_t parts) -> void {
    if (lo == hi)
      return;
    if (parts <= 1 || hi - lo == 1) {
      PartBox box{glm::dvec3(std::numeric_limits<double>::infinity()),
                  glm::dvec3(-std::numeric_limits<double>::infinity())};
      for (std::size_t k = lo; k < hi; ++k) {
        for (int j = 0; j < 3; ++j) {
          const glm::dvec3 p(mesh.positions_m[mesh.triangles[tris[k]][j]]);
          box.lo_m = glm::min(box.lo_m, p);
          box.hi_m = glm::max(box.hi_m, p);
        }
      }
      part_boxes_.push_back(box);
      return;
    }
    glm::dvec3 lo_c(std::numeric_limits<double>::infinity()), hi_c(-lo_c);
    for (std::size_t k = lo; k < hi; ++k) {
      lo_c = glm::min(lo_c, centroid(tris[k]));
      hi_c = glm::max(hi_c, centroid(tris[k]));
    }
    const glm::dvec3 extent = hi_c - lo_c;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0
                     : extent.y >= extent.z                       ? 1
                                                                  : 2;
    const std::size_t mid = lo + (hi - lo) / 2;
    std::nth_element(
        tris.begin() + static_cast<std::ptrdiff_t>(lo),
        tris.begin() + static_cast<std::ptrdiff_t>(mid),
        tris.begin() + static_cast<std::ptrdiff_t>(hi),
        [&](std::uint32_t a, std::uint32_t b) { return centroid(a)[axis] < centroid(b)[axis]; });
    self(self, lo, mid, parts / 2);
    self(self, mid, hi, parts - parts / 2);
  };
  split(split, 0, tris.size(), kMaskParts);
}

std::size_t SbrTracer::rays_in_rows(const Bundle& b, std::size_t lo,
                                    std::size_t hi) const noexcept {
  if (b.mask == kNoMask)
    return (hi - lo) * b.n_az;
  return row_spans_[b.mask + hi].first - row_spans_[b.mask + lo].first;
}

void SbrTracer::row_columns(const Bundle& b, std::size_t r, std::size_t& c0,
                            std::size_t& c1) const noexcept {
  if (b.mask == kNoMask) {
    c0 = 0;
    c1 = b.n_az;
    return;
  }
  c0 = row_spans_[b.mask + r].lo;
  c1 = row_spans_[b.mask + r].hi;
}

void SbrTracer::ray_cell(const Bundle& b, std::size_t j, std::size_t& ia,
                         std::size_t& ie) const noexcept {
  if (b.mask == kNoMask) {
    ia = j % b.n_az;
    ie = b.row_lo + j / b.n_az;
    return;
  }
  // The last row of [row_lo, row_hi) whose rays before it are at most the ray's.
  const RowSpan* rows = row_spans_.data() + b.mask;
  const std::size_t at = rows[b.row_lo].first + j;
  const RowSpan* r = std::upper_bound(rows + b.row_lo, rows + b.row_hi, at,
                                      [](std::size_t x, const RowSpan& s) { return x < s.first; });
  --r;
  ie = static_cast<std::size_t>(r - rows);
  ia = r->lo + (at - r->first);
}

const SbrTracer::GroundPlanes& SbrTracer::ground_under(std::uint32_t id) const noexcept {
  const scene::ObjectState& o = scene_->objects()[id];
  // A target's image in the ground, where its ground-first paths start (image method), is
  // mirrored in the planes of the lowest and highest ground under it, found by downward
  // queries at its box's corners and centre, from just above its base, past its own surfaces
  // (with nothing below, in the plane of its base, as the box's image).
  // Kept per object until its box moves (a static target's: found once).
  GroundPlanes& g = ground_planes_[id];
  if (config_.target_ground_image &&
      !(g.valid && g.bounds_min_m == o.bounds_min_m && g.bounds_max_m == o.bounds_max_m)) {
    const double base_z = o.bounds_min_m.z;
    double ground_lo = std::numeric_limits<double>::infinity(), ground_hi = -ground_lo;
    for (int k = 0; k < 5; ++k) {
      scene::Ray down;
      down.origin_m = glm::dvec3(k == 4    ? 0.5 * (o.bounds_min_m.x + o.bounds_max_m.x)
                                 : (k & 1) ? o.bounds_max_m.x
                                           : o.bounds_min_m.x,
                                 k == 4    ? 0.5 * (o.bounds_min_m.y + o.bounds_max_m.y)
                                 : (k & 2) ? o.bounds_max_m.y
                                           : o.bounds_min_m.y,
                                 base_z + 0.01);
      down.direction = glm::dvec3(0.0, 0.0, -1.0);
      down.t_near_m = 0.0;
      down.t_far_m = config_.max_range_m;
      scene::Hit hit;
      for (int tries = 0; tries < 4 && intersect(down, hit); ++tries) {
        if (hit.object_id != id && !scene_->objects()[hit.object_id].moving) {
          ground_lo = std::min(ground_lo, hit.position_m.z);
          ground_hi = std::max(ground_hi, hit.position_m.z);
          break;
        }
        down.t_near_m = hit.t_m + 1e-4;  // its own surface, or a mover's: on below it
      }
    }
    if (!(ground_lo <= ground_hi))
      ground_lo = ground_hi = base_z;  // nothing below: its base, as the box's image
    g.n_images = 0;
    for (const double z : {ground_lo, ground_hi}) {
      bool seen = false;
      for (int m = 0; m < g.n_images; ++m)
        seen = seen || std::abs(g.mirror_z[static_cast<std::size_t>(m)] - 2.0 * z) < 2e-3;
      if (!seen)
        g.mirror_z[static_cast<std::size_t>(g.n_images++)] = 2.0 * z;
    }
    g.valid = true;
    g.bounds_min_m = o.bounds_min_m;
    g.bounds_max_m = o.bounds_max_m;
  }
  return g;
}

void SbrTracer::mask_rows(const RadarPose& pose, std::uint32_t id, Bundle& b) const noexcept {
  if (part_first_[id] == part_first_[id + 1] || row_spans_used_ + b.n_el + 1 > row_spans_.size())
    return;
  // Its ground-first paths start where the rays aim at its image in the ground (image method).
  const GroundPlanes& g = ground_under(id);
  const int n_images = config_.target_ground_image ? g.n_images : 0;
  const std::array<double, 2>& mirror_z = g.mirror_z;
  RowSpan* rows = row_spans_.data() + row_spans_used_;
  for (std::size_t r = 0; r < b.n_el; ++r)
    rows[r] = RowSpan{static_cast<std::uint32_t>(b.n_az), 0, 0};
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  const glm::dmat4 xf = scene_->world_from_body(id);
  const auto n_az = static_cast<double>(b.n_az), n_el = static_cast<double>(b.n_el);
  // The largest angle from boresight of a direction in the field of view (|az| + |el| bounds
  // it), and a tube more.
  const double fov_rad = std::max(std::abs(config_.azimuth_min_rad), config_.azimuth_max_rad) +
                         std::max(std::abs(config_.elevation_min_rad), config_.elevation_max_rad) +
                         b.daz_rad + b.del_rad;
  // Each part's box (part_boxes_: its facets' corners, body frame), and its images, mark the
  // rows and columns their corners' azimuths and elevations span, one cell added on each side
  // (a straight edge's projection departs from its corners' box by far less). A box reaching
  // behind the antenna plane is halved along its longest side until each half is in front (then
  // marked), or out of the field of view whole (its nearest approach to the boresight axis, over
  // its farthest reach along it, is wider than the field of view: then left out); past 8
  // halvings the bundle shoots its whole grid.
  struct Box {
    glm::dvec3 lo_m, hi_m;
    int depth;
  };
  std::array<Box, 24> stack{};
  for (std::size_t q = part_first_[id]; q < part_first_[id + 1]; ++q) {
    for (int image = 0; image <= n_images; ++image) {
      const double z_mirror = image > 0 ? mirror_z[static_cast<std::size_t>(image - 1)] : 0.0;
      auto antenna = [&](const glm::dvec3& body) {
        glm::dvec3 p(xf * glm::dvec4(body, 1.0));
        if (image > 0)
          p.z = z_mirror - p.z;
        return antenna_from_world * (p - pose.position_m);
      };
      std::size_t n_stack = 0;
      stack[n_stack++] = {part_boxes_[q].lo_m, part_boxes_[q].hi_m, 0};
      while (n_stack > 0) {
        const Box box = stack[--n_stack];
        std::array<glm::dvec3, 8> a;
        bool behind = false;
        for (int k = 0; k < 8; ++k) {
          a[static_cast<std::size_t>(k)] = antenna(glm::dvec3((k & 1) ? box.hi_m.x : box.lo_m.x,
                                                              (k & 2) ? box.hi_m.y : box.lo_m.y,
                                                              (k & 4) ? box.hi_m.z : box.lo_m.z));
          behind = behind || a[static_cast<std::size_t>(k)].x <= 0.0;
        }
        if (behind) {
          const glm::dvec3 centre = antenna(0.5 * (box.lo_m + box.hi_m));
          const double half_m = 0.5 * glm::length(box.hi_m - box.lo_m);
          const double x_max = centre.x + half_m;
          const double lateral_min = std::hypot(centre.y, centre.z) - half_m;
          if (x_max <= 0.0 || (lateral_min > 0.0 && std::atan2(lateral_min, x_max) > fov_rad))
            continue;  // behind the antenna, or outside the field of view
          if (box.depth >= 8 || n_stack + 2 > stack.size())
            return;  // the whole grid
          const glm::dvec3 extent = box.hi_m - box.lo_m;
          const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0
                           : extent.y >= extent.z                       ? 1
                                                                        : 2;
          Box low = box, high = box;
          low.hi_m[axis] = high.lo_m[axis] = 0.5 * (box.lo_m[axis] + box.hi_m[axis]);
          low.depth = high.depth = box.depth + 1;
          stack[n_stack++] = low;
          stack[n_stack++] = high;
          continue;
        }
        double az_lo = 1e9, az_hi = -1e9, el_lo = 1e9, el_hi = -1e9;
        for (const glm::dvec3& corner : a) {
          const AzEl ae = arrival_azel(corner);  // within 4 ulp: far inside the cell added
          az_lo = std::min(az_lo, ae.azimuth_rad);
          az_hi = std::max(az_hi, ae.azimuth_rad);
          el_lo = std::min(el_lo, ae.elevation_rad);
          el_hi = std::max(el_hi, ae.elevation_rad);
        }
        const double r0 = std::floor((el_lo - b.el0_rad) / b.del_rad) - 1.0;
        const double r1 = std::floor((el_hi - b.el0_rad) / b.del_rad) + 1.0;
        const double c0 = std::floor((az_lo - b.az0_rad) / b.daz_rad) - 1.0;
        const double c1 = std::floor((az_hi - b.az0_rad) / b.daz_rad) + 1.0;
        if (!(r1 >= 0.0 && r0 < n_el && c1 >= 0.0 && c0 < n_az))
          continue;  // outside the (clipped) grid
        const auto row_lo = static_cast<std::size_t>(std::max(r0, 0.0));
        const auto row_hi = static_cast<std::size_t>(std::min(r1, n_el - 1.0));
        const auto col_lo = static_cast<std::uint32_t>(std::max(c0, 0.0));
        const auto col_hi = static_cast<std::uint32_t>(std::min(c1, n_az - 1.0)) + 1u;
        for (std::size_t r = row_lo; r <= row_hi; ++r) {
          rows[r].lo = std::min(rows[r].lo, col_lo);
          rows[r].hi = std::max(rows[r].hi, col_hi);
        }
      }
    }
  }
  std::size_t first = 0;
  for (std::size_t r = 0; r < b.n_el; ++r) {
    if (rows[r].hi <= rows[r].lo)
      rows[r].lo = rows[r].hi = 0;
    rows[r].first = first;
    first += rows[r].hi - rows[r].lo;
  }
  rows[b.n_el] = RowSpan{0, 0, first};
  b.mask = row_spans_used_;
  row_spans_used_ += b.n_el + 1;
}

SbrTracer::KeptPath* SbrTracer::kept_slot(const Bundle& bd, std::size_t ia, std::size_t ie,
                                          std::size_t per_ray) const noexcept {
  // Row ie's slice (slice_rows' rule, over its box's rows).
  const int n_slices = config_.reuse_refresh_slices;
  const std::size_t s =
      (2 * (ie + bd.row_offset) + 1) * static_cast<std::size_t>(n_slices) / (2 * bd.n_el_full);
  std::size_t lo = 0, hi = 0;
  bd.grid_slice_rows(n_slices, static_cast<int>(s), lo, hi);
  return kept_paths_.get() + kept_region_[bd.object_id] + s * kept_slice_slots() +
         ((ie - lo) * bd.n_az + ia) * per_ray;
}

std::uint64_t SbrTracer::oldest_kept_at(std::uint32_t id) const noexcept {
  std::uint64_t at = std::numeric_limits<std::uint64_t>::max();
  for (int s = 0; s < config_.reuse_refresh_slices; ++s)
    at = std::min(at, kept_[id].slices[static_cast<std::size_t>(s)].traced_at);
  return at;
}

std::size_t SbrTracer::untraced_kept(const Bundle& b) const noexcept {
  if (b.trace && b.slice == kAllSlices)
    return 0;
  std::size_t n = 0;
  for (int s = 0; s < config_.reuse_refresh_slices; ++s) {
    if (!b.traces_slice(s))
      n += kept_[b.object_id].slices[static_cast<std::size_t>(s)].count;
  }
  return n;
}

void SbrTracer::aspect_change(const RadarPose& pose, const Bundle& b, const glm::dvec3& then_m,
                              double& dtheta_rad, double& limit_rad,
                              double& extent_m) const noexcept {
  const scene::ObjectState& o = scene_->objects()[b.object_id];
  glm::dvec3 lo, hi;
  target_region(o, config_.target_ground_image, lo, hi);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const glm::dvec3 now = pose.position_m - centre, then = then_m - centre;
  dtheta_rad = std::atan2(glm::length(glm::cross(now, then)), glm::dot(now, then));
  // The spacing at the target: the bundle's angular step at its nearest range.
  const glm::dvec3 nearest = glm::clamp(pose.position_m, o.bounds_min_m, o.bounds_max_m);
  const double tube_m = std::min(b.daz_rad, b.del_rad) * glm::length(nearest - pose.position_m);
  extent_m = glm::length(hi - lo);
  limit_rad = 0.5 * tube_m / extent_m;
}

void SbrTracer::choose_memo(const RadarPose& pose, const TraceKnobs& knobs,
                            std::span<Bundle> bundles) const noexcept {
  for (Bundle& b : bundles) {
    b.memo = kMemoNone;
    b.memo_replay_groups = 0;
    b.memo_self_groups = 0;
    b.mover_near = false;
    if (!facet_memo_.empty() && mover_memo_first_[b.object_id] != kNoRegion) {
      // A mover: its groups of facets read back the answers recorded within the rule, except
      // this frame's turn, which asks again (mover_memo_). With another mover near (within its
      // region or across its line of sight), whose shadows the rule does not follow, only what
      // its own body blocks is read back, and no answer recorded then is read back whole.
      b.memo = kMemoRolling;
      b.mover_near = mover_near(pose, b.object_id);
      const std::size_t turn = frame_count_ % memo_groups_;
      for (std::size_t g = 0; g < memo_groups_; ++g) {
        const MemoState& m = mover_memo_[mover_memo_first_[b.object_id] + g];
        if (g == turn || !m.valid || m.spacing_m != b.spacing_m ||
            m.centroid_only != knobs.facet_centroid_only ||
            frame_count_ - m.recorded_at >=
                static_cast<std::uint64_t>(config_.reuse_refresh_frames))
          continue;
        // Everything read back while the motion keeps every shadow on it within half a tube;
        // else its own shadows, while its aspect alone keeps them there (the scene asked).
        double self = 0.0;
        if (mover_memo_fraction(pose, b, m, &self) <= 1.0 && !b.mover_near && !m.mover_near)
          b.memo_replay_groups |= std::uint32_t{1} << g;
        else if (self <= 1.0)
          b.memo_self_groups |= std::uint32_t{1} << g;
      }
      continue;
    }
    if (facet_memo_.empty() || !b.still)
      continue;
    // A bundle traced to keep its paths records its facets' answers with them.
    b.memo = kMemoRecord;
    if (b.trace && b.keep)
      continue;
    const MemoState& m = memo_state_[b.object_id];
    if (!m.valid || m.spacing_m != b.spacing_m || m.centroid_only != knobs.facet_centroid_only ||
        frame_count_ - m.recorded_at >= static_cast<std::uint64_t>(config_.reuse_refresh_frames))
      continue;
    double dtheta = 0.0, limit = 0.0, extent_m = 0.0;
    aspect_change(pose, b, m.radar_m, dtheta, limit, extent_m);
    if (dtheta <= limit)
      b.memo = kMemoReplay;
  }
}

double SbrTracer::mover_memo_fraction(const RadarPose& pose, const Bundle& b, const MemoState& m,
                                      double* self_fraction) const noexcept {
  // A moving target's occlusion answers toward the radar change in two ways:
  // - by its own parts (self-shadowing): these depend only on the direction to the radar in
  //   its body frame, which has turned by at most dtheta + phi since the recording (dtheta:
  //   the direction from its region's centre to the radar in the world, phi: the body's own
  //   turn); a shadow boundary of its own then moves across it by at most D (dtheta + phi)
  //   (D: the region's diagonal), as for a static target (SbrConfig::reuse_static_paths);
  // - by the rest of the scene (terrain, static objects; no other mover is near, choose_memo):
  //   a shadow boundary cast on it moves, relative to the target, by the aspect term above plus
  //   the target's own displacement against the scene, at most |d origin| + phi r for a body
  //   point within r of the body origin (a rotation by phi moves it by 2 r sin(phi / 2)).
  // Their sum within half a ray tube (D limit, limit = spacing / 2D from aspect_change) keeps
  // every answer to the rays' own resolution: the fraction returned is that sum over D limit.
  double dtheta = 0.0, limit = 0.0, extent_m = 0.0;
  glm::dvec3 lo, hi;
  target_region(scene_->objects()[b.object_id], config_.target_ground_image, lo, hi);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  aspect_change(pose, b, centre + (m.radar_m - m.centre_m), dtheta, limit, extent_m);
  const glm::dmat4& now = frame_world_from_body_[b.object_id];
  const glm::dmat3 turn = glm::dmat3(now) * glm::inverse(glm::dmat3(m.world_from_body));
  const double phi =
      std::acos(std::clamp(0.5 * (turn[0][0] + turn[1][1] + turn[2][2] - 1.0), -1.0, 1.0));
  const double moved_m = glm::length(glm::dvec3(now[3]) - glm::dvec3(m.world_from_body[3]));
  const double half_tube_m = limit * extent_m;
  if (!(half_tube_m > 0.0)) {
    if (self_fraction != nullptr)
      *self_fraction = std::numeric_limits<double>::infinity();
    return std::numeric_limits<double>::infinity();
  }
  if (self_fraction != nullptr)
    *self_fraction = extent_m * (dtheta + phi) / half_tube_m;
  return (extent_m * (dtheta + phi) + moved_m + phi * m.reach_m) / half_tube_m;
}

void SbrTracer::record_mover_memo(const RadarPose& pose, const TraceKnobs& knobs,
                                  TraceStats& stats) noexcept {
  for (const Bundle& bd : bundles_) {
    const std::size_t n = facet_first_[bd.object_id + 1] - facet_first_[bd.object_id];
    stats.mover_facets += scene_->objects()[bd.object_id].moving ? n : 0;
    if (bd.memo != kMemoRolling)
      continue;
    glm::dvec3 lo, hi;
    target_region(scene_->objects()[bd.object_id], config_.target_ground_image, lo, hi);
    MemoState now{true, pose.position_m, bd.spacing_m, knobs.facet_centroid_only, frame_count_};
    now.mover_near = bd.mover_near;
    now.centre_m = 0.5 * (lo + hi);
    now.world_from_body = frame_world_from_body_[bd.object_id];
    now.reach_m =
        glm::length(glm::dvec3(now.world_from_body[3]) - now.centre_m) + 0.5 * glm::length(hi - lo);
    for (std::size_t g = 0; g < memo_groups_; ++g) {
      const std::size_t in_group = g < n ? (n - g + memo_groups_ - 1) / memo_groups_ : 0;
      if (((bd.memo_replay_groups >> g) & 1u) != 0)  // its facets t = g, g + groups, ...
        stats.replayed_mover_facets += in_group;     // read their answers back
      else if (((bd.memo_self_groups >> g) & 1u) != 0)
        stats.self_replayed_mover_facets += in_group;  // their own shadows back
      else
        mover_memo_[mover_memo_first_[bd.object_id] + g] = now;
    }
  }
}

SbrTracer::FacetMemo* SbrTracer::memo_record(const Bundle& bd, std::size_t slot,
                                             std::size_t t) noexcept {
  if (bd.memo == kMemoRecord ||
      (bd.memo == kMemoRolling &&
       (((bd.memo_replay_groups | bd.memo_self_groups) >> (t % memo_groups_)) & 1u) == 0))
    return &facet_memo_[slot];
  return nullptr;
}

const SbrTracer::FacetMemo* SbrTracer::memo_replay(const Bundle& bd, std::size_t slot,
                                                   std::size_t t) const noexcept {
  if (bd.memo == kMemoReplay ||
      (bd.memo == kMemoRolling && ((bd.memo_replay_groups >> (t % memo_groups_)) & 1u) != 0))
    return &facet_memo_[slot];
  return nullptr;
}

bool SbrTracer::same_facets_by_rays(std::uint32_t id) const noexcept {
  for (std::size_t f = facet_first_[id]; f < facet_first_[id + 1]; ++f) {
    if ((facet_light_[f] == kLightByRays ? 1 : 0) != kept_facet_by_rays_[f])
      return false;
  }
  return true;
}

void SbrTracer::prune_outside_view(const RadarPose& pose, std::span<const Bundle> bundles,
                                   TraceStats& stats) noexcept {
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  for (const Bundle& b : bundles) {
    // Kept, whole or but for the slices traced this frame.
    if ((b.trace && b.slice == kAllSlices) || !b.clipped)
      continue;
    Kept& kp = kept_[b.object_id];
    for (int s = 0; s < config_.reuse_refresh_slices; ++s) {
      if (b.traces_slice(s))
        continue;
      KeptSlice& ks = kp.slices[static_cast<std::size_t>(s)];
      KeptPath* region = kept_paths_.get() + kept_region_[b.object_id] +
                         static_cast<std::size_t>(s) * kept_slice_slots();
      // A path's first segment is its ray: in view when the direction to its first hit is
      // (the facet pass's test, by the limits' tangents).
      std::size_t m = 0;
      for (std::size_t i = 0; i < ks.count; ++i) {
        if (in_field_of_view(fov_tan_,
                             antenna_from_world * (region[i].first_hit_m - pose.position_m)))
          region[m++] = region[i];
      }
      stats.kept_paths_left_view += ks.count - m;
      ks.count = m;
      ks.view = b.view;
    }
  }
}

void SbrTracer::count_reuse(std::span<const Bundle> bundles, TraceStats& stats) const noexcept {
  double worst_fraction = 0.0;
  std::uint64_t oldest = 0;
  for (const Bundle& b : bundles) {
    stats.refreshed_bundles += b.refreshed ? 1u : 0u;
    if (b.trace && b.slice == kAllSlices)
      continue;
    // Kept, or a slice of it traced again (its other slices kept).
    ++stats.reused_bundles;
    stats.reused_rays += all_rays(b) - traced_rays(b);
    stats.reused_contributions += untraced_kept(b);
    worst_fraction = std::max(worst_fraction, b.kept_fraction);
    oldest = std::max(oldest, frame_count_ - oldest_kept_at(b.object_id));
  }
  stats.reuse_max_angle_fraction = std::max(stats.reuse_max_angle_fraction, worst_fraction);
  stats.reuse_max_age_frames = std::max(stats.reuse_max_age_frames, oldest);
}

// A ray between its hits (trace_batch): where it is, what it carries, where its returns go.
struct SbrTracer::RayState {
  glm::dvec3 d{0.0};  ///< direction of the next segment
  /// Tube edge vectors per unit distance: derivatives of the direction times the spacings
  /// (Ling, Chou & Lee 1989: ray tubes). |u x v| = cos(el) daz del, the tube's solid angle; the
  /// spherical wave's tube at unfolded distance L has edges L u, L v.
  glm::dvec3 u{0.0}, v{0.0};
  CVec e;                     ///< field, unit amplitude at every hit (range: the sensor's)
  glm::dvec3 origin{0.0};     ///< of the next segment (lifted off the last hit)
  glm::dvec3 v_prev{0.0};     ///< velocity of what the ray last left [m/s]
  glm::dvec3 last_hit{0.0};   ///< the last hit, on the unlifted path
  double path_m = 0.0;        ///< unfolded path length from the radar to the last hit
  double path_rate = 0.0;     ///< d(path)/dt so far [m/s]
  glm::dvec3 first_hit{0.0};  ///< the path's first hit (static path reuse)
  /// Static path reuse: the ray's max_bounces slots of kept paths (null: its bundle keeps none).
  KeptPath* kept = nullptr;
  Contribution* slot = nullptr;   ///< the ray's max_bounces output slots
  std::uint8_t* count = nullptr;  ///< how many of them hold returns
  std::uint32_t owner = 0;        ///< the bundle's target (terrain rays: none)
  std::uint32_t path_owner = 0;   ///< the first target met (header: ownership)
  bool terrain = false;           ///< a terrain-grid ray
  bool met_target = false;
  bool active = true;  ///< still travelling
  /// The field's reflection at the last hit, left until the field is needed (a path that ends
  /// before it radiates or reflects again never needs it): the surface (null: none pending),
  /// the incident direction, the face's normal and cos(theta_i) there.
  const SurfaceModel* pending_surface = nullptr;
  glm::dvec3 pending_d{0.0}, pending_n{0.0};
  double pending_cos = 0.0;
};

namespace {
constexpr std::size_t kBatch = 64;  // rays per trace_batch (stack arrays: no allocation)
}  // namespace

void SbrTracer::trace_batch(const RadarPose& pose, const Frame& frame, std::span<RayState> rays,
                            TraceStats& stats) const noexcept {
  const SbrConfig& c = config_;
  const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
  const glm::dmat3& r = pose.world_from_antenna;
  const glm::dvec3 boresight = r[0];
  const glm::dvec3 up = -r[2];  // antenna z is down
  const glm::dmat3 antenna_from_world = glm::transpose(r);
  const bool rx_h = c.polarisation == Polarisation::kHH || c.polarisation == Polarisation::kHV;
  std::array<scene::Ray, kBatch> segments, shadows;
  std::array<scene::Hit, kBatch> hits;
  std::array<std::uint8_t, kBatch> found, blocked;
  std::array<std::uint32_t, kBatch> segment_of, shadow_of;
  const std::size_t n_rays = std::min(rays.size(), kBatch);
  // The pending reflection of a ray's field (RayState), applied: d_r = mirror(d, n) is the
  // ray's direction since.
  auto settle_field = [&](RayState& st) {
    if (st.pending_surface == nullptr)
      return;
    const SurfaceModel& sm = *st.pending_surface;
    const bool pec = sm.kind == SurfaceModel::Kind::kPec;
    const ReflectionCoefficients rc =
        pec ? ReflectionCoefficients{} : reflection_coefficients(sm, st.pending_cos, k);
    st.e = reflect_field(st.e, st.pending_d, st.d, st.pending_n, rc, pec);
    st.pending_surface = nullptr;
  };
  for (int bounce = 0; bounce < frame.max_bounces; ++bounce) {
    // This bounce's segments of the rays still travelling, queried together.
    std::size_t n_seg = 0;
    for (std::size_t q = 0; q < n_rays; ++q) {
      RayState& st = rays[q];
      if (!st.active)
        continue;
      scene::Ray& ray = segments[n_seg];  // kept (n_seg counts it) unless the ray ends here
      ray.origin_m = st.origin;
      ray.direction = st.d;
      ray.t_near_m = 0.0;  // reflected rays start lifted off the surface (below)
      // Range budget: a return counts only if half its total path is within max_range, so the
      // first segment may run max_range and later ones what is left of 2 max_range.
      ray.t_far_m = bounce == 0 ? c.max_range_m : 2.0 * c.max_range_m - st.path_m;
      if (ray.t_far_m <= ray.t_near_m) {
        st.active = false;
        continue;
      }
      if (bounce > 0 && !st.met_target && !may_reach_owner(ray, frame, st.owner, st.terrain)) {
        ++stats.pruned_paths;
        st.active = false;
        continue;
      }
      segment_of[n_seg++] = static_cast<std::uint32_t>(q);
    }
    if (n_seg == 0)
      return;
    intersect(std::span<const scene::Ray>(segments.data(), n_seg),
              std::span<scene::Hit>(hits.data(), n_seg),
              std::span<std::uint8_t>(found.data(), n_seg));
    // Each hit: returns (a shadowed one waits for its shadow ray's answer), then the reflection.
    std::size_t n_shadow = 0;
    for (std::size_t j = 0; j < n_seg; ++j) {
      RayState& st = rays[segment_of[j]];
      if (found[j] == 0) {
        st.active = false;
        continue;
      }
      scene::Hit& hit = hits[j];
      ++stats.hits;
      const bool hit_target = is_target_[hit.object_id] != 0;
      if (hit_target && !st.met_target) {
        // Ownership (header): the first target on the path decides which grid counts it.
        if (st.terrain ? bundled_[hit.object_id] != 0 : hit.object_id != st.owner) {
          st.active = false;
          continue;
        }
        st.met_target = true;
        st.path_owner = hit.object_id;
      }
      const Surface& surface = surfaces_.surfaces[hit.material_id];
      const glm::dvec3 v_obj = scene_->objects()[hit.object_id].velocity_mps;
      const glm::dvec3 d = st.d;
      hit.position_m =
          extend_path(bounce == 0, hit.t_m, st.last_hit, d, hit.position_m, hit.normal, st.path_m);
      st.last_hit = hit.position_m;
      if (bounce == 0)
        st.first_hit = hit.position_m;
      if (st.kept != nullptr && scene_->objects()[hit.object_id].moving)
        met_mover_[st.owner].store(1, std::memory_order_relaxed);  // its paths are not kept
      st.path_rate += glm::dot(v_obj - st.v_prev, d);
      const double path_m = st.path_m;
      glm::dvec3 n = hit.normal;
      if (glm::dot(n, d) > 0.0)
        n = -n;  // the face the ray meets
      const double n_dot_d = glm::dot(n, d);
      const double cos_i = -n_dot_d;
      if (cos_i < kGrazingCos) {
        ++stats.grazing_skipped;
        st.active = false;
        continue;
      }
      if (bounce == 0 && st.terrain && !hit_target && !surface.conductor) {
        // Diffuse clutter: sigma = sigma0(theta_i) * footprint area, footprint = dA_perp /
        // cos(theta_i) with dA_perp = L^2 dOmega; sigma0 of the antenna's channel from the
        // material's setup-time table (radar/clutter/terrain.hpp; every non-conductor has a row).
        const TubeFootprint fp = tube_footprint(st.u * path_m, st.v * path_m, d, n, -d);
        const double d_omega = glm::length(glm::cross(st.u, st.v));
        std::uint32_t sigma0_flags = 0u;
        const double sigma_m2 =
            static_cast<double>(surfaces_.sigma0(hit.material_id, cos_i, sigma0_flags)) * path_m *
            path_m * d_omega / cos_i;
        ++stats.terrain_returns;  // issue 28: the flagged sigma0 values the terrain read
        if (sigma0_flags != 0u) {
          ++stats.terrain_returns_flagged;
          stats.terrain_sigma0_flags |= sigma0_flags;
        }
        Contribution& out = st.slot[(*st.count)++];
        out.amplitude = {std::sqrt(sigma_m2), 0.0};
        out.range_m = path_m;
        out.range_spread_m = std::abs(glm::dot(fp.u_m, d)) + std::abs(glm::dot(fp.v_m, d));
        out.radial_velocity_mps = st.path_rate;  // out and back along the same line
        const AzEl ae = arrival_azel(antenna_from_world * d);
        out.azimuth_rad = ae.azimuth_rad;
        out.elevation_rad = ae.elevation_rad;
        out.object_id = hit.object_id;
        out.bounces = 1;
        out.coherent = false;
      }
      if (st.terrain && !st.met_target && frame.unbundled_in_range.empty()) {
        st.active = false;  // no target without a bundle within range: nothing can radiate
        continue;
      }
      const SurfaceModel& sm = surface.specular;
      const bool pec = sm.kind == SurfaceModel::Kind::kPec;
      const bool last = bounce + 1 == frame.max_bounces;
      if (last && !st.met_target) {  // nothing radiates here, and no reflection follows
        if (!pec)
          ++stats.dielectric_reflections;  // counted as if reflected, as before this shortcut
        st.active = false;
        continue;
      }
      // The local reflection coefficients, now when this hit radiates, else with the
      // field's reflection when it is needed (settle_field).
      settle_field(st);
      const ReflectionCoefficients rc =
          !st.met_target || pec ? ReflectionCoefficients{} : reflection_coefficients(sm, cos_i, k);
      const double off = surface_offset_m(hit.position_m);
      if (st.met_target) {
        // PO radiation of the footprint back to the radar (sbr_core.hpp).
        const glm::dvec3 to_radar = pose.position_m - hit.position_m;
        const double back_m = glm::length(to_radar);
        const glm::dvec3 s = to_radar / back_m;
        bool visible = true;
        bool shadowed_later = false;  // visible unless its shadow ray (below) is blocked
        if (bounce == 0) {
          // A bundle's first hit on its own target: the facet pass has bounce 1 (header)
          // unless it left this facet to the rays.
          visible = st.terrain ||
                    facet_light_[facet_first_[hit.object_id] + hit.primitive_id] == kLightByRays;
        } else {
          // Later bounces: the radar must see the lit side of the hit (sbr_core.hpp,
          // kGrazingCos) along a clear path.
          visible = glm::dot(n, s) >= kGrazingCos;
          if (visible) {
            scene::Ray& shadow = shadows[n_shadow];
            shadow.origin_m = hit.position_m + off * n;
            const glm::dvec3 to = pose.position_m - shadow.origin_m;
            shadow.t_far_m = glm::length(to);
            shadow.direction = to / shadow.t_far_m;
            shadow.t_near_m = 0.0;
            shadow_of[n_shadow++] = segment_of[j];
            shadowed_later = true;
          }
        }
        if (visible) {  // written now, kept (counted) once its shadow ray is known to be clear
          const TubeFootprint fp = tube_footprint(st.u * path_m, st.v * path_m, d, n, s);
          // The direction of arrival in the antenna frame gives both the return's angles and
          // the receive polarisation (receive_pol).
          const glm::dvec3 arrival = antenna_from_world * (-s);
          const double arrival_h = std::sqrt(arrival.x * arrival.x + arrival.y * arrival.y);
          const glm::dvec3 p = receive_pol(rx_h, r, up, boresight, -s, arrival, arrival_h);
          const double total_m = path_m + back_m;
          Contribution& out = st.slot[*st.count];
          const std::complex<double> a =
              po_amplitude_m(k, p, po_source(st.e, d, n, s, rc, pec), footprint_integral(fp, k));
          out.amplitude = times(a, unit_phasor(-k * total_m));
          if (st.kept != nullptr) {
            KeptPath& kp = st.kept[*st.count];
            kp.first_hit_m = st.first_hit;
            kp.last_hit_m = hit.position_m;
            kp.inner_m = path_m - glm::length(st.first_hit - pose.position_m);
            kp.amplitude_re_m = a.real();
            kp.amplitude_im_m = a.imag();
            kp.bounces = static_cast<std::uint8_t>(bounce + 1);
            kp.radiated_by_owner = hit.object_id == st.path_owner;
          }
          out.range_m = 0.5 * total_m;
          out.range_spread_m = 0.0;
          out.radial_velocity_mps = 0.5 * (st.path_rate + glm::dot(pose.velocity_mps - v_obj, s));
          const AzEl ae = arrival_azel(arrival, arrival_h);  // its square root shared
          out.azimuth_rad = ae.azimuth_rad;
          out.elevation_rad = ae.elevation_rad;
          out.object_id = st.path_owner;
          out.radiated_by_owner = hit.object_id == st.path_owner;
          out.bounces = static_cast<std::uint8_t>(bounce + 1);
          out.coherent = true;
          if (!shadowed_later)
            ++*st.count;
        }
      }
      // Specular reflection (law of reflection) of direction, tube and field (sbr_core.hpp);
      // none after the last hit (only counted).
      if (!pec)
        ++stats.dielectric_reflections;
      if (last) {
        st.active = false;
        continue;
      }
      st.d = mirror(d, n);  // d_r (written in place: no copy of a temporary)
      if (st.met_target) {
        st.e = reflect_field(st.e, d, st.d, n, rc, pec);
      } else {  // no return yet: the field may never be needed (pruned, lost, owned by another)
        st.pending_surface = &sm;
        st.pending_d = d;
        st.pending_n = n;
        st.pending_cos = cos_i;
      }
      st.u = mirror(st.u, n);
      st.v = mirror(st.v, n);
      st.origin = hit.position_m + off * n;  // lifted to the lit side: no self-hit
      st.v_prev = v_obj;
    }
    // The shadow rays of this bounce's returns, together: a clear one keeps its return.
    if (n_shadow > 0) {
      occluded(std::span<const scene::Ray>(shadows.data(), n_shadow),
               std::span<std::uint8_t>(blocked.data(), n_shadow));
      for (std::size_t j = 0; j < n_shadow; ++j) {
        if (blocked[j] == 0)
          ++*rays[shadow_of[j]].count;
      }
    }
  }
}

TracePlan SbrTracer::plan(const RadarPose& pose, const TraceKnobs& knobs,
                          std::span<std::size_t> rays_per_object) const noexcept {
  const Frame f = frame_for(knobs, nullptr);
  TracePlan p;
  p.terrain_rays = f.terrain_n_az * f.terrain_n_el;
  p.max_bounces = f.max_bounces;
  const auto objects = scene_->objects();
  plan_bundles_.clear();
  row_spans_used_ = 0;
  for (std::uint32_t id = 0; id < objects.size(); ++id) {
    if (id < rays_per_object.size())
      rays_per_object[id] = 0;
    Bundle b;
    bool coarsened = false;
    const double spacing_m = target_spacing(knobs, id, nullptr);
    if (is_target_[id] && bundle_for(pose, id, spacing_m, b, coarsened)) {
      b.spacing_m = spacing_m;
      plan_bundles_.push_back(b);  // within the capacity reserved at setup
      ++p.target_bundles;
      p.target_facets += facet_first_[id + 1] - facet_first_[id];
      p.coarsened_bundles += coarsened ? 1 : 0;
    }
  }
  double credit = refresh_credit_;
  choose_reuse(pose, f.max_bounces, plan_bundles_, credit, knobs.defer_refresh);
  for (const Bundle& b : plan_bundles_) {
    const std::size_t rays = traced_rays(b);
    p.reused_rays += all_rays(b) - rays;
    p.reused_contributions += untraced_kept(b);
    p.target_rays += rays;
    if (b.object_id < rays_per_object.size() && rays > 0)
      rays_per_object[b.object_id] = rays;
  }
  return p;
}

std::size_t SbrTracer::trace(const RadarPose& pose, std::span<Contribution> out, TraceStats& stats,
                             const TraceKnobs& knobs) noexcept {
  const SbrConfig& c = config_;
  Frame frame = frame_for(knobs, &stats);
  ++frame_count_;
  // Bundles for targets inside the field of view.
  bundles_.clear();
  unbundled_in_range_.clear();
  row_spans_used_ = 0;
  const std::size_t terrain_rays = frame.terrain_n_az * frame.terrain_n_el;
  std::size_t next_ray = terrain_rays;
  const auto objects = scene_->objects();
  for (std::uint32_t id = 0; id < objects.size(); ++id) {
    bundled_[id] = 0;
    if (!is_target_[id])
      continue;
    frame_box_[id] = scene::padded_box(objects[id].bounds_min_m, objects[id].bounds_max_m);
    Bundle b;
    bool coarsened = false;
    const double spacing_m = target_spacing(knobs, id, &stats);
    if (!bundle_for(pose, id, spacing_m, b, coarsened)) {
      const scene::ObjectState& o = objects[id];
      const glm::dvec3 nearest = glm::clamp(pose.position_m, o.bounds_min_m, o.bounds_max_m);
      if (glm::length(nearest - pose.position_m) <= c.max_range_m)
        unbundled_in_range_.push_back(id);  // within the capacity reserved at setup
      continue;
    }
    stats.coarsened_bundles += coarsened ? 1 : 0;
    b.spacing_m = spacing_m;
    bundles_.push_back(b);
    bundled_[id] = 1;
    ++stats.target_bundles;
  }
  frame.unbundled_in_range = unbundled_in_range_;
  // Static path reuse: which bundles shoot their rays this frame (the others' kept paths are
  // re-evaluated below), before the facet pass, whose kept bundles read their facets' occlusion
  // answers back (FacetMemo).
  choose_reuse(pose, frame.max_bounces, bundles_, refresh_credit_, knobs.defer_refresh);
  prune_outside_view(pose, bundles_, stats);
  stats.refresh_deferred += knobs.defer_refresh && c.reuse_static_paths ? 1u : 0u;
  // Bounce 1 of every facet of the bundled targets (header), before the rays that read it: one
  // parallel loop over all their facets (bundle b's run from its first_facet).
  for (const Bundle& bd : bundles_)
    frame_world_from_body_[bd.object_id] = scene_->world_from_body(bd.object_id);
  const std::size_t n_facets = lay_out_run(bundles_, &Bundle::first_facet, facet_first_);
  stats.target_facets += n_facets;
  std::atomic<std::uint64_t> facet_queries{0};
  choose_memo(pose, knobs, bundles_);
  // Batches of kFacetBatch facets (facet_batch), cut where the simple partitioner halves the
  // run: the same batches whatever the threads.
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n_facets, kFacetBatch),
      [&](const tbb::blocked_range<std::size_t>& range) {
        std::uint64_t queries = 0;
        std::size_t b = 0;
        for (std::size_t i = range.begin(); i < range.end(); i += kFacetBatch)
          facet_batch(pose, knobs, i, std::min(range.end(), i + kFacetBatch), b, queries);
        facet_queries += queries;
      },
      tbb::simple_partitioner());
  // The reuse rule's last condition: the same facets left to the rays as when the paths were
  // kept. A bundle that fails it is traced after all, its facets asked again (and recorded).
  for (Bundle& bd : bundles_) {
    if ((bd.trace && bd.slice == kAllSlices) || same_facets_by_rays(bd.object_id))
      continue;
    const std::size_t paid = traced_rays(bd);  // a slice's, when it was to be refreshed
    bd.trace_whole();
    bd.memo = kMemoRecord;
    refresh_credit_ = std::max(0.0, refresh_credit_ - static_cast<double>(all_rays(bd) - paid));
    std::uint64_t queries = 0;
    std::size_t b = 0;  // run_item's cursor, walks to bd
    const std::size_t end =
        bd.first_facet + facet_first_[bd.object_id + 1] - facet_first_[bd.object_id];
    for (std::size_t i = bd.first_facet; i < end; i += kFacetBatch)
      facet_batch(pose, knobs, i, std::min(end, i + kFacetBatch), b, queries);
    facet_queries += queries;
  }
  count_reuse(bundles_, stats);
  for (const Bundle& bd : bundles_) {
    if (bd.memo == kMemoRecord)
      memo_state_[bd.object_id] = {true, pose.position_m, bd.spacing_m, knobs.facet_centroid_only,
                                   frame_count_};
  }
  record_mover_memo(pose, knobs, stats);
  {
    std::uint64_t n_lit = 0, n_partial = 0;
    for (const Bundle& bd : bundles_) {
      for (std::size_t f = facet_first_[bd.object_id]; f < facet_first_[bd.object_id + 1]; ++f) {
        n_lit += facet_light_[f] == static_cast<std::uint8_t>(FacetLight::kLit) ? 1u : 0u;
        n_partial += facet_light_[f] == static_cast<std::uint8_t>(FacetLight::kPartial) ? 1u : 0u;
      }
    }
    stats.lit_facets += n_lit;
    stats.partial_facets += n_partial;
  }

  // Edge diffraction of the bundled targets (SbrConfig::edges), the same way.
  std::atomic<std::uint64_t> edge_queries{0};
  if (c.edges) {
    const std::size_t n_edges = lay_out_run(bundles_, &Bundle::first_edge, edge_first_);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_edges, 64),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        std::uint64_t queries = 0;
                        std::size_t b = 0;
                        for (std::size_t i = range.begin(); i != range.end(); ++i) {
                          const std::size_t j = run_item(bundles_, &Bundle::first_edge, i, b);
                          const Bundle& bd = bundles_[b];
                          const std::size_t e = edge_first_[bd.object_id] + j;
                          edge_state_[e] = edge_pass(pose, bd.object_id, e, edge_out_[e], queries);
                        }
                        edge_queries += queries;
                      });
    // Double diffraction between the edges that radiate (SbrConfig::edge_order 2).
    const std::size_t n_pairs = lay_out_run(bundles_, &Bundle::first_pair, pair_first_);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_pairs, 64),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        std::size_t b = 0;
                        for (std::size_t i = range.begin(); i != range.end(); ++i) {
                          const std::size_t j = run_item(bundles_, &Bundle::first_pair, i, b);
                          const Bundle& bd = bundles_[b];
                          const std::size_t p = pair_first_[bd.object_id] + j;
                          pair_used_[p] = pair_pass(pose, bd.object_id, p, pair_out_[p]) ? 1 : 0;
                        }
                      });
  }
  // The rays of the bundles traced, laid end to end after the terrain grid's.
  for (Bundle& bd : bundles_) {
    bd.first_ray = next_ray;
    next_ray += traced_rays(bd);
    if (bd.trace)
      stats.masked_rays += (bd.row_hi - bd.row_lo) * bd.n_az - traced_rays(bd);
    if (bd.keep)
      met_mover_[bd.object_id].store(0, std::memory_order_relaxed);
  }
  // Each grid column's azimuth, once (RayState's direction and tube edges take its cos, sin).
  {
    std::size_t col = 0;
    for (std::size_t ia = 0; ia < frame.terrain_n_az; ++ia, ++col) {
      const double az = c.azimuth_min_rad + (static_cast<double>(ia) + 0.5) * frame.terrain_daz_rad;
      column_cos_[col] = std::cos(az);
      column_sin_[col] = std::sin(az);
    }
    for (Bundle& bd : bundles_) {
      if (!bd.trace)
        continue;
      if (col + bd.n_az > column_cos_.size()) {  // beyond the table: per ray (same values)
        bd.first_column = kNoColumns;
        continue;
      }
      bd.first_column = col;
      for (std::size_t ia = 0; ia < bd.n_az; ++ia, ++col) {
        const double az = bd.az0_rad + (static_cast<double>(ia) + 0.5) * bd.daz_rad;
        column_cos_[col] = std::cos(az);
        column_sin_[col] = std::sin(az);
      }
    }
  }
  const std::size_t rays = next_ray;
  const auto per_ray = static_cast<std::size_t>(c.max_bounces);
  const std::size_t usable_rays = std::min({rays, out.size() / per_ray, counts_.size()});
  stats.rays += rays;

  std::atomic<std::uint64_t> hits{0}, grazing{0}, dielectric{0}, pruned{0};
  std::atomic<std::uint64_t> terrain_returns{0}, terrain_flagged{0};
  std::atomic<std::uint32_t> terrain_flags{0};
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, usable_rays, 256),
      [&](const tbb::blocked_range<std::size_t>& range) {
        TraceStats local;
        std::size_t b = 0;
        // The rays go in batches of neighbours (a row of a grid, mostly), traced together
        // (trace_batch).
        std::array<RayState, kBatch> batch;
        const glm::dmat3& rot = pose.world_from_antenna;
        const glm::dvec3 boresight = rot[0], up = -rot[2];  // antenna z is down
        const bool tx_h =
            c.polarisation == Polarisation::kHH || c.polarisation == Polarisation::kVH;
        double row_el = std::numeric_limits<double>::quiet_NaN(), ce = 0.0, se = 0.0;
        for (std::size_t i0 = range.begin(); i0 < range.end(); i0 += kBatch) {
          const std::size_t n_batch = std::min(kBatch, range.end() - i0);
          for (std::size_t q = 0; q < n_batch; ++q) {
            const std::size_t i = i0 + q;
            RayState& st = batch[q];
            st = RayState{};
            double el = 0.0, daz = 0.0, del = 0.0, ca = 0.0, sa = 0.0;
            if (i < terrain_rays) {
              const std::size_t ia = i % frame.terrain_n_az, ie = i / frame.terrain_n_az;
              el = c.elevation_min_rad + (static_cast<double>(ie) + 0.5) * frame.terrain_del_rad;
              daz = frame.terrain_daz_rad;
              del = frame.terrain_del_rad;
              ca = column_cos_[ia];
              sa = column_sin_[ia];
              st.terrain = true;
            } else {
              while (b + 1 < bundles_.size() && i >= bundles_[b + 1].first_ray)
                ++b;
              const Bundle& bd = bundles_[b];
              std::size_t ia = 0, ie = 0;
              ray_cell(bd, i - bd.first_ray, ia, ie);
              el = bd.el0_rad + (static_cast<double>(ie) + 0.5) * bd.del_rad;
              daz = bd.daz_rad;
              del = bd.del_rad;
              if (bd.first_column != kNoColumns) {
                ca = column_cos_[bd.first_column + ia];
                sa = column_sin_[bd.first_column + ia];
              } else {
                const double az = bd.az0_rad + (static_cast<double>(ia) + 0.5) * bd.daz_rad;
                ca = std::cos(az);
                sa = std::sin(az);
              }
              st.owner = bd.object_id;
              if (bd.keep)
                st.kept = kept_slot(bd, ia, ie, per_ray);
            }
            if (el != row_el) {  // one elevation per row of a grid
              row_el = el;
              ce = std::cos(el);
              se = std::sin(el);
            }
            st.d = rot * glm::dvec3(ce * ca, ce * sa, -se);
            st.u = rot * glm::dvec3(-ce * sa, ce * ca, 0.0) * daz;
            st.v = rot * glm::dvec3(-se * ca, -se * sa, -ce) * del;
            st.e = CVec{pol_vector(tx_h, up, boresight, st.d), glm::dvec3(0.0)};
            st.origin = pose.position_m;
            st.v_prev = pose.velocity_mps;
            st.last_hit = pose.position_m;
            st.slot = out.data() + i * per_ray;
            st.count = &counts_[i];
            st.path_owner = st.owner;
            counts_[i] = 0;
          }
          trace_batch(pose, frame, std::span<RayState>(batch.data(), n_batch), local);
        }
        hits += local.hits;
        grazing += local.grazing_skipped;
        dielectric += local.dielectric_reflections;
        pruned += local.pruned_paths;
        terrain_returns += local.terrain_returns;
        terrain_flagged += local.terrain_returns_flagged;
        terrain_flags.fetch_or(local.terrain_sigma0_flags, std::memory_order_relaxed);
      });
  stats.hits += hits.load();
  stats.grazing_skipped += grazing.load();
  stats.dielectric_reflections += dielectric.load();
  stats.pruned_paths += pruned.load();
  stats.terrain_returns += terrain_returns.load();
  stats.terrain_returns_flagged += terrain_flagged.load();
  stats.terrain_sigma0_flags |= terrain_flags.load();
  stats.facet_queries += facet_queries.load();
  stats.dropped_contributions += (rays - usable_rays) * per_ray;  // upper bound, counted
  // Compact the fixed per-ray slots in ray order: deterministic whatever the threading.
  std::size_t n = 0;
  for (std::size_t i = 0; i < usable_rays; ++i) {
    for (std::uint8_t k = 0; k < counts_[i]; ++k)
      out[n++] = out[i * per_ray + k];
  }
  // Static path reuse: the traced bundles that keep their paths compact them (the first ones of
  // each ray, in ray order) and remember the frame; then the others' kept paths are evaluated
  // for this pose, in bundle order, after the rays' returns.
  if (c.reuse_static_paths) {
    const int n_slices = c.reuse_refresh_slices;
    // The runs of kept returns to evaluate: each slice not traced this frame of a bundle that
    // was kept or had one slice traced again (taken before the traced slices are compacted).
    kept_runs_.clear();
    std::size_t n_kept = 0;
    for (const Bundle& bd : bundles_) {
      if (bd.trace && bd.slice == kAllSlices)
        continue;
      for (int s = 0; s < n_slices; ++s) {
        if (bd.traces_slice(s))
          continue;
        kept_runs_.push_back({n_kept, bd.object_id, static_cast<std::uint8_t>(s)});
        n_kept += kept_[bd.object_id].slices[static_cast<std::size_t>(s)].count;
      }
    }
    for (const Bundle& bd : bundles_) {
      const std::uint32_t id = bd.object_id;
      if (!bd.trace)
        continue;
      Kept& kp = kept_[id];
      if (!bd.keep || bd.first_ray + traced_rays(bd) > usable_rays ||
          met_mover_[id].load(std::memory_order_relaxed) != 0) {
        kp.valid = false;
        continue;
      }
      if (bd.slice == kAllSlices) {
        kp.valid = true;
        kp.spacing_m = bd.spacing_m;
        kp.max_bounces = frame.max_bounces;
        kp.n_el = bd.n_el_full;
      }
      // Each traced slice's paths to the front of its region (rays in order).
      for (int s = 0; s < n_slices; ++s) {
        if (!bd.traces_slice(s))
          continue;
        std::size_t lo = 0, hi = 0;
        bd.grid_slice_rows(n_slices, s, lo, hi);
        KeptPath* region =
            kept_paths_.get() + kept_region_[id] + static_cast<std::size_t>(s) * kept_slice_slots();
        std::size_t m = 0;
        std::size_t i = bd.first_ray + rays_in_rows(bd, bd.row_lo, lo);
        for (std::size_t r = lo; r < hi; ++r) {
          std::size_t c0 = 0, c1 = 0;
          row_columns(bd, r, c0, c1);
          for (std::size_t ia = c0; ia < c1; ++ia, ++i) {
            const std::size_t j = (r - lo) * bd.n_az + ia;  // its slot in the slice's region
            for (std::uint8_t q = 0; q < counts_[i]; ++q)
              region[m++] = region[j * per_ray + q];
          }
        }
        KeptSlice& ks = kp.slices[static_cast<std::size_t>(s)];
        ks.radar_m = pose.position_m;
        ks.world_from_antenna = pose.world_from_antenna;
        ks.view = bd.view;
        ks.count = m;
        ks.traced_at = frame_count_;
      }
      for (std::size_t f = facet_first_[id]; f < facet_first_[id + 1]; ++f)
        kept_facet_by_rays_[f] = facet_light_[f] == kLightByRays ? 1 : 0;
    }
    const std::size_t room = out.size() - n;
    const std::size_t n_eval = std::min(n_kept, room);
    stats.dropped_contributions += n_kept - n_eval;
    const double k = 2.0 * kPi * c.carrier_hz / kSpeedOfLight_mps;
    const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
    const glm::dvec3 v = pose.velocity_mps;
    // A kept path's fields that do not depend on the pose.
    auto set_fixed = [](const KeptPath& kp, std::uint32_t object_id, Contribution& x) {
      x.range_spread_m = 0.0;
      x.object_id = object_id;
      x.radiated_by_owner = kp.radiated_by_owner;
      x.bounces = kp.bounces;
      x.coherent = true;
    };
    // The kept path for this pose (SbrConfig::reuse_static_paths): exact end segments.
    auto evaluate = [&](const KeptPath& kp, std::uint32_t object_id, Contribution& x) {
      const glm::dvec3 to_first = kp.first_hit_m - pose.position_m;
      const double first_m = glm::length(to_first);
      const glm::dvec3 to_radar = pose.position_m - kp.last_hit_m;
      const double back_m = glm::length(to_radar);
      const glm::dvec3 s = to_radar / back_m;
      const double total_m = first_m + kp.inner_m + back_m;
      x.amplitude = times(std::complex<double>(kp.amplitude_re_m, kp.amplitude_im_m),
                          unit_phasor(-k * total_m));
      x.range_m = 0.5 * total_m;
      // Static path: d(path)/dt = -v . d1 + v . s (the radar's velocity on its two ends).
      x.radial_velocity_mps = 0.5 * (-glm::dot(v, to_first / first_m) + glm::dot(v, s));
      const AzEl ae = arrival_azel(antenna_from_world * (-s));
      x.azimuth_rad = ae.azimuth_rad;
      x.elevation_rad = ae.elevation_rad;
      set_fixed(kp, object_id, x);
    };
#if defined(RADAR_EMU_HAVE_MVEC)
    // Two kept paths at once, one a lane (D2): evaluate's operations in evaluate's order (glm's
    // length, dot, division by a scalar and matrix product written out as glm computes them),
    // so each lane is bit for bit what evaluate gives (libmvec's atan2 works lane by lane).
    const glm::dmat3& m = antenna_from_world;
    auto evaluate_pair = [&](const KeptPath& a, std::uint32_t id_a, const KeptPath& b,
                             std::uint32_t id_b, Contribution& xa, Contribution& xb) {
      const D2 px = d2(pose.position_m.x), py = d2(pose.position_m.y), pz = d2(pose.position_m.z);
      const D2 fx = d2(a.first_hit_m.x, b.first_hit_m.x) - px,
               fy = d2(a.first_hit_m.y, b.first_hit_m.y) - py,
               fz = d2(a.first_hit_m.z, b.first_hit_m.z) - pz;
      const D2 first_m = sqrt(fx * fx + fy * fy + fz * fz);
      const D2 rx = px - d2(a.last_hit_m.x, b.last_hit_m.x),
               ry = py - d2(a.last_hit_m.y, b.last_hit_m.y),
               rz = pz - d2(a.last_hit_m.z, b.last_hit_m.z);
      const D2 back_m = sqrt(rx * rx + ry * ry + rz * rz);
      const D2 sx = rx / back_m, sy = ry / back_m, sz = rz / back_m;
      const D2 total_m = first_m + d2(a.inner_m, b.inner_m) + back_m;
      // unit_phasor(-k total): sin_cos, its reduction two lanes at once.
      const D2 phase = -k * total_m;
      SinCos ua, ub;
      if (detail::sin_cos_reducible(lane0(phase)) && detail::sin_cos_reducible(lane1(phase))) {
        D2 fn{}, sn{}, cs{};
        detail::sin_cos_reduced(phase, fn, sn, cs);
        ua = detail::sin_cos_quadrant(lane0(fn), lane0(sn), lane0(cs));
        ub = detail::sin_cos_quadrant(lane1(fn), lane1(sn), lane1(cs));
      } else {
        ua = sin_cos(lane0(phase));
        ub = sin_cos(lane1(phase));
      }
      xa.amplitude = times(std::complex<double>(a.amplitude_re_m, a.amplitude_im_m),
                           std::complex<double>(ua.cos, ua.sin));
      xb.amplitude = times(std::complex<double>(b.amplitude_re_m, b.amplitude_im_m),
                           std::complex<double>(ub.cos, ub.sin));
      const D2 range_m = 0.5 * total_m;
      const D2 vx = d2(v.x), vy = d2(v.y), vz = d2(v.z);
      const D2 along_first = vx * (fx / first_m) + vy * (fy / first_m) + vz * (fz / first_m);
      const D2 along_back = vx * sx + vy * sy + vz * sz;
      const D2 radial = 0.5 * (-along_first + along_back);
      // antenna_from_world * (-s), then arrival_azel's two atan2: azimuths of both, elevations
      // of both.
      const D2 nx = -sx, ny = -sy, nz = -sz;
      const D2 dx = m[0][0] * nx + m[1][0] * ny + m[2][0] * nz;
      const D2 dy = m[0][1] * nx + m[1][1] * ny + m[2][1] * nz;
      const D2 dz = m[0][2] * nx + m[1][2] * ny + m[2][2] * nz;
      const D2 horizontal = sqrt(dx * dx + dy * dy);
      const D2 az{_ZGVbN2vv_atan2(dy.v, dx.v)};
      const D2 el{_ZGVbN2vv_atan2((-dz).v, horizontal.v)};
      xa.range_m = lane0(range_m);
      xb.range_m = lane1(range_m);
      xa.radial_velocity_mps = lane0(radial);
      xb.radial_velocity_mps = lane1(radial);
      xa.azimuth_rad = lane0(az);
      xb.azimuth_rad = lane1(az);
      xa.elevation_rad = lane0(el);
      xb.elevation_rad = lane1(el);
      set_fixed(a, id_a, xa);
      set_fixed(b, id_b, xb);
    };
#endif
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_eval, 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        std::size_t r = 0;
                        auto path = [&](std::size_t i,
                                        std::uint32_t& object_id) -> const KeptPath& {
                          while (r + 1 < kept_runs_.size() && i >= kept_runs_[r + 1].first)
                            ++r;
                          const KeptRun& run = kept_runs_[r];
                          object_id = run.object_id;
                          return kept_paths_[kept_region_[run.object_id] +
                                             run.slice * kept_slice_slots() + (i - run.first)];
                        };
                        std::size_t i = range.begin();
#if defined(RADAR_EMU_HAVE_MVEC)
                        for (; i + 1 < range.end(); i += 2) {
                          std::uint32_t id_a = 0, id_b = 0;
                          const KeptPath& a = path(i, id_a);
                          const KeptPath& b = path(i + 1, id_b);
                          evaluate_pair(a, id_a, b, id_b, out[n + i], out[n + i + 1]);
                        }
#endif
                        for (; i < range.end(); ++i) {
                          std::uint32_t id = 0;
                          const KeptPath& kp = path(i, id);
                          evaluate(kp, id, out[n + i]);
                        }
                      });
    n += n_eval;
  }
  // Then the bounce-1 terms (each appended while there is room, else counted as dropped): the
  // lit and partly lit facets, in object and triangle order.
  auto append = [&](const Contribution& x) {
    if (n < out.size())
      out[n++] = x;
    else
      ++stats.dropped_contributions;
  };
  for (const Bundle& bd : bundles_) {
    for (std::size_t f = facet_first_[bd.object_id]; f < facet_first_[bd.object_id + 1]; ++f) {
      if (facet_light_[f] != static_cast<std::uint8_t>(FacetLight::kLit) &&
          facet_light_[f] != static_cast<std::uint8_t>(FacetLight::kPartial))
        continue;
      append(facet_out_[f]);
    }
  }
  // Then the edges that radiate, in object and edge order.
  if (c.edges) {
    for (const Bundle& bd : bundles_) {
      for (std::size_t e = edge_first_[bd.object_id]; e < edge_first_[bd.object_id + 1]; ++e) {
        stats.edges_shadowed += edge_state_[e] == 1 ? 1u : 0u;
        stats.edges_skipped += edge_state_[e] == 2 ? 1u : 0u;
        if (edge_state_[e] != 0)
          continue;
        ++stats.edges_used;
        append(edge_out_[e]);
      }
      for (std::size_t p = pair_first_[bd.object_id]; p < pair_first_[bd.object_id + 1]; ++p) {
        if (pair_used_[p] == 0)
          continue;
        ++stats.edges_double;
        append(pair_out_[p]);
      }
    }
    stats.facet_queries += edge_queries.load();
  }
  stats.contributions += n;
  return n;
}

}  // namespace radar_emu::radar
