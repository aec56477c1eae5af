// A point's latitude / longitude -> scene -> SAR image pixel and back (issue 31), with GDAL as the
// independent reader of the SAR product:
//   1. the test writes a GeoTIFF DEM in UTM 31N (a tilted plane, closed form) and a `radar-emu
//      sar` case whose [scene.import] imports it around an anchor (datum "ellipsoid": the DEM's
//      heights are ellipsoidal), with trihedrals at three chosen latitude / longitude points;
//   2. latitude / longitude -> scene: the import's frame as scene/geodata/import.hpp defines it
//      (ENU around the anchor, at the ground's height there), the height from the plane at the
//      point's UTM coordinates (PROJ through GDAL's OGR);
//   3. the SAR tool images the scene (no clutter, focused on the DEM) and writes image.tif;
//   4. GDAL opens image.tif: its coordinate system and geotransform map each point's latitude /
//      longitude to a pixel, where the trihedral's peak must lie within one pixel; the peak's
//      pixel maps back to latitude / longitude within one pixel spacing of the point.
// The terrain is tilted so that an image focused on the flat z = 0 plane instead of the DEM
// would put the points several pixels off (checked too), and lies on a 3000 m plateau, where a
// transverse Mercator of scale 1 would stretch the image by h0 / R (4.7e-4): every pixel centre
// GDAL maps to latitude / longitude must also lie within 1 cm of where the import's frame puts
// that pixel's ground (its ENU x, y from the product's coordinates and the DEM band's height).

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "scene/geo.hpp"
#include "tools/sar.hpp"

namespace radar_emu {
namespace {

namespace fs = std::filesystem;
using common::radians;

constexpr double kLat0_deg = 43.45, kLon0_deg = 1.30;  // the anchor
constexpr double kIncidence_deg = 50.0;
constexpr double kSpacing_m = 2.0;  // image pixel, azimuth and ground range
// The DEM: a plane in UTM 31N metres around the anchor's easting / northing (e0, n0).
constexpr double kBase_m = 3000.0, kSlopeEast = 0.02, kSlopeNorth = 0.1;

struct Utm {
  OGRSpatialReference wgs84, utm;
  std::unique_ptr<OGRCoordinateTransformation> to_utm;
  double e0 = 0.0, n0 = 0.0;
  Utm() {
    wgs84.importFromEPSG(4326);
    utm.importFromEPSG(32631);
    wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // x = longitude
    utm.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    to_utm.reset(OGRCreateCoordinateTransformation(&wgs84, &utm));
    const auto [e, n] = project(kLat0_deg, kLon0_deg);
    e0 = e;
    n0 = n;
  }
  [[nodiscard]] std::array<double, 2> project(double lat_deg, double lon_deg) const {
    double x = lon_deg, y = lat_deg;
    EXPECT_TRUE(to_utm->Transform(1, &x, &y));
    return {x, y};
  }
  // The plane's (ellipsoidal) height at a latitude / longitude.
  [[nodiscard]] double height_m(double lat_deg, double lon_deg) const {
    const auto [e, n] = project(lat_deg, lon_deg);
    return kBase_m + kSlopeEast * (e - e0) + kSlopeNorth * (n - n0);
  }
};

void write_dem(const fs::path& path, const Utm& u) {
  constexpr double step = 10.0, half = 1500.0;
  constexpr int n = static_cast<int>(2 * half / step);
  std::vector<float> z(static_cast<std::size_t>(n * n));
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const double de = -half + step * (c + 0.5), dn = half - step * (r + 0.5);
      z[static_cast<std::size_t>(r * n + c)] =
          static_cast<float>(kBase_m + kSlopeEast * de + kSlopeNorth * dn);
    }
  GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(
      path.string().c_str(), n, n, 1, GDT_Float32, nullptr);
  ASSERT_NE(ds, nullptr);
  double gt[6] = {u.e0 - half, step, 0.0, u.n0 + half, 0.0, -step};
  ds->SetGeoTransform(gt);
  ds->SetSpatialRef(&u.utm);
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, n, n, z.data(), n, n, GDT_Float32, 0, 0),
            CE_None);
  GDALClose(ds);
}

TEST(SarGeoreference, LatLonToSceneToSarPixelAndBackWithinOnePixel) {
  GDALAllRegister();
  const fs::path dir = fs::temp_directory_path() / "radar_emu_sar_georeference";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Utm utm;
  write_dem(dir / "dem.tif", utm);

  // Three points inside the image (about 200 m along track, east-west, and 300 m of ground range
  // south of the track around the anchor), in degrees.
  const std::array<std::array<double, 2>, 3> points{{{kLat0_deg + 0.0010, kLon0_deg - 0.0008},
                                                     {kLat0_deg - 0.0005, kLon0_deg + 0.0005},
                                                     {kLat0_deg + 0.0003, kLon0_deg + 0.0009}}};
  // Latitude / longitude -> scene: ENU around the anchor at the ground's ellipsoidal height
  // there (the plane's value at the anchor), as scene/geodata/import.hpp defines the frame.
  const scene::wgs84::EnuFrame frame(
      scene::wgs84::Geodetic{radians(kLat0_deg), radians(kLon0_deg), kBase_m});
  std::vector<glm::dvec3> enu;
  std::string targets;
  for (const auto& [lat, lon] : points) {
    enu.push_back(frame.enu_from_geodetic({radians(lat), radians(lon), utm.height_m(lat, lon)}));
    char line[200];
    std::snprintf(line, sizeof line,
                  "[[scene.target]]\nkind = \"trihedral-square\"\na_m = 1.0\n"
                  "position_m = [%.6f, %.6f, %.6f]\n",
                  enu.back().x, enu.back().y, enu.back().z);
    targets += line;
  }
  std::ofstream(dir / "case.toml")
      << "[radar]\ncarrier_hz = 10e9\nbandwidth_hz = 50e6\npulse_duration_s = 0.2e-6\n"
         "prf_hz = 200.0\ntransmit_power_w = 100.0\npeak_gain_db = 30.0\n"
         "[platform]\naltitude_m = 600.0\nspeed_mps = 50.0\nheading_deg = 90.0\n"
         "look = \"right\"\n"
         "[antenna]\nincidence_deg = "
      << kIncidence_deg
      << "\nazimuth_beamwidth_deg = 1.0\nelevation_beamwidth_deg = 20.0\n"
         "[processing]\ngates = 96\nsynthetic_beamwidth_deg = 0.123\nupsample = 4\n"
         "image_width_m = 200.0\nazimuth_spacing_m = "
      << kSpacing_m << "\nground_range_spacing_m = " << kSpacing_m
      << "\n[scene]\nclutter = false\ntarget_ray_spacing_m = 0.1\nmax_bounces = 3\n"
         "[scene.import]\ndem = \""
      << (dir / "dem.tif").string() << "\"\nanchor_deg = [" << kLat0_deg << ", " << kLon0_deg
      << "]\ndatum = \"ellipsoid\"\ncentral_m = [1600.0, 1600.0]\ncell_m = 10.0\n"
         "tile_cells = 32\n"
      << targets;
  tools::SarToolOptions o;
  o.config = (dir / "case.toml").string();
  o.out_dir = (dir / "out").string();
  o.no_raw = true;
  o.quiet = true;
  ASSERT_EQ(tools::run_sar_tool(o), 0);

  // GDAL reads the product: its coordinate system, geotransform and complex band.
  GDALDataset* ds = GDALDataset::Open((dir / "out" / "image.tif").string().c_str(),
                                      GDAL_OF_RASTER | GDAL_OF_READONLY);
  ASSERT_NE(ds, nullptr);
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  double gt[6], inv[6];
  ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
  ASSERT_TRUE(GDALInvGeoTransform(gt, inv));
  OGRSpatialReference image_srs(*ds->GetSpatialRef());
  image_srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  const std::unique_ptr<OGRCoordinateTransformation> to_image(
      OGRCreateCoordinateTransformation(&wgs84, &image_srs));
  const std::unique_ptr<OGRCoordinateTransformation> to_wgs84(
      OGRCreateCoordinateTransformation(&image_srs, &wgs84));
  ASSERT_TRUE(to_image && to_wgs84);
  std::vector<std::complex<float>> px(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  ASSERT_EQ(
      ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, w, h, px.data(), w, h, GDT_CFloat32, 0, 0),
      CE_None);
  std::vector<float> dem_m(px.size());
  ASSERT_EQ(ds->GetRasterCount(), 3);
  ASSERT_EQ(
      ds->GetRasterBand(3)->RasterIO(GF_Read, 0, 0, w, h, dem_m.data(), w, h, GDT_Float32, 0, 0),
      CE_None);
  GDALClose(ds);

  // Every 8th pixel centre: GDAL's latitude / longitude against the import's frame at that
  // pixel's ground (product coordinates are ENU x, y; band 3 the DEM height, world up).
  double worst_grid_m = 0.0;
  for (int r = 0; r < h; r += 8)
    for (int c = 0; c < w; c += 8) {
      const double pc = c + 0.5, pr = r + 0.5;
      const glm::dvec3 ground{gt[0] + gt[1] * pc + gt[2] * pr, gt[3] + gt[4] * pc + gt[5] * pr,
                              dem_m[static_cast<std::size_t>(r * w + c)]};
      double lon = ground.x, lat = ground.y;
      ASSERT_TRUE(to_wgs84->Transform(1, &lon, &lat));
      const scene::wgs84::Geodetic g = frame.geodetic_from_enu(ground);
      const glm::dvec3 back = frame.enu_from_geodetic({radians(lat), radians(lon), g.height_m});
      worst_grid_m = std::max(worst_grid_m, std::hypot(back.x - ground.x, back.y - ground.y));
    }
  std::printf("pixel grid: GDAL's latitude / longitude within %.4f m of the scene's frame\n",
              worst_grid_m);
  EXPECT_LT(worst_grid_m, 0.01);

  auto amp = [&](int c, int r) {
    return std::abs(px[static_cast<std::size_t>(r) * static_cast<std::size_t>(w) +
                       static_cast<std::size_t>(c)]);
  };

  double worst_px = 0.0, worst_back_m = 0.0, largest_flat_px = 0.0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const auto [lat, lon] = points[k];
    // Latitude / longitude -> pixel (pixel centres at +0.5), through the product's own CRS.
    double x = lon, y = lat;
    ASSERT_TRUE(to_image->Transform(1, &x, &y));
    const double col = inv[0] + inv[1] * x + inv[2] * y;
    const double row = inv[3] + inv[4] * x + inv[5] * y;
    ASSERT_TRUE(col > 5 && col < w - 5 && row > 5 && row < h - 5)
        << "point " << k << " at pixel " << col << ", " << row << " of " << w << " x " << h;
    // The trihedral's peak near there (8 pixels around), refined by a parabola through the
    // amplitude's three samples on each axis.
    int pc = 0, pr = 0;
    float best = -1.0f;
    for (int r = static_cast<int>(row) - 8; r <= static_cast<int>(row) + 8; ++r)
      for (int c = static_cast<int>(col) - 8; c <= static_cast<int>(col) + 8; ++c)
        if (r > 0 && r < h - 1 && c > 0 && c < w - 1 && amp(c, r) > best) {
          best = amp(c, r);
          pc = c;
          pr = r;
        }
    auto vertex = [](double a, double b, double c) {
      const double d = a - 2.0 * b + c;
      return d < 0.0 ? 0.5 * (a - c) / d : 0.0;
    };
    const double peak_col = pc + 0.5 + vertex(amp(pc - 1, pr), amp(pc, pr), amp(pc + 1, pr));
    const double peak_row = pr + 0.5 + vertex(amp(pc, pr - 1), amp(pc, pr), amp(pc, pr + 1));
    const double off_px = std::hypot(peak_col - col, peak_row - row);
    // ... and back: the peak's pixel -> latitude / longitude, distance in metres (local
    // spherical scale: under 0.5 % off, far below the 2 m tolerance).
    double bx = gt[0] + gt[1] * peak_col + gt[2] * peak_row;
    double by = gt[3] + gt[4] * peak_col + gt[5] * peak_row;
    ASSERT_TRUE(to_wgs84->Transform(1, &bx, &by));
    const double back_m =
        std::hypot(111132.0 * (by - lat), 111320.0 * std::cos(radians(lat)) * (bx - lon));
    // Where a flat z = 0 focus would have put it: the height over the plane, in ground range.
    const double flat_px = std::abs(enu[k].z) / std::tan(radians(kIncidence_deg)) / kSpacing_m;
    std::printf(
        "point %zu (%.4f, %.4f deg; ENU %.1f, %.1f, %.2f m): expected pixel (%.2f, %.2f), peak "
        "(%.2f, %.2f): %.3f pixel; back %.3f m; flat focus would be %.1f pixels off\n",
        k, lat, lon, enu[k].x, enu[k].y, enu[k].z, col, row, peak_col, peak_row, off_px, back_m,
        flat_px);
    worst_px = std::max(worst_px, off_px);
    worst_back_m = std::max(worst_back_m, back_m);
    largest_flat_px = std::max(largest_flat_px, flat_px);
  }
  EXPECT_LT(worst_px, 1.0);
  EXPECT_LT(worst_back_m, kSpacing_m);
  // The test sees the DEM: ignoring it would have missed by more than the tolerance.
  EXPECT_GT(largest_flat_px, 3.0);
}

}  // namespace
}  // namespace radar_emu
