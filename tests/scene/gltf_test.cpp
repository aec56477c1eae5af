// glTF import/export: a hand-encoded fixture, round trips of the default scene, broken files.
// Runs under AddressSanitizer + UndefinedBehaviorSanitizer in CI (label "sanitize").

#include "scene/gltf.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <string>

#include "scene/default_scene.hpp"
#include "scene/scene.hpp"

namespace sc = radar_emu::scene;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// One scratch directory per process (ctest runs tests in parallel), removed at exit.
struct ScratchDir {
  fs::path path = fs::temp_directory_path() / ("radar_emu_gltf_test_" + std::to_string(::getpid()));
  ScratchDir() { fs::create_directories(path); }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

fs::path tmp(const std::string& name) {
  static const ScratchDir dir;
  return dir.path / name;
}

// RFC 4648 base64, written out here so that the fixture's bytes are encoded independently of
// tinygltf.
std::string base64(const std::vector<unsigned char>& in) {
  static constexpr char kTable[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (unsigned{in[i]} << 16) | (unsigned{in[i + 1]} << 8) | in[i + 2];
    out += {kTable[v >> 18], kTable[(v >> 12) & 63], kTable[(v >> 6) & 63], kTable[v & 63]};
  }
  if (i + 1 == in.size()) {
    const unsigned v = unsigned{in[i]} << 16;
    out += {kTable[v >> 18], kTable[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const unsigned v = (unsigned{in[i]} << 16) | (unsigned{in[i + 1]} << 8);
    out += {kTable[v >> 18], kTable[(v >> 12) & 63], kTable[(v >> 6) & 63], '='};
  }
  return out;
}

// The fixture's buffer, byte by byte (little-endian IEEE 754 binary32 and uint16): three VEC3
// positions in glTF axes (y up), (0,0,0), (1,0,0), (2.5,3,-4), then three indices.
std::vector<unsigned char> fixture_bytes(std::array<std::uint8_t, 3> indices = {0, 1, 2}) {
  return {
      0x00,       0x00, 0x00,       0x00, 0x00,       0x00,
      0x00,       0x00, 0x00,       0x00, 0x00,       0x00,  // 0, 0, 0
      0x00,       0x00, 0x80,       0x3F, 0x00,       0x00,
      0x00,       0x00, 0x00,       0x00, 0x00,       0x00,  // 1, 0, 0
      0x00,       0x00, 0x20,       0x40, 0x00,       0x00,
      0x40,       0x40, 0x00,       0x00, 0x80,       0xC0,  // 2.5, 3, -4
      indices[0], 0x00, indices[1], 0x00, indices[2], 0x00,  // u16 indices
  };
}

// The fixture: one triangle, material "metal", buffer as a base64 data: URI.
json make_fixture(const std::vector<unsigned char>& bytes = fixture_bytes()) {
  json j = json::parse(R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"name": "tri", "mesh": 0}],
    "meshes": [{"name": "m", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                             "material": 0}]}],
    "materials": [{"name": "metal",
                   "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 0.75, 1.0]}}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                   "min": [0, 0, -4], "max": [2.5, 3, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
  })");
  j["buffers"] = json::array({{{"byteLength", bytes.size()},
                               {"uri", "data:application/octet-stream;base64," + base64(bytes)}}});
  return j;
}

void write(const fs::path& p, const std::string& s) {
  std::ofstream(p, std::ios::binary) << s;
}

fs::path write_fixture(const std::string& name, const json& j) {
  const fs::path p = tmp(name);
  write(p, j.dump(2));
  return p;
}

std::string error_of(const fs::path& p) {
  try {
    (void)sc::load_gltf(p);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

// The error message must start with the file's path and contain `what`.
void expect_error(const fs::path& p, const std::string& what) {
  const std::string e = error_of(p);
  EXPECT_EQ(e.rfind(p.string() + ": ", 0), 0u) << e;
  EXPECT_NE(e.find(what), std::string::npos) << "expected '" << what << "' in: " << e;
}

glm::dvec3 world(const sc::ObjectDesc& o, glm::vec3 body) {
  const glm::dmat4 x = o.motion ? glm::dmat4(1.0) : o.world_from_body;
  return glm::dvec3(x * glm::dvec4(glm::dvec3(body), 1.0));
}

}  // namespace

// A scene whose import was stopped (issue 32) says so in its scene extras: the mark survives the
// round trip and loading it warns, naming the file.
TEST(Gltf, IncompleteMarkRoundTripsAndWarnsOnLoad) {
  sc::SceneDescription d = sc::default_scene();
  d.incomplete = "import stopped by SIGINT: central 4 of 16 rows of tiles";
  const fs::path p = tmp("partial.glb");
  sc::write_gltf(d, p);
  std::vector<std::string> warnings;
  const sc::SceneDescription r = sc::load_gltf(p, &warnings);
  EXPECT_EQ(r.incomplete, d.incomplete);
  EXPECT_NE(std::find(warnings.begin(), warnings.end(),
                      p.string() + ": an incomplete scene: " + d.incomplete),
            warnings.end());
  const fs::path whole = tmp("whole.glb");
  sc::write_gltf(sc::default_scene(), whole);
  warnings.clear();
  EXPECT_TRUE(sc::load_gltf(whole, &warnings).incomplete.empty());
  for (const std::string& w : warnings)
    EXPECT_EQ(w.find("incomplete"), std::string::npos) << w;
}

TEST(Gltf, HandEncodedFixtureLoadsInEnu) {
  const fs::path p = write_fixture("fixture.gltf", make_fixture());
  const sc::SceneDescription d = sc::load_gltf(p);
  ASSERT_EQ(d.objects.size(), 1u);
  const sc::ObjectDesc& o = d.objects[0];
  EXPECT_EQ(o.name, "tri");
  EXPECT_FALSE(o.motion.has_value());
  ASSERT_EQ(d.materials.size(), 1u);
  EXPECT_EQ(d.materials[0].name, "metal");
  EXPECT_EQ(d.materials[0].base_color, glm::vec3(0.5f, 0.25f, 0.75f));
  ASSERT_EQ(o.mesh.positions_m.size(), 3u);
  // glTF (x, y, z) with y up is ENU (x, -z, y): (2.5, 3, -4) is 2.5 m east, 4 m north, 3 m up.
  EXPECT_EQ(world(o, o.mesh.positions_m[0]), glm::dvec3(0, 0, 0));
  EXPECT_EQ(world(o, o.mesh.positions_m[1]), glm::dvec3(1, 0, 0));
  EXPECT_EQ(world(o, o.mesh.positions_m[2]), glm::dvec3(2.5, 4, 3));
  ASSERT_EQ(o.mesh.triangles.size(), 1u);
  EXPECT_EQ(o.mesh.triangles[0], glm::uvec3(0, 1, 2));
  EXPECT_EQ(o.mesh.triangle_material, std::vector<std::uint16_t>{0});
  // No anchor in the file: the default (0, 0, 0).
  EXPECT_EQ(d.anchor.latitude_rad, 0.0);
}

TEST(Gltf, NodeTransformsAreAppliedAndKeptInDouble) {
  json j = make_fixture();
  // Parent translates by (100, 20, -300) in glTF axes, child rotates 90 deg about glTF y (up)
  // and scales by 2: local x -> -z (north), local z -> x (east).
  j["nodes"] = json::parse(R"([
    {"name": "parent", "translation": [100, 20, -300], "children": [1]},
    {"name": "child", "mesh": 0, "rotation": [0, 0.7071067811865476, 0, 0.7071067811865476],
     "scale": [2, 2, 2]}])");
  const sc::SceneDescription d = sc::load_gltf(write_fixture("transform.gltf", j));
  ASSERT_EQ(d.objects.size(), 1u);
  const sc::ObjectDesc& o = d.objects[0];
  EXPECT_EQ(o.name, "child");
  // glTF: vertex (1,0,0) -> rotated (0,0,-1) -> scaled (0,0,-2) -> + (100,20,-300) =
  // (100, 20, -302), i.e. ENU (100, 302, 20). Vertex (2.5,3,-4) -> rotate: (x,y,z) ->
  // (z, y, -x) = (-4, 3, -2.5) -> x2 (-8, 6, -5) -> (92, 26, -305): ENU (92, 305, 26).
  EXPECT_LT(glm::length(world(o, o.mesh.positions_m[1]) - glm::dvec3(100, 302, 20)), 1e-12);
  EXPECT_LT(glm::length(world(o, o.mesh.positions_m[2]) - glm::dvec3(92, 305, 26)), 1e-12);
  // The placement is kept in world_from_body, the vertices stay small (body frame).
  EXPECT_LT(glm::length(glm::dvec3(o.world_from_body[3]) - glm::dvec3(100, 300, 20)), 1e-12);
  EXPECT_LT(glm::length(o.mesh.positions_m[2]), 10.0f);
}

TEST(Gltf, MirroringNodeKeepsTheNormalOutward) {
  json j = make_fixture();
  j["nodes"][0]["scale"] = {1, 1, -1};  // mirror glTF z (north-south in ENU)
  const sc::SceneDescription d = sc::load_gltf(write_fixture("mirror.gltf", j));
  const sc::ObjectDesc& o = d.objects[0];
  const glm::uvec3 t = o.mesh.triangles[0];
  const glm::dvec3 a = world(o, o.mesh.positions_m[t.x]), b = world(o, o.mesh.positions_m[t.y]),
                   c = world(o, o.mesh.positions_m[t.z]);
  // Local normal (0,4,3)/5 (glTF); mirrored in z: (0,4,-3)/5; in ENU (x, -z, y): (0,3,4)/5.
  const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
  EXPECT_LT(glm::length(n - glm::dvec3(0, 0.6, 0.8)), 1e-12) << n.x << " " << n.y << " " << n.z;
}

TEST(Gltf, IndexTypesNonIndexedAndInterleavedPrimitives) {
  // u8 indices.
  {
    json j = make_fixture();
    j["accessors"][1]["componentType"] = 5121;
    j["bufferViews"][1]["byteLength"] = 3;
    std::vector<unsigned char> b = fixture_bytes();
    b[37] = 1;  // bytes 36..38 = 0, 1, 2 as u8
    b[38] = 2;
    j["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(b);
    const auto d = sc::load_gltf(write_fixture("u8.gltf", j));
    EXPECT_EQ(d.objects[0].mesh.triangles[0], glm::uvec3(0, 1, 2));
  }
  // u32 indices (12 bytes after the positions).
  {
    json j = make_fixture();
    std::vector<unsigned char> b = fixture_bytes();
    b.resize(36);
    b.insert(b.end(), {2, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0});
    j["buffers"] = json::array(
        {{{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + base64(b)}}});
    j["accessors"][1]["componentType"] = 5125;
    j["bufferViews"][1]["byteLength"] = 12;
    const auto d = sc::load_gltf(write_fixture("u32.gltf", j));
    EXPECT_EQ(d.objects[0].mesh.triangles[0], glm::uvec3(2, 0, 1));
  }
  // Non-indexed: vertices 0, 1, 2 in order.
  {
    json j = make_fixture();
    j["meshes"][0]["primitives"][0].erase("indices");
    const auto d = sc::load_gltf(write_fixture("nonindexed.gltf", j));
    EXPECT_EQ(d.objects[0].mesh.triangles[0], glm::uvec3(0, 1, 2));
  }
  // Interleaved positions (byteStride 16: x y z + 4 bytes of something else).
  {
    std::vector<unsigned char> b;
    const std::vector<unsigned char> f = fixture_bytes();
    for (int v = 0; v < 3; ++v) {
      b.insert(b.end(), f.begin() + 12 * v, f.begin() + 12 * v + 12);
      b.insert(b.end(), {0xFF, 0xFF, 0xFF, 0xFF});
    }
    b.insert(b.end(), f.begin() + 36, f.end());
    json j = make_fixture(b);
    j["bufferViews"] = json::parse(R"([{"buffer": 0, "byteOffset": 0, "byteLength": 48,
                                         "byteStride": 16},
                                        {"buffer": 0, "byteOffset": 48, "byteLength": 6}])");
    const auto d = sc::load_gltf(write_fixture("stride.gltf", j));
    const auto& o = d.objects[0];
    EXPECT_EQ(world(o, o.mesh.positions_m[2]), glm::dvec3(2.5, 4, 3));
  }
  // Two primitives sharing one POSITION accessor share the vertices.
  {
    json j = make_fixture();
    j["meshes"][0]["primitives"].push_back(j["meshes"][0]["primitives"][0]);
    const auto d = sc::load_gltf(write_fixture("shared.gltf", j));
    EXPECT_EQ(d.objects[0].mesh.positions_m.size(), 3u);
    EXPECT_EQ(d.objects[0].mesh.triangles.size(), 2u);
  }
}

TEST(Gltf, MovingObjectsAndAnchorFromExtras) {
  json j = make_fixture();
  j["nodes"][0]["translation"] = {5, 0, -7};
  j["nodes"][0]["extras"] = json::parse(R"({"radar_emu": {"velocity_mps": [1.5, -2, 0]}})");
  j["scenes"][0]["extras"] = json::parse(R"({"radar_emu": {"anchor_deg_m": [43.6, 1.4, 150]}})");
  const sc::SceneDescription d = sc::load_gltf(write_fixture("moving.gltf", j));
  const sc::ObjectDesc& o = d.objects[0];
  ASSERT_TRUE(o.motion.has_value());
  EXPECT_EQ(o.motion->velocity_mps, glm::dvec3(1.5, -2, 0));
  // No explicit start: the node's translation (glTF (5, 0, -7) = ENU (5, 7, 0)).
  EXPECT_EQ(o.motion->start_position_m, glm::dvec3(5, 7, 0));
  EXPECT_EQ(glm::dvec3(o.mesh.positions_m[2]), glm::dvec3(2.5, 4, 3));  // body frame, in ENU axes
  EXPECT_NEAR(d.anchor.latitude_rad, 43.6 * std::numbers::pi / 180.0, 1e-15);
  EXPECT_NEAR(d.anchor.longitude_rad, 1.4 * std::numbers::pi / 180.0, 1e-15);
  EXPECT_EQ(d.anchor.height_m, 150.0);
  // A malformed velocity is an error, not a silently static object.
  j["nodes"][0]["extras"] = json::parse(R"({"radar_emu": {"velocity_mps": [1, "x", 0]}})");
  expect_error(write_fixture("badvel.gltf", j), "velocity_mps must be an array of 3 finite");
}

TEST(Gltf, TrajectoryAreaLodAndRadarMaterialFromExtras) {
  json j = make_fixture();
  j["nodes"][0]["translation"] = {5, 0, -7};  // ignored for a trajectory
  j["nodes"][0]["extras"] = json::parse(R"({"radar_emu": {
      "trajectory": {"waypoints_m": [[0, 0, 0], [100, 0, 0], [100, 50.5, 2]], "speed_mps": 7.5,
                     "turn_radius_m": 12, "loop": true, "bank": true},
      "area": "airport", "lod_group": 3, "lod_level": 2, "lod_facet_m": 40.5}})");
  j["materials"][0]["extras"] = json::parse(R"({"radar_emu": {"radar_material": "steel"}})");
  const sc::SceneDescription d = sc::load_gltf(write_fixture("trajectory.gltf", j));
  const sc::ObjectDesc& o = d.objects[0];
  ASSERT_TRUE(o.trajectory.has_value());
  EXPECT_FALSE(o.motion.has_value());
  const std::vector<glm::dvec3> w = {{0, 0, 0}, {100, 0, 0}, {100, 50.5, 2}};
  EXPECT_EQ(o.trajectory->waypoints_m, w);
  EXPECT_EQ(o.trajectory->speed_mps, 7.5);
  EXPECT_EQ(o.trajectory->turn_radius_m, 12.0);
  EXPECT_EQ(o.trajectory->turn_rate_rad_s, 0.0);
  EXPECT_TRUE(o.trajectory->loop);
  EXPECT_TRUE(o.trajectory->bank);
  EXPECT_EQ(o.area, "airport");
  EXPECT_EQ(o.lod_group, 3);
  EXPECT_EQ(o.lod_level, 2);
  EXPECT_EQ(o.lod_facet_m, 40.5);
  // Body-frame vertices: the translation is not baked in (glTF (2.5, 3, -4) = ENU (2.5, 4, 3)).
  EXPECT_EQ(glm::dvec3(o.mesh.positions_m[2]), glm::dvec3(2.5, 4, 3));
  // The radar material name overrides the glTF material name.
  ASSERT_EQ(d.materials.size(), 1u);
  EXPECT_EQ(d.materials[0].name, "steel");

  // Broken extras name the file, the node and the field.
  const auto broken = [&](const char* extras, const std::string& what) {
    json b = make_fixture();
    b["nodes"][0]["extras"] = json::parse(extras);
    expect_error(write_fixture("broken_extras.gltf", b), what);
  };
  broken(R"({"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0]], "speed_mps": 1}}})",
         "node 0 extras radar_emu.trajectory.waypoints_m must be an array of at least 2");
  broken(R"({"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0], [1, 0]], "speed_mps": 1}}})",
         "node 0 extras radar_emu.trajectory.waypoints_m[1] must be an array of 3 numbers");
  broken(R"({"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0], [1, 0, 0]]}}})",
         "node 0 extras radar_emu.trajectory.speed_mps is missing");
  broken(R"({"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0], [1, 0, 0]],
             "speed_mps": 1, "loop": 1}}})",
         "node 0 extras radar_emu.trajectory.loop must be true or false");
  broken(R"({"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0], [10, 0, 0], [10, 10, 0]],
             "speed_mps": 1, "turn_radius_m": 20}}})",
         "node 0 extras radar_emu.trajectory: trajectory: leg 0 (10.000000 m) is shorter");
  broken(R"({"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0], [1, 0, 0]],
             "speed_mps": 1}, "velocity_mps": [1, 0, 0]}})",
         "node 0 extras have both radar_emu.velocity_mps and .trajectory");
  broken(R"({"radar_emu": {"lod_group": 1.5}})",
         "node 0 extras radar_emu.lod_group must be an integer in [-1, 2147483647]");
  broken(R"({"radar_emu": {"lod_level": 256}})",
         "node 0 extras radar_emu.lod_level must be an integer in [0, 255]");
  broken(R"({"radar_emu": {"lod_facet_m": -2}})",
         "node 0 extras radar_emu.lod_facet_m must be >= 0");
  broken(R"({"radar_emu": {"area": 5}})", "node 0 extras radar_emu.area must be a string");
  json b = make_fixture();
  b["materials"][0]["extras"] = json::parse(R"({"radar_emu": {"radar_material": ["x"]}})");
  expect_error(write_fixture("badradarmat.gltf", b),
               "material 0 extras radar_emu.radar_material must be a string");
}

TEST(Gltf, UnknownRadarEmuExtrasKeysAreErrorsNamingTheKey) {
  // A typo must not leave an object silently static or a material silently renamed: every key
  // of a radar_emu object outside the documented schema (docs/scene_format.md) is an error
  // naming the file, the node / material / scene and the key, on one line.
  const auto expect_key_error = [](json j, const std::string& name, const std::string& what) {
    const fs::path p = write_fixture(name, j);
    expect_error(p, what);
    EXPECT_EQ(error_of(p).find('\n'), std::string::npos);
  };
  json j = make_fixture();
  j["nodes"][0]["extras"] = json::parse(R"({"radar_emu": {"velocity": [1, 0, 0]}})");
  expect_key_error(j, "unknown_node_key.gltf", "node 0 extras radar_emu: unknown key 'velocity'");
  EXPECT_NE(error_of(tmp("unknown_node_key.gltf")).find("known: area, lod_group"),
            std::string::npos);
  j = make_fixture();
  j["nodes"][0]["extras"] = json::parse(
      R"({"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0], [9, 0, 0]], "speed_mps": 1,
          "closed": true}}})");
  expect_key_error(j, "unknown_trajectory_key.gltf",
                   "node 0 extras radar_emu.trajectory: unknown key 'closed'");
  j = make_fixture();
  j["materials"][0]["extras"] = json::parse(R"({"radar_emu": {"material": "steel"}})");
  expect_key_error(j, "unknown_material_key.gltf",
                   "material 0 extras radar_emu: unknown key 'material' (known: radar_material)");
  j = make_fixture();
  j["scenes"][0]["extras"] = json::parse(R"({"radar_emu": {"anchor_deg": [43, 1, 0]}})");
  expect_key_error(
      j, "unknown_scene_key.gltf",
      "scene 0 extras radar_emu: unknown key 'anchor_deg' (known: anchor_deg_m, incomplete)");
  j = make_fixture();
  j["nodes"][0]["extras"] = json::parse(R"({"radar_emu": [1, 2]})");
  expect_key_error(j, "radar_emu_not_object.gltf", "node 0 extras radar_emu must be an object");
  // radar_emu extras where nothing reads them (a mesh, a primitive) are errors too.
  j = make_fixture();
  j["meshes"][0]["extras"] = json::parse(R"({"radar_emu": {"velocity_mps": [1, 0, 0]}})");
  expect_key_error(j, "mesh_extras.gltf", "mesh 0 extras radar_emu: not read here");
  j = make_fixture();
  j["meshes"][0]["primitives"][0]["extras"] =
      json::parse(R"({"radar_emu": {"radar_material": "steel"}})");
  expect_key_error(j, "primitive_extras.gltf", "mesh 0 primitive 0 extras radar_emu: not read");
  // Other tools' extras beside radar_emu stay allowed.
  j = make_fixture();
  j["nodes"][0]["extras"] =
      json::parse(R"({"blender_id": 7, "radar_emu": {"area": "airport"}, "notes": "x"})");
  EXPECT_EQ(sc::load_gltf(write_fixture("foreign_extras.gltf", j)).objects[0].area, "airport");
}

TEST(Gltf, TrajectoriesAndDatabaseFieldsRoundTrip) {
  sc::SceneDescription d = sc::default_scene();
  d.objects[0].area = "surround";
  d.objects[1].area = "airport";
  d.objects[1].lod_group = 12;
  d.objects[1].lod_level = 1;
  d.objects[1].lod_facet_m = 0.1 + 0.2;  // a double that needs all 17 digits
  sc::ObjectDesc mover = d.objects[3];
  mover.name = "patrol";
  mover.trajectory = sc::Trajectory{
      {{1.0 / 3.0, -2, 0}, {400, 0.125, 1}, {400, 300, 1}}, 8.0 / 3.0, 0.0, 0.05, true, true};
  d.objects.push_back(mover);
  for (const char* name : {"db.glb", "db.gltf"}) {
    const fs::path p = tmp(name);
    sc::write_gltf(d, p);
    const sc::SceneDescription r = sc::load_gltf(p);
    ASSERT_EQ(r.objects.size(), d.objects.size()) << name;
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      const sc::ObjectDesc &a = d.objects[i], &b = r.objects[i];
      EXPECT_EQ(a.area, b.area) << name << " " << a.name;
      EXPECT_EQ(a.lod_group, b.lod_group) << name << " " << a.name;
      EXPECT_EQ(a.lod_level, b.lod_level) << name << " " << a.name;
      EXPECT_EQ(a.lod_facet_m, b.lod_facet_m) << name << " " << a.name;
      ASSERT_EQ(a.trajectory.has_value(), b.trajectory.has_value()) << name << " " << a.name;
      if (a.trajectory) {
        EXPECT_EQ(a.trajectory->waypoints_m, b.trajectory->waypoints_m);
        EXPECT_EQ(a.trajectory->speed_mps, b.trajectory->speed_mps);
        EXPECT_EQ(a.trajectory->turn_radius_m, b.trajectory->turn_radius_m);
        EXPECT_EQ(a.trajectory->turn_rate_rad_s, b.trajectory->turn_rate_rad_s);
        EXPECT_EQ(a.trajectory->loop, b.trajectory->loop);
        EXPECT_EQ(a.trajectory->bank, b.trajectory->bank);
        EXPECT_EQ(a.mesh.positions_m, b.mesh.positions_m);  // body frame, nothing baked in
      }
    }
    // Every material carries its radar name in extras too.
    std::ifstream in(p, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(bytes.find("\"radar_material\""), std::string::npos) << name;
    // The loaded scene moves the patrol like the original.
    sc::Scene s1(d), s2(r);
    for (double t : {0.0, 17.0, 123.4}) {
      s1.set_time(t);
      s2.set_time(t);
      const auto id = static_cast<std::uint32_t>(d.objects.size() - 1);
      EXPECT_EQ(s1.world_from_body(id), s2.world_from_body(id)) << name << " " << t;
    }
  }
}

TEST(Gltf, DefaultSceneRoundTripsThroughGlbAndGltf) {
  const sc::SceneDescription d = sc::default_scene();
  const sc::Scene original(d);
  for (const char* name : {"default.glb", "default.gltf"}) {
    const fs::path p = tmp(name);
    sc::write_gltf(d, p);
    const sc::SceneDescription r = sc::load_gltf(p);
    ASSERT_EQ(r.objects.size(), d.objects.size()) << name;
    EXPECT_NEAR(r.anchor.latitude_rad, d.anchor.latitude_rad, 1e-15) << name;
    EXPECT_NEAR(r.anchor.longitude_rad, d.anchor.longitude_rad, 1e-15) << name;
    EXPECT_NEAR(r.anchor.height_m, d.anchor.height_m, 1e-12) << name;
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      const sc::ObjectDesc& a = d.objects[i];
      const sc::ObjectDesc& b = r.objects[i];
      EXPECT_EQ(a.name, b.name) << name;
      ASSERT_EQ(a.mesh.triangles.size(), b.mesh.triangles.size()) << a.name;
      ASSERT_EQ(a.mesh.positions_m.size(), b.mesh.positions_m.size()) << a.name;
      ASSERT_EQ(a.motion.has_value(), b.motion.has_value()) << a.name;
      if (a.motion) {
        EXPECT_EQ(a.motion->velocity_mps, b.motion->velocity_mps);
        EXPECT_EQ(a.motion->start_position_m, b.motion->start_position_m);
      } else {
        for (int c = 0; c < 4; ++c) {
          for (int k = 0; k < 4; ++k)
            EXPECT_NEAR(a.world_from_body[c][k], b.world_from_body[c][k], 1e-12) << a.name;
        }
      }
      for (std::size_t t = 0; t < a.mesh.triangles.size(); ++t) {
        EXPECT_EQ(a.mesh.triangles[t], b.mesh.triangles[t]) << a.name << " " << t;
        EXPECT_EQ(d.materials[a.mesh.triangle_material[t]].name,
                  r.materials[b.mesh.triangle_material[t]].name)
            << a.name << " " << t;
      }
      for (std::size_t v = 0; v < a.mesh.positions_m.size(); ++v) {
        EXPECT_LT(glm::length(world(a, a.mesh.positions_m[v]) - world(b, b.mesh.positions_m[v])),
                  1e-4)
            << a.name << " " << v;
      }
    }
    // The loaded scene answers rays like the original.
    const sc::Scene loaded(r);
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 200; ++k) {
      sc::Ray ray;
      ray.origin_m = {150 * u(rng), 450 + 300 * u(rng), 50.0};
      ray.direction = glm::normalize(glm::dvec3{u(rng), u(rng), -1.0});
      sc::Hit h1, h2;
      ASSERT_EQ(original.intersect(ray, h1), loaded.intersect(ray, h2)) << name << " " << k;
      EXPECT_NEAR(h1.t_m, h2.t_m, 1e-9) << name << " " << k;
      EXPECT_EQ(h1.object_id, h2.object_id);
      EXPECT_EQ(h1.primitive_id, h2.primitive_id);
    }
  }
}

TEST(Gltf, BrokenFilesNameTheFileAndTheProblem) {
  expect_error(tmp("missing.glb"), "no such file");
  {
    const fs::path p = tmp("json.gltf");
    write(p, "{ \"asset\": {\"version\": \"2.0\"}, not json");
    expect_error(p, "not a valid glTF 2.0 file");
  }
  json j = make_fixture();
  j["meshes"][0]["primitives"][0]["mode"] = 0;
  expect_error(write_fixture("points.gltf", j), "mesh 0 'm' primitive 0: mode 0 is not TRIANGLES");
  j = make_fixture(fixture_bytes({0, 1, 5}));
  expect_error(write_fixture("badidx.gltf", j), "index 2 = 5 is out of range (3 vertices)");
  j = make_fixture();
  j["meshes"][0]["primitives"][0].erase("material");
  expect_error(write_fixture("nomat.gltf", j), "mesh 0 'm' primitive 0 has no material");
  j = make_fixture();
  j["meshes"][0]["primitives"][0]["material"] = 3;
  expect_error(write_fixture("badmat.gltf", j), "material 3 does not exist");
  j = make_fixture();
  j["materials"][0].erase("name");
  expect_error(write_fixture("unnamed.gltf", j), "material 0 has no name");
  // Truncated buffer: the data holds 40 bytes but the index view needs 42.
  {
    std::vector<unsigned char> b = fixture_bytes();
    b.resize(40);
    j = make_fixture(b);
    expect_error(write_fixture("short.gltf", j), "buffer view 1 runs past the end of its buffer");
  }
  // Declared byteLength larger than the data: tinygltf rejects the buffer.
  j = make_fixture();
  j["buffers"][0]["byteLength"] = 100;
  expect_error(write_fixture("declared.gltf", j), "not a valid glTF 2.0 file");
  j = make_fixture();
  j["accessors"][0]["count"] = 4;
  expect_error(write_fixture("count.gltf", j), "accessor 0 (4 elements) runs past the end");
  j = make_fixture();
  j["accessors"][0]["byteOffset"] = 4;
  expect_error(write_fixture("offset.gltf", j), "runs past the end of its buffer view");
  j = make_fixture();
  j["accessors"][0]["count"] = 2147483647;
  expect_error(write_fixture("hugecount.gltf", j), "runs past the end of its buffer view");
  j = make_fixture();
  j["accessors"][0]["sparse"] = json::parse(R"({"count": 1,
      "indices": {"bufferView": 1, "componentType": 5123},
      "values": {"bufferView": 0}})");
  expect_error(write_fixture("sparse.gltf", j), "accessor 0 is sparse");
  j = make_fixture();
  j["accessors"][0]["componentType"] = 5123;
  j["accessors"][0]["count"] = 1;
  expect_error(write_fixture("intpos.gltf", j), "POSITION is not float");
  j = make_fixture();
  j["accessors"][0]["type"] = "VEC2";
  expect_error(write_fixture("vec2.gltf", j), "accessor 0 has type");
  j = make_fixture();
  j["accessors"][1]["count"] = 2;
  j["bufferViews"][1]["byteLength"] = 4;
  expect_error(write_fixture("two.gltf", j), "2 indices is not a multiple of 3");
  j = make_fixture();
  j["nodes"][0]["children"] = {0};
  expect_error(write_fixture("cycle.gltf", j), "node 0 appears twice");
  j = make_fixture();
  j["nodes"][0]["mesh"] = 4;
  expect_error(write_fixture("nomesh.gltf", j), "refers to mesh 4");
  j = make_fixture();
  j["nodes"][0].erase("mesh");
  expect_error(write_fixture("empty.gltf", j), "no triangle meshes");
  j = make_fixture();
  j["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  j["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  expect_error(write_fixture("draco.gltf", j), "KHR_draco_mesh_compression");
  // Binary container cut short, and garbage behind a glTF magic.
  {
    const fs::path full = tmp("full.glb");
    sc::write_gltf(sc::default_scene(), full);
    std::ifstream in(full, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const fs::path cut = tmp("cut.glb");
    write(cut, bytes.substr(0, bytes.size() / 2));
    expect_error(cut, "not a valid glTF 2.0 file");
    const fs::path garbage = tmp("garbage.glb");
    write(garbage, "glTF\x02\x00\x00\x00\xff\xff\xff\xff");
    expect_error(garbage, "not a valid glTF 2.0 file");
  }
}

TEST(Gltf, WriteFailuresNameTheFile) {
  const fs::path p = tmp("no_such_dir") / "x.glb";
  try {
    sc::write_gltf(sc::default_scene(), p);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(p.string() + ": ", 0), 0u) << e.what();
  }
  sc::SceneDescription bad = sc::default_scene();
  bad.objects[2].mesh.triangle_material[0] = 9;
  try {
    sc::write_gltf(bad, tmp("bad.glb"));
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("object 'parked_aircraft': triangle 0"), std::string::npos)
        << e.what();
  }
}

// Structured fuzzing: random edits of the fixture's numbers and random byte damage to a .glb.
// Every file must load or throw std::runtime_error; under ASan/UBSan nothing may read out of
// bounds.
TEST(Gltf, RandomlyDamagedFilesNeverCrash) {
  const std::uint32_t seed = 1234;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  const std::vector<std::pair<std::string, std::string>> fields = {
      {"/accessors/0/count", ""},
      {"/accessors/1/count", ""},
      {"/accessors/0/byteOffset", ""},
      {"/accessors/1/byteOffset", ""},
      {"/accessors/0/componentType", ""},
      {"/accessors/1/componentType", ""},
      {"/accessors/0/bufferView", ""},
      {"/accessors/1/bufferView", ""},
      {"/bufferViews/0/byteOffset", ""},
      {"/bufferViews/1/byteOffset", ""},
      {"/bufferViews/0/byteLength", ""},
      {"/bufferViews/1/byteLength", ""},
      {"/bufferViews/0/byteStride", ""},
      {"/bufferViews/0/buffer", ""},
      {"/meshes/0/primitives/0/indices", ""},
      {"/meshes/0/primitives/0/material", ""},
      {"/nodes/0/mesh", ""},
      {"/scene", ""},
      {"/meshes/0/primitives/0/attributes/POSITION", ""}};
  const std::vector<long long> values = {-1,  0,    1,    2,    3,    4,     5,         6,
                                         7,   11,   12,   16,   36,   41,    42,        43,
                                         255, 5121, 5123, 5125, 5126, 65535, 2147483647};
  int loaded = 0, rejected = 0;
  const fs::path p = tmp("fuzz.gltf");
  for (int i = 0; i < 400; ++i) {
    json j = make_fixture(fixture_bytes(
        {static_cast<std::uint8_t>(rng() % 4), static_cast<std::uint8_t>(rng() % 4), 2}));
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits; ++e) {
      const auto& f = fields[rng() % fields.size()];
      j[json::json_pointer(f.first)] = values[rng() % values.size()];
    }
    write(p, j.dump());
    try {
      (void)sc::load_gltf(p);
      ++loaded;
    } catch (const std::runtime_error& e) {
      ++rejected;
      EXPECT_EQ(std::string(e.what()).rfind(p.string() + ": ", 0), 0u) << e.what();
    }
  }
  // Byte damage to a binary file (header, JSON chunk and BIN chunk alike).
  const fs::path full = tmp("fuzz_src.glb");
  sc::SceneDescription small;
  small.materials = {{"metal", {}}};
  small.objects.push_back(sc::default_scene().objects[3]);  // parked_vehicle
  for (auto& m : small.objects[0].mesh.triangle_material)
    m = 0;
  sc::write_gltf(small, full);
  std::ifstream in(full, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const fs::path q = tmp("fuzz.glb");
  for (int i = 0; i < 400; ++i) {
    std::string b = bytes;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < flips; ++k)
      b[rng() % b.size()] = static_cast<char>(rng() & 0xFF);
    if (rng() % 4 == 0)
      b.resize(rng() % b.size());
    write(q, b);
    try {
      (void)sc::load_gltf(q);
      ++loaded;
    } catch (const std::runtime_error& e) {
      ++rejected;
      EXPECT_EQ(std::string(e.what()).rfind(q.string() + ": ", 0), 0u) << e.what();
    }
  }
  std::cout << loaded << " damaged files loaded, " << rejected << " rejected\n";
  EXPECT_GT(rejected, 100);
}
