#include "scene/scene.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

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

namespace radar_emu::scene {

namespace {

constexpr unsigned kInvalidId = RTC_INVALID_GEOMETRY_ID;

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

// Our ray in Embree's float layout. Returns false for rays Embree must not see (non-finite
// values, empty interval).
bool to_embree(const Ray& ray, RTCRay& r) noexcept {
  if (!finite(ray.origin_m) || !finite(ray.direction) || std::isnan(ray.t_near_m) ||
      std::isnan(ray.t_far_m) || !(ray.t_far_m >= ray.t_near_m)) {
    return false;
  }
  constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
  r.org_x = static_cast<float>(ray.origin_m.x);
  r.org_y = static_cast<float>(ray.origin_m.y);
  r.org_z = static_cast<float>(ray.origin_m.z);
  r.dir_x = static_cast<float>(ray.direction.x);
  r.dir_y = static_cast<float>(ray.direction.y);
  r.dir_z = static_cast<float>(ray.direction.z);
  r.tnear = static_cast<float>(std::clamp(ray.t_near_m, 0.0, kFloatMax));
  r.tfar = ray.t_far_m >= kFloatMax ? std::numeric_limits<float>::infinity()
                                    : static_cast<float>(std::max(ray.t_far_m, 0.0));
  r.time = 0.0f;
  r.mask = 0xFFFFFFFFu;
  r.id = 0;
  r.flags = 0;
  return true;
}

// Does the ray cross the box [lo, hi] somewhere in [t0, t1]? (Slab test in double, the box
// padded by a relative 1e-6 so that float traversal inside it cannot be culled wrongly.)
bool crosses_box(const Ray& ray, const glm::dvec3& lo, const glm::dvec3& hi, double t0,
                 double t1) noexcept {
  const double pad = 1e-6 * (1.0 + std::max(glm::length(lo), glm::length(hi)));
  for (glm::length_t k = 0; k < 3; ++k) {
    const double o = ray.origin_m[k], d = ray.direction[k];
    const double a = lo[k] - pad, b = hi[k] + pad;
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

struct Scene::Impl {
  struct Mover {
    RTCScene scene = nullptr;  // body-frame BVH
    std::uint32_t object = 0;
  };

  SceneDescription desc;
  std::vector<ObjectState> states;
  std::vector<glm::dmat4> world_from_body;       // current, per object
  std::vector<glm::dvec3> bounds_min_at_zero_m;  // world bounds at t = 0, per object
  std::vector<glm::dvec3> bounds_max_at_zero_m;
  std::vector<std::uint32_t> object_of_static_geometry;  // static_scene geomID -> object id
  std::vector<Mover> movers;
  ErrorSink errors;
  RTCDevice device = nullptr;
  RTCScene static_scene = nullptr;  // null when every object moves
  double time_s = 0.0;
  std::size_t triangles = 0;
  std::uint64_t static_builds = 0;
  std::uint64_t embree_commits = 0;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    for (const Mover& m : movers)
      rtcReleaseScene(m.scene);
    if (static_scene)
      rtcReleaseScene(static_scene);
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
      if (o.motion) {
        if (!finite(o.motion->start_position_m) || !finite(o.motion->velocity_mps))
          fail(who + ": the motion's start position or velocity is not finite");
      } else if (!finite(o.world_from_body)) {
        fail(who + ": world_from_body is not finite");
      }
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
  // objects, identity for the body-frame mesh of a moving object).
  RTCGeometry make_mesh(const Mesh& mesh, const glm::dmat4& xf) {
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
    rtcCommitGeometry(g);
    return g;
  }

  RTCScene new_scene(RTCSceneFlags flags, RTCBuildQuality quality) {
    RTCScene s = rtcNewScene(device);
    if (!s)
      fail("cannot create an Embree scene");
    rtcSetSceneFlags(s, flags);
    rtcSetSceneBuildQuality(s, quality);
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

  void build() {
    const std::size_t n = desc.objects.size();
    states.resize(n);
    world_from_body.resize(n);
    bounds_min_at_zero_m.resize(n);
    bounds_max_at_zero_m.resize(n);
    for (std::size_t id = 0; id < n; ++id) {
      const ObjectDesc& o = desc.objects[id];
      ObjectState& s = states[id];
      s.name = o.name;
      s.moving = o.motion.has_value();
      s.velocity_mps = o.motion ? o.motion->velocity_mps : glm::dvec3(0.0);
      s.triangle_count = o.mesh.triangles.size();
      triangles += o.mesh.triangles.size();
      const auto object_id = static_cast<std::uint32_t>(id);
      if (o.motion) {
        world_from_body[id] = moving_transform(*o.motion, 0.0);
        movers.push_back({new_scene(RTC_SCENE_FLAG_ROBUST, RTC_BUILD_QUALITY_HIGH), object_id});
        RTCGeometry mesh = make_mesh(o.mesh, glm::dmat4(1.0));
        rtcAttachGeometryByID(movers.back().scene, mesh, 0);
        rtcReleaseGeometry(mesh);
        commit(movers.back().scene, "object '" + o.name + "'");
      } else {
        world_from_body[id] = o.world_from_body;
        if (!static_scene)
          static_scene = new_scene(RTC_SCENE_FLAG_ROBUST, RTC_BUILD_QUALITY_HIGH);
        RTCGeometry mesh = make_mesh(o.mesh, o.world_from_body);
        const unsigned geom = rtcAttachGeometry(static_scene, mesh);
        rtcReleaseGeometry(mesh);
        if (object_of_static_geometry.size() <= geom)
          object_of_static_geometry.resize(geom + 1, kInvalidId);
        object_of_static_geometry[geom] = object_id;
      }
      check("adding object '" + o.name + "' failed");
      world_bounds(id, bounds_min_at_zero_m[id], bounds_max_at_zero_m[id]);
      s.bounds_min_m = bounds_min_at_zero_m[id];
      s.bounds_max_m = bounds_max_at_zero_m[id];
    }
    if (static_scene) {
      commit(static_scene, "the static geometry");
      ++static_builds;
    }
  }
};

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
}

Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

bool Scene::intersect(const Ray& ray, Hit& hit) const noexcept {
  const Impl& m = *impl_;
  RTCRayHit rh{};
  if (!to_embree(ray, rh.ray))
    return false;
  rh.hit.geomID = kInvalidId;
  rh.hit.primID = kInvalidId;
  rh.hit.instID[0] = kInvalidId;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  std::uint32_t object = kInvalidId;
  unsigned prim = kInvalidId;
  if (m.static_scene) {
    rtcIntersect1(m.static_scene, &ctx, &rh);
    if (rh.hit.geomID != kInvalidId && rh.hit.geomID < m.object_of_static_geometry.size()) {
      object = m.object_of_static_geometry[rh.hit.geomID];
      prim = rh.hit.primID;
    }
  }
  for (const Impl::Mover& mv : m.movers) {
    const ObjectState& st = m.states[mv.object];
    // rh.ray.tfar is the best hit so far (or the ray's t_far): only nearer movers can win.
    if (!crosses_box(ray, st.bounds_min_m, st.bounds_max_m, static_cast<double>(rh.ray.tnear),
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
  const glm::uvec3 tri = o.mesh.triangles[prim];
  const glm::dmat4& x = m.world_from_body[object];
  const glm::dvec3 a(x * glm::dvec4(glm::dvec3(o.mesh.positions_m[tri.x]), 1.0));
  const glm::dvec3 b(x * glm::dvec4(glm::dvec3(o.mesh.positions_m[tri.y]), 1.0));
  const glm::dvec3 c(x * glm::dvec4(glm::dvec3(o.mesh.positions_m[tri.z]), 1.0));
  const glm::dvec3 e1 = b - a, e2 = c - a;
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
    const double scale = 1.0 + std::abs(t) + glm::length(ray.origin_m);
    if (std::isfinite(t_refit) && std::abs(t_refit - t) <= 1e-4 * scale)
      t = t_refit;
  }
  hit.t_m = t;
  hit.position_m = ray.origin_m + ray.direction * t;
  const glm::dvec3 n = glm::cross(e1, e2);  // as wound: counter-clockwise = outside
  const double len = glm::length(n);
  hit.normal = len > 0.0 ? n / len : glm::dvec3(0.0, 0.0, 1.0);
  hit.object_id = object;
  hit.primitive_id = prim;
  hit.material_id = o.mesh.triangle_material[prim];
  return true;
}

bool Scene::occluded(const Ray& ray) const noexcept {
  const Impl& m = *impl_;
  RTCRay r{};
  if (!to_embree(ray, r))
    return false;
  RTCIntersectContext ctx;
  if (m.static_scene) {
    RTCRay rs = r;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(m.static_scene, &ctx, &rs);
    if (rs.tfar < 0.0f)  // Embree sets tfar to -inf on a hit
      return true;
  }
  for (const Impl::Mover& mv : m.movers) {
    const ObjectState& st = m.states[mv.object];
    if (!crosses_box(ray, st.bounds_min_m, st.bounds_max_m, static_cast<double>(r.tnear),
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

void Scene::set_time(double t_s) noexcept {
  Impl& m = *impl_;
  if (!std::isfinite(t_s))
    return;
  m.time_s = t_s;
  for (const Impl::Mover& mv : m.movers) {
    const LinearMotion& motion = *m.desc.objects[mv.object].motion;
    m.world_from_body[mv.object] = moving_transform(motion, t_s);
    // The rotation is constant, so the bounds translate with the body origin.
    const glm::dvec3 shift = motion.velocity_mps * t_s;
    m.states[mv.object].bounds_min_m = m.bounds_min_at_zero_m[mv.object] + shift;
    m.states[mv.object].bounds_max_m = m.bounds_max_at_zero_m[mv.object] + shift;
  }
}

double Scene::time_s() const noexcept {
  return impl_->time_s;
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
