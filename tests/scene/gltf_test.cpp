// glTF import/export: round trip of the default scene, a hand-encoded fixture, broken files.

#include "scene/gltf.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "scene/default_scene.hpp"

namespace sc = radar_emu::scene;
namespace fs = std::filesystem;

namespace {
fs::path tmp(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / "radar_emu_gltf_test";
  fs::create_directories(d);
  return d / name;
}

std::string base64(const std::vector<unsigned char>& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (in[i] << 16) | (in[i + 1] << 8) | in[i + 2];
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], t[v & 63]};
  }
  if (i + 1 == in.size()) {
    const unsigned v = in[i] << 16;
    out += {t[v >> 18], t[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const unsigned v = (in[i] << 16) | (in[i + 1] << 8);
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return out;
}

// One triangle, vertices (0,0,0), (1,0,0), (0,0,-1) in glTF (y up): in ENU (x, -z, y) that is
// (0,0,0), (1,0,0), (0,1,0). Material "metal".
std::string fixture(const std::string& mode_line, std::size_t buffer_bytes, int material = 0,
                    const std::string& indices_count = "3") {
  std::vector<unsigned char> buf(36 + 6);
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 0, -1};
  std::memcpy(buf.data(), v, 36);
  const unsigned short idx[3] = {0, 1, 2};
  std::memcpy(buf.data() + 36, idx, 6);
  buf.resize(buffer_bytes);
  std::string mat = material >= 0 ? ", \"material\": " + std::to_string(material) : "";
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"name": "tri", "mesh": 0}],
  "meshes": [{"name": "m", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1)" +
         mat + mode_line + R"(}]}],
  "materials": [{"name": "metal"}],
  "buffers": [{"byteLength": )" +
         std::to_string(buffer_bytes) + R"(, "uri": "data:application/octet-stream;base64,)" +
         base64(buf) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, -1], "max": [1, 0, 0]},
                {"bufferView": 1, "componentType": 5123, "count": )" +
         indices_count + R"(, "type": "SCALAR"}]})";
}

void write(const fs::path& p, const std::string& s) {
  std::ofstream(p, std::ios::binary) << s;
}

std::string error_of(const fs::path& p) {
  try {
    (void)sc::load_gltf(p);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Gltf, HandEncodedFixtureLoadsInEnu) {
  const fs::path p = tmp("fixture.gltf");
  write(p, fixture("", 42));
  const sc::SceneDescription d = sc::load_gltf(p);
  ASSERT_EQ(d.objects.size(), 1u);
  EXPECT_EQ(d.objects[0].name, "tri");
  ASSERT_EQ(d.materials.size(), 1u);
  EXPECT_EQ(d.materials[0].name, "metal");
  const auto& pos = d.objects[0].mesh.positions_m;
  ASSERT_EQ(pos.size(), 3u);
  EXPECT_EQ(pos[1], glm::vec3(1, 0, 0));
  EXPECT_EQ(pos[2], glm::vec3(0, 1, 0));  // glTF -z is north
  EXPECT_EQ(d.objects[0].mesh.triangles[0], glm::uvec3(0, 1, 2));
}

TEST(Gltf, BrokenFilesNameTheFileAndTheProblem) {
  const fs::path points = tmp("points.gltf"), shortbuf = tmp("short.gltf"),
                 nomat = tmp("nomat.gltf"), badidx = tmp("badidx.gltf"), json = tmp("json.gltf");
  write(points, fixture(", \"mode\": 0", 42));
  write(shortbuf, fixture("", 40));
  write(nomat, fixture("", 42, -1));
  write(badidx, fixture("", 42, 0, "6"));
  write(json, "{ not json");
  EXPECT_NE(error_of(points).find("points.gltf: mesh 'm' primitive 0: mode 0 is not TRIANGLES"),
            std::string::npos)
      << error_of(points);
  EXPECT_NE(error_of(shortbuf).find("short.gltf"), std::string::npos);
  EXPECT_NE(error_of(nomat).find("no material"), std::string::npos) << error_of(nomat);
  EXPECT_NE(error_of(badidx).find("runs past the end"), std::string::npos) << error_of(badidx);
  EXPECT_NE(error_of(json).find("json.gltf: not a valid glTF"), std::string::npos);
  EXPECT_NE(error_of(tmp("missing.glb")).find("missing.glb: no such file"), std::string::npos);
}

TEST(Gltf, DefaultSceneRoundTripsThroughGlbAndGltf) {
  const sc::SceneDescription d = sc::default_scene();
  for (const char* name : {"default.glb", "default.gltf"}) {
    const fs::path p = tmp(name);
    sc::write_gltf(d, p);
    const sc::SceneDescription r = sc::load_gltf(p);
    ASSERT_EQ(r.objects.size(), d.objects.size()) << name;
    EXPECT_NEAR(r.anchor.latitude_rad, d.anchor.latitude_rad, 1e-15);
    EXPECT_NEAR(r.anchor.height_m, d.anchor.height_m, 1e-12);
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      const auto& a = d.objects[i];
      const auto& b = r.objects[i];
      EXPECT_EQ(a.name, b.name);
      ASSERT_EQ(a.mesh.triangles.size(), b.mesh.triangles.size()) << a.name;
      EXPECT_EQ(a.motion.has_value(), b.motion.has_value()) << a.name;
      if (a.motion) {
        EXPECT_EQ(a.motion->velocity_mps, b.motion->velocity_mps);
        EXPECT_EQ(a.motion->start_position_m, b.motion->start_position_m);
      }
      // Same world-space triangles with the same material names (primitives regroup them by
      // material, so compare as sets of (centroid, material)).
      auto world = [](const sc::ObjectDesc& o, std::size_t t) {
        const glm::dmat4 x = o.motion ? glm::dmat4(1.0) : o.world_from_body;
        glm::dvec3 c(0.0);
        for (int k = 0; k < 3; ++k) {
          c += glm::dvec3(x *
                          glm::dvec4(glm::dvec3(o.mesh.positions_m[o.mesh.triangles[t][k]]), 1.0));
        }
        return c / 3.0;
      };
      std::vector<std::pair<std::string, glm::dvec3>> ca, cb;
      for (std::size_t t = 0; t < a.mesh.triangles.size(); ++t) {
        ca.emplace_back(d.materials[a.mesh.triangle_material[t]].name, world(a, t));
        cb.emplace_back(r.materials[b.mesh.triangle_material[t]].name, world(b, t));
      }
      auto less = [](const auto& x, const auto& y) {
        return std::tie(x.first, x.second.x, x.second.y, x.second.z) <
               std::tie(y.first, y.second.x, y.second.y, y.second.z);
      };
      std::sort(ca.begin(), ca.end(), less);
      std::sort(cb.begin(), cb.end(), less);
      for (std::size_t t = 0; t < ca.size(); ++t) {
        EXPECT_EQ(ca[t].first, cb[t].first);
        EXPECT_LT(glm::length(ca[t].second - cb[t].second), 1e-3) << a.name;
      }
    }
  }
}
