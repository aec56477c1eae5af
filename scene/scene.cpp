#include "scene/scene.hpp"

#include <embree3/rtcore.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace radar_emu::scene {

namespace {

void device_error(void* user, RTCError code, const char* message) {
  auto* last = static_cast<std::string*>(user);
  *last = "Embree error " + std::to_string(static_cast<int>(code)) + ": " +
          (message ? message : "(no message)");
}

glm::dmat4 moving_transform(const LinearMotion& m, double t_s) {
  // Body x along the horizontal velocity (yaw about up); origin at start + v t.
  const double yaw = (m.velocity_mps.x == 0.0 && m.velocity_mps.y == 0.0)
                         ? 0.0
                         : std::atan2(m.velocity_mps.y, m.velocity_mps.x);
  const double c = std::cos(yaw), s = std::sin(yaw);
  glm::dmat4 x(1.0);
  x[0] = glm::dvec4(c, s, 0, 0);
  x[1] = glm::dvec4(-s, c, 0, 0);
  x[3] = glm::dvec4(m.start_position_m + m.velocity_mps * t_s, 1.0);
  return x;
}

void set_embree_transform(RTCGeometry g, const glm::dmat4& m) {
  float xfm[12];
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 3; ++row)
      xfm[col * 3 + row] = static_cast<float>(m[col][row]);
  }
  rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
}

}  // namespace

struct Scene::Impl {
  SceneDescription desc;
  std::vector<ObjectState> states;
  std::vector<glm::dmat4> world_from_body;        // current, per object
  std::vector<std::uint32_t> object_of_geometry;  // top-level geomID -> object id
  std::vector<RTCGeometry> instance_of_object;    // moving objects' instances (else nullptr)
  std::vector<RTCScene> child_scenes;
  std::string last_error;
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  double time_s = 0.0;
  std::size_t triangles = 0;

  ~Impl() {
    for (RTCScene s : child_scenes)
      rtcReleaseScene(s);
    if (top)
      rtcReleaseScene(top);
    if (device)
      rtcReleaseDevice(device);
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("scene: " + what +
                             (last_error.empty() ? "" : " (" + last_error + ")"));
  }

  RTCGeometry make_mesh(const Mesh& mesh, const glm::dmat4* world_from_body_or_null) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g)
      fail("cannot create geometry");
    auto* v =
        static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                    3 * sizeof(float), mesh.positions_m.size()));
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                mesh.triangles.size()));
    if (!v || !idx)
      fail("cannot allocate geometry buffers");
    for (std::size_t i = 0; i < mesh.positions_m.size(); ++i) {
      glm::dvec3 p(mesh.positions_m[i]);
      if (world_from_body_or_null)
        p = glm::dvec3(*world_from_body_or_null * glm::dvec4(p, 1.0));
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

  void validate() const {
    if (desc.objects.empty())
      fail("the scene has no objects");
    if (desc.materials.empty())
      fail("the scene has no materials");
    for (const ObjectDesc& o : desc.objects) {
      const Mesh& m = o.mesh;
      const std::string who = "object '" + o.name + "'";
      if (m.triangles.empty())
        fail(who + " has no triangles");
      if (m.triangle_material.size() != m.triangles.size()) {
        fail(who + ": " + std::to_string(m.triangle_material.size()) + " material indices for " +
             std::to_string(m.triangles.size()) + " triangles");
      }
      for (std::size_t i = 0; i < m.positions_m.size(); ++i) {
        const glm::vec3& p = m.positions_m[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
          fail(who + ": vertex " + std::to_string(i) + " is not finite");
        }
      }
      bool any_area = false;
      for (std::size_t i = 0; i < m.triangles.size(); ++i) {
        const glm::uvec3 t = m.triangles[i];
        const std::size_t n = m.positions_m.size();
        if (t.x >= n || t.y >= n || t.z >= n) {
          fail(who + ": triangle " + std::to_string(i) + " indexes vertex beyond " +
               std::to_string(n));
        }
        if (m.triangle_material[i] >= desc.materials.size()) {
          fail(who + ": triangle " + std::to_string(i) + " has material index " +
               std::to_string(m.triangle_material[i]) + " of " +
               std::to_string(desc.materials.size()));
        }
        const glm::vec3 c = glm::cross(m.positions_m[t.y] - m.positions_m[t.x],
                                       m.positions_m[t.z] - m.positions_m[t.x]);
        any_area |= glm::dot(c, c) > 0.0f;
      }
      if (!any_area)
        fail(who + " has only degenerate triangles");
    }
  }

  void update_state(std::size_t id) {
    const ObjectDesc& o = desc.objects[id];
    ObjectState& s = states[id];
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : o.mesh.positions_m) {
      const glm::dvec3 w(world_from_body[id] * glm::dvec4(glm::dvec3(p), 1.0));
      lo = glm::min(lo, w);
      hi = glm::max(hi, w);
    }
    s.bounds_min_m = lo;
    s.bounds_max_m = hi;
  }
};

Scene::Scene(SceneDescription description) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.desc = std::move(description);
  m.validate();
  m.device = rtcNewDevice("threads=0");
  if (!m.device)
    throw std::runtime_error("scene: cannot create the Embree device");
  rtcSetDeviceErrorFunction(m.device, device_error, &m.last_error);
  m.top = rtcNewScene(m.device);
  rtcSetSceneBuildQuality(m.top, RTC_BUILD_QUALITY_HIGH);
  const std::size_t n = m.desc.objects.size();
  m.states.resize(n);
  m.world_from_body.resize(n);
  m.instance_of_object.assign(n, nullptr);
  for (std::size_t id = 0; id < n; ++id) {
    const ObjectDesc& o = m.desc.objects[id];
    m.states[id].name = o.name;
    m.states[id].moving = o.motion.has_value();
    m.states[id].velocity_mps = o.motion ? o.motion->velocity_mps : glm::dvec3(0.0);
    m.states[id].triangle_count = o.mesh.triangles.size();
    m.triangles += o.mesh.triangles.size();
    unsigned geom_id = 0;
    if (o.motion) {
      RTCScene child = rtcNewScene(m.device);
      RTCGeometry mesh = m.make_mesh(o.mesh, nullptr);
      rtcAttachGeometry(child, mesh);
      rtcReleaseGeometry(mesh);
      rtcCommitScene(child);
      m.child_scenes.push_back(child);
      RTCGeometry inst = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(inst, child);
      rtcSetGeometryTimeStepCount(inst, 1);
      m.world_from_body[id] = moving_transform(*o.motion, 0.0);
      set_embree_transform(inst, m.world_from_body[id]);
      rtcCommitGeometry(inst);
      geom_id = rtcAttachGeometry(m.top, inst);
      m.instance_of_object[id] = inst;
      rtcReleaseGeometry(inst);  // the scene keeps a reference
    } else {
      m.world_from_body[id] = o.world_from_body;
      RTCGeometry mesh = m.make_mesh(o.mesh, &o.world_from_body);
      geom_id = rtcAttachGeometry(m.top, mesh);
      rtcReleaseGeometry(mesh);
    }
    if (m.object_of_geometry.size() <= geom_id)
      m.object_of_geometry.resize(geom_id + 1, 0);
    m.object_of_geometry[geom_id] = static_cast<std::uint32_t>(id);
    m.update_state(id);
  }
  rtcCommitScene(m.top);
  if (!m.last_error.empty())
    m.fail("building the BVH failed");
}

Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

bool Scene::intersect(const Ray& ray, Hit& hit) const noexcept {
  const Impl& m = *impl_;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh{};
  rh.ray.org_x = static_cast<float>(ray.origin_m.x);
  rh.ray.org_y = static_cast<float>(ray.origin_m.y);
  rh.ray.org_z = static_cast<float>(ray.origin_m.z);
  rh.ray.dir_x = static_cast<float>(ray.direction.x);
  rh.ray.dir_y = static_cast<float>(ray.direction.y);
  rh.ray.dir_z = static_cast<float>(ray.direction.z);
  rh.ray.tnear = static_cast<float>(ray.t_near_m);
  rh.ray.tfar = ray.t_far_m >= 1e30 ? std::numeric_limits<float>::infinity()
                                    : static_cast<float>(ray.t_far_m);
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(m.top, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
    return false;
  const unsigned top_geom =
      rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rh.hit.instID[0] : rh.hit.geomID;
  if (top_geom >= m.object_of_geometry.size())
    return false;
  const std::uint32_t object = m.object_of_geometry[top_geom];
  const ObjectDesc& o = m.desc.objects[object];
  if (rh.hit.primID >= o.mesh.triangles.size())
    return false;
  const glm::uvec3 tri = o.mesh.triangles[rh.hit.primID];
  const glm::dmat4& x = m.world_from_body[object];
  const glm::dvec3 a(x * glm::dvec4(glm::dvec3(o.mesh.positions_m[tri.x]), 1.0));
  const glm::dvec3 b(x * glm::dvec4(glm::dvec3(o.mesh.positions_m[tri.y]), 1.0));
  const glm::dvec3 c(x * glm::dvec4(glm::dvec3(o.mesh.positions_m[tri.z]), 1.0));
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 n = glm::cross(e1, e2);
  // Refit in double precision: intersection of the ray with the triangle's plane (the hit is
  // known to lie on this triangle; Embree's float t is only a few ulp of the range off).
  double t = static_cast<double>(rh.ray.tfar);
  const double denom = glm::dot(n, ray.direction);
  if (std::abs(denom) > 1e-300) {
    const double t_plane = glm::dot(n, a - ray.origin_m) / denom;
    if (std::isfinite(t_plane) && std::abs(t_plane - t) <= 1e-3 * (1.0 + t))
      t = t_plane;
  }
  hit.t_m = t;
  hit.position_m = ray.origin_m + ray.direction * t;
  const double len = glm::length(n);
  hit.normal = len > 0.0 ? n / len : glm::dvec3(0.0, 0.0, 1.0);
  hit.object_id = object;
  hit.primitive_id = rh.hit.primID;
  hit.material_id = o.mesh.triangle_material[rh.hit.primID];
  return true;
}

bool Scene::occluded(const Ray& ray) const noexcept {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r{};
  r.org_x = static_cast<float>(ray.origin_m.x);
  r.org_y = static_cast<float>(ray.origin_m.y);
  r.org_z = static_cast<float>(ray.origin_m.z);
  r.dir_x = static_cast<float>(ray.direction.x);
  r.dir_y = static_cast<float>(ray.direction.y);
  r.dir_z = static_cast<float>(ray.direction.z);
  r.tnear = static_cast<float>(ray.t_near_m);
  r.tfar = ray.t_far_m >= 1e30 ? std::numeric_limits<float>::infinity()
                               : static_cast<float>(ray.t_far_m);
  r.mask = 0xFFFFFFFFu;
  rtcOccluded1(impl_->top, &ctx, &r);
  return r.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

void Scene::set_time(double t_s) noexcept {
  Impl& m = *impl_;
  m.time_s = t_s;
  bool any = false;
  for (std::size_t id = 0; id < m.desc.objects.size(); ++id) {
    RTCGeometry inst = m.instance_of_object[id];
    if (!inst)
      continue;
    m.world_from_body[id] = moving_transform(*m.desc.objects[id].motion, t_s);
    set_embree_transform(inst, m.world_from_body[id]);
    rtcCommitGeometry(inst);
    m.update_state(id);
    any = true;
  }
  if (any)
    rtcCommitScene(m.top);  // refits the top level only; static meshes are untouched
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

}  // namespace radar_emu::scene
