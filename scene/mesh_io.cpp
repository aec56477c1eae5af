#include "scene/mesh_io.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/path.hpp"
#include "scene/mesh_check.hpp"

namespace radar_emu::scene {

namespace {

[[noreturn]] void fail(const std::filesystem::path& p, std::size_t line, const std::string& what) {
  throw std::runtime_error(p.string() + (line ? ":" + std::to_string(line) : "") + ": " + what);
}

struct Builder {
  SceneDescription desc;
  ObjectDesc obj;
  std::map<std::string, std::uint16_t> material_index;
  std::uint16_t current = 0;
  bool have_current = false;

  std::uint16_t material(const std::string& name, const std::filesystem::path& path,
                         std::size_t line) {
    auto it = material_index.find(name);
    if (it != material_index.end())
      return it->second;
    if (desc.materials.size() > std::numeric_limits<std::uint16_t>::max())
      fail(path, line, "more than 65536 materials");
    desc.materials.push_back({name, {0.7f, 0.7f, 0.75f}});
    const auto i = static_cast<std::uint16_t>(desc.materials.size() - 1);
    material_index[name] = i;
    return i;
  }
  std::vector<std::size_t> lines;  ///< source line per triangle (0: binary)
};

bool parse_double(std::string_view s, double& out) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(out);
}

// Vertices are stored in single precision (scene::Mesh): a finite coordinate beyond float's
// range would become infinite there.
bool fits_float(const glm::dvec3& v) {
  constexpr auto kMax = static_cast<double>(std::numeric_limits<float>::max());
  return std::abs(v.x) <= kMax && std::abs(v.y) <= kMax && std::abs(v.z) <= kMax;
}

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r'))
      ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != '\r')
      ++j;
    if (j > i)
      out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

void load_obj(const std::filesystem::path& path, const MeshFileOptions& o, Builder& b) {
  std::ifstream in(path);
  std::string text;
  std::size_t line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    const auto tok = split(text);
    if (tok.empty() || tok[0][0] == '#')
      continue;
    if (tok[0] == "v") {
      if (tok.size() < 4)
        fail(path, line_no, "vertex needs 3 coordinates");
      double xyz[3];
      for (int k = 0; k < 3; ++k) {
        if (!parse_double(tok[static_cast<std::size_t>(k) + 1], xyz[k])) {
          fail(path, line_no,
               "vertex coordinate '" + std::string(tok[static_cast<std::size_t>(k) + 1]) +
                   "' is not a finite number");
        }
      }
      const glm::dvec3 p(xyz[0] * o.scale, xyz[1] * o.scale, xyz[2] * o.scale);
      if (!fits_float(p))
        fail(path, line_no, "vertex beyond the single-precision range (|coordinate| > 3.4e38 m)");
      b.obj.mesh.positions_m.emplace_back(p);
    } else if (tok[0] == "f") {
      if (tok.size() < 4)
        fail(path, line_no, "face needs at least 3 vertices");
      if (!b.have_current) {
        b.current = b.material(o.default_material, path, line_no);
        b.have_current = true;
      }
      std::vector<unsigned> idx;
      const auto n = static_cast<long long>(b.obj.mesh.positions_m.size());
      for (std::size_t k = 1; k < tok.size(); ++k) {
        const std::string_view v = tok[k].substr(0, tok[k].find('/'));  // v, v/vt, v//vn, v/vt/vn
        long long i = 0;
        const auto r = std::from_chars(v.data(), v.data() + v.size(), i);
        if (r.ec != std::errc() || r.ptr != v.data() + v.size() || i == 0) {
          fail(path, line_no, "bad vertex index '" + std::string(tok[k]) + "'");
        }
        const long long abs_i = i > 0 ? i - 1 : n + i;  // negative: relative to the end
        if (abs_i < 0 || abs_i >= n) {
          fail(path, line_no,
               "vertex index " + std::to_string(i) + " out of range (" + std::to_string(n) +
                   " vertices so far)");
        }
        idx.push_back(static_cast<unsigned>(abs_i));
      }
      for (std::size_t k = 1; k + 1 < idx.size(); ++k) {  // fan
        b.obj.mesh.triangles.push_back({idx[0], idx[k], idx[k + 1]});
        b.lines.push_back(line_no);
        b.obj.mesh.triangle_material.push_back(b.current);
      }
    } else if (tok[0] == "usemtl") {
      if (tok.size() < 2)
        fail(path, line_no, "usemtl needs a name");
      b.current = b.material(std::string(tok[1]), path, line_no);
      b.have_current = true;
    }
    // vt, vn, o, g, s, mtllib: irrelevant to radar geometry.
  }
  if (in.bad())
    fail(path, 0, "read error");
}

void load_stl(const std::filesystem::path& path, const MeshFileOptions& o, Builder& b) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad())
    fail(path, 0, "read error");
  const std::uint16_t mat = b.material(o.default_material, path, 0);
  auto add = [&](const glm::dvec3 v[3], std::size_t line) {
    for (int k = 0; k < 3; ++k) {  // binary STL: a float vertex times a scale > 1
      if (!fits_float(v[k] * o.scale))
        fail(path, line, "vertex beyond the single-precision range (|coordinate| > 3.4e38 m)");
    }
    b.lines.push_back(line);
    const auto base = static_cast<unsigned>(b.obj.mesh.positions_m.size());
    for (int k = 0; k < 3; ++k)
      b.obj.mesh.positions_m.emplace_back(v[k] * o.scale);
    b.obj.mesh.triangles.push_back({base, base + 1, base + 2});
    b.obj.mesh.triangle_material.push_back(mat);
  };
  std::uint32_t count = 0;
  if (data.size() >= 84)
    std::memcpy(&count, data.data() + 80, 4);
  const bool binary = data.size() >= 84 && data.size() == 84 + std::size_t{50} * count;
  if (binary) {
    for (std::uint32_t t = 0; t < count; ++t) {
      const char* rec = data.data() + 84 + std::size_t{50} * t;
      glm::dvec3 v[3];
      for (int k = 0; k < 3; ++k) {
        float xyz[3];
        std::memcpy(xyz, rec + 12 + 12 * k, 12);  // after the 12-byte normal
        if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
          fail(path, 0, "triangle " + std::to_string(t) + " has a non-finite vertex");
        }
        v[k] = glm::dvec3(xyz[0], xyz[1], xyz[2]);
      }
      add(v, 0);
    }
    return;
  }
  const std::string text(data.begin(), data.end());
  // Many binary STL headers begin with "solid" too: a file with NUL bytes is binary, whatever
  // its header says.
  const bool has_nul = text.find('\0') != std::string::npos;
  if (text.rfind("solid", 0) != 0 || (has_nul && data.size() >= 84)) {
    fail(path, 0,
         data.size() >= 84
             ? "binary STL size does not match its triangle count " + std::to_string(count)
             : "neither binary nor ASCII STL");
  }
  std::istringstream lines(text);
  std::string line;
  std::size_t line_no = 0;
  glm::dvec3 v[3];
  int nv = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    const auto tok = split(line);
    if (tok.empty())
      continue;
    if (tok[0] == "vertex") {
      if (tok.size() != 4 || nv == 3)
        fail(path, line_no, "bad vertex line");
      for (int k = 0; k < 3; ++k) {
        if (!parse_double(tok[static_cast<std::size_t>(k) + 1], v[nv][k])) {
          fail(path, line_no, "vertex coordinate is not a finite number");
        }
      }
      if (!fits_float(v[nv] * o.scale))
        fail(path, line_no, "vertex beyond the single-precision range (|coordinate| > 3.4e38 m)");
      ++nv;
    } else if (tok[0] == "endloop") {
      if (nv != 3)
        fail(path, line_no, "facet with " + std::to_string(nv) + " vertices");
      add(v, line_no);
      nv = 0;
    }
  }
  if (nv != 0) {
    fail(path, line_no,
         "the file ends inside a facet (" + std::to_string(nv) + " vertices, no endloop)");
  }
}

}  // namespace

SceneDescription load_mesh_file(const std::filesystem::path& path, const MeshFileOptions& o,
                                std::vector<std::string>* warnings) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    fail(path, 0, "no such file");
  if (!(o.scale > 0.0) || !std::isfinite(o.scale))
    fail(path, 0, "scale must be a positive number");
  Builder b;
  b.obj.name = path.stem().string();
  const std::string ext = common::lower_extension(path);
  if (ext == ".obj") {
    load_obj(path, o, b);
  } else if (ext == ".stl") {
    load_stl(path, o, b);
  } else {
    fail(path, 0, "unknown mesh format '" + ext + "' (OBJ or STL)");
  }
  if (b.obj.mesh.triangles.empty())
    fail(path, 0, "no triangles");
  std::vector<std::string> w = clean_loaded_mesh(b.obj.mesh, path.string(), b.lines);
  if (warnings != nullptr)
    warnings->insert(warnings->end(), w.begin(), w.end());
  b.desc.objects.push_back(std::move(b.obj));
  return std::move(b.desc);
}

void write_mesh_file(const Mesh& mesh, const std::vector<Material>& materials,
                     const std::filesystem::path& path) {
  const std::string ext = common::lower_extension(path);
  if (ext != ".obj" && ext != ".stl")  // before opening: a refused name leaves no empty file
    fail(path, 0, "unknown mesh format '" + ext + "' (OBJ or STL)");
  std::ofstream out(path, std::ios::binary);
  if (!out)
    fail(path, 0, "cannot open for writing");
  if (ext == ".obj") {
    out.precision(9);
    out << "# radar-emu target, metres\n";
    for (const glm::vec3& p : mesh.positions_m)
      out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    int current = -1;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const int m = mesh.triangle_material[t];
      if (m != current) {
        out << "usemtl " << materials.at(static_cast<std::size_t>(m)).name << '\n';
        current = m;
      }
      const glm::uvec3 f = mesh.triangles[t] + glm::uvec3(1);
      out << "f " << f.x << ' ' << f.y << ' ' << f.z << '\n';
    }
  } else {  // ".stl"
    char header[80] = "radar-emu target, metres, binary STL";
    out.write(header, 80);
    // Binary STL is little-endian, as is every platform radar-emu builds on (x86-64, aarch64).
    const auto n = static_cast<std::uint32_t>(mesh.triangles.size());
    char count[4];
    std::memcpy(count, &n, 4);
    out.write(count, 4);
    for (const glm::uvec3& t : mesh.triangles) {
      const glm::vec3 a = mesh.positions_m[t.x], b = mesh.positions_m[t.y],
                      c = mesh.positions_m[t.z];
      glm::vec3 nrm = glm::cross(b - a, c - a);
      const float len = glm::length(nrm);
      if (len > 0.0f)
        nrm /= len;
      const float values[12] = {nrm.x, nrm.y, nrm.z, a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
      char rec[50] = {};  // 12 floats, then a 2-byte attribute count of 0
      std::memcpy(rec, values, sizeof values);
      out.write(rec, sizeof rec);
    }
  }
  if (!out)
    fail(path, 0, "write failed");
}

}  // namespace radar_emu::scene
