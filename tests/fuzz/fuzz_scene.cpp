// Harnesses: the scene loaders (scene/gltf.hpp: .gltf JSON and .glb binary, told apart by the
// GLB magic; scene/mesh_io.hpp: Wavefront OBJ, binary and ASCII STL). The loaders read files,
// so each input is written to a file in a private temporary directory first.
//
// Oracles: the loader returns or throws std::runtime_error (its documented contract; any other
// exception is a finding); what it returns is usable: at least one object, every object with
// triangles, vertex indices inside the vertex array, a material per triangle that exists,
// finite vertex positions and a finite placement.

#include <stdlib.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {

namespace {

// A directory of this process's own, removed at exit: in $TMPDIR if set, else in /dev/shm
// (memory: rewriting a file on a disk file system can flush it on every close, ext4's
// auto_da_alloc, which slows a harness twenty-fold), else in /tmp.
const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    const char* env = std::getenv("TMPDIR");
    std::string base = env != nullptr && *env != '\0' ? env : "";
    if (base.empty())
      base = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    std::string pattern = base + "/radar-emu-fuzz-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) {
      std::perror("fuzz: mkdtemp");
      std::abort();
    }
    static const std::string keep = pattern;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(keep, ec);
    });
    return std::filesystem::path(pattern);
  }();
  return dir;
}

std::filesystem::path write_input(const char* name, const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = scratch_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  FUZZ_CHECK(out.good());
  return path;
}

void check_scene(const scene::SceneDescription& d) {
  FUZZ_CHECK(!d.objects.empty());
  for (const scene::ObjectDesc& o : d.objects) {
    const scene::Mesh& m = o.mesh;
    FUZZ_CHECK(!m.triangles.empty());
    FUZZ_CHECK(m.triangle_material.size() == m.triangles.size());
    for (const glm::vec3& p : m.positions_m)
      FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    for (const glm::uvec3& t : m.triangles) {
      FUZZ_CHECK(t.x < m.positions_m.size() && t.y < m.positions_m.size() &&
                 t.z < m.positions_m.size());
    }
    for (std::uint16_t mat : m.triangle_material)
      FUZZ_CHECK(mat < d.materials.size());
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r)
        FUZZ_CHECK(std::isfinite(o.world_from_body[c][r]));
    }
    if (o.motion) {
      FUZZ_CHECK(std::isfinite(o.motion->start_position_m.x) &&
                 std::isfinite(o.motion->velocity_mps.x));
    }
    FUZZ_CHECK(std::isfinite(o.lod_facet_m) && o.lod_facet_m >= 0.0);
  }
}

}  // namespace

int gltf(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = write_input("fuzz.gltf", data, size);
  try {
    check_scene(scene::load_gltf(path));
  } catch (const std::runtime_error&) {
    // A broken file, reported: the contract.
  }
  return 0;
}

int obj(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = write_input("fuzz.obj", data, size);
  try {
    std::vector<std::string> warnings;
    check_scene(scene::load_mesh_file(path, {}, &warnings));
  } catch (const std::runtime_error&) {
  }
  return 0;
}

int stl(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = write_input("fuzz.stl", data, size);
  try {
    std::vector<std::string> warnings;
    check_scene(scene::load_mesh_file(path, {}, &warnings));
  } catch (const std::runtime_error&) {
  }
  return 0;
}

}  // namespace radar_emu::fuzz
