#include "scene/scene.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

#include "scene/trajectory.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

// Structure of the acceleration:
//   static_scene: one Embree triangle geometry per static object, vertices pre-transformed to
//                 world; built once at construction, never touched again.
//   one Embree scene per moving object, in its body frame; built once. A query transforms the
//                 ray into each moving object's body frame (in double; only for objects whose
//                 world box at the current time the ray crosses before its best hit so far) and
//                 traverses that BVH.
// set_time() therefore only updates our double-precision transforms and boxes: no Embree commit
// in the frame path. (Embree instancing was the first design, but with Embree 3.13 every
// rtcCommitScene() of the top level allocates on the heap (std::string, 1 to 7 per commit
// depending on the scene flags, measured) and runs TBB tasks, which breaks "nothing in the frame
// path allocates"; with a handful of moving objects the explicit loop is as fast.)
//
// Embree traverses in float; every hit is then refined in double precision from the triangle's
// world-space vertices (Moller-Trumbore), so ranges and positions are exact to double rounding
// of the stored float vertices, whatever the traversal's float error at 20 km.
//
// Levels of detail: terrain tiles (LOD groups) are static geometries too, but in one more BVH per
// level (level_scenes[L] holds level L of every tile), built once. Each LOD geometry carries an
// Embree intersection and occlusion filter whose user pointer is that object's byte in
// `object_active`; set_view() writes those bytes, and the filter rejects candidate hits on
// inactive geometries, so traversal continues to the active level behind. Switching levels is
// then a byte store: no rebuild, no commit, no allocation. Geometries outside LOD groups carry no
// filter and cost nothing extra. One BVH per level keeps the levels' overlapping surfaces out of
// each other's traversal: a query skips the BVH of a level that no tile uses, and clips each
// level's ray interval to the ranges from the radar where that level's active tiles lie
// (set_view: [nearest, farthest] over their boxes; for a ray starting at distance d from the
// radar, widened by d either side, by the triangle inequality).

namespace radar_emu::scene {

namespace {

constexpr unsigned kInvalidId = RTC_INVALID_GEOMETRY_ID;

// Every BVH: robust mode, whose traversal is watertight. Embree's fast mode answers the same
// queries about 1.35 times sooner but lets a grazing ray through the edge two triangles share:
// in the default frame one of 221,383 closest-hit queries met a surface 2.8 m behind the one it
// should have (bench_frame BM_TraceRaw, fast_differs). High build quality: a BVH built once.
constexpr RTCSceneFlags kSceneFlags = RTC_SCENE_FLAG_ROBUST;
constexpr RTCBuildQuality kBuildQuality = RTC_BUILD_QUALITY_HIGH;

// Embree reports errors through a callback, possibly from several threads at once: keep the
// first message in a fixed buffer (no allocation, no data race) and count them all.
struct ErrorSink {
  std::atomic<unsigned> count{0};
  std::atomic<bool> message_ready{false};
  char message[256] = {};
};

void device_error(void* user, RTCError code, const char* message) noexcept {
  auto* sink = static_cast<ErrorSink*>(user);
  if (sink->count.fetch_add(1, std::memory_order_acq_rel) == 0) {
    std::snprintf(sink->message, sizeof sink->message, "Embree error %d: %s",
                  static_cast<int>(code), message ? message : "(no message)");
    sink->message_ready.store(true, std::memory_order_release);
  }
}

bool finite(const glm::dvec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool finite(const glm::dmat4& m) noexcept {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[c][r]))
        return false;
    }
  }
  return true;
}

// World from body of a moving object at time t: origin at start + v t, body +x along the
// horizontal velocity (yaw about up; no pitch or roll). A vertical or zero velocity keeps yaw 0.
glm::dmat4 moving_transform(const LinearMotion& m, double t_s) noexcept {
  const double vh = std::hypot(m.velocity_mps.x, m.velocity_mps.y);
  const double c = vh > 0.0 ? m.velocity_mps.x / vh : 1.0;
  const double s = vh > 0.0 ? m.velocity_mps.y / vh : 0.0;
  glm::dmat4 x(1.0);
  x[0] = glm::dvec4(c, s, 0.0, 0.0);
  x[1] = glm::dvec4(-s, c, 0.0, 0.0);
  x[3] = glm::dvec4(m.start_position_m + m.velocity_mps * t_s, 1.0);
  return x;
}

// Embree filter for LOD geometries: rejects every candidate hit while the object is inactive.
// `geometryUserPtr` points at the object's byte in Impl::object_active (set at setup, never
// moved). Called from query threads; set_view() writes the bytes between frames only.
void lod_filter(const RTCFilterFunctionNArguments* args) noexcept {
  const auto* active = static_cast<const std::uint8_t*>(args->geometryUserPtr);
  if (active != nullptr && *active != 0)
    return;
  for (unsigned i = 0; i < args->N; ++i)
    args->valid[i] = 0;
}

// Our ray in Embree's float layout. Returns false for rays Embree must not see (non-finite
// values, empty interval).
bool to_embree(const Ray& ray, RTCRay& r) noexcept {
  if (!finite(ray.origin_m) || !finite(ray.direction) || std::isnan(ray.t_near_m) ||
      std::isnan(ray.t_far_m) || !(ray.t_far_m >= ray.t_near_m)) {
    return false;
  }
  constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
  const float tnear = static_cast<float>(std::clamp(ray.t_near_m, 0.0, kFloatMax));
  const float tfar = ray.t_far_m >= kFloatMax ? std::numeric_limits<float>::infinity()
                                              : static_cast<float>(std::max(ray.t_far_m, 0.0));
#if defined(__SSE2__)
  // Each 16-byte row (origin + tnear, direction + time, tfar + mask + id + flags) as one store:
  // Embree loads the rows as 16-byte vectors, which a store-to-load forward serves only from a
  // store that covers them (scalar stores make each query wait for them to retire).
  _mm_storeu_ps(&r.org_x,
                _mm_setr_ps(static_cast<float>(ray.origin_m.x), static_cast<float>(ray.origin_m.y),
                            static_cast<float>(ray.origin_m.z), tnear));
  _mm_storeu_ps(&r.dir_x, _mm_setr_ps(static_cast<float>(ray.direction.x),
                                      static_cast<float>(ray.direction.y),
                                      static_cast<float>(ray.direction.z), 0.0f));
  _mm_storeu_ps(&r.tfar, _mm_castsi128_ps(_mm_setr_epi32(std::bit_cast<int>(tfar), -1, 0, 0)));
#else
  r.org_x = static_cast<float>(ray.origin_m.x);
  r.org_y = static_cast<float>(ray.origin_m.y);
  r.org_z = static_cast<float>(ray.origin_m.z);
  r.dir_x = static_cast<float>(ray.direction.x);
  r.dir_y = static_cast<float>(ray.direction.y);
  r.dir_z = static_cast<float>(ray.direction.z);
  r.tnear = tnear;
  r.tfar = tfar;
  r.time = 0.0f;
  r.mask = 0xFFFFFFFFu;
  r.id = 0;
  r.flags = 0;
#endif
  return true;
}

// The box [lo, hi] padded by a relative 1e-6 (ray_crosses_box). One square root: the larger of
// the two squared lengths first (sqrt is monotonic and correctly rounded, so this is exactly
// max(|lo|, |hi|)).
PaddedBox pad(const glm::dvec3& lo, const glm::dvec3& hi) noexcept {
  const double margin_m = 1e-6 * (1.0 + std::sqrt(std::max(glm::dot(lo, lo), glm::dot(hi, hi))));
  return {lo - margin_m, hi + margin_m};
}

// Does the ray cross the padded box somewhere in [t0, t1]? (ray_crosses_box)
bool crosses_box(const Ray& ray, const PaddedBox& box, double t0, double t1) noexcept {
  for (glm::length_t k = 0; k < 3; ++k) {
    const double o = ray.origin_m[k], d = ray.direction[k];
    const double a = box.lo_m[k], b = box.hi_m[k];
    if (d == 0.0) {
      if (o < a || o > b)
        return false;
      continue;
    }
    double ta = (a - o) / d, tb = (b - o) / d;
    if (ta > tb)
      std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1)
      return false;
  }
  return true;
}

// The ray in a moving object's body frame (rotation about up + translation: distances and so t
// are unchanged). `world` is the Embree ray already built from `ray` (tnear, tfar, mask).
void to_body(const Ray& ray, const glm::dmat4& world_from_body, const RTCRay& world,
             RTCRay& body) noexcept {
  const glm::dmat3 r(world_from_body);
  const glm::dmat3 rt = glm::transpose(r);  // orthonormal: inverse = transpose
  const glm::dvec3 o = rt * (ray.origin_m - glm::dvec3(world_from_body[3]));
  const glm::dvec3 d = rt * ray.direction;
  body = world;
  body.org_x = static_cast<float>(o.x);
  body.org_y = static_cast<float>(o.y);
  body.org_z = static_cast<float>(o.z);
  body.dir_x = static_cast<float>(d.x);
  body.dir_y = static_cast<float>(d.y);
  body.dir_z = static_cast<float>(d.z);
}

}  // namespace

namespace {

// The view volume as four half-spaces through the antenna plus a range sphere (Scene::set_view).
struct Frustum {
  glm::dvec3 apex_m{0.0};
  std::array<glm::dvec3, 4> inward{};  // world normals; inside: dot(n, p - apex) >= 0
  double max_range_m = 0.0;

  // False only when the box [lo, hi] is certainly outside: entirely behind one plane, or all
  // of it beyond the range.
  [[nodiscard]] bool meets(const glm::dvec3& lo, const glm::dvec3& hi) const noexcept {
    const glm::dvec3 c = 0.5 * (lo + hi) - apex_m, e = 0.5 * (hi - lo);
    const double tol = 1e-9 * (1.0 + glm::length(c) + glm::length(e));
    for (const glm::dvec3& n : inward) {
      if (glm::dot(n, c) + glm::dot(glm::abs(n), e) < -tol)
        return false;
    }
    return glm::length(glm::clamp(apex_m, lo, hi) - apex_m) <= max_range_m * (1.0 + 1e-12);
  }
};

bool valid_view(const ViewVolume& v) noexcept {
  constexpr double kHalfPi = 0.5 * std::numbers::pi;
  if (!finite(v.position_m))
    return false;
  for (int c = 0; c < 3; ++c) {
    if (!finite(v.world_from_antenna[c]))
      return false;
  }
  // A rotation: columns orthonormal.
  const glm::dmat3 rtr = glm::transpose(v.world_from_antenna) * v.world_from_antenna;
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) {
      if (std::abs(rtr[c][r] - (c == r ? 1.0 : 0.0)) > 1e-6)
        return false;
    }
  }
  auto in_range = [&](double lo, double hi) {
    return std::isfinite(lo) && std::isfinite(hi) && lo > -kHalfPi && hi < kHalfPi && lo < hi;
  };
  return in_range(v.azimuth_min_rad, v.azimuth_max_rad) &&
         in_range(v.elevation_min_rad, v.elevation_max_rad) && std::isfinite(v.max_range_m) &&
         v.max_range_m > 0.0 && std::isfinite(v.range_cell_m) && v.range_cell_m > 0.0 &&
         std::isfinite(v.angular_cell_rad) && v.angular_cell_rad >= 0.0;
}

// Bounding half-spaces of the field of view, antenna frame (x boresight, y right, z down;
// azimuth a = atan2(y, x), elevation e = atan2(-z, rho), rho = hypot(x, y)).
//   a >= a0  <=>  y cos a0 - x sin a0 >= 0;   a <= a1  <=>  x sin a1 - y cos a1 >= 0 (exact; the
//   two planes contain the z axis and, with a1 - a0 < pi, bound one wedge).
//   e <= e1  <=>  -z <= rho tan e1, a cone. Within the wedge, with ac and hw the centre and half
//   width of the azimuth span and x' = x cos ac + y sin ac = rho cos(a - ac), rho lies in
//   [x', x' / cos hw]; so for tan e1 >= 0 the cone's inside lies in -z <= x' tan e1 / cos hw,
//   and for tan e1 < 0 in -z <= x' tan e1. Likewise e >= e0 lies in -z >= x' k0 with
//   k0 = tan e0 / cos hw (tan e0 <= 0) or tan e0 (tan e0 > 0). Every point of the field of view
//   is inside all four planes: the test can keep too much, never too little.
Frustum make_frustum(const ViewVolume& v) noexcept {
  Frustum f;
  f.apex_m = v.position_m;
  f.max_range_m = v.max_range_m;
  const double a0 = v.azimuth_min_rad, a1 = v.azimuth_max_rad;
  const double ac = 0.5 * (a0 + a1), hw = 0.5 * (a1 - a0);
  const double t1 = std::tan(v.elevation_max_rad), t0 = std::tan(v.elevation_min_rad);
  const double k1 = t1 >= 0.0 ? t1 / std::cos(hw) : t1;
  const double k0 = t0 <= 0.0 ? t0 / std::cos(hw) : t0;
  const glm::dvec3 xp(std::cos(ac), std::sin(ac), 0.0);  // x' direction
  const std::array<glm::dvec3, 4> antenna = {
      glm::dvec3(-std::sin(a0), std::cos(a0), 0.0),  // a >= a0
      glm::dvec3(std::sin(a1), -std::cos(a1), 0.0),  // a <= a1
      k1 * xp + glm::dvec3(0.0, 0.0, 1.0),           // e <= e1: k1 x' + z >= 0
      -k0 * xp - glm::dvec3(0.0, 0.0, 1.0),          // e >= e0: -z - k0 x' >= 0
  };
  for (std::size_t i = 0; i < 4; ++i)
    f.inward[i] = v.world_from_antenna * antenna[i];
  return f;
}

// Longest edge of any triangle of `mesh` placed by `xf` [m].
double longest_edge_m(const Mesh& mesh, const glm::dmat4& xf) {
  double longest = 0.0;
  for (const glm::uvec3& t : mesh.triangles) {
    const glm::dvec3 a(xf * glm::dvec4(glm::dvec3(mesh.positions_m[t.x]), 1.0));
    const glm::dvec3 b(xf * glm::dvec4(glm::dvec3(mesh.positions_m[t.y]), 1.0));
    const glm::dvec3 c(xf * glm::dvec4(glm::dvec3(mesh.positions_m[t.z]), 1.0));
    longest = std::max({longest, glm::length(b - a), glm::length(c - b), glm::length(a - c)});
  }
  return longest;
}

}  // namespace

struct Scene::Impl {
  struct Mover {
    RTCScene scene = nullptr;  // body-frame BVH
    std::uint32_t object = 0;
    std::int32_t path = -1;  // index into `paths`; -1: LinearMotion
    // Body-frame box (trajectories: the world box is the rotated box's box).
    glm::dvec3 body_centre_m{0.0};
    glm::dvec3 body_half_m{0.0};
  };
  struct LodMember {
    std::uint32_t object = 0;
    std::uint8_t level = 0;
    double facet_m = 0.0;
  };
  // One terrain tile: its levels are lod_members[first, first + count), finest first.
  struct LodGroup {
    std::int32_t id = -1;
    std::uint32_t first = 0, count = 0;
    glm::dvec3 lo_m{0.0}, hi_m{0.0};  // world box over every level
    std::uint64_t triangles = 0;      // of the active level
    int active = 0;                   // index within the group, -1: culled
  };

  SceneDescription desc;
  std::vector<ObjectState> states;
  std::vector<glm::dmat4> world_from_body;  // current, per object
  // Per object: its current world box padded as ray_crosses_box pads it (kept for the movers,
  // whose boxes every query tests: refresh_padded_bounds after each move).
  std::vector<PaddedBox> padded_bounds;
  // Per object: 1 when world_from_body is the identity (static objects placed in world), so the
  // refit (finish_intersect) takes the mesh's vertices as they are; kept with padded_bounds.
  std::vector<std::uint8_t> identity_placement;
  // Per triangle of every static object (movers excluded: their placement changes), what the
  // refit (finish_intersect) needs of it in world space: its first vertex, its two edges from
  // it and its unit normal as wound, computed once at setup by the same operations the refit
  // would apply per hit (so bit for bit the same values), 96 bytes a triangle. Object id's
  // triangles start at static_first[id] (kNoTriangles: a mover).
  struct WorldTriangle {
    glm::dvec3 a_m{0.0}, e1_m{0.0}, e2_m{0.0}, normal{0.0};
  };
  static constexpr std::size_t kNoTriangles = std::numeric_limits<std::size_t>::max();
  std::vector<WorldTriangle> static_triangles;
  std::vector<std::size_t> static_first;
  // The world-space triangle of an object's mesh (the refit's vertices: float mesh positions,
  // placed in double unless the placement is the identity) and its unit normal as wound.
  static WorldTriangle world_triangle(const ObjectDesc& o, const glm::dmat4& x, bool identity,
                                      unsigned prim) noexcept {
    const glm::uvec3 tri = o.mesh.triangles[prim];
    glm::dvec3 a(o.mesh.positions_m[tri.x]), b(o.mesh.positions_m[tri.y]),
        c(o.mesh.positions_m[tri.z]);
    if (!identity) {
      a = glm::dvec3(x * glm::dvec4(a, 1.0));
      b = glm::dvec3(x * glm::dvec4(b, 1.0));
      c = glm::dvec3(x * glm::dvec4(c, 1.0));
    }
    WorldTriangle w;
    w.a_m = a;
    w.e1_m = b - a;
    w.e2_m = c - a;
    const glm::dvec3 n = glm::cross(w.e1_m, w.e2_m);  // as wound: counter-clockwise = outside
    const double len = glm::length(n);
    w.normal = len > 0.0 ? n / len : glm::dvec3(0.0, 0.0, 1.0);
    return w;
  }
  void prepare_static_triangles() {
    static_first.assign(states.size(), kNoTriangles);
    std::size_t n = 0;
    for (std::size_t id = 0; id < states.size(); ++id) {
      if (!states[id].moving) {
        static_first[id] = n;
        n += desc.objects[id].mesh.triangles.size();
      }
    }
    static_triangles.resize(n);
    for (std::size_t id = 0; id < states.size(); ++id) {
      if (static_first[id] == kNoTriangles)
        continue;
      const ObjectDesc& o = desc.objects[id];
      for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t)
        static_triangles[static_first[id] + t] = world_triangle(
            o, world_from_body[id], identity_placement[id] != 0, static_cast<unsigned>(t));
    }
  }
  void refresh_padded_bounds() noexcept {
    for (const Mover& mv : movers) {
      padded_bounds[mv.object] =
          pad(states[mv.object].bounds_min_m, states[mv.object].bounds_max_m);
      identity_placement[mv.object] = world_from_body[mv.object] == glm::dmat4(1.0) ? 1 : 0;
    }
  }
  std::vector<glm::dvec3> bounds_min_at_zero_m;  // world bounds at t = 0, per object
  std::vector<glm::dvec3> bounds_max_at_zero_m;
  std::vector<std::uint32_t> object_of_static_geometry;  // static_scene geomID -> object id
  // One BVH per LOD level (index = level; scene null when no tile has that level).
  struct LevelBvh {
    RTCScene scene = nullptr;
    std::vector<std::uint32_t> object_of_geometry;  // geomID -> object id
    std::uint32_t active_tiles = 0;                 // tiles whose active level this is
    double near_m = 0.0;  // active tiles' boxes lie between these distances from view_position
    double far_m = std::numeric_limits<double>::infinity();
  };
  std::vector<LevelBvh> level_scenes;
  glm::dvec3 view_position_m{0.0};
  bool view_bands = false;  // near_m/far_m valid (set_view); false: every ray's whole interval
  std::vector<Mover> movers;
  std::vector<TrajectoryPath> paths;
  std::vector<LodGroup> groups;  // by ascending id
  std::vector<LodMember> lod_members;
  std::vector<std::int32_t> group_of_object;  // index into groups, -1: not in a LOD group
  // Per object, 1 = queries may hit it. The LOD filter's user pointers point into it: sized once
  // at setup, never resized.
  std::vector<std::uint8_t> object_active;
  ViewStats view;
  ErrorSink errors;
  RTCDevice device = nullptr;
  RTCScene static_scene = nullptr;  // null when every object moves
  double time_s = 0.0;
  std::size_t triangles = 0;
  std::uint64_t static_builds = 0;
  std::uint64_t embree_commits = 0;

  // The parts of a query after the static BVH (defined with the queries below).
  bool finish_intersect(const Ray& ray, RTCRayHit& rh, Hit& hit) const noexcept;
  bool occluded_beyond_static(const Ray& ray, const RTCRay& r) const noexcept;
  // Batched occlusion of n rays, ray_at(i) the i-th, kStreamChunk at a time: the static BVH,
  // then each level of detail, then each moving object (in its body frame), each as one coherent
  // stream of the rays not blocked yet that can reach it.
  // `split` (optional, per ray): ask everything but the moving object split[i]
  // (MoverSplit::kRest) or that object alone (kOwn); kNoMover: everything.
  template <class RayAt>
  void occluded_batch(std::size_t n, const RayAt& ray_at, std::span<std::uint8_t> blocked,
                      const std::uint32_t* split = nullptr,
                      MoverSplit mode = MoverSplit::kRest) const noexcept;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    for (const Mover& m : movers)
      rtcReleaseScene(m.scene);
    if (static_scene)
      rtcReleaseScene(static_scene);
    for (const LevelBvh& l : level_scenes) {
      if (l.scene)
        rtcReleaseScene(l.scene);
    }
    if (device)
      rtcReleaseDevice(device);
  }

  [[noreturn]] void fail(const std::string& what) const {
    std::string detail;
    if (errors.message_ready.load(std::memory_order_acquire))
      detail = std::string(" (") + errors.message + ")";
    throw std::runtime_error("scene: " + what + detail);
  }

  void check(const std::string& what) const {
    if (errors.count.load(std::memory_order_acquire) != 0)
      fail(what);
  }
  void validate() const {
    if (desc.objects.empty())
      fail("the scene has no objects");
    if (desc.materials.empty())
      fail("the scene has no materials");
    if (desc.objects.size() >= kInvalidId)
      fail("too many objects");
    for (const ObjectDesc& o : desc.objects) {
      const Mesh& m = o.mesh;
      const std::string who = "object '" + o.name + "'";
      if (m.triangles.empty())
        fail(who + " has no triangles");
      if (m.triangle_material.size() != m.triangles.size()) {
        fail(who + ": " + std::to_string(m.triangle_material.size()) + " material indices for " +
             std::to_string(m.triangles.size()) + " triangles");
      }
      if (m.positions_m.size() >= kInvalidId || m.triangles.size() >= kInvalidId)
        fail(who + " has too many vertices or triangles");
      if (o.motion && o.trajectory)
        fail(who + " has both a linear motion and a trajectory");
      if (o.motion) {
        if (!finite(o.motion->start_position_m) || !finite(o.motion->velocity_mps))
          fail(who + ": the motion's start position or velocity is not finite");
      } else if (!o.trajectory && !finite(o.world_from_body)) {
        fail(who + ": world_from_body is not finite");
      }
      if (o.lod_group < -1)
        fail(who + ": lod_group " + std::to_string(o.lod_group) + " (expected -1 or >= 0)");
      if (o.lod_group >= 0 && (o.motion || o.trajectory))
        fail(who + ": a LOD tile (lod_group " + std::to_string(o.lod_group) + ") cannot move");
      if (!std::isfinite(o.lod_facet_m) || o.lod_facet_m < 0.0)
        fail(who + ": lod_facet_m must be a finite number >= 0");
      for (std::size_t i = 0; i < m.positions_m.size(); ++i) {
        const glm::vec3& p = m.positions_m[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
          fail(who + ": vertex " + std::to_string(i) + " is not finite");
      }
      bool any_area = false;
      const std::size_t n = m.positions_m.size();
      for (std::size_t i = 0; i < m.triangles.size(); ++i) {
        const glm::uvec3 t = m.triangles[i];
        if (t.x >= n || t.y >= n || t.z >= n) {
          fail(who + ": triangle " + std::to_string(i) + " indexes vertex " +
               std::to_string(std::max({t.x, t.y, t.z})) + ", beyond the " + std::to_string(n) +
               " vertices");
        }
        if (m.triangle_material[i] >= desc.materials.size()) {
          fail(who + ": triangle " + std::to_string(i) + " has material index " +
               std::to_string(m.triangle_material[i]) + " but there are only " +
               std::to_string(desc.materials.size()) + " materials");
        }
        const glm::dvec3 a(m.positions_m[t.x]), b(m.positions_m[t.y]), c(m.positions_m[t.z]);
        const glm::dvec3 cr = glm::cross(b - a, c - a);
        any_area = any_area || glm::dot(cr, cr) > 0.0;
      }
      if (!any_area)
        fail(who + " has only degenerate (zero-area) triangles");
    }
  }

  // One Embree triangle geometry; vertices transformed by `xf` (world from body for static
  // objects, identity for the body-frame mesh of a moving object). `active_flag` (LOD objects):
  // the byte the LOD filter reads.
  RTCGeometry make_mesh(const Mesh& mesh, const glm::dmat4& xf,
                        const std::uint8_t* active_flag = nullptr) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g)
      fail("cannot create a triangle geometry");
    auto* v =
        static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                    3 * sizeof(float), mesh.positions_m.size()));
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                mesh.triangles.size()));
    if (!v || !idx) {
      rtcReleaseGeometry(g);
      fail("cannot allocate geometry buffers");
    }
    for (std::size_t i = 0; i < mesh.positions_m.size(); ++i) {
      const glm::dvec3 p(xf * glm::dvec4(glm::dvec3(mesh.positions_m[i]), 1.0));
      v[3 * i + 0] = static_cast<float>(p.x);
      v[3 * i + 1] = static_cast<float>(p.y);
      v[3 * i + 2] = static_cast<float>(p.z);
    }
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      idx[3 * i + 0] = mesh.triangles[i].x;
      idx[3 * i + 1] = mesh.triangles[i].y;
      idx[3 * i + 2] = mesh.triangles[i].z;
    }
    if (active_flag != nullptr) {
      // Embree keeps the pointer as opaque user data; the filter only reads through it.
      rtcSetGeometryUserData(g, const_cast<std::uint8_t*>(active_flag));
      rtcSetGeometryIntersectFilterFunction(g, lod_filter);
      rtcSetGeometryOccludedFilterFunction(g, lod_filter);
    }
    rtcCommitGeometry(g);
    return g;
  }

  RTCScene new_scene() {
    RTCScene s = rtcNewScene(device);
    if (!s)
      fail("cannot create an Embree scene");
    rtcSetSceneFlags(s, kSceneFlags);
    rtcSetSceneBuildQuality(s, kBuildQuality);
    return s;
  }

  void world_bounds(std::size_t id, glm::dvec3& lo, glm::dvec3& hi) const {
    lo = glm::dvec3(std::numeric_limits<double>::max());
    hi = glm::dvec3(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : desc.objects[id].mesh.positions_m) {
      const glm::dvec3 w(world_from_body[id] * glm::dvec4(glm::dvec3(p), 1.0));
      lo = glm::min(lo, w);
      hi = glm::max(hi, w);
    }
  }

  void commit(RTCScene scene, const std::string& what) {
    rtcCommitScene(scene);
    ++embree_commits;
    check("building the BVH of " + what + " failed");
  }

  // The ray `in` (Embree layout, tfar = best hit so far) restricted to where level `l` can be
  // hit; false when there is nothing to query (no BVH, no tile at this level, empty interval).
  // Distances become ray parameters through the direction's length (1 for unit directions).
  // The bounds are padded (relative 1e-5, absolute 1 cm, far above float traversal error) so
  // that rounding never clips a hit inside a tile's box.
  bool level_ray(const LevelBvh& l, const RTCRay& in, double origin_offset_m,
                 double direction_length, RTCRay& out) const noexcept {
    if (!l.scene || l.active_tiles == 0)
      return false;
    out = in;
    if (view_bands && direction_length > 0.0) {
      const double lo = ((l.near_m - origin_offset_m) * (1.0 - 1e-5) - 1e-2) / direction_length;
      const double hi = ((l.far_m + origin_offset_m) * (1.0 + 1e-5) + 1e-2) / direction_length;
      if (lo > 0.0)
        out.tnear = std::max(out.tnear, static_cast<float>(lo));
      if (hi < static_cast<double>(out.tfar))
        out.tfar = static_cast<float>(hi);
      if (!(out.tnear <= out.tfar))
        return false;
    }
    return true;
  }

  // Trajectories (validated with the object's name) and LOD groups (levels unique per group,
  // finest first), before any Embree object exists.
  void prepare() {
    const std::size_t n = desc.objects.size();
    std::size_t trajectories = 0;
    for (const ObjectDesc& o : desc.objects)
      trajectories += o.trajectory ? 1u : 0u;
    paths.reserve(trajectories);
    std::map<std::int32_t, std::vector<std::uint32_t>> members;
    for (std::size_t id = 0; id < n; ++id) {
      const ObjectDesc& o = desc.objects[id];
      if (o.trajectory) {
        try {
          paths.emplace_back(*o.trajectory);
        } catch (const std::invalid_argument& e) {
          fail("object '" + o.name + "': " + e.what());
        }
      }
      if (o.lod_group >= 0)
        members[o.lod_group].push_back(static_cast<std::uint32_t>(id));
    }
    group_of_object.assign(n, -1);
    object_active.assign(n, 1);
    for (auto& [id, objects] : members) {
      std::sort(objects.begin(), objects.end(), [&](std::uint32_t a, std::uint32_t b) {
        return desc.objects[a].lod_level < desc.objects[b].lod_level;
      });
      LodGroup g;
      g.id = id;
      g.first = static_cast<std::uint32_t>(lod_members.size());
      g.count = static_cast<std::uint32_t>(objects.size());
      for (std::size_t k = 0; k < objects.size(); ++k) {
        const ObjectDesc& o = desc.objects[objects[k]];
        if (k > 0 && desc.objects[objects[k - 1]].lod_level == o.lod_level) {
          fail("object '" + o.name + "': LOD group " + std::to_string(id) +
               " already has a mesh at level " + std::to_string(o.lod_level) + " ('" +
               desc.objects[objects[k - 1]].name + "')");
        }
        const double facet =
            o.lod_facet_m > 0.0 ? o.lod_facet_m : longest_edge_m(o.mesh, o.world_from_body);
        lod_members.push_back({objects[k], o.lod_level, facet});
        group_of_object[objects[k]] = static_cast<std::int32_t>(groups.size());
      }
      groups.push_back(g);
    }
  }

  // Trajectory movers: position, velocity, orientation and the world box of the rotated body
  // box (centre R c + p, half extents |R| h: Arvo, "Transforming axis-aligned bounding boxes",
  // Graphics Gems, 1990).
  void place_on_path(const Mover& mv, double t_s) noexcept {
    const TrajectorySample p = paths[static_cast<std::size_t>(mv.path)].at(t_s);
    glm::dmat4 x(p.world_from_body);
    x[3] = glm::dvec4(p.position_m, 1.0);
    world_from_body[mv.object] = x;
    const glm::dmat3& r = p.world_from_body;
    const glm::dmat3 abs_r(glm::abs(r[0]), glm::abs(r[1]), glm::abs(r[2]));
    const glm::dvec3 c = r * mv.body_centre_m + p.position_m, h = abs_r * mv.body_half_m;
    ObjectState& st = states[mv.object];
    st.bounds_min_m = c - h;
    st.bounds_max_m = c + h;
    st.velocity_mps = p.velocity_mps;
  }

  // Activity flags for the default view: everything outside LOD groups, finest level of each
  // tile.
  void default_view() noexcept {
    std::fill(object_active.begin(), object_active.end(), std::uint8_t{1});
    view_bands = false;
    for (LevelBvh& l : level_scenes)
      l.active_tiles = 0;
    for (LodGroup& g : groups) {
      g.active = 0;
      for (std::uint32_t k = 0; k < g.count; ++k)
        object_active[lod_members[g.first + k].object] = k == 0 ? 1 : 0;
      ++level_scenes[lod_members[g.first].level].active_tiles;
    }
    for (std::size_t i = 0; i < states.size(); ++i)
      states[i].active = object_active[i] != 0;
    view.lod_groups_in_view = 0;
    view.lod_groups_culled = 0;
    view.lod_groups_at_level = {};
    view.objects_in_view = 0;
    view.triangles_in_view = 0;
    view.triangles_active = 0;
    for (std::size_t i = 0; i < states.size(); ++i)
      view.triangles_active += object_active[i] ? states[i].triangle_count : 0;
    for (const LodGroup& g : groups)
      ++view.lod_groups_at_level[std::min<std::size_t>(lod_members[g.first].level, 3)];
  }

  void build() {
    const std::size_t n = desc.objects.size();
    states.resize(n);
    world_from_body.resize(n);
    bounds_min_at_zero_m.resize(n);
    bounds_max_at_zero_m.resize(n);
    prepare();
    std::size_t next_path = 0;
    for (std::size_t id = 0; id < n; ++id) {
      const ObjectDesc& o = desc.objects[id];
      ObjectState& s = states[id];
      s.name = o.name;
      s.moving = o.motion.has_value() || o.trajectory.has_value();
      s.velocity_mps = o.motion ? o.motion->velocity_mps : glm::dvec3(0.0);
      s.triangle_count = o.mesh.triangles.size();
      triangles += o.mesh.triangles.size();
      const auto object_id = static_cast<std::uint32_t>(id);
      if (o.motion || o.trajectory) {
        Mover mv;
        mv.object = object_id;
        if (o.trajectory) {
          mv.path = static_cast<std::int32_t>(next_path++);
          glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-lo);
          for (const glm::vec3& p : o.mesh.positions_m) {
            lo = glm::min(lo, glm::dvec3(p));
            hi = glm::max(hi, glm::dvec3(p));
          }
          mv.body_centre_m = 0.5 * (lo + hi);
          mv.body_half_m = 0.5 * (hi - lo);
          world_from_body[id] = glm::dmat4(1.0);  // placed below, after the BVH
        } else {
          world_from_body[id] = moving_transform(*o.motion, 0.0);
        }
        mv.scene = new_scene();
        movers.push_back(mv);
        RTCGeometry mesh = make_mesh(o.mesh, glm::dmat4(1.0));
        rtcAttachGeometryByID(movers.back().scene, mesh, 0);
        rtcReleaseGeometry(mesh);
        commit(movers.back().scene, "object '" + o.name + "'");
      } else {
        world_from_body[id] = o.world_from_body;
        const bool lod = o.lod_group >= 0;
        if (lod && level_scenes.size() <= o.lod_level)
          level_scenes.resize(std::size_t{o.lod_level} + 1);
        RTCScene& target = lod ? level_scenes[o.lod_level].scene : static_scene;
        std::vector<std::uint32_t>& ids =
            lod ? level_scenes[o.lod_level].object_of_geometry : object_of_static_geometry;
        if (!target)
          target = new_scene();
        RTCGeometry mesh = make_mesh(o.mesh, o.world_from_body, lod ? &object_active[id] : nullptr);
        const unsigned geom = rtcAttachGeometry(target, mesh);
        rtcReleaseGeometry(mesh);
        if (ids.size() <= geom)
          ids.resize(geom + 1, kInvalidId);
        ids[geom] = object_id;
      }
      check("adding object '" + o.name + "' failed");
      world_bounds(id, bounds_min_at_zero_m[id], bounds_max_at_zero_m[id]);
      s.bounds_min_m = bounds_min_at_zero_m[id];
      s.bounds_max_m = bounds_max_at_zero_m[id];
      if (o.trajectory)
        place_on_path(movers.back(), 0.0);
    }
    if (static_scene)
      commit(static_scene, "the static geometry");
    for (std::size_t l = 0; l < level_scenes.size(); ++l) {
      if (level_scenes[l].scene)
        commit(level_scenes[l].scene, "LOD level " + std::to_string(l));
    }
    if (static_scene || !level_scenes.empty())
      ++static_builds;
    for (LodGroup& g : groups) {
      g.lo_m = glm::dvec3(std::numeric_limits<double>::max());
      g.hi_m = -g.lo_m;
      for (std::uint32_t k = 0; k < g.count; ++k) {
        const std::uint32_t obj = lod_members[g.first + k].object;
        g.lo_m = glm::min(g.lo_m, states[obj].bounds_min_m);
        g.hi_m = glm::max(g.hi_m, states[obj].bounds_max_m);
      }
    }
    view.lod_groups = static_cast<std::uint32_t>(groups.size());
    view.triangles_total = triangles;
    default_view();
  }
};

EmbreeBuild embree_build() noexcept {
  return {static_cast<int>(kSceneFlags), static_cast<int>(kBuildQuality)};
}

Scene::Scene(SceneDescription description) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.desc = std::move(description);
  m.validate();
  // Default device: one build thread per core at setup; queries run on the caller's threads.
  m.device = rtcNewDevice(nullptr);
  if (!m.device) {
    throw std::runtime_error("scene: cannot create the Embree device (error " +
                             std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
  }
  rtcSetDeviceErrorFunction(m.device, device_error, &m.errors);
  m.build();
  m.padded_bounds.assign(m.states.size(), PaddedBox{});
  m.identity_placement.resize(m.states.size());
  for (std::size_t id = 0; id < m.states.size(); ++id)
    m.identity_placement[id] = m.world_from_body[id] == glm::dmat4(1.0) ? 1 : 0;
  m.refresh_padded_bounds();
  m.prepare_static_triangles();
}

Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

bool ray_crosses_box(const Ray& ray, const glm::dvec3& lo, const glm::dvec3& hi) noexcept {
  return crosses_box(ray, pad(lo, hi), ray.t_near_m, ray.t_far_m);
}

PaddedBox padded_box(const glm::dvec3& lo, const glm::dvec3& hi) noexcept {
  return pad(lo, hi);
}

bool ray_crosses_box(const Ray& ray, const PaddedBox& box) noexcept {
  return crosses_box(ray, box, ray.t_near_m, ray.t_far_m);
}

namespace {

// Rays per Embree stream call of the batched queries (a stack buffer: no allocation).
constexpr std::size_t kStreamChunk = 64;
static_assert(kStreamChunk <= 256, "occluded_batch keeps a ray's lane in a byte");

}  // namespace

// The rest of a closest-hit query once the static BVH has been traversed (rh holds its result,
// tfar = the best hit so far): the levels of detail, the moving objects and the double-precision
// refit. Shared by the single and the batched query.
bool Scene::Impl::finish_intersect(const Ray& ray, RTCRayHit& rh, Hit& hit) const noexcept {
  const Impl& m = *this;
  std::uint32_t object = kInvalidId;
  unsigned prim = kInvalidId;
  if (rh.hit.geomID != kInvalidId && rh.hit.geomID < m.object_of_static_geometry.size()) {
    object = m.object_of_static_geometry[rh.hit.geomID];
    prim = rh.hit.primID;
  }
  RTCIntersectContext ctx;
  // Levels of detail only (most scenes have none): a square root each, per query.
  const bool levels = !m.level_scenes.empty();
  const double origin_offset_m =
      levels && m.view_bands ? glm::length(ray.origin_m - m.view_position_m) : 0.0;
  const double direction_length = levels ? glm::length(ray.direction) : 0.0;
  for (const Impl::LevelBvh& l : m.level_scenes) {
    RTCRayHit rl{};
    if (!m.level_ray(l, rh.ray, origin_offset_m, direction_length, rl.ray))
      continue;
    rl.hit.geomID = kInvalidId;
    rl.hit.instID[0] = kInvalidId;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(l.scene, &ctx, &rl);
    if (rl.hit.geomID != kInvalidId && rl.ray.tfar < rh.ray.tfar &&
        rl.hit.geomID < l.object_of_geometry.size()) {
      rh.ray.tfar = rl.ray.tfar;
      object = l.object_of_geometry[rl.hit.geomID];
      prim = rl.hit.primID;
    }
  }
  for (const Impl::Mover& mv : m.movers) {
    // rh.ray.tfar is the best hit so far (or the ray's t_far): only nearer movers can win.
    if (!crosses_box(ray, m.padded_bounds[mv.object], static_cast<double>(rh.ray.tnear),
                     static_cast<double>(rh.ray.tfar))) {
      continue;
    }
    RTCRayHit rb{};
    to_body(ray, m.world_from_body[mv.object], rh.ray, rb.ray);
    rb.hit.geomID = kInvalidId;
    rb.hit.instID[0] = kInvalidId;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(mv.scene, &ctx, &rb);
    if (rb.hit.geomID != kInvalidId && rb.ray.tfar < rh.ray.tfar) {
      rh.ray.tfar = rb.ray.tfar;
      object = mv.object;
      prim = rb.hit.primID;
    }
  }
  if (object == kInvalidId)
    return false;
  const ObjectDesc& o = m.desc.objects[object];
  if (prim >= o.mesh.triangles.size())
    return false;
  // A static object's triangle as prepared at setup; a mover's placed now (the identity
  // changes nothing).
  const std::size_t first = m.static_first[object];
  const Impl::WorldTriangle w = first != Impl::kNoTriangles
                                    ? m.static_triangles[first + prim]
                                    : Impl::world_triangle(o, m.world_from_body[object],
                                                           m.identity_placement[object] != 0, prim);
  const glm::dvec3& a = w.a_m;
  const glm::dvec3 &e1 = w.e1_m, &e2 = w.e2_m;
  // Double-precision refit (Moller & Trumbore, "Fast, minimum storage ray-triangle
  // intersection", JGT 1997). The triangle is the one Embree found; only t is taken from the
  // refit, so a hit a float ulp outside an edge still counts. Embree's float t is kept when
  // the ray is parallel to the plane or the refit disagrees beyond float traversal error.
  double t = static_cast<double>(rh.ray.tfar);
  const glm::dvec3 pvec = glm::cross(ray.direction, e2);
  const double det = glm::dot(e1, pvec);
  if (std::abs(det) > 0.0) {
    const glm::dvec3 tvec = ray.origin_m - a;
    const glm::dvec3 qvec = glm::cross(tvec, e1);
    const double t_refit = glm::dot(e2, qvec) / det;
    // Accepted within 1e-4 (1 + |t| + |origin|). The bound without |origin| is no larger (each
    // rounded step is monotonic), so a refit within it is accepted without the square root.
    const double diff = std::abs(t_refit - t);
    const double base = 1.0 + std::abs(t);
    if (std::isfinite(t_refit) &&
        (diff <= 1e-4 * base || diff <= 1e-4 * (base + glm::length(ray.origin_m))))
      t = t_refit;
  }
  hit.t_m = t;
  hit.position_m = ray.origin_m + ray.direction * t;
  hit.normal = w.normal;
  hit.object_id = object;
  hit.primitive_id = prim;
  hit.material_id = o.mesh.triangle_material[prim];
  return true;
}

bool Scene::intersect(const Ray& ray, Hit& hit) const noexcept {
  const Impl& m = *impl_;
  RTCRayHit rh{};
  if (!to_embree(ray, rh.ray))
    return false;
  rh.hit.geomID = kInvalidId;
  rh.hit.primID = kInvalidId;
  rh.hit.instID[0] = kInvalidId;
  if (m.static_scene) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(m.static_scene, &ctx, &rh);
  }
  return m.finish_intersect(ray, rh, hit);
}

void Scene::intersect(std::span<const Ray> rays, std::span<Hit> hits,
                      std::span<std::uint8_t> found) const noexcept {
  const Impl& m = *impl_;
  const std::size_t n = std::min({rays.size(), hits.size(), found.size()});
  std::array<RTCRayHit, kStreamChunk> buf;
  std::array<std::uint32_t, kStreamChunk> index;
  for (std::size_t begin = 0; begin < n; begin += kStreamChunk) {
    const std::size_t count = std::min(kStreamChunk, n - begin);
    unsigned valid = 0;
    for (std::size_t i = 0; i < count; ++i) {
      RTCRayHit& rh = buf[valid];
      if (!to_embree(rays[begin + i], rh.ray)) {
        found[begin + i] = 0;
        continue;
      }
      rh.hit.geomID = kInvalidId;
      rh.hit.primID = kInvalidId;
      rh.hit.instID[0] = kInvalidId;
      index[valid++] = static_cast<std::uint32_t>(begin + i);
    }
    if (m.static_scene && valid > 0) {
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      rtcIntersect1M(m.static_scene, &ctx, buf.data(), valid, sizeof(RTCRayHit));
    }
    for (unsigned k = 0; k < valid; ++k) {
      const std::uint32_t i = index[k];
      found[i] = m.finish_intersect(rays[i], buf[k], hits[i]) ? 1 : 0;
    }
  }
}

// The rest of an occlusion query once the static BVH has found nothing: the levels of detail
// and the moving objects. `r` is the ray in Embree's layout.
bool Scene::Impl::occluded_beyond_static(const Ray& ray, const RTCRay& r) const noexcept {
  const Impl& m = *this;
  RTCIntersectContext ctx;
  // Levels of detail only (most scenes have none): a square root each, per query.
  const bool levels = !m.level_scenes.empty();
  const double origin_offset_m =
      levels && m.view_bands ? glm::length(ray.origin_m - m.view_position_m) : 0.0;
  const double direction_length = levels ? glm::length(ray.direction) : 0.0;
  for (const Impl::LevelBvh& l : m.level_scenes) {
    RTCRay rl{};
    if (!m.level_ray(l, r, origin_offset_m, direction_length, rl))
      continue;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(l.scene, &ctx, &rl);
    if (rl.tfar < 0.0f)
      return true;
  }
  for (const Impl::Mover& mv : m.movers) {
    if (!crosses_box(ray, m.padded_bounds[mv.object], static_cast<double>(r.tnear),
                     static_cast<double>(r.tfar))) {
      continue;
    }
    RTCRay rb{};
    to_body(ray, m.world_from_body[mv.object], r, rb);
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(mv.scene, &ctx, &rb);
    if (rb.tfar < 0.0f)
      return true;
  }
  return false;
}

bool Scene::occluded(const Ray& ray) const noexcept {
  const Impl& m = *impl_;
  RTCRay r{};
  if (!to_embree(ray, r))
    return false;
  if (m.static_scene) {
    RTCRay rs = r;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(m.static_scene, &ctx, &rs);
    if (rs.tfar < 0.0f)  // Embree sets tfar to -inf on a hit
      return true;
  }
  return m.occluded_beyond_static(ray, r);
}

template <class RayAt>
void Scene::Impl::occluded_batch(std::size_t n, const RayAt& ray_at,
                                 std::span<std::uint8_t> blocked, const std::uint32_t* split,
                                 MoverSplit mode) const noexcept {
  // kOwn: the static BVH and the levels are not asked, only each lane's own mover.
  const bool own_only = split != nullptr && mode == MoverSplit::kOwn;
  std::array<std::uint32_t, kStreamChunk> lane_split;
  // Per chunk: the rays in our layout and in Embree's (`world`: as to_embree made them, kept for
  // the levels and movers since a stream call overwrites tfar), their indices in the span, and
  // the stream handed to Embree (`buf`) with, per entry, its lane in the chunk.
  std::array<Ray, kStreamChunk> rays;
  std::array<RTCRay, kStreamChunk> world;
  std::array<RTCRay, kStreamChunk> buf;
  std::array<std::uint32_t, kStreamChunk> index;
  std::array<std::uint8_t, kStreamChunk> lane_blocked;
  std::array<std::uint8_t, kStreamChunk> lane_of;
  // Per lane, for the levels' bands (level_ray): as the single query computes them.
  std::array<double, kStreamChunk> origin_offset_m{}, direction_length{};
  const bool levels = !level_scenes.empty();
  // One coherent stream of `count` rays of buf on `scene`; marks the lanes it finds blocked
  // (Embree sets tfar to -inf on a hit).
  auto stream = [&](RTCScene scene, unsigned count) {
    if (count == 0)
      return;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcOccluded1M(scene, &ctx, buf.data(), count, sizeof(RTCRay));
    for (unsigned k = 0; k < count; ++k) {
      if (buf[k].tfar < 0.0f)
        lane_blocked[lane_of[k]] = 1;
    }
  };
  for (std::size_t begin = 0; begin < n; begin += kStreamChunk) {
    const std::size_t count = std::min(kStreamChunk, n - begin);
    unsigned valid = 0;
    for (std::size_t i = 0; i < count; ++i) {
      rays[valid] = ray_at(begin + i);
      if (!to_embree(rays[valid], world[valid])) {
        blocked[begin + i] = 0;
        continue;
      }
      buf[valid] = world[valid];
      lane_of[valid] = static_cast<std::uint8_t>(valid);
      lane_blocked[valid] = 0;
      lane_split[valid] = split != nullptr ? split[begin + i] : kNoMover;
      if (levels && !own_only) {
        origin_offset_m[valid] =
            view_bands ? glm::length(rays[valid].origin_m - view_position_m) : 0.0;
        direction_length[valid] = glm::length(rays[valid].direction);
      }
      index[valid++] = static_cast<std::uint32_t>(begin + i);
    }
    // The single query's stages (occluded, occluded_beyond_static), each as one stream of the
    // lanes that no earlier stage has blocked: a ray is blocked when any stage blocks it, so
    // the answers are the single query's whichever stage answers first.
    if (static_scene && !own_only)
      stream(static_scene, valid);
    for (const LevelBvh& l : level_scenes) {
      if (own_only)
        break;
      unsigned asked = 0;
      for (unsigned k = 0; k < valid; ++k) {
        if (lane_blocked[k] != 0 ||
            !level_ray(l, world[k], origin_offset_m[k], direction_length[k], buf[asked]))
          continue;
        lane_of[asked++] = static_cast<std::uint8_t>(k);
      }
      stream(l.scene, asked);
    }
    for (const Mover& mv : movers) {
      unsigned asked = 0;
      for (unsigned k = 0; k < valid; ++k) {
        // With a split, lane k skips its own mover (kRest) or asks it alone (kOwn).
        const bool own = lane_split[k] == mv.object;
        if (lane_blocked[k] != 0 || (split != nullptr && own != own_only) ||
            !crosses_box(rays[k], padded_bounds[mv.object], static_cast<double>(world[k].tnear),
                         static_cast<double>(world[k].tfar))) {
          continue;
        }
        to_body(rays[k], world_from_body[mv.object], world[k], buf[asked]);
        lane_of[asked++] = static_cast<std::uint8_t>(k);
      }
      stream(mv.scene, asked);
    }
    for (unsigned k = 0; k < valid; ++k)
      blocked[index[k]] = lane_blocked[k];
  }
}

void Scene::occluded(std::span<const Ray> rays, std::span<std::uint8_t> blocked) const noexcept {
  const std::size_t n = std::min(rays.size(), blocked.size());
  impl_->occluded_batch(
      n, [&](std::size_t i) -> const Ray& { return rays[i]; }, blocked);
}

void Scene::occluded(std::span<const Ray> rays, std::span<const std::uint32_t> mover,
                     MoverSplit split, std::span<std::uint8_t> blocked) const noexcept {
  const std::size_t n = std::min({rays.size(), mover.size(), blocked.size()});
  impl_->occluded_batch(
      n, [&](std::size_t i) -> const Ray& { return rays[i]; }, blocked, mover.data(), split);
}

void Scene::occluded_along(const glm::dvec3& direction, std::span<const glm::dvec3> origins,
                           std::span<std::uint8_t> blocked) const noexcept {
  const std::size_t n = std::min(origins.size(), blocked.size());
  // Rays from 0 to infinity (to_embree refuses a non-finite origin or direction: not blocked).
  impl_->occluded_batch(
      n,
      [&](std::size_t i) {
        return Ray{origins[i], direction, 0.0, std::numeric_limits<double>::infinity()};
      },
      blocked);
}

void Scene::set_time(double t_s) noexcept {
  Impl& m = *impl_;
  if (!std::isfinite(t_s))
    return;
  m.time_s = t_s;
  for (const Impl::Mover& mv : m.movers) {
    if (mv.path >= 0) {
      m.place_on_path(mv, t_s);
      continue;
    }
    const LinearMotion& motion = *m.desc.objects[mv.object].motion;
    m.world_from_body[mv.object] = moving_transform(motion, t_s);
    // The rotation is constant, so the bounds translate with the body origin.
    const glm::dvec3 shift = motion.velocity_mps * t_s;
    m.states[mv.object].bounds_min_m = m.bounds_min_at_zero_m[mv.object] + shift;
    m.states[mv.object].bounds_max_m = m.bounds_max_at_zero_m[mv.object] + shift;
  }
  m.refresh_padded_bounds();
}

double Scene::time_s() const noexcept {
  return impl_->time_s;
}

void Scene::set_view(const ViewVolume& v) noexcept {
  Impl& m = *impl_;
  if (!valid_view(v)) {
    m.default_view();
    ++m.view.invalid_views;
    return;
  }
  const Frustum f = make_frustum(v);
  ViewStats& st = m.view;
  for (Impl::LevelBvh& l : m.level_scenes) {
    l.active_tiles = 0;
    l.near_m = std::numeric_limits<double>::infinity();
    l.far_m = 0.0;
  }
  m.view_position_m = v.position_m;
  m.view_bands = true;
  st.lod_groups_in_view = 0;
  st.lod_groups_culled = 0;
  st.lod_groups_at_level = {};
  for (Impl::LodGroup& g : m.groups) {
    const bool in_view = f.meets(g.lo_m, g.hi_m);
    st.lod_groups_in_view += in_view ? 1 : 0;
    int pick = 0;  // finest unless a coarser level qualifies
    const double range_m = glm::length(glm::clamp(v.position_m, g.lo_m, g.hi_m) - v.position_m);
    if (!in_view && v.cull_outside) {
      pick = -1;
    } else {
      const double allowed_m = std::max(v.range_cell_m, range_m * v.angular_cell_rad);
      for (std::uint32_t k = 0; k < g.count; ++k) {
        if (m.lod_members[g.first + k].facet_m <= allowed_m)
          pick = static_cast<int>(k);  // levels ascend: the last that qualifies is the coarsest
      }
    }
    g.active = pick;
    for (std::uint32_t k = 0; k < g.count; ++k) {
      const std::uint32_t obj = m.lod_members[g.first + k].object;
      const bool on = static_cast<int>(k) == pick;
      m.object_active[obj] = on ? 1 : 0;
      m.states[obj].active = on;
    }
    if (pick < 0) {
      ++st.lod_groups_culled;
    } else {
      const std::uint8_t level = m.lod_members[g.first + static_cast<std::uint32_t>(pick)].level;
      ++st.lod_groups_at_level[std::min<std::size_t>(level, 3)];
      // Farthest point of the box: the far corner on each axis.
      const glm::dvec3 far_corner = glm::mix(
          g.lo_m, g.hi_m, glm::dvec3(glm::lessThan(v.position_m, 0.5 * (g.lo_m + g.hi_m))));
      Impl::LevelBvh& l = m.level_scenes[level];
      ++l.active_tiles;
      l.near_m = std::min(l.near_m, range_m);
      l.far_m = std::max(l.far_m, glm::length(far_corner - v.position_m));
    }
  }
  st.objects_in_view = 0;
  st.triangles_active = 0;
  st.triangles_in_view = 0;
  for (std::size_t i = 0; i < m.states.size(); ++i) {
    const ObjectState& s = m.states[i];
    if (!s.active)
      continue;
    st.triangles_active += s.triangle_count;
    const std::int32_t g = m.group_of_object[i];
    const bool in_view = g >= 0 ? f.meets(m.groups[static_cast<std::size_t>(g)].lo_m,
                                          m.groups[static_cast<std::size_t>(g)].hi_m)
                                : f.meets(s.bounds_min_m, s.bounds_max_m);
    if (in_view) {
      ++st.objects_in_view;
      st.triangles_in_view += s.triangle_count;
    }
  }
  ++st.views_set;
}

void Scene::clear_view() noexcept {
  impl_->default_view();
}

const ViewStats& Scene::view_stats() const noexcept {
  return impl_->view;
}

int Scene::active_lod_level(std::int32_t lod_group) const noexcept {
  const Impl& m = *impl_;
  const auto it =
      std::lower_bound(m.groups.begin(), m.groups.end(), lod_group,
                       [](const Impl::LodGroup& g, std::int32_t id) { return g.id < id; });
  if (it == m.groups.end() || it->id != lod_group || it->active < 0)
    return -1;
  return m.lod_members[it->first + static_cast<std::uint32_t>(it->active)].level;
}
std::span<const Material> Scene::materials() const noexcept {
  return impl_->desc.materials;
}
std::span<const ObjectState> Scene::objects() const noexcept {
  return impl_->states;
}
const GeoAnchor& Scene::anchor() const noexcept {
  return impl_->desc.anchor;
}

const std::string& Scene::incomplete() const noexcept {
  return impl_->desc.incomplete;
}
const SceneDescription& Scene::description() const noexcept {
  return impl_->desc;
}
std::size_t Scene::triangle_count() const noexcept {
  return impl_->triangles;
}
glm::dmat4 Scene::world_from_body(std::uint32_t object_id) const noexcept {
  const Impl& m = *impl_;
  return object_id < m.world_from_body.size() ? m.world_from_body[object_id] : glm::dmat4(1.0);
}
std::uint64_t Scene::static_build_count() const noexcept {
  return impl_->static_builds;
}
std::uint64_t Scene::embree_commit_count() const noexcept {
  return impl_->embree_commits;
}
std::uint32_t Scene::embree_error_count() const noexcept {
  return impl_->errors.count.load(std::memory_order_acquire);
}

}  // namespace radar_emu::scene
