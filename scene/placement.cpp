#include "scene/placement.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/path.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "scene/trajectory.hpp"

namespace radar_emu::scene {

namespace {

[[noreturn]] void fail(const TargetPlacement& t, const std::string& what) {
  throw std::runtime_error(t.context + ": " + what);
}

glm::dvec3 axis_vector(MeshAxis a) noexcept {
  switch (a) {
    case MeshAxis::kPlusX:
      return {1, 0, 0};
    case MeshAxis::kMinusX:
      return {-1, 0, 0};
    case MeshAxis::kPlusY:
      return {0, 1, 0};
    case MeshAxis::kMinusY:
      return {0, -1, 0};
    case MeshAxis::kPlusZ:
      return {0, 0, 1};
    case MeshAxis::kMinusZ:
      return {0, 0, -1};
  }
  return {1, 0, 0};
}

// Rotation about the up axis by `yaw_rad`, counter-clockwise seen from above.
glm::dmat3 rot_z(double yaw_rad) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  return glm::dmat3(glm::dvec3(c, s, 0), glm::dvec3(-s, c, 0), glm::dvec3(0, 0, 1));
}

// Compass angle (clockwise from north) to the ENU yaw (counter-clockwise from east).
double enu_yaw(double compass_rad) {
  return std::numbers::pi / 2.0 - compass_rad;
}

// The target's mesh in its body frame (x forward, y left, z up) and its materials.
SceneDescription target_mesh(const TargetPlacement& t) {
  SceneDescription d;
  if (t.builtin) {
    TargetSpec spec = *t.builtin;
    spec.facet_m = t.facet_m;
    try {
      d = make_target(spec);
    } catch (const std::invalid_argument& e) {
      fail(t, e.what());
    }
  } else {
    if (!(std::isfinite(t.mesh_scale) && t.mesh_scale > 0.0))
      fail(t, "mesh_scale must be > 0");
    const std::string ext = common::lower_extension(t.mesh_file);
    const bool gltf = ext == ".glb" || ext == ".gltf";
    if (!gltf && ext != ".obj" && ext != ".stl") {
      fail(t, "mesh_file " + t.mesh_file.string() + ": unknown format '" + ext +
                  "' (expected .glb, .gltf, .obj or .stl)");
    }
    SceneDescription file;
    try {
      file = gltf ? load_gltf(t.mesh_file) : load_mesh_file(t.mesh_file);
    } catch (const std::exception& e) {
      fail(t, std::string("mesh_file: ") + e.what());
    }
    // Body from file axes: rows are the front, left (= up x front) and up axes in file
    // coordinates, so that a point's body coordinates are its projections on them.
    const glm::dvec3 front = axis_vector(t.mesh_front_axis.value_or(MeshAxis::kPlusX));
    const glm::dvec3 up =
        axis_vector(t.mesh_up_axis.value_or(gltf ? MeshAxis::kPlusY : MeshAxis::kPlusZ));
    if (std::abs(glm::dot(front, up)) > 0.5)
      fail(t, "mesh_front_axis and mesh_up_axis must be perpendicular");
    const glm::dvec3 left = glm::cross(up, front);
    const glm::dmat3 body_from_file = glm::transpose(glm::dmat3(front, left, up));
    // The glTF loader has turned the file's y-up axes into ENU ones (x, -z, y); undo it.
    const glm::dmat3 file_from_loaded =
        gltf ? glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0))
             : glm::dmat3(1.0);
    const glm::dmat3 r = body_from_file * file_from_loaded * t.mesh_scale;
    // Every node of the file becomes part of one body, its placement baked in.
    d.materials = file.materials;
    ObjectDesc merged;
    for (const ObjectDesc& o : file.objects) {
      if (o.motion || o.trajectory) {
        fail(t, "mesh_file " + t.mesh_file.string() + ": node '" + o.name +
                    "' moves (radar_emu velocity_mps or trajectory extras); a target's mesh "
                    "must be static, its motion comes from the [[target]] table");
      }
      const auto base = static_cast<std::uint32_t>(merged.mesh.positions_m.size());
      for (const glm::vec3& p : o.mesh.positions_m) {
        const glm::dvec3 loaded(o.world_from_body * glm::dvec4(glm::dvec3(p), 1.0));
        merged.mesh.positions_m.emplace_back(r * loaded);
      }
      for (const glm::uvec3& tri : o.mesh.triangles)
        merged.mesh.triangles.push_back(tri + glm::uvec3(base));
      merged.mesh.triangle_material.insert(merged.mesh.triangle_material.end(),
                                           o.mesh.triangle_material.begin(),
                                           o.mesh.triangle_material.end());
    }
    d.objects = {std::move(merged)};
  }
  if (!t.material.empty()) {
    d.materials = {{t.material, {0.75f, 0.75f, 0.8f}}};
    std::fill(d.objects[0].mesh.triangle_material.begin(),
              d.objects[0].mesh.triangle_material.end(), std::uint16_t{0});
  }
  return d;
}

}  // namespace

std::optional<MeshAxis> mesh_axis_from_name(std::string_view name) noexcept {
  static constexpr std::array<std::pair<std::string_view, MeshAxis>, 6> kAxes{{
      {"+x", MeshAxis::kPlusX},
      {"-x", MeshAxis::kMinusX},
      {"+y", MeshAxis::kPlusY},
      {"-y", MeshAxis::kMinusY},
      {"+z", MeshAxis::kPlusZ},
      {"-z", MeshAxis::kMinusZ},
  }};
  for (const auto& [n, a] : kAxes) {
    if (n == name)
      return a;
  }
  return std::nullopt;
}

GroundProbe::GroundProbe(const SceneDescription& scene) {
  for (const ObjectDesc& o : scene.objects) {
    if (o.motion || o.trajectory || (o.lod_group >= 0 && o.lod_level != 0) ||
        o.mesh.triangles.empty()) {
      continue;
    }
    Object g;
    g.min_m = glm::dvec2(std::numeric_limits<double>::infinity());
    g.max_m = -g.min_m;
    g.vertices_m.reserve(o.mesh.positions_m.size());
    for (const glm::vec3& p : o.mesh.positions_m) {
      const glm::dvec3 w(o.world_from_body * glm::dvec4(glm::dvec3(p), 1.0));
      g.vertices_m.push_back(w);
      g.min_m = glm::min(g.min_m, glm::dvec2(w));
      g.max_m = glm::max(g.max_m, glm::dvec2(w));
    }
    g.triangles = &o.mesh.triangles;
    objects_.push_back(std::move(g));
  }
}

std::optional<double> GroundProbe::height_m(double east_m, double north_m) const {
  // Vertical line through q against each triangle's projection on the horizontal plane:
  // barycentric coordinates of q in the projected triangle (edge functions; Ericson, Real-Time
  // Collision Detection, 2005, sec. 3.4), the height interpolated with them.
  const glm::dvec2 q(east_m, north_m);
  std::optional<double> best;
  for (const Object& g : objects_) {
    if (q.x < g.min_m.x || q.x > g.max_m.x || q.y < g.min_m.y || q.y > g.max_m.y)
      continue;
    for (const glm::uvec3& tri : *g.triangles) {
      const glm::dvec3 &a = g.vertices_m[tri.x], &b = g.vertices_m[tri.y], &c = g.vertices_m[tri.z];
      const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
      if (std::abs(area) < 1e-12)
        continue;  // vertical (or degenerate): no height of its own
      const double u = ((b.x - q.x) * (c.y - q.y) - (c.x - q.x) * (b.y - q.y)) / area;
      const double v = ((c.x - q.x) * (a.y - q.y) - (a.x - q.x) * (c.y - q.y)) / area;
      const double w = 1.0 - u - v;
      constexpr double kEdge = -1e-9;  // points on a shared edge belong to both triangles
      if (u < kEdge || v < kEdge || w < kEdge)
        continue;
      const double z = u * a.z + v * b.z + w * c.z;
      if (!best || z > *best)
        best = z;
    }
  }
  return best;
}

void add_targets(SceneDescription& scene, std::span<const TargetPlacement> targets) {
  std::optional<GroundProbe> ground;
  std::set<std::string> names;
  for (const ObjectDesc& o : scene.objects)
    names.insert(o.name);
  // Built aside and committed at the end: a failing target leaves the scene as it was.
  std::vector<ObjectDesc> added;
  std::vector<Material> materials = scene.materials;
  for (const TargetPlacement& t : targets) {
    if (t.name.empty())
      fail(t, "name must not be empty");
    if (!names.insert(t.name).second)
      fail(t, "name '" + t.name + "' is already taken by another object of the scene");
    SceneDescription body = target_mesh(t);
    ObjectDesc o = std::move(body.objects.at(0));
    o.name = t.name;
    o.area = "target";
    o.world_from_body = glm::dmat4(1.0);
    o.lod_group = -1;
    double lowest_m = std::numeric_limits<double>::infinity();
    for (const glm::vec3& p : o.mesh.positions_m)
      lowest_m = std::min(lowest_m, static_cast<double>(p.z));
    if (!std::isfinite(lowest_m))
      fail(t, "the mesh has no vertices");
    // With on_ground, a point's z is the height of the mesh's lowest point above the ground.
    auto grounded = [&](glm::dvec3 p, const std::string& what) {
      if (!t.on_ground)
        return p;
      if (!ground)
        ground.emplace(scene);
      const std::optional<double> h = ground->height_m(p.x, p.y);
      if (!h) {
        std::ostringstream os;
        os << "on_ground: no ground below " << what << " (" << p.x << ", " << p.y
           << ") m: outside the scene";
        fail(t, os.str());
      }
      return glm::dvec3(p.x, p.y, *h + p.z - lowest_m);
    };
    if (!t.waypoints_m.empty()) {
      Trajectory tr;
      for (std::size_t i = 0; i < t.waypoints_m.size(); ++i)
        tr.waypoints_m.push_back(grounded(t.waypoints_m[i], "waypoint " + std::to_string(i + 1)));
      tr.speed_mps = t.speed_mps;
      tr.turn_radius_m = t.turn_radius_m;
      tr.loop = t.closed;
      tr.bank = t.bank;
      try {
        (void)TrajectoryPath(tr);
      } catch (const std::invalid_argument& e) {
        fail(t, std::string("waypoints_enu_m: ") + e.what());
      }
      o.trajectory = std::move(tr);
    } else {
      const glm::dvec3 p = grounded(t.position_m, "position_enu_m");
      if (t.speed_mps > 0.0) {
        // LinearMotion turns the body's x along the velocity: turn the mesh in the body frame
        // by the nose's angle from the course (counter-clockwise: course - heading).
        const double offset = t.course_rad - t.heading_rad;
        if (std::abs(std::remainder(offset, 2.0 * std::numbers::pi)) > 1e-12) {
          const glm::dmat3 r = rot_z(offset);
          for (glm::vec3& v : o.mesh.positions_m)
            v = glm::vec3(r * glm::dvec3(v));
        }
        const double yaw = enu_yaw(t.course_rad);
        o.motion = LinearMotion{p, t.speed_mps * glm::dvec3(std::cos(yaw), std::sin(yaw), 0.0)};
      } else {
        glm::dmat4 x(rot_z(enu_yaw(t.heading_rad)));
        x[3] = glm::dvec4(p, 1.0);
        o.world_from_body = x;
      }
    }
    // Materials merged by name (equal names are one radar material).
    for (std::uint16_t& k : o.mesh.triangle_material) {
      const Material& m = body.materials.at(k);
      std::size_t i = 0;
      while (i < materials.size() && materials[i].name != m.name)
        ++i;
      if (i == materials.size()) {
        if (i > std::numeric_limits<std::uint16_t>::max())
          fail(t, "the scene has more than 65536 materials");
        materials.push_back(m);
      }
      k = static_cast<std::uint16_t>(i);
    }
    added.push_back(std::move(o));
  }
  scene.materials = std::move(materials);
  for (ObjectDesc& o : added)
    scene.objects.push_back(std::move(o));
}

}  // namespace radar_emu::scene
