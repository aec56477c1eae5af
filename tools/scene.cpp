#include "tools/scene.hpp"

#include <stb/stb_image_write.h>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/path.hpp"
#include "common/units.hpp"
#include "scene/airport_gen.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "scene/preview.hpp"
#include "scene/scene.hpp"
#include "scene/terrain_gen.hpp"

namespace radar_emu::tools {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// "E,N,U" in metres.
glm::dvec3 parse_enu(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t comma = text.find(',', begin);
    const std::string part =
        text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
    double x = 0.0;
    const char* first = part.data();
    const char* last = part.data() + part.size();
    while (first < last && *first == ' ')
      ++first;
    const auto [ptr, ec] = std::from_chars(first, last, x);
    if (ec != std::errc() || ptr != last || !std::isfinite(x))
      throw std::invalid_argument(option + ": '" + text + "' is not three numbers E,N,U [m]");
    v.push_back(x);
    if (comma == std::string::npos)
      break;
    begin = comma + 1;
  }
  if (v.size() != 3)
    throw std::invalid_argument(option + ": '" + text + "' is not three numbers E,N,U [m]");
  return {v[0], v[1], v[2]};
}

std::string thousands(std::size_t n) {
  std::string s = std::to_string(n);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3)
    s.insert(static_cast<std::size_t>(i), ",");
  return s;
}

std::string level_name(int level) {
  return level < 0 ? "none" : std::to_string(level);
}

}  // namespace

std::uint64_t parse_seed(const std::string& text, const std::string& option) {
  std::uint64_t v = 0;
  const char* last = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), last, v);
  if (text.empty() || ec != std::errc() || ptr != last) {
    throw std::invalid_argument(option + ": '" + text +
                                "' is not a whole number in 0..18446744073709551615");
  }
  return v;
}

int run_scene_gen(const SceneGenOptions& o) {
  const std::uint64_t seed = parse_seed(o.seed, "--seed");
  const std::filesystem::path out(o.out);
  const std::string ext = common::lower_extension(out);
  if (ext != ".glb" && ext != ".gltf")
    throw std::invalid_argument("--out: '" + o.out + "' is not a .glb or .gltf file");
  const auto t0 = std::chrono::steady_clock::now();
  scene::SceneDescription desc;
  o.control.report(0, 2);
  if (o.kind == "terrain") {
    scene::TerrainSpec spec;
    spec.seed = seed;
    desc = scene::generate_terrain(spec);
  } else if (o.kind == "airport") {
    scene::AirportSpec spec;
    spec.seed = seed;
    desc = scene::generate_airport(spec);
  } else {
    throw std::invalid_argument("unknown scene kind '" + o.kind + "' (known: terrain|airport)");
  }
  const double gen_s = seconds_since(t0);
  o.control.report(1, 2);
  const auto t1 = std::chrono::steady_clock::now();
  scene::write_gltf(desc, out);
  const double write_s = seconds_since(t1);
  // A stop heard during the generation or the writing: the database is whole, and written.
  if (const int stopped = o.control.stop_signal(); stopped != 0)
    return 128 + stopped;
  o.control.report(2, 2);
  if (!o.quiet) {
    const scene::SceneInfo info = scene::scene_info(desc);
    std::string areas;
    for (const auto& [area, n] : info.triangles_by_area)
      areas += (areas.empty() ? "" : ", ") + area + " " + thousands(n);
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(out, ec);
    std::printf(
        "%s: %s seed %llu, %zu objects, %s polygons at full detail (%s), %s in all LOD levels; "
        "generated in %.2f s, written in %.2f s (%.1f MB)\n",
        o.out.c_str(), o.kind.c_str(), static_cast<unsigned long long>(seed), info.objects,
        thousands(info.triangles_full_detail).c_str(), areas.c_str(),
        thousands(info.triangles_total).c_str(), gen_s, write_s,
        ec ? 0.0 : static_cast<double>(bytes) / 1e6);
  }
  return 0;
}

std::string scene_info_json(const scene::SceneInfo& info, const std::string& file,
                            std::size_t load_warnings) {
  using Json = nlohmann::ordered_json;
  Json j;
  j["file"] = file;
  j["counting"] =
      "polygons_total and polygons_by_lod_level count every LOD level; polygons_full_detail, "
      "polygons_by_area and polygons_by_material count the scene at full detail (LOD level 0 "
      "of every tile plus every object outside LOD groups)";
  j["polygons_total"] = info.triangles_total;
  j["polygons_full_detail"] = info.triangles_full_detail;
  Json levels = Json::object();
  for (const auto& [level, n] : info.triangles_by_lod_level)
    levels[level_name(level)] = n;
  j["polygons_by_lod_level"] = levels;
  Json areas = Json::object(), areas_all = Json::object(), mats = Json::object(),
       kinds = Json::object();
  for (const auto& [area, n] : info.triangles_by_area)
    areas[area] = n;
  for (const auto& [area, n] : info.triangles_by_area_all_levels)
    areas_all[area] = n;
  for (const auto& [m, n] : info.triangles_by_material)
    mats[m] = n;
  for (const auto& [k, n] : info.objects_by_kind)
    kinds[k] = n;
  j["polygons_by_area"] = areas;
  j["polygons_by_material"] = mats;
  j["polygons_by_area_all_levels"] = areas_all;
  j["objects"] = info.objects;
  j["objects_by_kind"] = kinds;
  j["lod_groups"] = info.lod_groups;
  j["materials"] = info.materials;
  j["vertices"] = info.vertices;
  j["extent_m"] = {{"min", {info.extent_min_m.x, info.extent_min_m.y, info.extent_min_m.z}},
                   {"max", {info.extent_max_m.x, info.extent_max_m.y, info.extent_max_m.z}}};
  j["anchor_deg_m"] = {info.anchor.latitude_rad / common::kRadPerDeg,
                       info.anchor.longitude_rad / common::kRadPerDeg, info.anchor.height_m};
  j["load_warnings"] = load_warnings;
  if (!info.incomplete.empty())
    j["incomplete"] = info.incomplete;
  return j.dump(2) + "\n";
}

std::string scene_info_text(const scene::SceneInfo& info, const std::string& file,
                            std::size_t load_warnings) {
  std::ostringstream s;
  char line[256];
  s << "scene " << file << "\n";
  if (!info.incomplete.empty())
    s << "  INCOMPLETE        " << info.incomplete << "\n";
  std::snprintf(line, sizeof line, "  anchor            %.6f deg N, %.6f deg E, %.1f m\n",
                info.anchor.latitude_rad / common::kRadPerDeg,
                info.anchor.longitude_rad / common::kRadPerDeg, info.anchor.height_m);
  s << line;
  std::snprintf(line, sizeof line,
                "  extent [m]        E %.1f .. %.1f, N %.1f .. %.1f, U %.1f .. %.1f\n",
                info.extent_min_m.x, info.extent_max_m.x, info.extent_min_m.y, info.extent_max_m.y,
                info.extent_min_m.z, info.extent_max_m.z);
  s << line;
  s << "  objects           " << info.objects << " (" << info.lod_groups << " LOD groups), "
    << info.materials << " materials, " << thousands(info.vertices) << " vertices\n";
  s << "  polygons          " << thousands(info.triangles_full_detail)
    << " at full detail (LOD level 0 + objects outside LOD groups); "
    << thousands(info.triangles_total) << " in all LOD levels\n";
  s << "  by LOD level      ";
  for (std::size_t k = 0; k < info.triangles_by_lod_level.size(); ++k) {
    const auto& [level, n] = info.triangles_by_lod_level[k];
    s << (k ? ", " : "") << level_name(level) << " " << thousands(n);
  }
  s << "  (levels >= 1: coarser copies, not in the full-detail counts)\n";
  s << "  by area           ";
  for (std::size_t k = 0; k < info.triangles_by_area.size(); ++k) {
    const auto& [area, n] = info.triangles_by_area[k];
    s << (k ? ", " : "") << area << " " << thousands(n);
  }
  s << "  (full detail)\n";
  s << "  by material       (full detail)\n";
  for (const auto& [m, n] : info.triangles_by_material) {
    std::snprintf(line, sizeof line, "    %-14s %9s\n", m.c_str(), thousands(n).c_str());
    s << line;
  }
  s << "  objects by kind   ";
  for (std::size_t k = 0; k < info.objects_by_kind.size(); ++k) {
    const auto& [kind, n] = info.objects_by_kind[k];
    s << (k ? ", " : "") << kind << " " << n;
  }
  s << "\n";
  if (load_warnings > 0) {
    s << "  load warnings     " << load_warnings
      << " (open surfaces: expected for terrain tiles, water sheets and wires)\n";
  }
  return s.str();
}

int run_scene_info(const SceneInfoOptions& o) {
  std::vector<std::string> warnings;
  const scene::SceneDescription desc = scene::load_gltf(o.file, &warnings);
  const scene::SceneInfo info = scene::scene_info(desc);
  const std::string text = o.json ? scene_info_json(info, o.file, warnings.size())
                                  : scene_info_text(info, o.file, warnings.size());
  std::fwrite(text.data(), 1, text.size(), stdout);
  return 0;
}

int run_scene_preview(const ScenePreviewOptions& o) {
  if (o.width_px < 1 || o.width_px > 16384 || o.height_px < 1 || o.height_px > 16384)
    throw std::invalid_argument("--width / --height must be in 1..16384 pixels");
  if (o.fov_deg && !(*o.fov_deg > 0.0 && *o.fov_deg < 180.0))
    throw std::invalid_argument("--fov-deg must be in (0, 180) deg");
  {
    const std::filesystem::path dir = std::filesystem::path(o.out).parent_path();
    std::error_code ec;
    if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
      throw std::invalid_argument("--out: directory " + dir.string() + " does not exist");
  }
  std::optional<glm::dvec3> camera, look_at;
  if (!o.camera.empty())
    camera = parse_enu(o.camera, "--camera");
  if (!o.look_at.empty())
    look_at = parse_enu(o.look_at, "--look-at");
  const auto t0 = std::chrono::steady_clock::now();
  const scene::Scene scene(scene::load_gltf(o.file));
  scene::PreviewCamera cam = scene::default_preview_camera(scene, o.width_px, o.height_px);
  if (camera)
    cam.position_m = *camera;
  if (look_at)
    cam.look_at_m = *look_at;
  if (o.fov_deg)
    cam.vertical_fov_rad = common::radians(*o.fov_deg);
  const scene::PreviewImage img = scene::render_preview(scene, cam);
  if (stbi_write_png(o.out.c_str(), img.width_px, img.height_px, 3, img.rgb.data(),
                     img.width_px * 3) == 0) {
    throw std::runtime_error(o.out + ": cannot write the PNG");
  }
  if (!o.quiet) {
    std::printf(
        "%s: %d x %d preview of %s from (%.1f, %.1f, %.1f) m toward (%.1f, %.1f, %.1f) m, "
        "%.1f deg vertical field, %.2f s\n",
        o.out.c_str(), img.width_px, img.height_px, o.file.c_str(), cam.position_m.x,
        cam.position_m.y, cam.position_m.z, cam.look_at_m.x, cam.look_at_m.y, cam.look_at_m.z,
        cam.vertical_fov_rad / common::kRadPerDeg, seconds_since(t0));
  }
  return 0;
}

}  // namespace radar_emu::tools
