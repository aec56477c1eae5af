#include "scene/gltf.hpp"

#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

namespace radar_emu::scene {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

// glTF is y-up; the world is ENU (z up): x_enu = x, y_enu = -z, z_enu = y.
const glm::dmat4 kEnuFromGltf(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 0, 1, 0),
                              glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 0, 1));

glm::dmat4 local_matrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    glm::dmat4 m;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r)
        m[c][r] = n.matrix[static_cast<std::size_t>(c * 4 + r)];
    }
    return m;
  }
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (n.translation.size() == 3)
    t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1);
  if (n.rotation.size() == 4) {
    r = glm::mat4_cast(glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]));
  }
  if (n.scale.size() == 3) {
    s[0][0] = n.scale[0];
    s[1][1] = n.scale[1];
    s[2][2] = n.scale[2];
  }
  return t * r * s;
}

// Bounds-checked view of an accessor's elements.
struct AccessorView {
  const unsigned char* base = nullptr;
  std::size_t stride = 0;
  std::size_t count = 0;
  int component_type = 0;
};

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

AccessorView view_of(const tinygltf::Model& model, int index, int expect_type,
                     const std::filesystem::path& path, const std::string& what) {
  if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
    fail(path, what + ": accessor " + std::to_string(index) + " does not exist");
  }
  const tinygltf::Accessor& a = model.accessors[static_cast<std::size_t>(index)];
  if (a.sparse.isSparse)
    fail(path, what + ": sparse accessors are not supported");
  if (a.type != expect_type)
    fail(path, what + ": accessor " + std::to_string(index) + " has the wrong type");
  if (a.bufferView < 0 || static_cast<std::size_t>(a.bufferView) >= model.bufferViews.size()) {
    fail(path, what + ": accessor " + std::to_string(index) + " has no buffer view");
  }
  const tinygltf::BufferView& bv = model.bufferViews[static_cast<std::size_t>(a.bufferView)];
  if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model.buffers.size()) {
    fail(path, what + ": buffer view refers to a missing buffer");
  }
  const tinygltf::Buffer& b = model.buffers[static_cast<std::size_t>(bv.buffer)];
  const std::size_t csize = component_size(a.componentType);
  const auto ncomp = static_cast<std::size_t>(
      tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type)));
  if (csize == 0 || ncomp == 0)
    fail(path, what + ": unsupported component type");
  const std::size_t elem = csize * ncomp;
  const std::size_t stride = bv.byteStride ? bv.byteStride : elem;
  if (stride < elem)
    fail(path, what + ": byte stride smaller than an element");
  if (bv.byteOffset > b.data.size() || bv.byteLength > b.data.size() - bv.byteOffset) {
    fail(path, what + ": buffer view runs past the end of its buffer");
  }
  if (a.count > 0) {
    const std::size_t avail = a.byteOffset <= bv.byteLength ? bv.byteLength - a.byteOffset : 0;
    if (a.byteOffset > bv.byteLength || avail < elem || (a.count - 1) > (avail - elem) / stride) {
      fail(path,
           what + ": accessor " + std::to_string(index) + " runs past the end of its buffer view");
    }
  }
  return {b.data.data() + bv.byteOffset + a.byteOffset, stride, a.count, a.componentType};
}

std::uint32_t read_index(const AccessorView& v, std::size_t i) {
  const unsigned char* p = v.base + i * v.stride;
  switch (v.component_type) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return p[0];
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t x;
      std::memcpy(&x, p, 2);
      return x;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t x;
      std::memcpy(&x, p, 4);
      return x;
    }
    default:
      return 0xFFFFFFFFu;
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

bool read_vec3(const tinygltf::Value* v, glm::dvec3& out) {
  if (!v || !v->IsArray() || v->ArrayLen() != 3)
    return false;
  for (int i = 0; i < 3; ++i) {
    const tinygltf::Value& e = v->Get(i);
    if (!e.IsNumber())
      return false;
    out[i] = e.GetNumberAsDouble();
    if (!std::isfinite(out[i]))
      return false;
  }
  return true;
}

struct Loader {
  const tinygltf::Model& model;
  const std::filesystem::path& path;
  SceneDescription& desc;
  std::map<int, std::uint16_t> material_of_gltf;

  std::uint16_t material(int gltf_index, const std::string& where) {
    if (gltf_index < 0 || static_cast<std::size_t>(gltf_index) >= model.materials.size()) {
      fail(path, where + ": primitive has no material (the material name is the radar material)");
    }
    auto it = material_of_gltf.find(gltf_index);
    if (it != material_of_gltf.end())
      return it->second;
    const tinygltf::Material& m = model.materials[static_cast<std::size_t>(gltf_index)];
    if (m.name.empty())
      fail(path, where + ": material " + std::to_string(gltf_index) + " has no name");
    Material out;
    out.name = m.name;
    const auto& c = m.pbrMetallicRoughness.baseColorFactor;
    if (c.size() >= 3)
      out.base_color = {c[0], c[1], c[2]};
    // Materials with the same name are one radar material.
    for (std::size_t i = 0; i < desc.materials.size(); ++i) {
      if (desc.materials[i].name == out.name)
        return material_of_gltf[gltf_index] = static_cast<std::uint16_t>(i);
    }
    desc.materials.push_back(out);
    return material_of_gltf[gltf_index] = static_cast<std::uint16_t>(desc.materials.size() - 1);
  }

  void node(int index, const glm::dmat4& parent, int depth) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.nodes.size()) {
      fail(path, "node " + std::to_string(index) + " does not exist");
    }
    if (depth > 64)
      fail(path, "node hierarchy deeper than 64 (a cycle?)");
    const tinygltf::Node& n = model.nodes[static_cast<std::size_t>(index)];
    const glm::dmat4 global = parent * local_matrix(n);
    if (n.mesh >= 0)
      mesh_object(n, index, global);
    for (int child : n.children)
      node(child, global, depth + 1);
  }

  void mesh_object(const tinygltf::Node& n, int node_index, const glm::dmat4& global) {
    if (static_cast<std::size_t>(n.mesh) >= model.meshes.size()) {
      fail(path, "node " + std::to_string(node_index) + " refers to a missing mesh");
    }
    const std::string name = n.name.empty() ? "node" + std::to_string(node_index) : n.name;
    ObjectDesc o;
    o.name = name;
    glm::dvec3 velocity(0.0), start(0.0);
    const bool moving = read_vec3(radar_extras(n.extras, "velocity_mps"), velocity);
    glm::dmat4 to_body = kEnuFromGltf * global;  // static: vertices straight to world
    if (moving) {
      if (!read_vec3(radar_extras(n.extras, "start_position_m"), start)) {
        start = glm::dvec3(to_body[3]);
      }
      to_body[3] = glm::dvec4(0, 0, 0, 1);  // body frame: rotation/scale only
      o.motion = LinearMotion{start, velocity};
    }
    const tinygltf::Mesh& mesh = model.meshes[static_cast<std::size_t>(n.mesh)];
    for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& prim = mesh.primitives[p];
      const std::string where = "mesh '" + mesh.name + "' primitive " + std::to_string(p);
      if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
        fail(path, where + ": mode " + std::to_string(prim.mode) + " is not TRIANGLES");
      }
      const auto pos_it = prim.attributes.find("POSITION");
      if (pos_it == prim.attributes.end())
        fail(path, where + ": no POSITION attribute");
      const AccessorView pos = view_of(model, pos_it->second, TINYGLTF_TYPE_VEC3, path, where);
      if (pos.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT)
        fail(path, where + ": POSITION is not float");
      const std::uint16_t mat = material(prim.material, where);
      const auto base = static_cast<std::uint32_t>(o.mesh.positions_m.size());
      for (std::size_t i = 0; i < pos.count; ++i) {
        float xyz[3];
        std::memcpy(xyz, pos.base + i * pos.stride, sizeof xyz);
        const glm::dvec3 w(to_body * glm::dvec4(xyz[0], xyz[1], xyz[2], 1.0));
        o.mesh.positions_m.emplace_back(w);
      }
      std::size_t nidx = pos.count;
      AccessorView idx{};
      if (prim.indices >= 0) {
        idx = view_of(model, prim.indices, TINYGLTF_TYPE_SCALAR, path, where + " indices");
        nidx = idx.count;
      }
      if (nidx % 3 != 0)
        fail(path, where + ": index count is not a multiple of 3");
      for (std::size_t i = 0; i < nidx; i += 3) {
        glm::uvec3 t;
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t v = prim.indices >= 0
                                      ? read_index(idx, i + static_cast<std::size_t>(k))
                                      : static_cast<std::uint32_t>(i + static_cast<std::size_t>(k));
          if (v >= pos.count)
            fail(path, where + ": index " + std::to_string(v) + " out of range");
          t[k] = base + v;
        }
        o.mesh.triangles.push_back(t);
        o.mesh.triangle_material.push_back(mat);
      }
    }
    if (!o.mesh.triangles.empty())
      desc.objects.push_back(std::move(o));
  }
};

}  // namespace

SceneDescription load_gltf(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    fail(path, "no such file");
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(
      [](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*,
         int, void*) { return true; },  // images are irrelevant to radar: never decoded
      nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = path.extension() == ".glb";
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path.string())
                         : loader.LoadASCIIFromFile(&model, &err, &warn, path.string());
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == '\r'))
      err.pop_back();
    for (auto& c : err)
      if (c == '\n')
        c = ' ';
    fail(path, "not a valid glTF 2.0 file: " + err);
  }
  SceneDescription desc;
  Loader l{model, path, desc, {}};
  if (model.scenes.empty()) {
    for (std::size_t i = 0; i < model.nodes.size(); ++i)
      l.node(static_cast<int>(i), glm::dmat4(1.0), 0);
  } else {
    const std::size_t s =
        model.defaultScene >= 0 ? static_cast<std::size_t>(model.defaultScene) : 0;
    if (s >= model.scenes.size())
      fail(path, "default scene does not exist");
    for (int n : model.scenes[s].nodes)
      l.node(n, glm::dmat4(1.0), 0);
    glm::dvec3 anchor;
    if (read_vec3(radar_extras(model.scenes[s].extras, "anchor_deg_m"), anchor)) {
      desc.anchor = {anchor.x * kDeg, anchor.y * kDeg, anchor.z};
    }
  }
  if (desc.objects.empty())
    fail(path, "no triangle meshes");
  return desc;
}

void write_gltf(const SceneDescription& d, const std::filesystem::path& path) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "radar-emu";
  for (const Material& m : d.materials) {
    tinygltf::Material gm;
    gm.name = m.name;
    gm.pbrMetallicRoughness.baseColorFactor = {m.base_color.r, m.base_color.g, m.base_color.b, 1.0};
    model.materials.push_back(gm);
  }
  tinygltf::Buffer buffer;
  const glm::dmat4 gltf_from_enu = glm::inverse(kEnuFromGltf);
  tinygltf::Scene scene;
  for (const ObjectDesc& o : d.objects) {
    // One primitive per material; positions in glTF axes (static objects in world coordinates).
    std::map<std::uint16_t, std::vector<std::uint32_t>> by_material;
    for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
      auto& v = by_material[o.mesh.triangle_material[t]];
      v.insert(v.end(), {o.mesh.triangles[t].x, o.mesh.triangles[t].y, o.mesh.triangles[t].z});
    }
    const glm::dmat4 xf = o.motion ? gltf_from_enu : gltf_from_enu * o.world_from_body;
    const std::size_t pos_offset = buffer.data.size();
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const glm::vec3& p : o.mesh.positions_m) {
      const glm::vec3 q(xf * glm::dvec4(glm::dvec3(p), 1.0));
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
      const auto* bytes = reinterpret_cast<const unsigned char*>(&q);  // float[3] -> bytes
      buffer.data.insert(buffer.data.end(), bytes, bytes + sizeof q);
    }
    tinygltf::BufferView pos_view;
    pos_view.buffer = 0;
    pos_view.byteOffset = pos_offset;
    pos_view.byteLength = buffer.data.size() - pos_offset;
    pos_view.target = TINYGLTF_TARGET_ARRAY_BUFFER;
    model.bufferViews.push_back(pos_view);
    tinygltf::Accessor pos;
    pos.bufferView = static_cast<int>(model.bufferViews.size() - 1);
    pos.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    pos.type = TINYGLTF_TYPE_VEC3;
    pos.count = o.mesh.positions_m.size();
    pos.minValues = {lo.x, lo.y, lo.z};
    pos.maxValues = {hi.x, hi.y, hi.z};
    model.accessors.push_back(pos);
    const int pos_accessor = static_cast<int>(model.accessors.size() - 1);
    tinygltf::Mesh mesh;
    mesh.name = o.name;
    for (const auto& [mat, indices] : by_material) {
      const std::size_t off = buffer.data.size();
      const auto* bytes = reinterpret_cast<const unsigned char*>(indices.data());
      buffer.data.insert(buffer.data.end(), bytes, bytes + indices.size() * sizeof(std::uint32_t));
      tinygltf::BufferView iv;
      iv.buffer = 0;
      iv.byteOffset = off;
      iv.byteLength = indices.size() * sizeof(std::uint32_t);
      iv.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
      model.bufferViews.push_back(iv);
      tinygltf::Accessor ia;
      ia.bufferView = static_cast<int>(model.bufferViews.size() - 1);
      ia.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
      ia.type = TINYGLTF_TYPE_SCALAR;
      ia.count = indices.size();
      model.accessors.push_back(ia);
      tinygltf::Primitive prim;
      prim.attributes["POSITION"] = pos_accessor;
      prim.indices = static_cast<int>(model.accessors.size() - 1);
      prim.material = mat;
      prim.mode = TINYGLTF_MODE_TRIANGLES;
      mesh.primitives.push_back(prim);
    }
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = o.name;
    node.mesh = static_cast<int>(model.meshes.size() - 1);
    if (o.motion) {
      auto vec = [](const glm::dvec3& v) {
        return tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(v.x), tinygltf::Value(v.y),
                                                      tinygltf::Value(v.z)});
      };
      tinygltf::Value::Object r;
      r["velocity_mps"] = vec(o.motion->velocity_mps);
      r["start_position_m"] = vec(o.motion->start_position_m);
      tinygltf::Value::Object e;
      e["radar_emu"] = tinygltf::Value(r);
      node.extras = tinygltf::Value(e);
    }
    model.nodes.push_back(node);
    scene.nodes.push_back(static_cast<int>(model.nodes.size() - 1));
  }
  tinygltf::Value::Object anchor;
  anchor["anchor_deg_m"] = tinygltf::Value(tinygltf::Value::Array{
      tinygltf::Value(d.anchor.latitude_rad / kDeg), tinygltf::Value(d.anchor.longitude_rad / kDeg),
      tinygltf::Value(d.anchor.height_m)});
  tinygltf::Value::Object se;
  se["radar_emu"] = tinygltf::Value(anchor);
  scene.extras = tinygltf::Value(se);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  model.buffers.push_back(buffer);
  tinygltf::TinyGLTF writer;
  const bool binary = path.extension() == ".glb";
  if (!writer.WriteGltfSceneToFile(&model, path.string(), true, true, !binary, binary)) {
    throw std::runtime_error(path.string() + ": cannot write glTF");
  }
}

}  // namespace radar_emu::scene
