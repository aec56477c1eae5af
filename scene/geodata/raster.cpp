#include "scene/geodata/raster.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <proj.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/units.hpp"

namespace radar_emu::scene::geodata {
namespace {

std::runtime_error fail(const std::filesystem::path& path, const std::string& what) {
  return std::runtime_error(path.string() + ": " + what);
}

struct DatasetCloser {
  void operator()(GDALDataset* d) const noexcept { GDALClose(d); }
};

}  // namespace

const char* vertical_datum_name(VerticalDatum d) noexcept {
  switch (d) {
    case VerticalDatum::kEllipsoid:
      return "WGS84 ellipsoid";
    case VerticalDatum::kEgm96:
      return "EGM96 geoid";
    default:
      return "unstated";
  }
}

struct GeoRaster::Gdal {
  std::unique_ptr<OGRCoordinateTransformation> crs_from_wgs84;  ///< null: the CRS is WGS84 lon/lat
  std::unique_ptr<OGRCoordinateTransformation> wgs84_from_crs;
};

GeoRaster::GeoRaster(const std::filesystem::path& path, std::string role, bool heights,
                     std::size_t max_pixels)
    : path_(path), role_(std::move(role)), gdal_(std::make_unique<Gdal>()) {
  GDALAllRegister();
  // The GeoTIFF driver drops a vertical CRS unless told to report the compound one.
  CPLSetThreadLocalConfigOption("GTIFF_REPORT_COMPD_CS", "YES");
  std::unique_ptr<GDALDataset, DatasetCloser> ds(
      GDALDataset::Open(path.string().c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  CPLSetThreadLocalConfigOption("GTIFF_REPORT_COMPD_CS", nullptr);
  if (!ds)
    throw fail(path, role_ + ": GDAL cannot open it as a raster (" + CPLGetLastErrorMsg() + ")");
  width_ = ds->GetRasterXSize();
  height_ = ds->GetRasterYSize();
  if (ds->GetRasterCount() < 1 || width_ < 2 || height_ < 2)
    throw fail(path, role_ + ": needs one band of at least 2 x 2 pixels");
  if (static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) > max_pixels)
    throw fail(path, role_ + ": " + std::to_string(width_) + " x " + std::to_string(height_) +
                         " pixels is over the limit of " + std::to_string(max_pixels));
  const OGRSpatialReference* srs = ds->GetSpatialRef();
  if (ds->GetGeoTransform(crs_from_pixel_) != CE_None || srs == nullptr || srs->IsEmpty())
    throw fail(path, role_ +
                         ": no georeference (the file has no geotransform or no coordinate "
                         "system; ground control points alone are not supported)");
  if (!GDALInvGeoTransform(crs_from_pixel_, pixel_from_crs_))
    throw fail(path, role_ + ": the geotransform cannot be inverted");

  // Vertical datum as stated.
  if (srs->IsCompound() || srs->IsVertical()) {
    const char* vname = srs->GetAttrValue(srs->IsCompound() ? "COMPD_CS|VERT_CS" : "VERT_CS");
    const char* vcode = srs->GetAuthorityCode(srs->IsCompound() ? "COMPD_CS|VERT_CS" : "VERT_CS");
    vertical_name_ = vname ? vname : "unnamed vertical CRS";
    const std::string code = vcode ? vcode : "";
    if (code == "5773" || vertical_name_.find("EGM96") != std::string::npos)
      vertical_ = VerticalDatum::kEgm96;
    else if (vertical_name_.find("ellipsoid") != std::string::npos)
      vertical_ = VerticalDatum::kEllipsoid;
    else
      throw fail(path, role_ + ": vertical CRS \"" + vertical_name_ + "\" (EPSG " +
                           (code.empty() ? "?" : code) +
                           ") is not supported: EGM96 (EPSG 5773) or the ellipsoid");
  } else if (srs->IsGeographic() && srs->GetAxesCount() == 3) {
    vertical_ = VerticalDatum::kEllipsoid;
    vertical_name_ = "ellipsoidal height";
  }

  // Horizontal CRS and WGS84 lon/lat.
  OGRSpatialReference horizontal(*srs);
  if (horizontal.IsCompound())
    horizontal.StripVertical();
  horizontal.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  if (!(horizontal.IsGeographic() && horizontal.IsSameGeogCS(&wgs84))) {
    gdal_->crs_from_wgs84.reset(OGRCreateCoordinateTransformation(&wgs84, &horizontal));
    gdal_->wgs84_from_crs.reset(OGRCreateCoordinateTransformation(&horizontal, &wgs84));
    if (!gdal_->crs_from_wgs84 || !gdal_->wgs84_from_crs)
      throw fail(path, role_ + ": no transformation between its CRS and WGS84 (" +
                           CPLGetLastErrorMsg() + ")");
  }

  GDALRasterBand* band = ds->GetRasterBand(1);
  double scale = 1.0;
  if (heights) {
    const std::string unit = band->GetUnitType() ? band->GetUnitType() : "";
    if (unit == "ft" || unit == "foot" || unit == "feet")
      scale = 0.3048;
    else if (unit == "US survey foot")
      scale = 1200.0 / 3937.0;
    else if (!(unit.empty() || unit == "m" || unit == "metre" || unit == "meter" ||
               unit == "metres" || unit == "meters"))
      throw fail(path, role_ + ": height unit \"" + unit + "\" is not supported (m or ft)");
  }
  values_.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_));
  if (band->RasterIO(GF_Read, 0, 0, width_, height_, values_.data(), width_, height_, GDT_Float32,
                     0, 0) != CE_None)
    throw fail(path, role_ + ": read failed (" + std::string(CPLGetLastErrorMsg()) + ")");
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  const double band_scale = band->GetScale(), band_offset = band->GetOffset();
  for (std::size_t k = 0; k < values_.size(); ++k) {
    const float v = values_[k];
    const bool hole =
        !std::isfinite(v) ||
        (has_nodata && static_cast<double>(v) == static_cast<double>(static_cast<float>(nodata)));
    if (hole) {
      if (nodata_.empty())
        nodata_.assign(values_.size(), 0);
      nodata_[k] = 1;
      ++nodata_count_;
      continue;
    }
    values_[k] = static_cast<float>((static_cast<double>(v) * band_scale + band_offset) * scale);
  }

  // Ground spacing at the centre: the pixel's two sides mapped to WGS84, then to metres.
  double lat0 = 0, lon0 = 0, lat1 = 0, lon1 = 0, lat2 = 0, lon2 = 0;
  const double cc = width_ / 2.0, rc = height_ / 2.0;
  geodetic_from_pixel(cc, rc, lat0, lon0);
  geodetic_from_pixel(cc + 1.0, rc, lat1, lon1);
  geodetic_from_pixel(cc, rc + 1.0, lat2, lon2);
  constexpr double kR = 6371000.0;
  auto dist = [&](double la, double lo) {
    return kR * std::hypot(la - lat0, (lo - lon0) * std::cos(lat0));
  };
  spacing_m_ = std::sqrt(dist(lat1, lon1) * dist(lat2, lon2));
}

GeoRaster::~GeoRaster() = default;
GeoRaster::GeoRaster(GeoRaster&&) noexcept = default;
GeoRaster& GeoRaster::operator=(GeoRaster&&) noexcept = default;

void GeoRaster::pixels_from_geodetic(std::span<const double> latitude_rad,
                                     std::span<const double> longitude_rad, std::span<double> col,
                                     std::span<double> row) const {
  const std::size_t n = latitude_rad.size();
  for (std::size_t i = 0; i < n; ++i) {
    col[i] = common::degrees(longitude_rad[i]);  // x = lon
    row[i] = common::degrees(latitude_rad[i]);   // y = lat
  }
  if (gdal_->crs_from_wgs84) {
    std::vector<int> ok(n, 0);
    gdal_->crs_from_wgs84->Transform(static_cast<int>(n), col.data(), row.data(), nullptr,
                                     ok.data());
    for (std::size_t i = 0; i < n; ++i) {
      if (!ok[i])
        col[i] = row[i] = std::numeric_limits<double>::quiet_NaN();
    }
  }
  const double* g = pixel_from_crs_;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = col[i], y = row[i];
    col[i] = g[0] + g[1] * x + g[2] * y;
    row[i] = g[3] + g[4] * x + g[5] * y;
  }
}

void GeoRaster::geodetic_from_pixel(double col, double row, double& latitude_rad,
                                    double& longitude_rad) const {
  const double* g = crs_from_pixel_;
  double x = g[0] + g[1] * col + g[2] * row;
  double y = g[3] + g[4] * col + g[5] * row;
  if (gdal_->wgs84_from_crs)
    gdal_->wgs84_from_crs->Transform(1, &x, &y);
  latitude_rad = common::radians(y);
  longitude_rad = common::radians(x);
}

bool GeoRaster::contains(double col, double row) const noexcept {
  return col >= 0.0 && row >= 0.0 && col <= width_ && row <= height_;  // NaN: false
}

double GeoRaster::bilinear(double col, double row) const noexcept {
  const double u = std::clamp(col - 0.5, 0.0, width_ - 1.0);
  const double v = std::clamp(row - 0.5, 0.0, height_ - 1.0);
  const int c0 = std::min(static_cast<int>(u), width_ - 2);
  const int r0 = std::min(static_cast<int>(v), height_ - 2);
  const double fu = u - c0, fv = v - r0;
  return (1 - fv) * ((1 - fu) * at(c0, r0) + fu * at(c0 + 1, r0)) +
         fv * ((1 - fu) * at(c0, r0 + 1) + fu * at(c0 + 1, r0 + 1));
}

double GeoRaster::nearest(double col, double row) const noexcept {
  const int c = std::clamp(static_cast<int>(std::floor(col)), 0, width_ - 1);
  const int r = std::clamp(static_cast<int>(std::floor(row)), 0, height_ - 1);
  return at(c, r);
}

std::size_t GeoRaster::fill_holes() {
  if (nodata_count_ == 0)
    return 0;
  if (nodata_count_ == values_.size())
    throw fail(path_, role_ + ": every pixel is no-data");
  std::vector<std::uint8_t> hole = nodata_;
  std::size_t left = nodata_count_;
  std::vector<std::size_t> now;
  while (left > 0) {
    now.clear();
    for (int r = 0; r < height_; ++r) {
      for (int c = 0; c < width_; ++c) {
        const std::size_t k = static_cast<std::size_t>(r) * static_cast<std::size_t>(width_) +
                              static_cast<std::size_t>(c);
        if (!hole[k])
          continue;
        double sum = 0.0;
        int n = 0;
        const int dc[4] = {-1, 1, 0, 0}, dr[4] = {0, 0, -1, 1};
        for (int d = 0; d < 4; ++d) {
          const int cc = c + dc[d], rr = r + dr[d];
          if (cc < 0 || rr < 0 || cc >= width_ || rr >= height_)
            continue;
          const std::size_t kk = static_cast<std::size_t>(rr) * static_cast<std::size_t>(width_) +
                                 static_cast<std::size_t>(cc);
          if (!hole[kk]) {
            sum += static_cast<double>(values_[kk]);
            ++n;
          }
        }
        if (n > 0) {
          values_[k] = static_cast<float>(sum / n);
          now.push_back(k);
        }
      }
    }
    for (std::size_t k : now)
      hole[k] = 0;  // filled this pass: valid for the next
    left -= now.size();
  }
  return nodata_count_;
}

struct Egm96::Proj {
  PJ_CONTEXT* ctx = nullptr;
  PJ* shift = nullptr;
  ~Proj() {
    if (shift)
      proj_destroy(shift);
    if (ctx)
      proj_context_destroy(ctx);
  }
};

Egm96::Egm96() : proj_(std::make_unique<Proj>()) {
  proj_->ctx = proj_context_create();
  // Forward: z + 1 x grid value, so an EGM96 height H becomes h = H + N (N from the grid).
  proj_->shift = proj_create(proj_->ctx, "+proj=vgridshift +grids=egm96_15.gtx +multiplier=1");
  if (proj_->shift == nullptr) {
    const int err = proj_context_errno(proj_->ctx);
    throw std::runtime_error(
        std::string("EGM96 geoid: PROJ cannot use the grid egm96_15.gtx (Debian package "
                    "proj-data, in /usr/share/proj): ") +
        proj_context_errno_string(proj_->ctx, err));
  }
}

Egm96::~Egm96() = default;

double Egm96::undulation_m(double latitude_rad, double longitude_rad) const {
  PJ_COORD c = proj_coord(longitude_rad, latitude_rad, 0.0, 0.0);
  const PJ_COORD r = proj_trans(proj_->shift, PJ_FWD, c);
  if (!std::isfinite(r.xyz.z) || r.xyz.z == HUGE_VAL)
    throw std::runtime_error("EGM96 geoid: no undulation at latitude " +
                             std::to_string(common::degrees(latitude_rad)) + " deg, longitude " +
                             std::to_string(common::degrees(longitude_rad)) + " deg");
  return r.xyz.z;
}

}  // namespace radar_emu::scene::geodata
