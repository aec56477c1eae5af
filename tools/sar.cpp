#include "tools/sar.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tools/sar_case.hpp"

#ifdef RADAR_EMU_HAVE_GDAL
#include <cpl_conv.h>
#include <cpl_string.h>
#include <gdal.h>
#include <ogr_srs_api.h>
#endif

#include "common/polarisation.hpp"
#include "common/units.hpp"
#include "config/memory_limit.hpp"
#include "config/progress.hpp"
#include "config/toml_reader.hpp"
#include "loop/closed_loop.hpp"
#include "plot/charts.hpp"
#include "radar/clutter/speckle.hpp"
#include "radar/clutter/terrain.hpp"
#include "radar/constants.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/irf.hpp"
#include "radar/products/sar.hpp"
#include "radar/products/sar_terrain.hpp"
#include "scene/geo.hpp"
#include "scene/scene.hpp"
#include "scene/targets.hpp"
#include "tools/mpi_work.hpp"

namespace radar_emu::tools {

using plot::LineChart;
using plot::Series;

namespace {

namespace rd = radar_emu::radar;
namespace sc = radar_emu::scene;
namespace cl = radar_emu::radar::clutter;
using Clock = std::chrono::steady_clock;

constexpr double kC = rd::kSpeedOfLight_mps;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
double db10(double x) {
  return common::db_from_power(std::max(x, 1e-300));
}

// ------------------------------------------------------------------------------ the TOML case

using config::Range;
using config::Table;

// The case from its parsed TOML; the file's name starts every error.
SarCase case_from_table(const Table& root) {
  const std::string& path = root.file();
  root.refuse_unknown({"radar", "platform", "antenna", "processing", "scene"});
  SarCase c;
  rd::SarParams& p = c.p;
  const Table radar = root.table("radar");
  radar.refuse_unknown({"carrier_hz", "bandwidth_hz", "sample_rate_hz", "pulse_duration_s",
                        "prf_hz", "transmit_power_w", "peak_gain_db", "polarisation"});
  radar.number("carrier_hz", p.carrier_hz, {1e8, 1e12});
  radar.number("bandwidth_hz", p.bandwidth_hz, {1e5, 1e10});
  p.sample_rate_hz = 1.2 * p.bandwidth_hz;
  radar.number("sample_rate_hz", p.sample_rate_hz, {1e5, 2e10});
  radar.number("pulse_duration_s", p.pulse_duration_s, {1e-8, 1e-3});
  radar.number("prf_hz", p.prf_hz, {1.0, 1e6});
  radar.number("transmit_power_w", p.transmit_power_w, {1e-6, 1e9});
  p.peak_gain = 1.0;  // 0 dB
  radar.decibels("peak_gain_db", p.peak_gain, {-20.0, 80.0});
  radar.string("polarisation", c.pol_name);
  try {
    c.pol = common::parse_polarisation(c.pol_name);
  } catch (const std::invalid_argument& e) {
    radar.fail("polarisation", e.what());
  }
  c.pol_name = common::polarisation_name(c.pol);

  const Table plat = root.table("platform");
  plat.refuse_unknown({"altitude_m", "speed_mps", "heading_deg", "look"});
  plat.number("altitude_m", c.altitude_m, {10.0, 20000.0});
  plat.number("speed_mps", c.speed_mps, {0.1, 2000.0});
  plat.degrees("heading_deg", c.heading_rad, {-360.0, 360.0});
  std::string look = "right";
  plat.choice("look", look, {"right", "left"});
  p.look_right = look == "right";

  const Table ant = root.table("antenna");
  ant.refuse_unknown({"incidence_deg", "azimuth_beamwidth_deg", "elevation_beamwidth_deg"});
  p.incidence_rad = common::radians(63.0);
  p.azimuth_beamwidth_rad = common::radians(0.12);
  p.elevation_beamwidth_rad = common::radians(13.0);
  ant.degrees("incidence_deg", p.incidence_rad, {5.0, 85.0});
  ant.degrees("azimuth_beamwidth_deg", p.azimuth_beamwidth_rad, {1e-3, 30.0, true});
  ant.degrees("elevation_beamwidth_deg", p.elevation_beamwidth_rad, {1e-2, 60.0, true});

  const Table proc = root.table("processing");
  proc.refuse_unknown({"gates", "synthetic_beamwidth_deg", "taper", "upsample", "image_width_m",
                       "azimuth_spacing_m", "ground_range_spacing_m", "centre_east_m",
                       "centre_north_m"});
  proc.number("centre_east_m", c.centre_east_m, {-15000.0, 15000.0});
  proc.number("centre_north_m", c.centre_north_m, {-15000.0, 15000.0});
  proc.integer("gates", p.gates, 8, 65536);
  proc.degrees("synthetic_beamwidth_deg", c.synthetic_beamwidth_rad, {1e-5, 5.0, true});
  std::string taper = "none";
  proc.choice("taper", taper, {"none", "hamming"});
  if (taper == "hamming")
    c.taper = rd::SarTaper::kHamming;
  proc.integer("upsample", c.upsample, 1, 64);
  proc.number("image_width_m", c.image_width_m, {1.0, 20000.0});
  proc.number("azimuth_spacing_m", c.azimuth_spacing_m, {0.0, 100.0});
  proc.number("ground_range_spacing_m", c.ground_range_spacing_m, {0.0, 100.0});

  const Table scene = root.table("scene");
  std::vector<std::string_view> scene_keys{
      "ground_material", "clutter",      "clutter_cell_m", "speckle_seed", "target_ray_spacing_m",
      "max_bounces",     "latitude_deg", "longitude_deg",  "target"};
  scene_keys.insert(scene_keys.end(), std::begin(loop::kSceneSourceKeys),
                    std::end(loop::kSceneSourceKeys));
  scene.refuse_unknown(scene_keys);
  // A scene database (the scenario's [scene] keys, one reader), or the flat ground.
  c.database = scene.has("builtin") || scene.has("file") || scene.has("import");
  if (c.database) {
    loop::read_scene_source(scene, c.source);
    for (const char* flat : {"ground_material", "latitude_deg", "longitude_deg"})
      if (scene.has(flat))
        scene.fail(flat,
                   "applies to the flat ground only; builtin, file or import name a scene database "
                   "(which has its own materials and anchor)");
  } else {
    for (const char* key : {"seed", "corner_reflectors"})
      if (scene.has(key))
        scene.fail(key, "needs builtin = \"...\" (a generated scene database)");
  }
  scene.string("ground_material", c.ground_material);
  if (c.ground_material != "none" && cl::find_terrain_material(c.ground_material) == nullptr)
    scene.unknown_value("ground_material", c.ground_material,
                        "none, " + cl::terrain_material_names());
  scene.boolean("clutter", c.clutter);
  scene.number("clutter_cell_m", c.clutter_cell_m, {0.0, 100.0});
  scene.integer("speckle_seed", c.speckle_seed, 0, std::numeric_limits<std::int64_t>::max());
  scene.number("target_ray_spacing_m", c.target_ray_spacing_m, {1e-3, 10.0});
  scene.integer("max_bounces", c.max_bounces, 1, 16);
  scene.number("latitude_deg", c.latitude_deg, {-89.0, 89.0});
  scene.number("longitude_deg", c.longitude_deg, {-180.0, 180.0});
  for (const Table& t : scene.tables("target")) {
    t.refuse_unknown(
        {"name", "kind", "a_m", "b_m", "c_m", "position_m", "velocity_mps", "heading_deg"});
    TargetCase tc;
    tc.name = "target" + std::to_string(c.targets.size());
    t.string("name", tc.name);
    std::string kind = "trihedral-square";
    t.string("kind", kind);
    const auto k = sc::target_kind_from_name(kind);
    if (!k)
      t.unknown_value("kind", kind, sc::target_names());
    tc.spec.kind = *k;
    t.number("a_m", tc.spec.a_m, {1e-3, 100.0, true});
    tc.spec.b_m = tc.spec.a_m;
    tc.spec.c_m = tc.spec.a_m;
    t.number("b_m", tc.spec.b_m, {1e-3, 100.0, true});
    t.number("c_m", tc.spec.c_m, {1e-3, 100.0, true});
    t.vec3("position_m", tc.position_m, 15000.0);
    t.vec3("velocity_mps", tc.velocity_mps, 1000.0);
    t.degrees("heading_deg", tc.heading_rad, {-360.0, 360.0});
    c.targets.push_back(tc);
  }

  // Derived geometry: the image centre at the world origin, the track beside it.
  const double lambda = kC / p.carrier_hz;
  const double r0 = c.altitude_m / std::cos(p.incidence_rad);
  c.ground_centre_m = c.altitude_m * std::tan(p.incidence_rad);
  c.theta_rad = lambda / (2.0 * r0 * c.synthetic_beamwidth_rad);
  if (c.theta_rad > p.azimuth_beamwidth_rad)
    throw std::invalid_argument(
        path + ": [processing] synthetic_beamwidth_deg: the processed aperture (" +
        std::to_string(c.theta_rad / common::kRadPerDeg) +
        " deg) is wider than the antenna's azimuth beamwidth; widen the beam or the synthetic "
        "beamwidth");
  const double gate = kC / (2.0 * p.sample_rate_hz);
  p.near_range_m = r0 - 0.5 * static_cast<double>(p.gates) * gate;
  if (p.near_range_m <= c.altitude_m)
    throw std::invalid_argument(path + ": the swath (gates x gate) reaches nadir; fewer gates");
  const double far = p.near_range_m + static_cast<double>(p.gates) * gate;
  // Along-track sampling: everything the beam lights to -40 dB (two-way voltage 0.01, 1.29
  // beamwidths off boresight) must be Nyquist-sampled in Doppler: spacing <= lambda / (4 sin).
  const double spacing = c.speed_mps / p.prf_hz;
  const double need = lambda / (4.0 * std::sin(1.29 * p.azimuth_beamwidth_rad));
  if (spacing > need)
    throw std::invalid_argument(path + ": [radar] prf_hz: pulses every " + std::to_string(spacing) +
                                " m along track; the azimuth beam " + "needs at most " +
                                std::to_string(need) + " m (raise prf_hz)");
  const double aperture = 2.0 * far * std::tan(c.theta_rad / 2);
  const double track = c.image_width_m + aperture + 2.0 * spacing;
  p.pulses = static_cast<std::size_t>(std::ceil(track / spacing)) + 1;
  if (p.pulses > 200000)
    throw std::invalid_argument(path + ": " + std::to_string(p.pulses) +
                                " pulses (over 200000): shorten image_width_m or lower prf_hz");
  const glm::dvec3 tdir{std::sin(c.heading_rad), std::cos(c.heading_rad), 0.0};
  p.velocity_mps = c.speed_mps * tdir;
  const glm::dvec3 ldir = rd::sar_look_dir(p);
  p.start_position_m = glm::dvec3(c.centre_east_m, c.centre_north_m, 0.0) -
                       c.ground_centre_m * ldir - 0.5 * track * tdir +
                       glm::dvec3(0.0, 0.0, c.altitude_m);
  if (c.azimuth_spacing_m == 0.0)
    c.azimuth_spacing_m = 0.8 * r0 * c.synthetic_beamwidth_rad;  // 0.8 x Nyquist
  if (c.ground_range_spacing_m == 0.0)
    c.ground_range_spacing_m = 0.8 * kC / (2.0 * p.bandwidth_hz) / std::sin(p.incidence_rad);
  if (c.clutter_cell_m == 0.0)
    c.clutter_cell_m = std::min(c.azimuth_spacing_m, c.ground_range_spacing_m) / 2.0;
  try {
    rd::validate(p);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return c;
}

// The reader's errors (config::ConfigError) as this tool's contract has them.
SarCase load_case(const std::string& path) {
  try {
    return case_from_table(config::TomlFile::load(path).root());
  } catch (const config::ConfigError& e) {
    throw std::invalid_argument(e.what());
  }
}

// ------------------------------------------------------------------------------ the scene

// Rotation taking unit a onto unit b (Rodrigues).
glm::dmat3 rotation_onto(const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 v = glm::cross(a, b);
  const double s = glm::length(v), cth = glm::dot(a, b);
  if (s < 1e-12)
    return cth > 0 ? glm::dmat3(1.0) : glm::dmat3(-1.0);
  const glm::dvec3 u = v / s;
  const glm::dmat3 k(glm::dvec3(0, u.z, -u.y), glm::dvec3(-u.z, 0, u.x), glm::dvec3(u.y, -u.x, 0));
  return glm::dmat3(1.0) + s * k + (1.0 - cth) * k * k;
}

bool is_trihedral(sc::TargetKind k) {
  return k == sc::TargetKind::kTrihedralSquare || k == sc::TargetKind::kTrihedralTriangular;
}

// The platform at broadside of world point x (its along-track coordinate).
glm::dvec3 broadside_platform(const rd::SarParams& p, const glm::dvec3& x) {
  const glm::dvec3 t = rd::sar_track_dir(p);
  const double s = glm::dot(x - p.start_position_m, t);
  return p.start_position_m + s * t;
}

sc::SceneDescription build_scene(const SarCase& c, double half_extent_m) {
  sc::SceneDescription d;
  std::uint16_t metal = 0;
  if (c.database) {
    // The scenario's database (its own anchor and materials); targets in its "metal".
    d = loop::scene_database(c.source);
    std::size_t k = 0;
    while (k < d.materials.size() && d.materials[k].name != "metal")
      ++k;
    if (k == d.materials.size())
      d.materials.push_back({"metal", {0.8f, 0.8f, 0.8f}});
    metal = static_cast<std::uint16_t>(k);
  } else {
    d.anchor.latitude_rad = common::radians(c.latitude_deg);
    d.anchor.longitude_rad = common::radians(c.longitude_deg);
    d.materials.push_back({"metal", {0.8f, 0.8f, 0.8f}});
  }
  if (!c.database && c.ground_material != "none") {
    d.materials.push_back({c.ground_material, {0.3f, 0.5f, 0.2f}});
    sc::ObjectDesc g;
    g.name = "ground";
    const auto e = static_cast<float>(half_extent_m);
    const auto x = static_cast<float>(c.centre_east_m), y = static_cast<float>(c.centre_north_m);
    g.mesh.positions_m = {
        {x - e, y - e, 0.0f}, {x + e, y - e, 0.0f}, {x + e, y + e, 0.0f}, {x - e, y + e, 0.0f}};
    g.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    g.mesh.triangle_material = {1, 1};
    d.objects.push_back(std::move(g));
  }
  for (const TargetCase& t : c.targets) {
    sc::SceneDescription one = sc::make_target(t.spec);
    sc::ObjectDesc o = std::move(one.objects.at(0));
    o.name = t.name;
    std::fill(o.mesh.triangle_material.begin(), o.mesh.triangle_material.end(), metal);
    glm::dmat3 rot(1.0);
    if (is_trihedral(t.spec.kind)) {
      // Symmetry axis (1,1,1) toward the platform at broadside.
      const glm::dvec3 to_radar =
          glm::normalize(broadside_platform(c.p, t.position_m) - t.position_m);
      rot = rotation_onto(glm::normalize(glm::dvec3(1.0)), to_radar);
    } else {
      const double a = rd::kPi / 2 - t.heading_rad;  // body +x along the heading
      rot = glm::dmat3(glm::dvec3(std::cos(a), std::sin(a), 0),
                       glm::dvec3(-std::sin(a), std::cos(a), 0), glm::dvec3(0, 0, 1));
    }
    glm::dmat4 m(rot);
    m[3] = glm::dvec4(t.position_m, 1.0);
    if (glm::length(t.velocity_mps) > 0.0) {
      // LinearMotion turns the body's +x along the velocity: keep the mesh as built.
      o.motion = sc::LinearMotion{t.position_m, t.velocity_mps};
      // Bake the rotation into the vertices, less the yaw the motion will add.
      const double psi = std::atan2(t.velocity_mps.y, t.velocity_mps.x);
      const glm::dmat3 unyaw(glm::dvec3(std::cos(psi), -std::sin(psi), 0),
                             glm::dvec3(std::sin(psi), std::cos(psi), 0), glm::dvec3(0, 0, 1));
      for (auto& v : o.mesh.positions_m)
        v = glm::vec3(unyaw * rot * glm::dvec3(v));
      o.world_from_body = glm::dmat4(1.0);
    } else {
      o.world_from_body = m;
    }
    d.objects.push_back(std::move(o));
  }
  return d;
}

// ------------------------------------------------------------------------------ outputs

// The image in grey (dB over 50 dB below the 99.9th percentile), ground range across (near left)
// and along track up (the flight goes down the image, row 0 at the top), at equal scales in
// metres with a scale bar (docs/plotting.md).
plot::Heatmap image_figure(const rd::SarImage& img, const std::string& title) {
  const auto& g = img.grid;
  plot::Heatmap m;
  m.title = title;
  m.x_label = "ground range from the near edge [m]";
  m.y_label = "along track [m] (flight toward the bottom)";
  m.value_label = "pixel power [dB]";
  m.grey = true;
  m.scale_bar = 0.0;
  m.equal_aspect = true;
  for (std::size_t c = 0; c < g.cols; ++c)
    m.x.push_back((static_cast<double>(c) + 0.5) * g.ground_range_spacing_m);
  for (std::size_t r = 0; r < g.rows; ++r)
    m.y.push_back((static_cast<double>(r) + 0.5) * g.azimuth_spacing_m);
  m.values.resize(img.pixels.size());
  for (std::size_t r = 0; r < g.rows; ++r) {
    for (std::size_t c = 0; c < g.cols; ++c)
      m.values[r * g.cols + c] =
          db10(static_cast<double>(std::norm(img.pixels[(g.rows - 1 - r) * g.cols + c])));
  }
  std::vector<double> sorted = m.values;
  std::sort(sorted.begin(), sorted.end());
  m.value_max = sorted[static_cast<std::size_t>(0.999 * static_cast<double>(sorted.size() - 1))];
  m.value_range = 50.0;
  // About the picture's aspect (the colour bar and labels beside it).
  const double w_m = static_cast<double>(g.cols) * g.ground_range_spacing_m;
  const double h_m = static_cast<double>(g.rows) * g.azimuth_spacing_m;
  m.width = 1100;
  m.height = std::clamp(static_cast<int>(900.0 * h_m / std::max(w_m, 1e-9)) + 160, 400, 1400);
  return m;
}

#ifdef RADAR_EMU_HAVE_GDAL
// Local transverse Mercator at the scene anchor, its scale factor (R + h0) / R for the anchor's
// ellipsoidal height h0 (R the ellipsoid's Gaussian radius sqrt(M N) there): within a few km
// its easting/northing equal the ENU x/y of the scene to millimetres (scale error
// x^2 / (2 R^2) < 1e-7 at 2 km, plus x (h - h0) / R for ground at another height h). With a
// scale of 1 the ENU distances of ground at h0 would read h0 / R too long: 1.6 m at 10 km on a
// 1000 m plateau.
std::string local_wkt(const SarCase& c) {
  namespace g = sc::wgs84;
  const double s = std::sin(common::radians(c.latitude_deg));
  const double w = 1.0 - g::kFirstEccentricitySquared * s * s;
  const double n_m = g::kSemiMajorAxis_m / std::sqrt(w);
  const double m_m =
      g::kSemiMajorAxis_m * (1.0 - g::kFirstEccentricitySquared) / (w * std::sqrt(w));
  const double scale = 1.0 + c.anchor_height_m / std::sqrt(m_m * n_m);
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRSetWellKnownGeogCS(srs, "WGS84");
  OSRSetTM(srs, c.latitude_deg, c.longitude_deg, scale, 0.0, 0.0);
  OSRSetLinearUnits(srs, SRS_UL_METER, 1.0);
  char* wkt = nullptr;
  OSRExportToWkt(srs, &wkt);
  std::string out = wkt != nullptr ? wkt : "";
  CPLFree(wkt);
  OSRDestroySpatialReference(srs);
  return out;
}

struct GdalDataset {
  GDALDatasetH h = nullptr;
  ~GdalDataset() {
    if (h != nullptr)
      GDALClose(h);
  }
};

void write_geotiff(const std::string& path, std::size_t rows, std::size_t cols,
                   const std::vector<std::complex<float>>& data, const SarCase& c,
                   const double* geotransform, const std::vector<GDAL_GCP>& gcps,
                   const std::vector<std::pair<std::string, std::string>>& metadata,
                   const std::vector<std::pair<std::string, std::vector<float>>>& extra = {}) {
  GDALAllRegister();
  GDALDriverH drv = GDALGetDriverByName("GTiff");
  if (drv == nullptr)
    throw std::runtime_error(path + ": GDAL has no GTiff driver");
  char** opts = nullptr;
  opts = CSLSetNameValue(opts, "BIGTIFF", "IF_SAFER");
  GdalDataset ds;
  ds.h = GDALCreate(drv, path.c_str(), static_cast<int>(cols), static_cast<int>(rows),
                    static_cast<int>(1 + extra.size()), GDT_CFloat32, opts);
  CSLDestroy(opts);
  if (ds.h == nullptr)
    throw std::runtime_error(path + ": GDAL cannot create the file: " + CPLGetLastErrorMsg());
  const std::string wkt = local_wkt(c);
  if (geotransform != nullptr) {
    GDALSetGeoTransform(ds.h, const_cast<double*>(geotransform));
    GDALSetProjection(ds.h, wkt.c_str());
  } else if (!gcps.empty()) {
    GDALSetGCPs(ds.h, static_cast<int>(gcps.size()), gcps.data(), wkt.c_str());
  }
  for (const auto& [k, v] : metadata)
    GDALSetMetadataItem(ds.h, k.c_str(), v.c_str(), nullptr);
  GDALRasterBandH band = GDALGetRasterBand(ds.h, 1);
  const CPLErr err =
      GDALRasterIO(band, GF_Write, 0, 0, static_cast<int>(cols), static_cast<int>(rows),
                   const_cast<std::complex<float>*>(data.data()), static_cast<int>(cols),
                   static_cast<int>(rows), GDT_CFloat32, 0, 0);
  if (err != CE_None)
    throw std::runtime_error(path + ": GDAL write failed: " + CPLGetLastErrorMsg());
  // Further bands (real values in the file's complex type: GDAL sets the imaginary part 0).
  for (std::size_t b = 0; b < extra.size(); ++b) {
    GDALRasterBandH h = GDALGetRasterBand(ds.h, static_cast<int>(b + 2));
    GDALSetDescription(h, extra[b].first.c_str());
    if (GDALRasterIO(h, GF_Write, 0, 0, static_cast<int>(cols), static_cast<int>(rows),
                     const_cast<float*>(extra[b].second.data()), static_cast<int>(cols),
                     static_cast<int>(rows), GDT_Float32, 0, 0) != CE_None)
      throw std::runtime_error(path + ": GDAL write failed: " + CPLGetLastErrorMsg());
  }
  if (!extra.empty())
    GDALSetDescription(band, "scattering amplitude [m]");
}
#endif

std::string fmt(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

}  // namespace

SarCase parse_sar_case(std::string_view text, const std::string& origin) {
  try {
    return case_from_table(config::TomlFile::parse(text, origin).root());
  } catch (const config::ConfigError& e) {
    throw std::invalid_argument(e.what());
  }
}

bool sar_geotiff_available() noexcept {
#ifdef RADAR_EMU_HAVE_GDAL
  return true;
#else
  return false;
#endif
}

// The rates of the estimate printed before the raw data, on the 2-core reference machine:
// seconds per pulse and lit clutter patch (sar_terrain.toml: 46 s for 2616 pulses x 2.47 M
// patches, docs/performance.md), per pulse of SBR tracing and echo synthesis
// (sar_trihedrals.toml: 2.2 s for 658 pulses), per pixel and pulse of its synthetic aperture
// (the same case's backprojection).
constexpr double kSarClutterS = 7e-9;
constexpr double kSarTraceS = 3.4e-3;
constexpr double kSarBackprojectionS = 1.3e-7;

int run_sar_tool(const SarToolOptions& o) {
  if (!sar_geotiff_available())
    throw std::invalid_argument(
        "sar: GeoTIFF output needs GDAL, and this radar-emu was built without it (install "
        "libgdal-dev and reconfigure)");
  SarCase c = load_case(o.config);
  const rd::SarParams& p = c.p;
  std::filesystem::create_directories(o.out_dir);
  const std::filesystem::path dir(o.out_dir);
  const double lambda = rd::sar_wavelength_m(p);
  const glm::dvec3 tdir = rd::sar_track_dir(p), ldir = rd::sar_look_dir(p);
  const double gate = rd::sar_gate_m(p);
  const double far = p.near_range_m + static_cast<double>(p.gates) * gate;
  const double g_near = std::sqrt(p.near_range_m * p.near_range_m - c.altitude_m * c.altitude_m);
  const double g_far = std::sqrt(far * far - c.altitude_m * c.altitude_m);
  const double track_len = static_cast<double>(p.pulses - 1) * c.speed_mps / p.prf_hz;

  // Image grid: image_width_m along track centred on the origin, the swath in ground range.
  rd::SarImageGrid grid;
  grid.azimuth_spacing_m = c.azimuth_spacing_m;
  grid.ground_range_spacing_m = c.ground_range_spacing_m;
  grid.rows = static_cast<std::size_t>(std::floor(c.image_width_m / c.azimuth_spacing_m)) + 1;
  grid.cols = static_cast<std::size_t>(std::floor((g_far - g_near) / c.ground_range_spacing_m)) + 1;
  const glm::dvec3 centre{c.centre_east_m, c.centre_north_m, 0.0};
  grid.origin_m = centre - 0.5 * c.image_width_m * tdir + (g_near - c.ground_centre_m) * ldir;
  auto progress = [&](const std::string& line) {
    if (!o.quiet)
      std::fprintf(stderr, "sar: %s\n", line.c_str());
  };

  // Scene: ground wide enough for the whole track and swath.
  const double half_extent = 0.5 * track_len + g_far + 100.0;
  progress(c.database ? "building the scene database" : "building the scene");
  sc::Scene scene(build_scene(c, half_extent));
  if (c.database) {
    c.latitude_deg = common::degrees(scene.anchor().latitude_rad);
    c.longitude_deg = common::degrees(scene.anchor().longitude_rad);
    c.anchor_height_m = scene.anchor().height_m;
  }
  rd::SbrConfig cfg;
  cfg.carrier_hz = p.carrier_hz;
  cfg.azimuth_min_rad = -1.29 * p.azimuth_beamwidth_rad;
  cfg.azimuth_max_rad = 1.29 * p.azimuth_beamwidth_rad;
  cfg.elevation_min_rad = std::max(-1.29 * p.elevation_beamwidth_rad, -1.5);
  cfg.elevation_max_rad = std::min(1.29 * p.elevation_beamwidth_rad, 1.5);
  cfg.terrain_ray_spacing_rad = 5e-3;  // diffuse terrain comes from the clutter cells
  cfg.target_ray_spacing_m = c.target_ray_spacing_m;
  cfg.max_range_m = far + p.pulse_duration_s * kC;
  cfg.max_bounces = c.max_bounces;
  cfg.polarisation = c.pol;
  rd::SbrTracer tracer(scene, cfg);

  // --- terrain: the terrain engine's patches as fixed scatterers, the DEM and its mask (setup
  // ray casting counted as ray tracing).
  const auto t_raw0 = Clock::now();
  double trace_s = 0.0;
  std::vector<rd::SarScatterer> cells;
  std::size_t shadowed = 0, patches = 0;
  std::optional<rd::clutter::TerrainEngine> engine;
  rd::SarDem dem;
  std::vector<rd::clutter::Sigma0Use> sigma0_use;  // issue 28: flagged sigma0 the clutter read
  // A scene database is always focused on its DEM (with or without clutter: the image's
  // georeferencing holds for what stands on the terrain); the flat ground needs the engine only
  // for its clutter.
  if (c.database || (c.clutter && c.ground_material != "none")) {
    const auto t0 = Clock::now();
    // The image plus the beam's reach beyond it along track and a margin in range: its
    // horizontal bounding box (the track may have any heading).
    const double reach = far * std::tan(1.58 * p.azimuth_beamwidth_rad) + 2.0;
    const double a0 = -0.5 * c.image_width_m - reach, a1 = 0.5 * c.image_width_m + reach;
    const double r0 = g_near - c.ground_centre_m - 20.0, r1 = g_far - c.ground_centre_m + 20.0;
    rd::clutter::TerrainEngineSpec es;
    es.clip_to_region = true;
    es.region_min_m = glm::dvec2(std::numeric_limits<double>::infinity());
    es.region_max_m = -es.region_min_m;
    for (double a : {a0, a1})
      for (double r : {r0, r1}) {
        const glm::dvec3 q = centre + a * tdir + r * ldir;
        es.region_min_m = glm::min(es.region_min_m, glm::dvec2(q));
        es.region_max_m = glm::max(es.region_max_m, glm::dvec2(q));
      }
    es.max_facet_m = 25.0;
    es.speckle.seed = c.speckle_seed;
    progress("terrain engine: facets of the scene's terrain");
    engine.emplace(rd::make_terrain_engine(scene, tracer, es));
    if (c.clutter) {
      progress("terrain engine: " + std::to_string(engine->facets().size()) +
               " facets; patches of " + fmt(c.clutter_cell_m) + " m with shadowing");
      rd::TerrainCells tc = rd::terrain_cells(*engine, p, c.clutter_cell_m);
      sigma0_use = std::move(tc.sigma0_use);
      cells = std::move(tc.cells);
      shadowed = tc.shadowed;
      patches = tc.patches;
      progress("terrain engine: " + std::to_string(cells.size()) + " lit patches (" +
               std::to_string(shadowed) + " in shadow); DEM and mask of the image grid");
    } else {
      progress("terrain engine: " + std::to_string(engine->facets().size()) +
               " facets, no clutter; DEM and mask of the image grid");
    }
    dem = rd::sar_dem(*engine, p, grid);
    grid.height_m = dem.height_m;
    if (dem.holes > 0)
      std::fprintf(stderr,
                   "sar: warning: %zu image pixels have no terrain under them (a DEM hole): "
                   "imaged at the nearest terrain height of their row, flagged 8 in the mask "
                   "band\n",
                   dem.holes);
    trace_s += seconds_since(t0);
  }
  // Issue 28: the clutter's sigma0 values outside a model's validity (extrapolated or assumed
  // curves), said whatever -q says, in sar.json, the GeoTIFFs' metadata and the mask band.
  std::vector<std::string> sigma0_lines;
  if (engine)
    sigma0_lines = rd::clutter::sigma0_use_lines(
        sigma0_use, rd::clutter::sigma0_row_names(engine->materials()), p.carrier_hz);
  const std::uint32_t sigma0_flags = rd::clutter::sigma0_use_flags(sigma0_use);
  const double sigma0_pixel_fraction =
      dem.sigma0_pixels > 0
          ? static_cast<double>(dem.sigma0_flagged) / static_cast<double>(dem.sigma0_pixels)
          : 0.0;
  if (sigma0_flags != 0) {
    std::fprintf(stderr,
                 "sar: warning: sigma0 outside model validity in %.1f %% of the image's terrain "
                 "pixels (%.1f %% of the clutter patches; sar.json sigma0_validity, mask bit "
                 "16):\n",
                 100.0 * sigma0_pixel_fraction,
                 100.0 * rd::clutter::sigma0_use_patch_fraction(sigma0_use));
    for (const std::string& line : sigma0_lines)
      std::fprintf(stderr, "  %s\n", line.c_str());
  }

  // --- raw data: clutter cells, then the tracer's coherent returns per pulse.
  {
    const auto samples = static_cast<double>(rd::sar_raw_samples(p));
    // Before the long part: the arrays (complex floats: the raw rows, the range-compressed gates
    // upsampled, the image) and a time scaled from the reference 2-core machine (rates of
    // docs/performance.md's SAR cases); the progress line then measures the real pace.
    const double pulses = static_cast<double>(p.pulses);
    const double bytes =
        8.0 * (pulses * samples + pulses * static_cast<double>(p.gates * c.upsample) +
               static_cast<double>(grid.rows * grid.cols)) +
        64.0 * static_cast<double>(cells.size());
    const double raw_est_s = kSarClutterS * pulses * static_cast<double>(cells.size()) +
                             (c.targets.empty() && !c.database ? 0.0 : kSarTraceS * pulses);
    // Each pixel sums the pulses of its synthetic aperture, about far range x the synthetic
    // beamwidth long.
    const double aperture_pulses =
        std::min(pulses, far * c.theta_rad * p.prf_hz / std::max(c.speed_mps, 1e-3));
    const double bp_est_s =
        kSarBackprojectionS * static_cast<double>(grid.rows * grid.cols) * aperture_pulses;
    o.control.tell_estimate(std::to_string(p.pulses) + " pulses x " +
                            std::to_string(rd::sar_raw_samples(p)) + " samples, image " +
                            std::to_string(grid.rows) + " x " + std::to_string(grid.cols) +
                            ": memory about " + config::format_bytes(bytes) + ", raw data about " +
                            config::format_duration(raw_est_s) + ", backprojection about " +
                            config::format_duration(bp_est_s) + " (2-core reference machine)");
    // Refused past the memory limit before the raw matrix is allocated.
    if (const auto over = config::over_memory_limit(
            bytes, std::to_string(p.pulses) + " pulses x " +
                       std::to_string(rd::sar_raw_samples(p)) + " samples, image " +
                       std::to_string(grid.rows) + " x " + std::to_string(grid.cols))) {
      throw std::runtime_error("sar: " + *over +
                               ": a shorter aperture (fewer pulses), a smaller image or a "
                               "coarser pixel");
    }
  }
  rd::SarRaw raw = rd::make_raw(p);
  // Under mpirun the pulses split into one contiguous block a rank (docs/cluster.md): each rank
  // synthesises its rows exactly as one process would, rank 0 gathers them and alone forms the
  // image and writes. The clutter cells above are computed by every rank (setup, not split).
  mpi_work::start();
  const mpi_work::Block block = mpi_work::my_block(p.pulses);
  std::vector<rd::Contribution> out(tracer.max_contributions());
  std::vector<rd::SarEcho> echoes;
  std::vector<glm::dvec3> dirs;
  rd::TraceStats stats;
  const glm::dmat3 w = rd::sar_world_from_antenna(p);
  double echo_s = 0.0;
  // Per pulse, gathered with the raw rows: target echoes and rays traced.
  std::vector<std::uint64_t> echoes_per_pulse(p.pulses, 0), rays_per_pulse(p.pulses, 0);
  // Pulses [begin, end) of the targets' echoes into the preallocated raw matrix (the clutter's
  // synthesise_points takes the same range): a rank of a scale-out can run its share.
  auto target_pulses = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const double t = rd::sar_pulse_time_s(p, i);
      const auto t0 = Clock::now();
      scene.set_time(t);
      rd::RadarPose pose;
      pose.position_m = rd::sar_platform_m(p, t);
      pose.velocity_mps = p.velocity_mps;
      pose.world_from_antenna = w;
      const std::uint64_t rays_before = stats.rays;
      const std::size_t n = tracer.trace(pose, out, stats);
      rays_per_pulse[i] = stats.rays - rays_before;
      const auto t1 = Clock::now();
      trace_s += std::chrono::duration<double>(t1 - t0).count();
      echoes.clear();
      dirs.clear();
      for (std::size_t k = 0; k < n; ++k) {
        const rd::Contribution& ct = out[k];
        if (!ct.coherent || !tracer.is_target(ct.object_id))
          continue;
        echoes.push_back({ct.amplitude, ct.range_m});
        dirs.push_back(w * rd::direction_from_azel({ct.azimuth_rad, ct.elevation_rad}));
      }
      echoes_per_pulse[i] = echoes.size();
      rd::add_echoes(p, echoes, dirs, std::span(raw.data).subspan(i * raw.samples, raw.samples));
      echo_s += seconds_since(t1);
    }
  };
  // Pulse blocks, each the terrain's echoes then the targets' and the database's own structures
  // (conductors: pylons, wires, ...): every row is its pulse's alone, so the order changes
  // nothing, and a stop request (polled between blocks, in one process) leaves the pulses
  // [block.begin, pulses_done) whole and the rest zero.
  const bool traced = !c.targets.empty() || c.database;
  progress(std::string(cells.empty() ? "" : "terrain echoes") +
           (!cells.empty() && traced ? " and " : "") +
           (traced ? "targets and structures (SBR)" : "") + " per pulse");
  const std::size_t n_mine = block.end - block.begin;
  const std::size_t pulse_step = std::max<std::size_t>(1, n_mine / 200);
  std::size_t pulses_done = block.begin;
  double clutter_s = 0.0;
  for (std::size_t b = block.begin; b < block.end; b += pulse_step) {
    if (mpi_work::launched_size() <= 1 && o.control.stop_signal() != 0)
      break;
    const std::size_t e = std::min(block.end, b + pulse_step);
    if (!cells.empty()) {
      const auto t0 = Clock::now();
      rd::synthesise_points(p, cells, b, e, raw);
      clutter_s += seconds_since(t0);
    }
    if (traced)
      target_pulses(b, e);
    pulses_done = e;
    if (mpi_work::is_root())
      o.control.report(pulses_done - block.begin, n_mine);
  }
  const bool interrupted = pulses_done < block.end;
  mpi_work::gather_blocks(std::span(raw.data), raw.samples);
  mpi_work::gather_blocks(std::span(echoes_per_pulse));
  mpi_work::gather_blocks(std::span(rays_per_pulse));
  if (!mpi_work::is_root())
    return 0;
  std::uint64_t target_echoes = 0, rays = 0;
  for (std::size_t i = 0; i < p.pulses; ++i) {
    target_echoes += echoes_per_pulse[i];
    rays += rays_per_pulse[i];
  }
  const double raw_s = seconds_since(t_raw0);

  // --- image.
  const auto t_img0 = Clock::now();
  const rd::SarCompressed rc = rd::range_compress(p, raw, c.taper);
  const double rc_s = seconds_since(t_img0);
  const auto t_bp0 = Clock::now();
  progress(std::string("backprojection onto ") +
           (grid.height_m.empty() ? "the ground plane" : "the DEM"));
  // Interrupted: the pulses done focus a partial aperture (the rest of the raw rows are zero);
  // a second Ctrl-C during the backprojection exits at once.
  const rd::SarImage img = rd::backproject(p, rc, grid, {c.theta_rad, c.taper, c.upsample, 0.01});
  const double bp_s = seconds_since(t_bp0);
  const double image_s = seconds_since(t_img0);

  // --- point targets: static trihedrals get the IRF analysis; movers their displacement.
  nlohmann::json jt = nlohmann::json::array();
  const double rho_r = kC / (2.0 * p.bandwidth_hz), rho_a = lambda / (2.0 * c.theta_rad);
  for (const TargetCase& t : c.targets) {
    nlohmann::json j;
    j["name"] = t.name;
    j["kind"] = std::string(sc::target_name(t.spec.kind));
    j["position_m"] = {t.position_m.x, t.position_m.y, t.position_m.z};
    const glm::dvec3 rel = t.position_m - grid.origin_m;
    const double row = glm::dot(rel, tdir) / grid.azimuth_spacing_m;
    const double col = glm::dot(rel, ldir) / grid.ground_range_spacing_m;
    const glm::dvec3 radar = broadside_platform(p, t.position_m);
    const double range = glm::length(radar - t.position_m);
    const double sin_inc = glm::length(glm::dvec2(radar - t.position_m)) / range;
    j["expected_pixel"] = {row, col};
    if (glm::length(t.velocity_mps) > 0.0) {
      // Raney (1971): a target with radial velocity v_r images shifted along track by
      // -R v_r / V (v_r > 0 receding).
      const double v_r = glm::dot(t.velocity_mps, glm::normalize(t.position_m - radar));
      j["radial_velocity_mps"] = v_r;
      const double shift = -range * v_r / c.speed_mps;
      j["predicted_azimuth_shift_m"] = shift;
      // The shift is where the mover's echo has zero Doppler: the radar sees that only when the
      // beam reaches that place. With the Gaussian beam (radar/products/sar.hpp) the two-way
      // power gain at azimuth angle a = |shift| / R is -8 ln2 (a / theta_az)^2 nepers, in dB
      // 10 log10 of it; below the synthesis' own cut (-60 dB) the mover is seen only near
      // broadside, at a Doppler 2 v_r / lambda the processing does not pass: it images (faint,
      // defocused) near its own place, not at the shift.
      const double a_rel = std::abs(shift) / range / p.azimuth_beamwidth_rad;
      const double gain_db = -80.0 * std::log10(2.0) * a_rel * a_rel;  // 10 log10 e^(-8 ln2 x^2)
      const bool in_beam = gain_db >= -60.0;
      j["doppler_hz"] = 2.0 * v_r / lambda;
      j["zero_doppler_two_way_gain_db"] = gain_db;
      j["zero_doppler_in_beam"] = in_beam;
      const double search_shift = in_beam ? shift : 0.0;
      // Where it imaged: the brightest pixel within +-15 m along track and +-10 m in ground range
      // of the predicted place (the zero-Doppler place when in the beam, else its own; its ground
      // range where the platform passes its along-track place).
      const double t_b = glm::dot(t.position_m - p.start_position_m, tdir) / c.speed_mps;
      const glm::dvec3 at_b = t.position_m + t.velocity_mps * t_b;
      const double col_b = glm::dot(at_b - grid.origin_m, ldir) / grid.ground_range_spacing_m;
      const double row_p = glm::dot(at_b - grid.origin_m, tdir) / grid.azimuth_spacing_m +
                           search_shift / grid.azimuth_spacing_m;
      const auto span_r = static_cast<std::ptrdiff_t>(15.0 / grid.azimuth_spacing_m);
      const auto span_c = static_cast<std::ptrdiff_t>(10.0 / grid.ground_range_spacing_m);
      double best = -1.0;
      std::ptrdiff_t br = -1, bc = -1;
      for (std::ptrdiff_t r = std::llround(row_p) - span_r; r <= std::llround(row_p) + span_r; ++r)
        for (std::ptrdiff_t cc = std::llround(col_b) - span_c; cc <= std::llround(col_b) + span_c;
             ++cc) {
          if (r < 0 || cc < 0 || r >= static_cast<std::ptrdiff_t>(grid.rows) ||
              cc >= static_cast<std::ptrdiff_t>(grid.cols))
            continue;
          const double v = static_cast<double>(std::norm(
              img.pixels[static_cast<std::size_t>(r) * grid.cols + static_cast<std::size_t>(cc)]));
          if (v > best) {
            best = v;
            br = r;
            bc = cc;
          }
        }
      if (br >= 0) {
        j["measured_azimuth_shift_m"] =
            (static_cast<double>(br) - (row_p - search_shift / grid.azimuth_spacing_m)) *
            grid.azimuth_spacing_m;
        j["measured_ground_range_offset_m"] =
            (static_cast<double>(bc) - col_b) * grid.ground_range_spacing_m;
        j["peak_dbsm"] = db10(best);
      }
      jt.push_back(j);
      continue;
    }
    // Extended targets have no impulse response to measure.
    if (!is_trihedral(t.spec.kind) || row < 0 || col < 0 || row >= static_cast<double>(grid.rows) ||
        col >= static_cast<double>(grid.cols)) {
      jt.push_back(j);
      continue;
    }
    rd::IrfOptions io;
    io.chip = 96;
    io.quadratic_phase_row_rad = rd::sar_azimuth_quadratic_phase(p, range, grid.azimuth_spacing_m);
    try {
      const rd::IrfResult r = rd::analyse_point_target(
          img.pixels, grid.rows, grid.cols, static_cast<std::size_t>(std::lround(row)),
          static_cast<std::size_t>(std::lround(col)), io);
      const double energy = r.chip_energy * grid.azimuth_spacing_m * grid.ground_range_spacing_m /
                            (rho_r / sin_inc * rho_a);
      j["range_resolution_m"] = r.range.resolution_px * grid.ground_range_spacing_m * sin_inc;
      j["azimuth_resolution_m"] = r.azimuth.resolution_px * grid.azimuth_spacing_m;
      j["range_pslr_db"] = r.range.pslr_db;
      j["azimuth_pslr_db"] = r.azimuth.pslr_db;
      j["range_islr_db"] = r.range.islr_db;
      j["azimuth_islr_db"] = r.azimuth.islr_db;
      j["range_offset_m"] = (r.peak_col - col) * grid.ground_range_spacing_m * sin_inc;
      j["azimuth_offset_m"] = (r.peak_row - row) * grid.azimuth_spacing_m;
      j["peak_dbsm"] = db10(r.peak_power);
      j["integrated_energy_dbsm"] = db10(energy);
      j["range_cut_db"] = r.range.power_db;
      j["azimuth_cut_db"] = r.azimuth.power_db;
      j["cut_step_px"] = 1.0 / static_cast<double>(io.oversample);
      j["sin_incidence"] = sin_inc;
      if (t.spec.kind == sc::TargetKind::kTrihedralSquare)
        j["rcs_theory_dbsm"] = db10(12.0 * rd::kPi * std::pow(t.spec.a_m, 4) / (lambda * lambda));
      else if (t.spec.kind == sc::TargetKind::kTrihedralTriangular)
        j["rcs_theory_dbsm"] =
            db10(4.0 * rd::kPi * std::pow(t.spec.a_m, 4) / (3.0 * lambda * lambda));
    } catch (const std::invalid_argument& e) {
      j["irf_error"] = e.what();
    }
    jt.push_back(j);
  }

  // --- outputs.
  std::vector<std::pair<std::string, std::string>> md{
      {"CARRIER_HZ", fmt(p.carrier_hz)},         {"BANDWIDTH_HZ", fmt(p.bandwidth_hz)},
      {"SAMPLE_RATE_HZ", fmt(p.sample_rate_hz)}, {"PRF_HZ", fmt(p.prf_hz)},
      {"NEAR_RANGE_M", fmt(p.near_range_m)},     {"POLARISATION", c.pol_name}};
  // Issue 28: whether the clutter read sigma0 values outside a model's validity, and where.
  md.emplace_back("SIGMA0_VALIDITY",
                  sigma0_flags == 0
                      ? std::string("valid")
                      : "outside model validity: " + rd::clutter::describe_validity(sigma0_flags));
  for (std::size_t i = 0; i < sigma0_lines.size(); ++i)
    md.emplace_back("SIGMA0_FLAGGED_" + std::to_string(i + 1), sigma0_lines[i]);
#ifdef RADAR_EMU_HAVE_GDAL
  if (!o.no_raw) {
    // Raw data in radar geometry (pulse, fast-time sample): GCPs at the four corners and the
    // centre, each the flat-ground point at that sample's slant range, broadside of that pulse.
    std::vector<GDAL_GCP> gcps;
    std::vector<std::string> ids;
    const std::size_t h = (rd::sar_chirp_samples(p) - 1) / 2;
    for (double fp : {0.0, 0.5, 1.0})
      for (double fs : {0.0, 0.5, 1.0}) {
        const double pulse = fp * static_cast<double>(p.pulses - 1);
        const double sample = fs * static_cast<double>(raw.samples - 1);
        const double range = p.near_range_m + (sample - static_cast<double>(h)) * gate;
        if (range <= c.altitude_m)
          continue;
        const glm::dvec3 pos = rd::sar_platform_m(p, pulse / p.prf_hz);
        const double g = std::sqrt(range * range - c.altitude_m * c.altitude_m);
        const glm::dvec3 x = glm::dvec3(pos.x, pos.y, 0.0) + g * ldir;
        ids.push_back(std::to_string(gcps.size() + 1));
        GDAL_GCP gcp{};
        gcp.dfGCPPixel = sample + 0.5;
        gcp.dfGCPLine = pulse + 0.5;
        gcp.dfGCPX = x.x;
        gcp.dfGCPY = x.y;
        gcp.dfGCPZ = 0.0;
        gcps.push_back(gcp);
      }
    for (std::size_t i = 0; i < gcps.size(); ++i) {
      gcps[i].pszId = ids[i].data();
      gcps[i].pszInfo = const_cast<char*>("");
    }
    auto mdr = md;
    mdr.emplace_back("RAW_FIRST_SAMPLE_RANGE_M",
                     fmt(p.near_range_m - static_cast<double>(h) * gate));
    mdr.emplace_back("PULSE_DURATION_S", fmt(p.pulse_duration_s));
    write_geotiff((dir / "raw.tif").string(), raw.pulses, raw.samples, raw.data, c, nullptr, gcps,
                  mdr);
  }
  {
    const glm::dvec3 corner = grid.origin_m - 0.5 * grid.azimuth_spacing_m * tdir -
                              0.5 * grid.ground_range_spacing_m * ldir;
    const double gt[6] = {
        corner.x, grid.ground_range_spacing_m * ldir.x, grid.azimuth_spacing_m * tdir.x,
        corner.y, grid.ground_range_spacing_m * ldir.y, grid.azimuth_spacing_m * tdir.y};
    auto mdi = md;
    mdi.emplace_back("UNITS", "scattering amplitude [m]: |pixel|^2 = sigma of a point target");
    mdi.emplace_back("INTEGRATION_ANGLE_RAD", fmt(c.theta_rad));
    std::vector<std::pair<std::string, std::vector<float>>> bands;
    if (!dem.mask.empty()) {
      mdi.emplace_back("BAND_2",
                       "mask: 1 shadow, 2 layover, 4 foreshortening, 8 no DEM, 16 sigma0 outside "
                       "model validity (sum)");
      mdi.emplace_back("BAND_3", "DEM height the image is focused on [m], world up");
      std::vector<float> mask_band(dem.mask.size());
      for (std::size_t i = 0; i < mask_band.size(); ++i)
        mask_band[i] = static_cast<float>(
            dem.mask[i] | (c.clutter && dem.sigma0_flags[i] != 0u ? rd::kSarSigma0Flagged : 0));
      bands.emplace_back(
          "mask: 1 shadow, 2 layover, 4 foreshortening, 8 no DEM, 16 sigma0 outside validity",
          std::move(mask_band));
      bands.emplace_back("DEM height [m]", dem.height_m);
    }
    write_geotiff((dir / "image.tif").string(), grid.rows, grid.cols, img.pixels, c, gt, {}, mdi,
                  bands);
  }
#endif
  std::ostringstream title;
  title << "radar-emu sar: " << p.carrier_hz / 1e9 << " GHz, B " << p.bandwidth_hz / 1e6
        << " MHz, incidence " << p.incidence_rad / common::kRadPerDeg << " deg, " << c.pol_name;
  plot::FigureBatch figures;  // the image and the impulse response by one renderer
  figures.add(plot::single(image_figure(img, title.str())), dir / "image.png");

  // The impulse response of the first analysed trihedral: range and azimuth cuts, dB.
  for (const auto& t : jt) {
    if (!t.contains("range_cut_db"))
      continue;
    LineChart chart;
    chart.title = "SAR impulse response, " + t["name"].get<std::string>() + " (" +
                  (c.taper == rd::SarTaper::kNone ? "unweighted" : "Hamming") + ")";
    chart.x_label = "offset from the peak [resolution cells c/(2B), lambda/(2 Theta)]";
    chart.y_label = "power [dB]";
    chart.y_min = -70.0;
    chart.y_max = 3.0;
    const double step = t["cut_step_px"].get<double>();
    for (const char* axis : {"range", "azimuth"}) {
      const auto cut = t[std::string(axis) + "_cut_db"].get<std::vector<double>>();
      const std::size_t k =
          static_cast<std::size_t>(std::max_element(cut.begin(), cut.end()) - cut.begin());
      // Pixels to resolution cells: ground-range pixels through the incidence, azimuth pixels.
      const double cell_px =
          std::string(axis) == "range"
              ? rho_r / t["sin_incidence"].get<double>() / grid.ground_range_spacing_m
              : rho_a / grid.azimuth_spacing_m;
      Series se;
      se.label = axis;
      for (std::size_t i = 0; i < cut.size(); ++i) {
        const double x = (static_cast<double>(i) - static_cast<double>(k)) * step / cell_px;
        if (std::abs(x) <= 25.0) {
          se.x.push_back(x);
          se.y.push_back(std::max(cut[i], -70.0));
        }
      }
      chart.series.push_back(std::move(se));
    }
    figures.add(plot::single(std::move(chart)), dir / "irf.png");
    break;
  }
  figures.write();

  nlohmann::json j;
  j["config"] = o.config;
  j["radar"] = {{"carrier_hz", p.carrier_hz},
                {"wavelength_m", lambda},
                {"bandwidth_hz", p.bandwidth_hz},
                {"sample_rate_hz", p.sample_rate_hz},
                {"pulse_duration_s", p.pulse_duration_s},
                {"prf_hz", p.prf_hz},
                {"transmit_power_w", p.transmit_power_w},
                {"peak_gain", p.peak_gain},
                {"polarisation", c.pol_name}};
  j["platform"] = {
      {"altitude_m", c.altitude_m},
      {"speed_mps", c.speed_mps},
      {"heading_deg", c.heading_rad / common::kRadPerDeg},
      {"look", p.look_right ? "right" : "left"},
      {"start_position_m", {p.start_position_m.x, p.start_position_m.y, p.start_position_m.z}},
      {"track_length_m", track_len},
      {"pulses", p.pulses}};
  j["antenna"] = {{"incidence_deg", p.incidence_rad / common::kRadPerDeg},
                  {"azimuth_beamwidth_deg", p.azimuth_beamwidth_rad / common::kRadPerDeg},
                  {"elevation_beamwidth_deg", p.elevation_beamwidth_rad / common::kRadPerDeg}};
  j["processing"] = {
      {"algorithm", "time-domain backprojection"},
      {"gates", p.gates},
      {"gate_m", gate},
      {"near_range_m", p.near_range_m},
      {"synthetic_beamwidth_deg", c.synthetic_beamwidth_rad / common::kRadPerDeg},
      {"integration_angle_deg", c.theta_rad / common::kRadPerDeg},
      {"taper", c.taper == rd::SarTaper::kNone ? "none" : "hamming"},
      {"upsample", c.upsample},
      {"theory_range_resolution_m", rd::theory_range_resolution_m(p, c.taper)},
      {"theory_azimuth_resolution_m", rd::theory_azimuth_resolution_m(p, c.theta_rad, c.taper)},
      {"image_rows", grid.rows},
      {"image_cols", grid.cols},
      {"azimuth_spacing_m", grid.azimuth_spacing_m},
      {"ground_range_spacing_m", grid.ground_range_spacing_m}};
  // Land-cover regions (the DEM's top facet's material): the mean sigma0 the image gives over
  // each region's interior pixels (every pixel within 3 of it the same material, no mask bit),
  // intensity / (rho_r / sin(theta) rho_a) (sar.hpp: a distributed target's mean intensity), next
  // to the catalogue's sigma0 at each pixel's local incidence (Sigma0Table through the engine).
  nlohmann::json regions = nlohmann::json::array();
  if (engine && c.taper == rd::SarTaper::kNone) {
    const auto facets = engine->facets();
    const std::size_t nm = scene.materials().size();
    std::vector<double> meas(nm, 0.0), cat(nm, 0.0);
    std::vector<std::size_t> count(nm, 0);
    const long k = 3;
    for (std::size_t r = 0; r < grid.rows; ++r)
      for (std::size_t col = 0; col < grid.cols; ++col) {
        const std::size_t i = r * grid.cols + col;
        if (dem.facet[i] < 0 || dem.mask[i] != 0)
          continue;
        const rd::clutter::TerrainFacet& f = facets[static_cast<std::size_t>(dem.facet[i])];
        bool interior = true;
        for (long dr = -k; dr <= k && interior; ++dr)
          for (long dc = -k; dc <= k && interior; ++dc) {
            const long rr = static_cast<long>(r) + dr, cc = static_cast<long>(col) + dc;
            if (rr < 0 || cc < 0 || rr >= static_cast<long>(grid.rows) ||
                cc >= static_cast<long>(grid.cols)) {
              interior = false;
              break;
            }
            const std::size_t j2 =
                static_cast<std::size_t>(rr) * grid.cols + static_cast<std::size_t>(cc);
            interior = dem.facet[j2] >= 0 && dem.mask[j2] == 0 &&
                       facets[static_cast<std::size_t>(dem.facet[j2])].material == f.material;
          }
        if (!interior)
          continue;
        const glm::dvec3 x = grid.origin_m + double(r) * grid.azimuth_spacing_m * tdir +
                             double(col) * grid.ground_range_spacing_m * ldir;
        const glm::dvec3 pt{x.x, x.y, static_cast<double>(dem.height_m[i])};
        const glm::dvec3 radar = broadside_platform(p, pt);
        const glm::dvec3 u = glm::normalize(radar - pt);
        const double sin_inc = glm::length(glm::dvec2(u));
        meas[f.material] +=
            static_cast<double>(std::norm(img.pixels[i])) / (rho_r / sin_inc * rho_a);
        cat[f.material] += engine->sigma0(f, std::abs(glm::dot(f.normal, u)));
        ++count[f.material];
      }
    for (std::size_t m = 0; m < nm; ++m) {
      if (count[m] == 0)
        continue;
      const double a = meas[m] / double(count[m]), b = cat[m] / double(count[m]);
      regions.push_back({{"material", scene.materials()[m].name},
                         {"pixels", count[m]},
                         {"image_sigma0_db", db10(a)},
                         {"catalogue_sigma0_db", db10(b)},
                         {"difference_db", db10(a) - db10(b)}});
    }
  }
  j["regions"] = regions;
  j["sigma0_validity"] = {
      {"flagged", sigma0_flags != 0},
      {"flags", sigma0_flags},
      {"description", rd::clutter::describe_validity(sigma0_flags)},
      {"terrain_pixels", c.clutter ? dem.sigma0_pixels : 0},
      {"flagged_pixels", c.clutter ? dem.sigma0_flagged : 0},
      {"flagged_pixel_fraction", c.clutter ? sigma0_pixel_fraction : 0.0},
      {"flagged_patch_fraction", rd::clutter::sigma0_use_patch_fraction(sigma0_use)},
      {"flagged_power_fraction", rd::clutter::sigma0_use_power_fraction(sigma0_use)},
      {"mask_bit", 16},
      {"materials", sigma0_lines}};
  if (engine)
    j["mask"] = {{"shadow_pixels", dem.shadow},
                 {"layover_pixels", dem.layover},
                 {"foreshortening_pixels", dem.foreshortening},
                 {"dem_hole_pixels", dem.holes},
                 {"band", 2},
                 {"sigma0_flagged_pixels", c.clutter ? dem.sigma0_flagged : 0},
                 {"bits",
                  "1 shadow, 2 layover, 4 foreshortening, 8 no DEM, 16 sigma0 outside "
                  "model validity"}};
  j["scene"] = {{"database", !c.database             ? std::string("none")
                             : c.source.import       ? "import:" + c.source.import->dem.string()
                             : c.source.file.empty() ? c.source.builtin
                                                     : c.source.file.string()},
                {"terrain_patches", patches},
                {"ground_material", c.ground_material},
                {"clutter", c.clutter},
                {"clutter_cells", cells.size()},
                {"shadowed_cells", shadowed},
                {"clutter_cell_m", c.clutter_cell_m},
                {"speckle_seed", c.speckle_seed},
                {"targets", c.targets.size()},
                {"target_echoes", target_echoes},
                {"rays", rays},
                {"latitude_deg", c.latitude_deg},
                {"longitude_deg", c.longitude_deg}};
  j["timing_s"] = {{"raw", raw_s},
                   {"raw_ray_tracing", trace_s},
                   {"raw_clutter_synthesis", clutter_s},
                   {"raw_target_synthesis", echo_s},
                   {"image", image_s},
                   {"image_range_compression", rc_s},
                   {"image_backprojection", bp_s},
                   {"image_ray_tracing", 0.0}};
  j["point_targets"] = jt;
  if (interrupted) {
    // The raw rows of pulses [0, pulses_done) are synthesised, the rest zero; the image is
    // focused from those only (its point-target measurements above are of a partial aperture).
    j["incomplete"] = true;
    j["stop_signal"] = config::signal_name(o.control.stop_signal());
    j["pulses_done"] = pulses_done;
  } else {
    j["incomplete"] = false;
  }
  std::ofstream f(dir / "sar.json");
  f << j.dump(2) << "\n";
  if (!f)
    throw std::runtime_error((dir / "sar.json").string() + ": cannot write");
  if (!o.quiet) {
    std::printf(
        "sar: %zu pulses x %zu gates, image %zu x %zu, raw %.2f s (ray tracing %.0f %%), "
        "image %.2f s (ray tracing 0 %%)\n",
        p.pulses, p.gates, grid.rows, grid.cols, raw_s, raw_s > 0 ? 100.0 * trace_s / raw_s : 0.0,
        image_s);
    for (const auto& t : jt)
      if (t.contains("range_resolution_m"))
        std::printf(
            "  %s: res %.3f / %.3f m, PSLR %.2f / %.2f dB, ISLR %.2f / %.2f dB, peak "
            "%.2f dBsm, energy %.2f dBsm\n",
            t["name"].get<std::string>().c_str(), t["range_resolution_m"].get<double>(),
            t["azimuth_resolution_m"].get<double>(), t["range_pslr_db"].get<double>(),
            t["azimuth_pslr_db"].get<double>(), t["range_islr_db"].get<double>(),
            t["azimuth_islr_db"].get<double>(), t["peak_dbsm"].get<double>(),
            t["integrated_energy_dbsm"].get<double>());
    std::printf("  outputs in %s\n", o.out_dir.c_str());
  }
  return interrupted ? 128 + o.control.stop_signal() : 0;
}

}  // namespace radar_emu::tools
