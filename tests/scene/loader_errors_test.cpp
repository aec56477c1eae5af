// Broken glTF, OBJ and STL files, generated here at run time: each must fail with one line that
// names the file and the problem (never a crash, never a multi-line dump). Runs under ASan +
// UBSan (label "sanitize").

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"

namespace sc = radar_emu::scene;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct ScratchDir {
  fs::path path =
      fs::temp_directory_path() / ("radar_emu_loader_errors_" + std::to_string(::getpid()));
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

fs::path write(const std::string& name, const std::string& bytes) {
  const fs::path p = tmp(name);
  std::ofstream(p, std::ios::binary) << bytes;
  return p;
}

void put_u32(std::string& s, std::uint32_t v) {
  for (int k = 0; k < 4; ++k)
    s.push_back(static_cast<char>((v >> (8 * k)) & 0xFFu));  // little-endian
}

void put_f32(std::string& s, float f) {
  std::uint32_t v = 0;
  std::memcpy(&v, &f, 4);
  put_u32(s, v);
}

// One triangle: positions (0,0,0), (1,0,0), (2.5,3,-4) and u16 indices 0, 1, 2 (42 bytes).
std::string triangle_bin() {
  std::string b;
  for (float f : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 2.5f, 3.0f, -4.0f})
    put_f32(b, f);
  for (const char c : {'\0', '\0', '\1', '\0', '\2', '\0'})
    b.push_back(c);
  return b;
}

json triangle_json(std::size_t bin_bytes) {
  json j = json::parse(R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"name": "tri", "mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
    "materials": [{"name": "metal"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                   "min": [0, 0, -4], "max": [2.5, 3, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})");
  j["buffers"] = json::array({{{"byteLength", bin_bytes}}});
  return j;
}

// GLB container (glTF 2.0 spec, sec. 4.4 "Binary glTF layout"): 12-byte header (magic "glTF",
// version, total length), then chunks of (length, type, data), JSON padded with spaces and BIN
// with zeros to 4 bytes. `total_length` / `json_length` override the computed fields (0: keep).
std::string glb(const std::string& json_text, const std::string& bin, std::uint32_t version = 2,
                std::uint32_t total_length = 0, std::uint32_t json_length = 0) {
  std::string js = json_text, bn = bin;
  while (js.size() % 4 != 0)
    js.push_back(' ');
  while (bn.size() % 4 != 0)
    bn.push_back('\0');
  std::string out = "glTF";
  put_u32(out, version);
  const auto total =
      static_cast<std::uint32_t>(12 + 8 + js.size() + (bn.empty() ? 0 : 8 + bn.size()));
  put_u32(out, total_length ? total_length : total);
  put_u32(out, json_length ? json_length : static_cast<std::uint32_t>(js.size()));
  put_u32(out, 0x4E4F534Au);  // "JSON"
  out += js;
  if (!bn.empty()) {
    put_u32(out, static_cast<std::uint32_t>(bn.size()));
    put_u32(out, 0x004E4942u);  // "BIN\0"
    out += bn;
  }
  return out;
}

template <typename Load>
std::string error_of(Load load, const fs::path& p) {
  try {
    load(p);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

// One line, starting with the file's path, containing `what`.
template <typename Load>
void expect_one_line(Load load, const fs::path& p, const std::string& what) {
  SCOPED_TRACE(p.filename().string());
  const std::string e = error_of(load, p);
  EXPECT_EQ(e.rfind(p.string() + ":", 0), 0u) << e;
  EXPECT_EQ(e.find_first_of("\r\n"), std::string::npos) << "not one line: " << e;
  EXPECT_NE(e.find(what), std::string::npos) << "expected '" << what << "' in: " << e;
}

const auto gltf = [](const fs::path& p) { (void)sc::load_gltf(p); };
const auto mesh = [](const fs::path& p) { (void)sc::load_mesh_file(p); };

}  // namespace

TEST(LoaderErrors, GlbContainer) {
  const std::string bin = triangle_bin();
  const std::string js = triangle_json(bin.size()).dump();
  // The well-formed file loads (the broken ones below differ from it in one thing each).
  ASSERT_EQ(sc::load_gltf(write("good.glb", glb(js, bin))).objects.size(), 1u);
  const std::string good = glb(js, bin);
  expect_one_line(gltf, write("empty.glb", ""), "GLB header truncated (0 bytes, 12 expected)");
  expect_one_line(gltf, write("header6.glb", good.substr(0, 6)),
                  "GLB header truncated (6 bytes, 12 expected)");
  expect_one_line(gltf, write("header12.glb", good.substr(0, 12)),
                  "the GLB header gives a length of " + std::to_string(good.size()) +
                      " bytes but the file has 12 (truncated or damaged)");
  expect_one_line(gltf, write("version1.glb", glb(js, bin, 1)),
                  "GLB container version 1 (2 expected)");
  expect_one_line(gltf, write("totallength.glb", glb(js, bin, 2, 100000)),
                  "the GLB header gives a length of 100000 bytes but the file has");
  expect_one_line(gltf, write("chunklength.glb", glb(js, bin, 2, 0, 0x7FFFFFF0u)),
                  "the GLB JSON chunk length 2147483632 runs past the end of the file");
  std::string bad_bin = good;
  bad_bin[20 + (js.size() + 3) / 4 * 4] = '\x7F';  // BIN chunk length 127 + ... > what is left
  expect_one_line(gltf, write("binlength.glb", bad_bin),
                  "the GLB BIN chunk length 127 runs past the end of the file");
  std::string not_json = good;
  not_json[16] = 'X';
  expect_one_line(gltf, write("chunktype.glb", not_json), "the first GLB chunk is not JSON");
  expect_one_line(gltf, write("cut_in_json.glb", good.substr(0, 40)),
                  "but the file has 40 (truncated or damaged)");
  expect_one_line(gltf, write("cut_in_bin.glb", good.substr(0, good.size() - 8)),
                  "(truncated or damaged)");
  expect_one_line(gltf, write("badjson.glb", glb("{\"asset\": {\"version\": \"2.0\"}, ]", bin)),
                  "not a valid glTF 2.0 file");
  // JSON that parses but whose accessor runs past its buffer view.
  json j = triangle_json(bin.size());
  j["accessors"][0]["count"] = 1000;
  expect_one_line(gltf, write("accessor.glb", glb(j.dump(), bin)),
                  "accessor 0 (1000 elements) runs past the end of its buffer view");
  j = triangle_json(bin.size());
  j["bufferViews"][1]["byteLength"] = 600;
  expect_one_line(gltf, write("view.glb", glb(j.dump(), bin)),
                  "buffer view 1 runs past the end of its buffer");
  // A buffer with no URI and no BIN chunk.
  expect_one_line(gltf, write("nobin.glb", glb(triangle_json(bin.size()).dump(), "")),
                  "not a valid glTF 2.0 file");
  // Accessor pointing at a buffer view that does not exist.
  j = triangle_json(bin.size());
  j["accessors"][1]["bufferView"] = 9;
  expect_one_line(gltf, write("noview.glb", glb(j.dump(), bin)), "");
  // Not a GLB at all behind a .glb name.
  expect_one_line(gltf, write("text.glb", "hello, this is text"), "no GLB magic 'glTF'");
}

TEST(LoaderErrors, GltfJsonAndBuffers) {
  const std::string bin = triangle_bin();
  json j = triangle_json(bin.size());
  // External buffer that is missing, then present.
  j["buffers"][0]["uri"] = "triangle.bin";
  const fs::path p = write("external.gltf", j.dump());
  expect_one_line(gltf, p, "not a valid glTF 2.0 file");
  write("triangle.bin", bin);
  EXPECT_EQ(sc::load_gltf(p).objects.size(), 1u);
  // A .bin file shorter than byteLength.
  write("short.bin", bin.substr(0, 20));
  j["buffers"][0]["uri"] = "short.bin";
  expect_one_line(gltf, write("shortbin.gltf", j.dump()), "not a valid glTF 2.0 file");
  // A data: URI that is not base64.
  j["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@@";
  expect_one_line(gltf, write("base64.gltf", j.dump()), "not a valid glTF 2.0 file");
  // No buffers at all.
  j.erase("buffers");
  expect_one_line(gltf, write("nobuffers.gltf", j.dump()), "");
  // Broken JSON, in several ways (multi-line parser messages are folded into one line).
  expect_one_line(gltf, write("trunc.gltf", triangle_json(42).dump().substr(0, 100)),
                  "not a valid glTF 2.0 file");
  expect_one_line(gltf, write("notjson.gltf", "this is not json\nat all\n"),
                  "not a valid glTF 2.0 file");
  expect_one_line(gltf, write("array.gltf", "[1, 2, 3]"), "not a valid glTF 2.0 file");
  expect_one_line(gltf, write("nul.gltf", std::string("{\"asset\"\0: 1}", 14)),
                  "not a valid glTF 2.0 file");
  expect_one_line(gltf, tmp("absent.gltf"), "no such file");
}

TEST(LoaderErrors, Stl) {
  // Binary STL: 80-byte header, u32 count, 50 bytes per triangle (normal, 3 vertices,
  // attribute count).
  const auto binary = [](const std::string& header, std::uint32_t count,
                         const std::vector<float>& xyz9) {
    std::string s = header;
    s.resize(80, ' ');
    put_u32(s, count);
    for (std::size_t t = 0; t < xyz9.size() / 9; ++t) {
      for (int k = 0; k < 3; ++k)
        put_f32(s, 0.0f);
      for (std::size_t k = 0; k < 9; ++k)
        put_f32(s, xyz9[9 * t + k]);
      s += std::string(2, '\0');
    }
    return s;
  };
  const std::vector<float> two = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1};
  ASSERT_EQ(sc::load_mesh_file(write("good.stl", binary("bin", 2, two))).objects.size(), 1u);
  // Truncated: fewer records than the count, with and without a "solid" header (many binary
  // files start with "solid" too).
  std::string cut = binary("bin", 2, two);
  expect_one_line(mesh, write("trunc.stl", cut.substr(0, cut.size() - 30)),
                  "binary STL size does not match its triangle count 2");
  cut = binary("solid exported by a CAD tool", 2, two);
  expect_one_line(mesh, write("trunc_solid.stl", cut.substr(0, cut.size() - 30)),
                  "binary STL size does not match its triangle count 2");
  expect_one_line(mesh, write("count.stl", binary("bin", 1000000, two)),
                  "binary STL size does not match its triangle count 1000000");
  expect_one_line(mesh, write("tiny.stl", "abc"), "neither binary nor ASCII STL");
  expect_one_line(mesh, write("empty.stl", ""), "neither binary nor ASCII STL");
  std::vector<float> bad = two;
  bad[13] = std::numeric_limits<float>::quiet_NaN();
  expect_one_line(mesh, write("nan.stl", binary("bin", 2, bad)),
                  "triangle 1 has a non-finite vertex");
  bad = two;
  bad[2] = std::numeric_limits<float>::infinity();
  expect_one_line(mesh, write("inf.stl", binary("bin", 2, bad)),
                  "triangle 0 has a non-finite vertex");
  // ASCII STL.
  const std::string facet = "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n";
  expect_one_line(mesh, write("asc_nan.stl", "solid s\n" + facet + "  vertex 0 nan 0\n"),
                  "asc_nan.stl:6: vertex coordinate is not a finite number");
  expect_one_line(mesh, write("asc_word.stl", "solid s\n" + facet + "  vertex 0 one 0\n"),
                  "asc_word.stl:6: vertex coordinate is not a finite number");
  expect_one_line(mesh, write("asc_short.stl", "solid s\n" + facet + "  vertex 0 1\n"),
                  "asc_short.stl:6: bad vertex line");
  expect_one_line(mesh, write("asc_two.stl", "solid s\n" + facet + " endloop\nendfacet\n"),
                  "asc_two.stl:6: facet with 2 vertices");
  expect_one_line(mesh, write("asc_cut.stl", "solid s\n" + facet),
                  "the file ends inside a facet (2 vertices, no endloop)");
  expect_one_line(mesh, write("asc_none.stl", "solid s\nendsolid s\n"), "no triangles");
  // Found by fuzzing (tests/fuzz/regressions/stl/): a finite coordinate beyond float's range
  // became an infinite vertex, then undefined behaviour in the mesh check.
  expect_one_line(mesh,
                  write("asc_huge.stl", "solid s\n" + facet + "  vertex 1" + std::string(60, '2') +
                                            " 0 1\n endloop\n"),
                  "asc_huge.stl:6: vertex beyond the single-precision range");
  const float big = std::numeric_limits<float>::max();
  std::vector<float> large = two;
  large[4] = big;
  const fs::path scaled = write("scaled.stl", binary("bin", 2, large));
  EXPECT_EQ(sc::load_mesh_file(scaled).objects.size(), 1u);  // at float's top: still fine
  const std::string e =
      error_of([](const fs::path& p) { (void)sc::load_mesh_file(p, {.scale = 10.0}); }, scaled);
  EXPECT_NE(e.find("vertex beyond the single-precision range"), std::string::npos) << e;
}

TEST(LoaderErrors, Obj) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  ASSERT_EQ(sc::load_mesh_file(write("good.obj", v + "f 1 2 3\n")).objects.size(), 1u);
  expect_one_line(mesh, write("idx_word.obj", v + "f 1 2 x\n"),
                  "idx_word.obj:4: bad vertex index 'x'");
  expect_one_line(mesh, write("idx_zero.obj", v + "f 0 1 2\n"),
                  "idx_zero.obj:4: bad vertex index '0'");
  expect_one_line(mesh, write("idx_range.obj", v + "f 1 2 4\n"),
                  "idx_range.obj:4: vertex index 4 out of range (3 vertices so far)");
  expect_one_line(mesh, write("idx_neg.obj", v + "f -4 1 2\n"),
                  "idx_neg.obj:4: vertex index -4 out of range");
  expect_one_line(mesh, write("idx_huge.obj", v + "f 1 2 99999999999999999999\n"),
                  "idx_huge.obj:4: bad vertex index '99999999999999999999'");
  expect_one_line(mesh, write("num_word.obj", "v 0 0 abc\n"),
                  "num_word.obj:1: vertex coordinate 'abc' is not a finite number");
  expect_one_line(mesh, write("num_nan.obj", "v 0 nan 0\n"),
                  "num_nan.obj:1: vertex coordinate 'nan' is not a finite number");
  expect_one_line(mesh, write("num_inf.obj", "v 1e999 0 0\n"),
                  "num_inf.obj:1: vertex coordinate '1e999' is not a finite number");
  // Found by fuzzing (tests/fuzz/regressions/obj/): 8.9e49 is a finite double but no float.
  expect_one_line(mesh, write("num_huge.obj", "v 0 0" + std::string(50, '8') + " 1\n"),
                  "num_huge.obj:1: vertex beyond the single-precision range");
  expect_one_line(mesh, write("num_two.obj", "v 0 0\n"),
                  "num_two.obj:1: vertex needs 3 coordinates");
  expect_one_line(mesh, write("face_two.obj", v + "f 1 2\n"),
                  "face_two.obj:4: face needs at least 3 vertices");
  expect_one_line(mesh, write("usemtl.obj", v + "usemtl\n"), "usemtl.obj:4: usemtl needs a name");
  expect_one_line(mesh, write("faces_none.obj", v), "faces_none.obj: no triangles");
  expect_one_line(mesh, write("degenerate.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n"),
                  "degenerate");
  expect_one_line(mesh, write("x.ply", "ply\n"), "unknown mesh format '.ply'");
}
