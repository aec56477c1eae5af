// The geodata import (scene/geodata/import.hpp) against closed forms: GeoTIFFs and an OSM file are
// written here (a plane, a cone, a ridge; with and without a geoid vertical datum), imported, and
// the scene is probed with vertical rays. Reference heights are the bilinear values of the
// rasters' own samples (computed here from the arrays written), the EGM96 reference values are
// NGA's published test values.

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "scene/geo.hpp"
#include "scene/geodata/import.hpp"
#include "scene/geodata/raster.hpp"
#include "scene/scene.hpp"

namespace radar_emu::scene::geodata {
namespace {

using common::degrees;
using common::radians;

// A site in southern France; rasters are laid around it in WGS84 longitude / latitude.
constexpr double kLat0_deg = 43.45, kLon0_deg = 1.30;
constexpr double kStep_deg = 0.0002;  // raster spacing: 22.2 m north, 16.1 m east
constexpr int kSize = 120;            // pixels a side (about 2.7 x 1.9 km)

std::filesystem::path tmp(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "radar_emu_geodata_test";
  std::filesystem::create_directories(dir);
  return dir / name;
}

// A north-up geographic raster centred on (lat0, lon0): pixel (c, r) centre at
// lon = lon0 + (c + 0.5 - n/2) step, lat = lat0 - (r + 0.5 - n/2) step.
struct TestRaster {
  double lat0_deg = kLat0_deg, lon0_deg = kLon0_deg, step_deg = kStep_deg;
  int n = kSize;
  std::vector<float> values;
  [[nodiscard]] double west() const { return lon0_deg - n / 2.0 * step_deg; }
  [[nodiscard]] double north() const { return lat0_deg + n / 2.0 * step_deg; }
  [[nodiscard]] double lon(double c) const { return west() + c * step_deg; }
  [[nodiscard]] double lat(double r) const { return north() - r * step_deg; }
  // Bilinear value between pixel centres (edge held), the reference surface.
  [[nodiscard]] double bilinear(double lat_deg, double lon_deg) const {
    const double u = std::clamp((lon_deg - west()) / step_deg - 0.5, 0.0, n - 1.0);
    const double v = std::clamp((north() - lat_deg) / step_deg - 0.5, 0.0, n - 1.0);
    const int c = std::min(static_cast<int>(u), n - 2), r = std::min(static_cast<int>(v), n - 2);
    const double fu = u - c, fv = v - r;
    auto at = [&](int cc, int rr) {
      return static_cast<double>(values[static_cast<std::size_t>(rr * n + cc)]);
    };
    return (1 - fv) * ((1 - fu) * at(c, r) + fu * at(c + 1, r)) +
           fv * ((1 - fu) * at(c, r + 1) + fu * at(c + 1, r + 1));
  }
  void fill(const std::function<double(double lat_deg, double lon_deg)>& f) {
    values.resize(static_cast<std::size_t>(n * n));
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        values[static_cast<std::size_t>(r * n + c)] =
            static_cast<float>(f(lat(r + 0.5), lon(c + 0.5)));
  }
};

// Writes a GeoTIFF. srs "" writes no coordinate system and no geotransform.
void write_tif(const std::filesystem::path& path, int w, int h, const std::vector<float>& v,
               const double gt[6], const std::string& srs, std::optional<double> nodata = {},
               GDALDataType type = GDT_Float32) {
  GDALAllRegister();
  GDALDriver* drv = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = drv->Create(path.string().c_str(), w, h, 1, type, nullptr);
  ASSERT_NE(ds, nullptr);
  if (!srs.empty()) {
    ds->SetGeoTransform(const_cast<double*>(gt));
    OGRSpatialReference s;
    ASSERT_EQ(s.SetFromUserInput(srs.c_str()), OGRERR_NONE) << srs;
    ds->SetSpatialRef(&s);
  }
  if (nodata)
    ds->GetRasterBand(1)->SetNoDataValue(*nodata);
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, w, h, const_cast<float*>(v.data()), w, h,
                                           GDT_Float32, 0, 0),
            CE_None);
  GDALClose(ds);
}

void write_tif(const std::filesystem::path& path, const TestRaster& r, const std::string& srs,
               std::optional<double> nodata = {}) {
  const double gt[6] = {r.west(), r.step_deg, 0.0, r.north(), 0.0, -r.step_deg};
  write_tif(path, r.n, r.n, r.values, gt, srs, nodata);
}

ImportSpec base_spec(const std::filesystem::path& dem) {
  ImportSpec s;
  s.dem = dem;
  s.anchor_latitude_rad = radians(kLat0_deg);
  s.anchor_longitude_rad = radians(kLon0_deg);
  s.central_east_m = 1200.0;
  s.central_north_m = 1600.0;
  s.central_cell_m = 10.0;
  s.tile_cells = 32;
  return s;
}

// Ellipsoidal height and lat/lon of the scene's first surface straight below ENU (x, y).
struct Probe {
  bool hit = false;
  glm::dvec3 enu_m{0.0};
  wgs84::Geodetic geo;
};
Probe probe(const Scene& scene, double x, double y) {
  Ray ray;
  ray.origin_m = {x, y, 3000.0};
  ray.direction = {0.0, 0.0, -1.0};
  Hit hit;
  Probe p;
  p.hit = scene.intersect(ray, hit);
  p.enu_m = hit.position_m;
  p.geo = wgs84::EnuFrame(scene.anchor()).geodetic_from_enu(hit.position_m);
  return p;
}

// Scene heights at a spread of points (nodes, cell middles, odd places) against the raster's
// bilinear surface (+ geoid_m): within a tenth of the raster spacing.
void expect_heights(const TestRaster& r, const ImportSpec& spec, double geoid_m, const char* what) {
  ImportReport report;
  const Scene scene(import_geodata(spec, report));
  const double spacing_m = report.dem_spacing_m;
  const double expected_m =
      std::sqrt(111132.0 * r.step_deg * 111320.0 * r.step_deg * std::cos(radians(r.lat0_deg)));
  EXPECT_NEAR(spacing_m, expected_m, 0.01 * expected_m) << what;
  double worst = 0.0;
  for (double x = -590.0; x <= 590.0; x += 73.3) {
    for (double y = -790.0; y <= 790.0; y += 61.7) {
      const Probe p = probe(scene, x, y);
      ASSERT_TRUE(p.hit) << what << " at " << x << ", " << y;
      const double ref =
          r.bilinear(degrees(p.geo.latitude_rad), degrees(p.geo.longitude_rad)) + geoid_m;
      worst = std::max(worst, std::abs(p.geo.height_m - ref));
    }
  }
  std::printf("%s: worst |scene - bilinear| = %.4f m (limit %.2f m)\n", what, worst,
              0.1 * spacing_m);
  EXPECT_LT(worst, 0.1 * spacing_m) << what;
}

// NGA's EGM96 test values (the 15-minute grid interpolation program INTPT.F and its expected
// output OUTINTPT.DAT, distributed with the EGM96 geoid files): latitude, east longitude [deg],
// undulation [m].
TEST(Geodata, Egm96UndulationAtPublishedPoints) {
  const Egm96 geoid;
  EXPECT_NEAR(geoid.undulation_m(radians(38.6281550), radians(269.7791550 - 360.0)), -31.628, 0.5);
  EXPECT_NEAR(geoid.undulation_m(radians(-14.6212170), radians(305.0211140 - 360.0)), -2.969, 0.5);
}

TEST(Geodata, PlaneConeRidgeHeightsWithinATenthOfTheSpacing) {
  TestRaster plane;
  const double m_per_deg_lat = 111132.0, m_per_deg_lon = 111320.0 * std::cos(radians(kLat0_deg));
  plane.fill([&](double la, double lo) {
    return 250.0 + 0.03 * (lo - kLon0_deg) * m_per_deg_lon -
           0.05 * (la - kLat0_deg) * m_per_deg_lat;
  });
  write_tif(tmp("plane.tif"), plane, "EPSG:4326");
  ImportSpec spec = base_spec(tmp("plane.tif"));
  spec.datum = DatumChoice::kEllipsoid;
  expect_heights(plane, spec, 0.0, "plane");

  TestRaster cone;
  cone.fill([&](double la, double lo) {
    const double r_m =
        std::hypot((lo - kLon0_deg) * m_per_deg_lon, (la - kLat0_deg) * m_per_deg_lat);
    return 300.0 + std::max(0.0, 120.0 - 0.25 * r_m);
  });
  write_tif(tmp("cone.tif"), cone, "EPSG:4326");
  spec.dem = tmp("cone.tif");
  expect_heights(cone, spec, 0.0, "cone");

  TestRaster ridge;
  ridge.fill([&](double, double lo) {
    return 200.0 + std::max(0.0, 60.0 - 0.2 * std::abs((lo - kLon0_deg) * m_per_deg_lon - 100.0));
  });
  write_tif(tmp("ridge.tif"), ridge, "EPSG:4326");
  spec.dem = tmp("ridge.tif");
  expect_heights(ridge, spec, 0.0, "ridge");
}

// The same plane at NGA's first published point, once stating the EGM96 vertical datum (a
// compound CRS in the GeoTIFF keys) and once stating none (EGM96 assumed and reported).
TEST(Geodata, GeoidVerticalDatumStatedOrAssumed) {
  TestRaster plane;
  plane.lat0_deg = 38.6281550;
  plane.lon0_deg = 269.7791550 - 360.0;
  plane.fill([&](double la, double) { return 150.0 + 2000.0 * (la - plane.lat0_deg); });
  constexpr double kN_m = -31.628;  // published (see above); varies < 0.1 m over this tile
  write_tif(tmp("geoid_plane.tif"), plane, "EPSG:4326+5773");
  ImportSpec spec = base_spec(tmp("geoid_plane.tif"));
  spec.anchor_latitude_rad = radians(plane.lat0_deg);
  spec.anchor_longitude_rad = radians(plane.lon0_deg);
  {
    const GeoRaster r(tmp("geoid_plane.tif"), "dem", true);
    EXPECT_EQ(r.stated_vertical_datum(), VerticalDatum::kEgm96) << r.vertical_crs_name();
  }
  expect_heights(plane, spec, kN_m, "plane, EGM96 stated");
  ImportReport report;
  (void)import_geodata(spec, report);
  EXPECT_NE(report.vertical.find("stated by the file"), std::string::npos) << report.vertical;
  EXPECT_NEAR(report.anchor_undulation_m, kN_m, 0.5);
  EXPECT_NEAR(report.anchor_height_m, 150.0 + kN_m, 0.5);

  write_tif(tmp("nodatum_plane.tif"), plane, "EPSG:4326");
  spec.dem = tmp("nodatum_plane.tif");
  expect_heights(plane, spec, kN_m, "plane, no datum stated");
  (void)import_geodata(spec, report);
  EXPECT_NE(report.vertical.find("assumed"), std::string::npos) << report.vertical;
  spec.datum = DatumChoice::kEllipsoid;
  expect_heights(plane, spec, 0.0, "plane, told ellipsoidal");
}

// Latitude / longitude of pixel centres -> scene ENU -> the scene's surface -> latitude /
// longitude -> pixel of the GeoTIFF as GDAL reads it: back within one pixel. (`radar-emu sar`
// images a built-in SAR case, not a scene file, so the pixel is the DEM's.)
TEST(Geodata, LatLonToSceneToRasterPixelRoundTrip) {
  TestRaster ridge;
  ridge.fill([&](double la, double lo) {
    return 100.0 + 3000.0 * std::abs(la - kLat0_deg) + 1000.0 * (lo - kLon0_deg);
  });
  write_tif(tmp("rt.tif"), ridge, "EPSG:4326");
  ImportSpec spec = base_spec(tmp("rt.tif"));
  ImportReport report;
  const Scene scene(import_geodata(spec, report));
  GDALAllRegister();
  GDALDataset* ds = GDALDataset::Open(tmp("rt.tif").string().c_str(), GDAL_OF_RASTER);
  ASSERT_NE(ds, nullptr);
  double gt[6], inv[6];
  ds->GetGeoTransform(gt);
  ASSERT_TRUE(GDALInvGeoTransform(gt, inv));
  GDALClose(ds);
  const wgs84::EnuFrame frame(scene.anchor());
  double worst_px = 0.0;
  for (int r = 30; r <= 90; r += 7) {
    for (int c = 30; c <= 90; c += 9) {
      const double lat = radians(ridge.lat(r + 0.5)), lon = radians(ridge.lon(c + 0.5));
      const double h = ridge.bilinear(degrees(lat), degrees(lon)) + report.anchor_undulation_m;
      const glm::dvec3 e = frame.enu_from_geodetic({lat, lon, h});
      const Probe p = probe(scene, e.x, e.y);
      ASSERT_TRUE(p.hit);
      const double x = degrees(p.geo.longitude_rad), y = degrees(p.geo.latitude_rad);
      const double col = inv[0] + inv[1] * x + inv[2] * y, row = inv[3] + inv[4] * x + inv[5] * y;
      worst_px = std::max(worst_px, std::hypot(col - (c + 0.5), row - (r + 0.5)));
    }
  }
  std::printf("round trip: worst %.5f pixel\n", worst_px);
  EXPECT_LT(worst_px, 1.0);
}

// Land cover in an orthographic CRS on the anchor (ENU at the ground) with the scene's cells:
// every level-0 cell takes exactly one pixel, so material counts equal the raster's class counts.
TEST(Geodata, ClassToMaterialCountsEqualTheRasters) {
  TestRaster flat;
  flat.fill([](double, double) { return 0.0; });
  write_tif(tmp("flat.tif"), flat, "EPSG:4326");
  const int w = 40, h = 60;  // 10 m pixels over 400 x 600 m
  const std::vector<std::int64_t> codes = {10, 30, 40, 50, 80};
  std::vector<float> lc(static_cast<std::size_t>(w * h));
  std::map<std::int64_t, std::size_t> raster_counts;
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const std::int64_t k = codes[static_cast<std::size_t>((c / 3 + 2 * (r / 4) + c * r % 7) % 5)];
      lc[static_cast<std::size_t>(r * w + c)] = static_cast<float>(k);
      ++raster_counts[k];
    }
  }
  const double gt[6] = {-200.0, 10.0, 0.0, 300.0, 0.0, -10.0};
  const std::string ortho = "+proj=ortho +lat_0=" + std::to_string(kLat0_deg) +
                            " +lon_0=" + std::to_string(kLon0_deg) +
                            " +ellps=WGS84 +units=m +no_defs";
  write_tif(tmp("lc.tif"), w, h, lc, gt, ortho);
  ImportSpec spec = base_spec(tmp("flat.tif"));
  spec.datum = DatumChoice::kEllipsoid;
  spec.central_east_m = 400.0;
  spec.central_north_m = 600.0;
  spec.landcover = tmp("lc.tif");
  spec.classes.name = "test";
  spec.classes.material_by_class = {
      {10, "forest"}, {30, "grass"}, {40, "crops"}, {50, "urban"}, {80, "water"}};
  ImportReport report;
  const SceneDescription d = import_geodata(spec, report);
  EXPECT_EQ(report.cells_by_class, raster_counts);
  std::map<std::string, std::size_t> triangles;
  for (const ObjectDesc& o : d.objects) {
    if (o.lod_group < 0 || o.lod_level != 0)
      continue;
    for (std::uint16_t m : o.mesh.triangle_material)
      ++triangles[d.materials[m].name];
  }
  for (const auto& [code, name] : spec.classes.material_by_class)
    EXPECT_EQ(triangles[name], 2 * raster_counts[code]) << name;

  // An unknown class: one line naming it; with a fallback: counted.
  lc[5] = 99.0f;
  write_tif(tmp("lc99.tif"), w, h, lc, gt, ortho);
  spec.landcover = tmp("lc99.tif");
  try {
    (void)import_geodata(spec, report);
    ADD_FAILURE() << "unknown class accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("class 99 is not in the table"), std::string::npos)
        << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  spec.classes.fallback = "grass";
  (void)import_geodata(spec, report);
  EXPECT_EQ(report.unknown_class_cells, 1u);
}

std::string osm_node(int id, double lat, double lon, const std::string& tags = "") {
  char b[160];
  std::snprintf(b, sizeof b, R"( <node id="%d" lat="%.7f" lon="%.7f")", id, lat, lon);
  return std::string(b) + (tags.empty() ? "/>\n" : ">" + tags + "</node>\n");
}

// Buildings from height and from levels, a road draped on a ridge, broken ways counted.
TEST(Geodata, OsmBuildingsRoadsAndBrokenWays) {
  TestRaster ridge;
  const double m_per_deg_lon = 111320.0 * std::cos(radians(kLat0_deg));
  ridge.fill([&](double, double lo) {
    return 200.0 + std::max(0.0, 40.0 - 0.1 * std::abs((lo - kLon0_deg) * m_per_deg_lon));
  });
  write_tif(tmp("osm_ridge.tif"), ridge, "EPSG:4326");
  const double a = kLat0_deg, o = kLon0_deg, d = 0.0002;
  std::string x =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<osm version=\"0.6\" generator=\"test\">\n";
  // Two squares ~16 x 22 m.
  for (int k = 0; k < 2; ++k) {
    const double la = a + 0.002 * (k + 1), lo = o + 0.001;
    x += osm_node(10 * k + 1, la, lo) + osm_node(10 * k + 2, la, lo + d) +
         osm_node(10 * k + 3, la + d, lo + d) + osm_node(10 * k + 4, la + d, lo);
  }
  x += osm_node(31, a - 0.002, o + 0.001) + osm_node(32, a - 0.002, o + 0.0012) +
       osm_node(33, a - 0.0018, o + 0.0012);  // an unclosed building
  x += osm_node(41, a - 0.004, o - 0.004) + osm_node(42, a + 0.004, o + 0.004);  // road
  x +=
      R"( <way id="100"><nd ref="1"/><nd ref="2"/><nd ref="3"/><nd ref="4"/><nd ref="1"/><tag k="building" v="yes"/><tag k="height" v="20"/></way>
 <way id="101"><nd ref="11"/><nd ref="12"/><nd ref="13"/><nd ref="14"/><nd ref="11"/><tag k="building" v="yes"/><tag k="building:levels" v="6"/></way>
 <way id="102"><nd ref="31"/><nd ref="32"/><nd ref="33"/><tag k="building" v="yes"/></way>
 <way id="103"><nd ref="41"/><nd ref="42"/><tag k="highway" v="primary"/></way>
 <way id="104"><nd ref="41"/><nd ref="999"/><nd ref="42"/><tag k="highway" v="primary"/></way>
 <way id="105"><nd ref="41"/><tag k="highway" v="track"/></way>
</osm>
)";
  std::ofstream(tmp("test.osm")) << x;
  ImportSpec spec = base_spec(tmp("osm_ridge.tif"));
  spec.datum = DatumChoice::kEllipsoid;
  spec.osm = tmp("test.osm");
  ImportReport report;
  const SceneDescription scene = import_geodata(spec, report);
  EXPECT_EQ(report.osm_buildings, 2u);
  EXPECT_EQ(report.osm_buildings_height, 1u);
  EXPECT_EQ(report.osm_buildings_levels, 1u);
  EXPECT_EQ(report.osm_roads, 1u);
  EXPECT_EQ(report.osm_broken_ways, 3u);  // 104 (missing node), 105 (one node), 102 (not closed)
  std::map<std::string, double> tops;
  const wgs84::EnuFrame frame(scene.anchor);
  for (const ObjectDesc& obj : scene.objects) {
    if (obj.name.rfind("building_", 0) == 0) {
      float top = 0.0f;
      for (const glm::vec3 p : obj.mesh.positions_m)
        top = std::max(top, p.z);
      tops[obj.name] = static_cast<double>(top);
    }
    if (obj.name.rfind("road_", 0) == 0) {
      double worst = 0.0;
      for (const glm::vec3 p : obj.mesh.positions_m) {
        const wgs84::Geodetic g =
            frame.geodetic_from_enu({p.x, p.y, static_cast<double>(p.z) - spec.draped_offset_m});
        worst = std::max(worst, std::abs(g.height_m - ridge.bilinear(degrees(g.latitude_rad),
                                                                     degrees(g.longitude_rad))));
      }
      std::printf("road: worst |road - offset - DEM| = %.4f m over %zu vertices\n", worst,
                  obj.mesh.positions_m.size());
      EXPECT_LT(worst, 0.1);
    }
  }
  EXPECT_DOUBLE_EQ(tops["building_0"], 20.0);
  EXPECT_DOUBLE_EQ(tops["building_1"], 6 * spec.level_height_m);
}

TEST(Geodata, BadInputIsOneLineOrCounted) {
  auto expect_error = [](const ImportSpec& s, const std::string& part) {
    ImportReport r;
    try {
      (void)import_geodata(s, r);
      ADD_FAILURE() << "accepted; expected " << part;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  };
  TestRaster plane;
  plane.fill([](double la, double) { return 100.0 + 5000.0 * (la - kLat0_deg); });
  // No georeference.
  write_tif(tmp("nogeo.tif"), plane, "");
  expect_error(base_spec(tmp("nogeo.tif")), "no georeference");
  // Anchor outside the raster.
  write_tif(tmp("plane2.tif"), plane, "EPSG:4326");
  ImportSpec spec = base_spec(tmp("plane2.tif"));
  spec.anchor_latitude_rad = radians(kLat0_deg + 1.0);
  expect_error(spec, "is outside the raster");
  // The area past the raster's edge.
  spec = base_spec(tmp("plane2.tif"));
  spec.central_east_m = 5000.0;
  expect_error(spec, "is outside the raster: give a smaller area");
  // Over the memory limit: refused with the estimate before reading anything.
  spec = base_spec(tmp("missing.tif"));
  spec.max_memory_bytes = 1u << 20;
  expect_error(spec, "estimated");
  // Holes: filled from the neighbours (exact on a plane for one-pixel holes) and counted.
  TestRaster holed = plane;
  std::size_t holes = 0;
  for (int k = 0; k < 40; ++k) {
    holed.values[static_cast<std::size_t>((20 + k) * holed.n + 13 + 2 * k)] = -9999.0f;
    ++holes;
  }
  holed.values[static_cast<std::size_t>(60 * holed.n + 60)] = std::nanf("");
  ++holes;
  write_tif(tmp("holes.tif"), holed, "EPSG:4326", -9999.0);
  spec = base_spec(tmp("holes.tif"));
  spec.datum = DatumChoice::kEllipsoid;
  ImportReport report;
  (void)import_geodata(spec, report);
  EXPECT_EQ(report.dem_holes_filled, holes);
  expect_heights(plane, spec, 0.0, "plane with holes");
}

}  // namespace
}  // namespace radar_emu::scene::geodata
