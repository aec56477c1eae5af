#include "scene/gltf.hpp"

#include <tbb/parallel_for.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <glm/gtc/quaternion.hpp>
#include <initializer_list>
#include <limits>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "common/path.hpp"
#include "common/units.hpp"
#include "scene/mesh_check.hpp"
#include "scene/trajectory.hpp"

// tinygltf parses the JSON / GLB container and decodes buffers (data: URIs, .bin files, the GLB
// BIN chunk). Everything below that (accessor and buffer-view ranges, strides, index values,
// node graph) is checked here before a single byte is read: a broken file gives "FILE: reason",
// never an out-of-bounds read.

namespace radar_emu::scene {

namespace {

constexpr int kMaxNodeDepth = 256;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

// glTF is y-up (x right, y up, z toward the viewer); the world is ENU (z up): x_enu = x,
// y_enu = -z, z_enu = y. A pure signed permutation, so conversions are exact.
const glm::dmat4 kEnuFromGltf(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 0, 1, 0),
                              glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 0, 1));
const glm::dmat4 kGltfFromEnu = glm::transpose(kEnuFromGltf);

bool is_identity(const glm::dmat4& m) {
  return m == glm::dmat4(1.0);
}

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[c][r]))
        return false;
    }
  }
  return true;
}

// Local transform of a node: its matrix, or T * R * S (glTF 2.0 spec, 5.25 "node").
glm::dmat4 local_matrix(const tinygltf::Node& n, const std::filesystem::path& path, int index) {
  const std::string where = "node " + std::to_string(index);
  if (!n.matrix.empty()) {
    if (n.matrix.size() != 16)
      fail(path, where + ": matrix must have 16 elements");
    glm::dmat4 m;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r)
        m[c][r] = n.matrix[static_cast<std::size_t>(c * 4 + r)];  // column-major
    }
    return m;
  }
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (!n.translation.empty()) {
    if (n.translation.size() != 3)
      fail(path, where + ": translation must have 3 elements");
    t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
  }
  if (!n.rotation.empty()) {
    if (n.rotation.size() != 4)
      fail(path, where + ": rotation must have 4 elements");
    // glTF stores (x, y, z, w); glm's quaternion constructor takes (w, x, y, z).
    const glm::dquat q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
    const double len = glm::length(q);
    if (!(len > 0.0))
      fail(path, where + ": rotation quaternion has zero length");
    r = glm::mat4_cast(q / len);
  }
  if (!n.scale.empty()) {
    if (n.scale.size() != 3)
      fail(path, where + ": scale must have 3 elements");
    s[0][0] = n.scale[0];
    s[1][1] = n.scale[1];
    s[2][2] = n.scale[2];
  }
  return t * r * s;
}

std::size_t component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

std::size_t component_count(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
    case TINYGLTF_TYPE_MAT2:
      return 4;
    case TINYGLTF_TYPE_MAT3:
      return 9;
    case TINYGLTF_TYPE_MAT4:
      return 16;
    default:
      return 0;
  }
}

// Bounds-checked view of an accessor's elements: every element i in [0, count) lies entirely
// inside `bytes` at i * stride.
struct AccessorView {
  std::span<const unsigned char> bytes;
  std::size_t stride = 0;
  std::size_t count = 0;
  int component_type = 0;

  [[nodiscard]] const unsigned char* element(std::size_t i) const { return &bytes[i * stride]; }
};

AccessorView view_of(const tinygltf::Model& model, int index, int expect_type,
                     const std::filesystem::path& path, const std::string& what) {
  const std::string acc = what + ": accessor " + std::to_string(index);
  if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size())
    fail(path, acc + " does not exist");
  const tinygltf::Accessor& a = model.accessors[static_cast<std::size_t>(index)];
  if (a.sparse.isSparse)
    fail(path, acc + " is sparse (not supported)");
  if (a.type != expect_type)
    fail(path,
         acc + " has type " + std::to_string(a.type) + ", expected " + std::to_string(expect_type));
  if (a.bufferView < 0 || static_cast<std::size_t>(a.bufferView) >= model.bufferViews.size())
    fail(path, acc + " has no valid buffer view");
  const tinygltf::BufferView& bv = model.bufferViews[static_cast<std::size_t>(a.bufferView)];
  if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model.buffers.size())
    fail(path, acc + ": buffer view " + std::to_string(a.bufferView) + " has no valid buffer");
  const tinygltf::Buffer& b = model.buffers[static_cast<std::size_t>(bv.buffer)];
  const std::size_t csize = component_size(a.componentType);
  const std::size_t ncomp = component_count(a.type);
  if (csize == 0 || ncomp == 0)
    fail(path, acc + " has an unsupported component type " + std::to_string(a.componentType));
  const std::size_t elem = csize * ncomp;
  const std::size_t stride = bv.byteStride != 0 ? bv.byteStride : elem;
  if (stride < elem)
    fail(path, acc + ": byte stride " + std::to_string(stride) + " is smaller than an element");
  if (bv.byteOffset > b.data.size() || bv.byteLength > b.data.size() - bv.byteOffset) {
    fail(path, acc + ": buffer view " + std::to_string(a.bufferView) +
                   " runs past the end of its buffer (" + std::to_string(b.data.size()) +
                   " bytes)");
  }
  const std::span<const unsigned char> view(b.data.data() + bv.byteOffset, bv.byteLength);
  if (a.count == 0)
    return {{}, stride, 0, a.componentType};
  // Last element ends at byteOffset + (count - 1) * stride + elem <= byteLength (no overflow:
  // every step is compared before it is added).
  if (a.byteOffset > view.size() || view.size() - a.byteOffset < elem ||
      (a.count - 1) > (view.size() - a.byteOffset - elem) / stride) {
    fail(path, acc + " (" + std::to_string(a.count) + " elements) runs past the end of its " +
                   "buffer view (" + std::to_string(view.size()) + " bytes)");
  }
  return {view.subspan(a.byteOffset), stride, a.count, a.componentType};
}

std::uint32_t read_index(const AccessorView& v, std::size_t i) {
  const unsigned char* p = v.element(i);
  switch (v.component_type) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return p[0];
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t x = 0;
      std::memcpy(&x, p, sizeof x);
      return x;
    }
    default: {  // UNSIGNED_INT (checked by the caller)
      std::uint32_t x = 0;
      std::memcpy(&x, p, sizeof x);
      return x;
    }
  }
}

const tinygltf::Value* radar_extras(const tinygltf::Value& extras, const char* key) {
  if (!extras.IsObject() || !extras.Has("radar_emu"))
    return nullptr;
  const tinygltf::Value& r = extras.Get("radar_emu");
  if (!r.IsObject() || !r.Has(key))
    return nullptr;
  return &r.Get(key);
}

// The keys an extras.radar_emu object may hold where it is read (docs/scene_format.md): an
// unknown key is an error, so that a typo ("velocity" for "velocity_mps") cannot leave an
// object silently static. Extras outside "radar_emu" belong to other tools and are ignored.
constexpr std::array<std::string_view, 7> kNodeExtras{
    "area",         "lod_group",        "lod_level", "lod_facet_m",
    "velocity_mps", "start_position_m", "trajectory"};
constexpr std::array<std::string_view, 6> kTrajectoryExtras{
    "waypoints_m", "speed_mps", "turn_radius_m", "turn_rate_rad_s", "loop", "bank"};
constexpr std::array<std::string_view, 1> kMaterialExtras{"radar_material"};
constexpr std::array<std::string_view, 2> kSceneExtras{"anchor_deg_m", "incomplete"};

std::string known_list(std::span<const std::string_view> keys) {
  std::string s;
  for (std::string_view k : keys)
    s += (s.empty() ? "" : ", ") + std::string(k);
  return s;
}

// Throws "FILE: WHAT: unknown key 'K' (known: ...)" for a key of `object` outside `allowed`.
void check_keys(const tinygltf::Value& object, std::span<const std::string_view> allowed,
                const std::filesystem::path& path, const std::string& what) {
  if (!object.IsObject())
    fail(path, what + " must be an object");
  for (const std::string& key : object.Keys()) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
      fail(path, what + ": unknown key '" + key + "' (known: " + known_list(allowed) + ")");
  }
}

// extras.radar_emu of a node, material or scene, when present: an object of known keys.
void check_radar_extras(const tinygltf::Value& extras, std::span<const std::string_view> allowed,
                        const std::filesystem::path& path, const std::string& where) {
  if (extras.IsObject() && extras.Has("radar_emu"))
    check_keys(extras.Get("radar_emu"), allowed, path, where + " extras radar_emu");
}

// extras.radar_emu where nothing reads it (meshes, primitives): an error, not a silent no-op.
void reject_radar_extras(const tinygltf::Value& extras, const std::filesystem::path& path,
                         const std::string& where) {
  if (extras.IsObject() && extras.Has("radar_emu")) {
    fail(path, where +
                   " extras radar_emu: not read here (radar_emu extras belong on nodes, "
                   "materials and the scene)");
  }
}

// Reads an optional [x, y, z] from extras: false when absent; throws when present but broken.
bool read_vec3(const tinygltf::Value* v, glm::dvec3& out, const std::filesystem::path& path,
               const std::string& what) {
  if (!v)
    return false;
  if (!v->IsArray() || v->ArrayLen() != 3)
    fail(path, what + " must be an array of 3 numbers");
  for (int i = 0; i < 3; ++i) {
    const tinygltf::Value& e = v->Get(i);
    if (!e.IsNumber() || !std::isfinite(e.GetNumberAsDouble()))
      fail(path, what + " must be an array of 3 finite numbers");
    out[i] = e.GetNumberAsDouble();
  }
  return true;
}

// Optional scalar extras: false when absent; throw "FILE: WHAT must be ..." when present but
// of the wrong kind.
bool read_number(const tinygltf::Value* v, double& out, const std::filesystem::path& path,
                 const std::string& what) {
  if (!v)
    return false;
  if (!v->IsNumber() || !std::isfinite(v->GetNumberAsDouble()))
    fail(path, what + " must be a finite number");
  out = v->GetNumberAsDouble();
  return true;
}

bool read_integer(const tinygltf::Value* v, long long lo, long long hi, long long& out,
                  const std::filesystem::path& path, const std::string& what) {
  double x = 0.0;
  if (!read_number(v, x, path, what))
    return false;
  if (x != std::floor(x) || x < static_cast<double>(lo) || x > static_cast<double>(hi)) {
    fail(path,
         what + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  out = static_cast<long long>(x);
  return true;
}

bool read_bool(const tinygltf::Value* v, bool& out, const std::filesystem::path& path,
               const std::string& what) {
  if (!v)
    return false;
  if (!v->IsBool())
    fail(path, what + " must be true or false");
  out = v->Get<bool>();
  return true;
}

bool read_string(const tinygltf::Value* v, std::string& out, const std::filesystem::path& path,
                 const std::string& what) {
  if (!v)
    return false;
  if (!v->IsString())
    fail(path, what + " must be a string");
  out = v->Get<std::string>();
  return true;
}

const tinygltf::Value* member(const tinygltf::Value& object, const char* key) {
  return object.IsObject() && object.Has(key) ? &object.Get(key) : nullptr;
}

// extras.radar_emu.trajectory of a node (scene::Trajectory): {"waypoints_m": [[e, n, u], ...],
// "speed_mps": v, "turn_radius_m": r, "turn_rate_rad_s": w, "loop": bool, "bank": bool}.
Trajectory read_trajectory(const tinygltf::Value& v, const std::filesystem::path& path,
                           const std::string& what) {
  check_keys(v, kTrajectoryExtras, path, what);
  Trajectory t;
  const tinygltf::Value* wp = member(v, "waypoints_m");
  if (!wp || !wp->IsArray() || wp->ArrayLen() < 2)
    fail(path, what + ".waypoints_m must be an array of at least 2 [e, n, u] points");
  for (int i = 0; i < static_cast<int>(wp->ArrayLen()); ++i) {
    glm::dvec3 p(0.0);
    (void)read_vec3(&wp->Get(i), p, path, what + ".waypoints_m[" + std::to_string(i) + "]");
    t.waypoints_m.push_back(p);
  }
  if (!read_number(member(v, "speed_mps"), t.speed_mps, path, what + ".speed_mps"))
    fail(path, what + ".speed_mps is missing");
  (void)read_number(member(v, "turn_radius_m"), t.turn_radius_m, path, what + ".turn_radius_m");
  (void)read_number(member(v, "turn_rate_rad_s"), t.turn_rate_rad_s, path,
                    what + ".turn_rate_rad_s");
  (void)read_bool(member(v, "loop"), t.loop, path, what + ".loop");
  (void)read_bool(member(v, "bank"), t.bank, path, what + ".bank");
  try {
    (void)TrajectoryPath(t);  // every geometric check, now, with the file's name
  } catch (const std::invalid_argument& e) {
    fail(path, what + ": " + e.what());
  }
  return t;
}

bool supported_required_extension(const std::string& name) {
  // Material and texture extensions do not change geometry; everything else might.
  return name.starts_with("KHR_materials_") || name.starts_with("KHR_texture_");
}

struct Loader {
  const tinygltf::Model& model;
  const std::filesystem::path& path;
  SceneDescription& desc;
  std::map<int, std::uint16_t> material_of_gltf{};
  std::vector<bool> visited = std::vector<bool>(model.nodes.size(), false);

  std::uint16_t material(int gltf_index, const std::string& where) {
    if (gltf_index < 0)
      fail(path, where + " has no material (its name is the radar material)");
    if (static_cast<std::size_t>(gltf_index) >= model.materials.size())
      fail(path, where + ": material " + std::to_string(gltf_index) + " does not exist");
    if (const auto it = material_of_gltf.find(gltf_index); it != material_of_gltf.end())
      return it->second;
    const tinygltf::Material& m = model.materials[static_cast<std::size_t>(gltf_index)];
    check_radar_extras(m.extras, kMaterialExtras, path, "material " + std::to_string(gltf_index));
    Material out;
    out.name = m.name;
    // extras {"radar_emu": {"radar_material": NAME}} overrides the glTF name.
    (void)read_string(
        radar_extras(m.extras, "radar_material"), out.name, path,
        "material " + std::to_string(gltf_index) + " extras radar_emu.radar_material");
    if (out.name.empty())
      fail(path, where + ": material " + std::to_string(gltf_index) + " has no name");
    const std::vector<double>& c = m.pbrMetallicRoughness.baseColorFactor;
    if (c.size() >= 3) {
      out.base_color = glm::vec3(glm::clamp(glm::dvec3(c[0], c[1], c[2]), 0.0, 1.0));
    }
    // Materials with the same name are one radar material.
    for (std::size_t i = 0; i < desc.materials.size(); ++i) {
      if (desc.materials[i].name == out.name)
        return material_of_gltf[gltf_index] = static_cast<std::uint16_t>(i);
    }
    if (desc.materials.size() > std::numeric_limits<std::uint16_t>::max())
      fail(path, "more than 65536 distinct materials");
    desc.materials.push_back(out);
    return material_of_gltf[gltf_index] = static_cast<std::uint16_t>(desc.materials.size() - 1);
  }

  void node(int index, const glm::dmat4& parent, int depth) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.nodes.size())
      fail(path, "node " + std::to_string(index) + " does not exist");
    const auto i = static_cast<std::size_t>(index);
    if (visited[i]) {
      fail(path, "node " + std::to_string(index) +
                     " appears twice in the scene graph (a node may have only one parent)");
    }
    visited[i] = true;
    if (depth > kMaxNodeDepth)
      fail(path, "node hierarchy deeper than " + std::to_string(kMaxNodeDepth));
    const tinygltf::Node& n = model.nodes[i];
    check_radar_extras(n.extras, kNodeExtras, path, "node " + std::to_string(index));
    const glm::dmat4 global = parent * local_matrix(n, path, index);
    if (!finite(global))
      fail(path, "node " + std::to_string(index) + " has a non-finite transform");
    if (n.mesh >= 0)
      mesh_object(n, index, global);
    for (int child : n.children)
      node(child, global, depth + 1);
  }

  void mesh_object(const tinygltf::Node& n, int node_index, const glm::dmat4& gltf_global) {
    const std::string node_name = "node " + std::to_string(node_index);
    if (static_cast<std::size_t>(n.mesh) >= model.meshes.size())
      fail(path,
           node_name + " refers to mesh " + std::to_string(n.mesh) + ", which does not exist");
    ObjectDesc o;
    o.name = n.name.empty() ? "node" + std::to_string(node_index) : n.name;
    // World from glTF-local, in ENU.
    const glm::dmat4 world_from_local = kEnuFromGltf * gltf_global;
    glm::dmat4 body_from_local = kEnuFromGltf;  // vertices: glTF axes -> ENU axes
    glm::dvec3 velocity(0.0), start(0.0);
    const std::string extras = node_name + " extras radar_emu.";
    (void)read_string(radar_extras(n.extras, "area"), o.area, path, extras + "area");
    long long integer = 0;
    if (read_integer(radar_extras(n.extras, "lod_group"), -1,
                     std::numeric_limits<std::int32_t>::max(), integer, path,
                     extras + "lod_group")) {
      o.lod_group = static_cast<std::int32_t>(integer);
    }
    if (read_integer(radar_extras(n.extras, "lod_level"), 0, 255, integer, path,
                     extras + "lod_level")) {
      o.lod_level = static_cast<std::uint8_t>(integer);
    }
    if (read_number(radar_extras(n.extras, "lod_facet_m"), o.lod_facet_m, path,
                    extras + "lod_facet_m") &&
        o.lod_facet_m < 0.0) {
      fail(path, extras + "lod_facet_m must be >= 0");
    }
    if (const tinygltf::Value* tv = radar_extras(n.extras, "trajectory")) {
      if (radar_extras(n.extras, "velocity_mps") != nullptr)
        fail(path, node_name + " extras have both radar_emu.velocity_mps and .trajectory");
      // Moving on a trajectory: it places the body; the node's rotation and scale are baked
      // into the body-frame vertices, its translation is ignored.
      o.trajectory = read_trajectory(*tv, path, extras + "trajectory");
      body_from_local = world_from_local;
      body_from_local[3] = glm::dvec4(0.0, 0.0, 0.0, 1.0);
    } else if (read_vec3(radar_extras(n.extras, "velocity_mps"), velocity, path,
                         extras + "velocity_mps")) {
      // Moving: the motion places the body; the node's rotation and scale are baked into the
      // body-frame vertices, its translation is the start position unless given explicitly.
      if (!read_vec3(radar_extras(n.extras, "start_position_m"), start, path,
                     extras + "start_position_m")) {
        start = glm::dvec3(world_from_local[3]);
      }
      body_from_local = world_from_local;
      body_from_local[3] = glm::dvec4(0.0, 0.0, 0.0, 1.0);
      o.motion = LinearMotion{start, velocity};
    } else {
      // Static: the node's transform becomes world_from_body (kept in double), vertices stay
      // small numbers in the body frame.
      o.world_from_body = world_from_local * kGltfFromEnu;
    }
    // A mirroring transform reverses the winding (glTF 2.0 spec, 3.7.4 "meshes"): swap two
    // indices so that counter-clockwise stays "outside" in the world.
    const bool mirrored = glm::determinant(glm::dmat3(gltf_global)) < 0.0;

    const tinygltf::Mesh& mesh = model.meshes[static_cast<std::size_t>(n.mesh)];
    // radar_emu extras are read on nodes, materials and the scene only: elsewhere they would
    // do nothing, so they are an error rather than a silent no-op.
    const std::string mesh_name = "mesh " + std::to_string(n.mesh);
    reject_radar_extras(mesh.extras, path, mesh_name);
    for (std::size_t p = 0; p < mesh.primitives.size(); ++p)
      reject_radar_extras(mesh.primitives[p].extras, path,
                          mesh_name + " primitive " + std::to_string(p));
    std::map<int, std::uint32_t> base_of_accessor;  // primitives sharing POSITION share vertices
    for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& prim = mesh.primitives[p];
      const std::string where = "mesh " + std::to_string(n.mesh) +
                                (mesh.name.empty() ? "" : " '" + mesh.name + "'") + " primitive " +
                                std::to_string(p);
      if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
        fail(path, where + ": mode " + std::to_string(prim.mode) +
                       " is not TRIANGLES (4); only triangle lists are supported");
      }
      const auto pos_it = prim.attributes.find("POSITION");
      if (pos_it == prim.attributes.end())
        fail(path, where + " has no POSITION attribute");
      const AccessorView pos =
          view_of(model, pos_it->second, TINYGLTF_TYPE_VEC3, path, where + " POSITION");
      if (pos.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT)
        fail(path, where + ": POSITION is not float (quantised positions are not supported)");
      const std::uint16_t mat = material(prim.material, where);
      std::uint32_t base = 0;
      if (const auto it = base_of_accessor.find(pos_it->second); it != base_of_accessor.end()) {
        base = it->second;
      } else {
        if (o.mesh.positions_m.size() + pos.count >= std::numeric_limits<std::uint32_t>::max())
          fail(path, where + ": too many vertices");
        base = static_cast<std::uint32_t>(o.mesh.positions_m.size());
        base_of_accessor[pos_it->second] = base;
        for (std::size_t i = 0; i < pos.count; ++i) {
          std::array<float, 3> xyz{};
          std::memcpy(xyz.data(), pos.element(i), sizeof xyz);
          if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
            fail(path, where + ": POSITION " + std::to_string(i) + " is not finite");
          const glm::dvec4 local(xyz[0], xyz[1], xyz[2], 1.0);
          o.mesh.positions_m.emplace_back(glm::dvec3(body_from_local * local));
        }
      }
      std::size_t nidx = pos.count;
      AccessorView idx{};
      const bool indexed = prim.indices >= 0;
      if (indexed) {
        idx = view_of(model, prim.indices, TINYGLTF_TYPE_SCALAR, path, where + " indices");
        if (idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
          fail(path, where + ": indices must be unsigned byte, short or int");
        }
        nidx = idx.count;
      }
      if (nidx % 3 != 0) {
        fail(path, where + ": " + std::to_string(nidx) + (indexed ? " indices" : " vertices") +
                       " is not a multiple of 3");
      }
      for (std::size_t i = 0; i < nidx; i += 3) {
        glm::uvec3 t;
        for (glm::length_t k = 0; k < 3; ++k) {
          const std::size_t j = i + static_cast<std::size_t>(k);
          const std::uint32_t v = indexed ? read_index(idx, j) : static_cast<std::uint32_t>(j);
          if (v >= pos.count) {
            fail(path, where + ": index " + std::to_string(j) + " = " + std::to_string(v) +
                           " is out of range (" + std::to_string(pos.count) + " vertices)");
          }
          t[k] = base + v;
        }
        if (mirrored)
          std::swap(t.y, t.z);
        o.mesh.triangles.push_back(t);
        o.mesh.triangle_material.push_back(mat);
      }
    }
    if (!o.mesh.triangles.empty())
      desc.objects.push_back(std::move(o));
  }
};

bool starts_with_glb_magic(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  return in.read(magic, sizeof magic) && std::string_view(magic, sizeof magic) == "glTF";
}

// Little-endian u32 at p (GLB integers are little-endian, spec sec. 4.4.1).
std::uint32_t le32(const char* p) {
  std::uint32_t v = 0;
  for (int k = 3; k >= 0; --k)
    v = (v << 8) | static_cast<unsigned char>(p[k]);
  return v;
}

// The binary container's header and chunk framing (glTF 2.0 spec, sec. 4.4 "Binary glTF
// layout": 12-byte header magic "glTF", version 2, total length = file length; then chunks of
// u32 length, u32 type, data; the first is JSON (0x4E4F534A), an optional second BIN
// (0x004E4942)), checked before tinygltf sees the file so that each defect gets its own message.
void check_glb_container(const std::filesystem::path& path) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec)
    fail(path, "cannot read the file size: " + ec.message());
  std::ifstream in(path, std::ios::binary);
  char h[20] = {};
  in.read(h, sizeof h);
  const auto got = static_cast<std::size_t>(in.gcount());
  if (got < 12) {
    fail(path, "not a valid glTF 2.0 file: GLB header truncated (" + std::to_string(got) +
                   " bytes, 12 expected)");
  }
  if (std::memcmp(h, "glTF", 4) != 0)
    fail(path, "not a valid glTF 2.0 file: no GLB magic 'glTF'");
  if (le32(h + 4) != 2) {
    fail(path, "not a valid glTF 2.0 file: GLB container version " + std::to_string(le32(h + 4)) +
                   " (2 expected)");
  }
  if (le32(h + 8) != size) {
    fail(path, "not a valid glTF 2.0 file: the GLB header gives a length of " +
                   std::to_string(le32(h + 8)) + " bytes but the file has " + std::to_string(size) +
                   " (truncated or damaged)");
  }
  if (got < 20)
    fail(path, "not a valid glTF 2.0 file: GLB file ends before its JSON chunk header");
  const std::uint64_t json_end = 20ull + le32(h + 12);
  if (le32(h + 16) != 0x4E4F534Au)
    fail(path, "not a valid glTF 2.0 file: the first GLB chunk is not JSON");
  if (json_end > size) {
    fail(path, "not a valid glTF 2.0 file: the GLB JSON chunk length " +
                   std::to_string(le32(h + 12)) + " runs past the end of the file (" +
                   std::to_string(size) + " bytes)");
  }
  if (json_end + 8 <= size) {
    char c[8] = {};
    in.seekg(static_cast<std::streamoff>(json_end));
    in.read(c, sizeof c);
    if (in.gcount() == 8 && json_end + 8 + le32(c) > size) {
      fail(path, "not a valid glTF 2.0 file: the GLB BIN chunk length " + std::to_string(le32(c)) +
                     " runs past the end of the file (" + std::to_string(size) + " bytes)");
    }
  }
}

std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r'))
    s.pop_back();
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}

void check_writable(const SceneDescription& d, const std::filesystem::path& path) {
  if (d.materials.size() > std::numeric_limits<std::uint16_t>::max() + std::size_t{1})
    fail(path, "too many materials");
  for (const ObjectDesc& o : d.objects) {
    const std::string who = "object '" + o.name + "'";
    if (o.mesh.triangle_material.size() != o.mesh.triangles.size())
      fail(path, who + ": one material index per triangle is required");
    for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
      const glm::uvec3 tri = o.mesh.triangles[t];
      const std::size_t n = o.mesh.positions_m.size();
      if (tri.x >= n || tri.y >= n || tri.z >= n)
        fail(path, who + ": triangle " + std::to_string(t) + " indexes a missing vertex");
      if (o.mesh.triangle_material[t] >= d.materials.size())
        fail(path, who + ": triangle " + std::to_string(t) + " has a missing material");
    }
  }
}

// Appends raw bytes to the buffer, 4-byte aligned (glTF 2.0 spec 3.6.2.4: accessor offsets must
// be multiples of the component size).
std::size_t append(std::vector<unsigned char>& buffer, const void* data, std::size_t n) {
  buffer.resize((buffer.size() + 3) / 4 * 4, 0);
  const std::size_t offset = buffer.size();
  buffer.resize(offset + n);
  if (n > 0)
    std::memcpy(buffer.data() + offset, data, n);
  return offset;
}

int add_view(tinygltf::Model& model, std::size_t offset, std::size_t length, int target) {
  tinygltf::BufferView v;
  v.buffer = 0;
  v.byteOffset = offset;
  v.byteLength = length;
  v.target = target;
  model.bufferViews.push_back(v);
  return static_cast<int>(model.bufferViews.size() - 1);
}

tinygltf::Value number_array(std::initializer_list<double> xs) {
  tinygltf::Value::Array a;
  for (double x : xs)
    a.emplace_back(x);
  return tinygltf::Value(std::move(a));
}

}  // namespace

SceneDescription load_gltf(const std::filesystem::path& path, std::vector<std::string>* warnings) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    fail(path, "no such file");
  tinygltf::TinyGLTF loader;
  // Images are irrelevant to radar: never decoded.
  loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int,
                           const unsigned char*, int, void*) { return true; },
                        nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = starts_with_glb_magic(path) || common::lower_extension(path) == ".glb";
  if (binary)
    check_glb_container(path);
  bool ok = false;
  try {
    ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path.string())
                : loader.LoadASCIIFromFile(&model, &err, &warn, path.string());
  } catch (const std::exception& e) {  // e.g. allocation failure on absurd sizes
    fail(path, std::string("not a valid glTF 2.0 file: ") + e.what());
  }
  if (!ok)
    fail(path, "not a valid glTF 2.0 file: " + one_line(err.empty() ? "unknown error" : err));
  for (const std::string& ext : model.extensionsRequired) {
    if (!supported_required_extension(ext))
      fail(path, "requires the unsupported extension " + ext);
  }
  SceneDescription desc;
  Loader l{model, path, desc};
  if (model.scenes.empty()) {
    // No scene: every root node (a node that is nobody's child).
    std::vector<bool> is_child(model.nodes.size(), false);
    for (const tinygltf::Node& n : model.nodes) {
      for (int c : n.children) {
        if (c >= 0 && static_cast<std::size_t>(c) < model.nodes.size())
          is_child[static_cast<std::size_t>(c)] = true;
      }
    }
    for (std::size_t i = 0; i < model.nodes.size(); ++i) {
      if (!is_child[i])
        l.node(static_cast<int>(i), glm::dmat4(1.0), 0);
    }
  } else {
    const std::size_t s =
        model.defaultScene >= 0 ? static_cast<std::size_t>(model.defaultScene) : 0;
    if (s >= model.scenes.size())
      fail(path, "default scene " + std::to_string(s) + " does not exist");
    for (int n : model.scenes[s].nodes)
      l.node(n, glm::dmat4(1.0), 0);
    check_radar_extras(model.scenes[s].extras, kSceneExtras, path, "scene " + std::to_string(s));
    glm::dvec3 anchor(0.0);
    if (read_vec3(radar_extras(model.scenes[s].extras, "anchor_deg_m"), anchor, path,
                  "scene extras radar_emu.anchor_deg_m")) {
      if (std::abs(anchor.x) > 90.0)
        fail(path, "scene extras radar_emu.anchor_deg_m: latitude beyond +-90 deg");
      desc.anchor = {common::radians(anchor.x), common::radians(anchor.y), anchor.z};
    }
    (void)read_string(radar_extras(model.scenes[s].extras, "incomplete"), desc.incomplete, path,
                      "scene extras radar_emu.incomplete");
    if (!desc.incomplete.empty() && warnings != nullptr)
      warnings->push_back(path.string() + ": an incomplete scene: " + desc.incomplete);
  }
  if (desc.objects.empty())
    fail(path, "no triangle meshes in the scene");
  // Degenerate triangles are dropped (a node with nothing else is dropped whole), reported
  // with the node; open and non-manifold surfaces are reported (scene/mesh_check.hpp).
  // One check per node (it welds and builds the node's topology, most of the load's time), the
  // nodes in parallel: each check reads its own mesh only.
  std::vector<MeshCheck> checks(desc.objects.size());
  tbb::parallel_for(std::size_t{0}, desc.objects.size(),
                    [&](std::size_t i) { checks[i] = check_mesh(desc.objects[i].mesh); });
  std::vector<ObjectDesc> kept;
  for (std::size_t i = 0; i < desc.objects.size(); ++i) {
    ObjectDesc& o = desc.objects[i];
    const std::string source = path.string() + ": node " + o.name;
    if (checks[i].degenerate.size() == o.mesh.triangles.size()) {
      if (warnings != nullptr)
        warnings->push_back(source + ": every triangle is degenerate: node dropped");
      continue;
    }
    std::vector<std::string> w = clean_loaded_mesh(o.mesh, checks[i], source);
    if (warnings != nullptr)
      warnings->insert(warnings->end(), w.begin(), w.end());
    kept.push_back(std::move(o));
  }
  if (kept.empty())
    fail(path, "every triangle is degenerate");
  desc.objects = std::move(kept);
  return desc;
}

void write_gltf(const SceneDescription& d, const std::filesystem::path& path) {
  check_writable(d, path);
  {
    std::error_code ec;
    const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
    if (!std::filesystem::is_directory(dir, ec))
      fail(path, "cannot write glTF: directory " + dir.string() + " does not exist");
  }
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "radar-emu";
  for (const Material& m : d.materials) {
    tinygltf::Material gm;
    gm.name = m.name;
    gm.pbrMetallicRoughness.baseColorFactor = {static_cast<double>(m.base_color.r),
                                               static_cast<double>(m.base_color.g),
                                               static_cast<double>(m.base_color.b), 1.0};
    gm.doubleSided = false;
    tinygltf::Value::Object r;
    r["radar_material"] = tinygltf::Value(m.name);
    tinygltf::Value::Object e;
    e["radar_emu"] = tinygltf::Value(std::move(r));
    gm.extras = tinygltf::Value(std::move(e));
    model.materials.push_back(gm);
  }
  std::vector<unsigned char> buffer;
  tinygltf::Scene scene;
  for (const ObjectDesc& o : d.objects) {
    // Body-frame vertices in glTF axes; the placement of static objects goes in the node matrix.
    std::vector<float> xyz;
    xyz.reserve(3 * o.mesh.positions_m.size());
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : o.mesh.positions_m) {
      const glm::dvec3 q(kGltfFromEnu * glm::dvec4(glm::dvec3(p), 1.0));
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
      xyz.insert(xyz.end(),
                 {static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)});
    }
    tinygltf::Mesh mesh;
    mesh.name = o.name;
    if (!xyz.empty()) {
      const std::size_t off = append(buffer, xyz.data(), xyz.size() * sizeof(float));
      tinygltf::Accessor pos;
      pos.bufferView =
          add_view(model, off, xyz.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
      pos.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
      pos.type = TINYGLTF_TYPE_VEC3;
      pos.count = o.mesh.positions_m.size();
      pos.minValues = {lo.x, lo.y, lo.z};
      pos.maxValues = {hi.x, hi.y, hi.z};
      model.accessors.push_back(pos);
    }
    const int pos_accessor = static_cast<int>(model.accessors.size()) - 1;
    // One primitive per run of consecutive triangles with the same material: the triangle order
    // (and so primitive ids) survives the round trip.
    const bool small = o.mesh.positions_m.size() <= std::numeric_limits<std::uint16_t>::max();
    for (std::size_t begin = 0; begin < o.mesh.triangles.size();) {
      const std::uint16_t mat = o.mesh.triangle_material[begin];
      std::size_t end = begin;
      while (end < o.mesh.triangles.size() && o.mesh.triangle_material[end] == mat)
        ++end;
      std::vector<std::uint32_t> idx32;
      std::vector<std::uint16_t> idx16;
      for (std::size_t t = begin; t < end; ++t) {
        for (glm::length_t k = 0; k < 3; ++k) {
          if (small)
            idx16.push_back(static_cast<std::uint16_t>(o.mesh.triangles[t][k]));
          else
            idx32.push_back(o.mesh.triangles[t][k]);
        }
      }
      const std::size_t bytes = small ? idx16.size() * 2 : idx32.size() * 4;
      const std::size_t off =
          small ? append(buffer, idx16.data(), bytes) : append(buffer, idx32.data(), bytes);
      tinygltf::Accessor ia;
      ia.bufferView = add_view(model, off, bytes, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
      ia.componentType =
          small ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
      ia.type = TINYGLTF_TYPE_SCALAR;
      ia.count = 3 * (end - begin);
      model.accessors.push_back(ia);
      tinygltf::Primitive prim;
      prim.attributes["POSITION"] = pos_accessor;
      prim.indices = static_cast<int>(model.accessors.size() - 1);
      prim.material = mat;
      prim.mode = TINYGLTF_MODE_TRIANGLES;
      mesh.primitives.push_back(prim);
      begin = end;
    }
    tinygltf::Node node;
    node.name = o.name;
    if (!mesh.primitives.empty()) {
      model.meshes.push_back(mesh);
      node.mesh = static_cast<int>(model.meshes.size() - 1);
    }
    tinygltf::Value::Object radar;
    if (!o.area.empty())
      radar["area"] = tinygltf::Value(o.area);
    if (o.lod_group >= 0) {
      radar["lod_group"] = tinygltf::Value(static_cast<int>(o.lod_group));
      radar["lod_level"] = tinygltf::Value(static_cast<int>(o.lod_level));
      radar["lod_facet_m"] = tinygltf::Value(o.lod_facet_m);
    }
    if (o.motion) {
      const glm::dvec3 v = o.motion->velocity_mps, s = o.motion->start_position_m;
      radar["velocity_mps"] = number_array({v.x, v.y, v.z});
      radar["start_position_m"] = number_array({s.x, s.y, s.z});
    }
    if (o.trajectory) {
      const Trajectory& t = *o.trajectory;
      tinygltf::Value::Array points;
      for (const glm::dvec3& p : t.waypoints_m)
        points.push_back(number_array({p.x, p.y, p.z}));
      tinygltf::Value::Object tj;
      tj["waypoints_m"] = tinygltf::Value(std::move(points));
      tj["speed_mps"] = tinygltf::Value(t.speed_mps);
      tj["turn_radius_m"] = tinygltf::Value(t.turn_radius_m);
      if (t.turn_rate_rad_s != 0.0)
        tj["turn_rate_rad_s"] = tinygltf::Value(t.turn_rate_rad_s);
      tj["loop"] = tinygltf::Value(t.loop);
      if (t.bank)
        tj["bank"] = tinygltf::Value(true);
      radar["trajectory"] = tinygltf::Value(std::move(tj));
    }
    if (!radar.empty()) {
      tinygltf::Value::Object e;
      e["radar_emu"] = tinygltf::Value(std::move(radar));
      node.extras = tinygltf::Value(std::move(e));
    }
    if (!o.motion && !o.trajectory) {
      const glm::dmat4 gltf_from_body = kGltfFromEnu * o.world_from_body * kEnuFromGltf;
      if (!is_identity(gltf_from_body)) {
        node.matrix.resize(16);
        for (int c = 0; c < 4; ++c) {
          for (int r = 0; r < 4; ++r)
            node.matrix[static_cast<std::size_t>(c * 4 + r)] = gltf_from_body[c][r];
        }
      }
    }
    model.nodes.push_back(node);
    scene.nodes.push_back(static_cast<int>(model.nodes.size() - 1));
  }
  tinygltf::Value::Object anchor;
  anchor["anchor_deg_m"] =
      number_array({d.anchor.latitude_rad / common::kRadPerDeg,
                    d.anchor.longitude_rad / common::kRadPerDeg, d.anchor.height_m});
  if (!d.incomplete.empty())
    anchor["incomplete"] = tinygltf::Value(d.incomplete);
  tinygltf::Value::Object se;
  se["radar_emu"] = tinygltf::Value(std::move(anchor));
  scene.extras = tinygltf::Value(std::move(se));
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  buffer.resize((buffer.size() + 3) / 4 * 4, 0);
  tinygltf::Buffer b;
  b.data = std::move(buffer);
  model.buffers.push_back(std::move(b));
  tinygltf::TinyGLTF writer;
  const bool binary = common::lower_extension(path) == ".glb";
  bool ok = false;
  try {
    ok = writer.WriteGltfSceneToFile(&model, path.string(), /*embedImages=*/true,
                                     /*embedBuffers=*/true, /*prettyPrint=*/!binary,
                                     /*writeBinary=*/binary);
  } catch (const std::exception& e) {
    fail(path, std::string("cannot write glTF: ") + e.what());
  }
  std::error_code ec;
  if (!ok || !std::filesystem::is_regular_file(path, ec) ||
      std::filesystem::file_size(path, ec) == 0)
    fail(path, "cannot write glTF");
}

}  // namespace radar_emu::scene
