#pragma once
// Georeferenced rasters (GDAL) and the EGM96 geoid (PROJ), for the geodata import
// (scene/geodata/import.hpp). GDAL and PROJ stay inside scene/geodata/*.cpp: this header shows
// only our own types.
//
// Conventions: latitude / longitude in radians (WGS84); a raster's pixel (col, row) covers
// [col, col + 1) x [row, row + 1) in pixel coordinates, its value sits at the pixel centre
// (col + 0.5, row + 0.5) (GDAL's "pixel is area"); bilinear sampling interpolates between centres
// and holds the edge value over the outer half pixel.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace radar_emu::scene::geodata {

/// The vertical datum of a raster's values.
enum class VerticalDatum : std::uint8_t {
  kUnstated,   ///< the file states none (the caller decides; see ImportSpec::vertical_datum)
  kEllipsoid,  ///< heights above the WGS84 ellipsoid
  kEgm96,      ///< heights above the EGM96 geoid (EPSG:5773, "EGM96 height")
};
[[nodiscard]] const char* vertical_datum_name(VerticalDatum d) noexcept;

/// One band of a georeferenced raster, read whole into memory at construction. Setup only.
class GeoRaster {
 public:
  /// Opens `path` (any GDAL raster: GeoTIFF, DTED, ...) and reads band 1. `role` names the raster
  /// in messages ("dem", "landcover"). Throws std::runtime_error "PATH: what" when GDAL cannot
  /// open it, when it has no georeference (no geotransform or no coordinate system), when it is
  /// larger than `max_pixels`, or when its values are in a unit other than metres (DEMs:
  /// `heights` true; "ft" / "US survey foot" are converted).
  GeoRaster(const std::filesystem::path& path, std::string role, bool heights,
            std::size_t max_pixels = 400'000'000);
  ~GeoRaster();
  GeoRaster(GeoRaster&&) noexcept;
  GeoRaster& operator=(GeoRaster&&) noexcept;
  GeoRaster(const GeoRaster&) = delete;
  GeoRaster& operator=(const GeoRaster&) = delete;

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  /// The vertical datum the file states (GeoTIFF vertical keys, a compound CRS).
  [[nodiscard]] VerticalDatum stated_vertical_datum() const noexcept { return vertical_; }
  /// The name of the stated vertical CRS ("" when none).
  [[nodiscard]] const std::string& vertical_crs_name() const noexcept { return vertical_name_; }
  /// Approximate ground spacing of a pixel [m] (the geometric mean of its two sides, at the
  /// raster's centre).
  [[nodiscard]] double spacing_m() const noexcept { return spacing_m_; }

  /// Continuous pixel coordinates of WGS84 points (radians), in place of nothing: writes
  /// col[i], row[i] (NaN where the transformation fails). Spans of equal length.
  void pixels_from_geodetic(std::span<const double> latitude_rad,
                            std::span<const double> longitude_rad, std::span<double> col,
                            std::span<double> row) const;
  /// WGS84 latitude / longitude [rad] of continuous pixel coordinates (the inverse).
  void geodetic_from_pixel(double col, double row, double& latitude_rad,
                           double& longitude_rad) const;
  /// Whether the continuous pixel coordinates lie on the raster ([0, width] x [0, height]).
  [[nodiscard]] bool contains(double col, double row) const noexcept;
  /// Bilinear value between pixel centres (edge values held over the outer half pixel); the
  /// caller checks contains() first (outside: the nearest edge value).
  [[nodiscard]] double bilinear(double col, double row) const noexcept;
  /// The pixel under (col, row) (clamped to the raster).
  [[nodiscard]] double nearest(double col, double row) const noexcept;
  /// Value of pixel (c, r), 0 <= c < width, 0 <= r < height (after hole filling).
  [[nodiscard]] double at(int c, int r) const noexcept {
    return static_cast<double>(
        values_[static_cast<std::size_t>(r) * static_cast<std::size_t>(width_) +
                static_cast<std::size_t>(c)]);
  }
  /// Whether pixel (c, r) was no-data in the file.
  [[nodiscard]] bool was_nodata(int c, int r) const noexcept {
    return !nodata_.empty() &&
           nodata_[static_cast<std::size_t>(r) * static_cast<std::size_t>(width_) +
                   static_cast<std::size_t>(c)] != 0;
  }
  /// No-data pixels in the file (before fill_holes()).
  [[nodiscard]] std::size_t nodata_count() const noexcept { return nodata_count_; }
  /// Fills every no-data pixel with the mean of its valid 4-neighbours, pass after pass, until
  /// none is left (a hole of width w takes about w / 2 passes). Returns the number filled.
  /// Throws when the raster has no valid pixel at all.
  std::size_t fill_holes();

 private:
  struct Gdal;  // the coordinate transformations (GDAL / OGR types)
  std::filesystem::path path_;
  std::string role_;
  int width_ = 0, height_ = 0;
  std::vector<float> values_;
  std::vector<std::uint8_t> nodata_;  ///< 1 where the file had no data (empty when none)
  std::size_t nodata_count_ = 0;
  double pixel_from_crs_[6]{};  ///< inverse geotransform
  double crs_from_pixel_[6]{};  ///< geotransform
  VerticalDatum vertical_ = VerticalDatum::kUnstated;
  std::string vertical_name_;
  double spacing_m_ = 0.0;
  std::unique_ptr<Gdal> gdal_;
};

/// EGM96 geoid undulation N (geoid above the WGS84 ellipsoid) through PROJ's vertical grid
/// shift over Debian proj-data's egm96_15.gtx (the 15-minute grid, bilinear): h = H + N.
/// Throws std::runtime_error naming the grid when PROJ cannot find it. Setup only.
class Egm96 {
 public:
  Egm96();
  ~Egm96();
  Egm96(const Egm96&) = delete;
  Egm96& operator=(const Egm96&) = delete;
  /// N [m] at a WGS84 point [rad].
  [[nodiscard]] double undulation_m(double latitude_rad, double longitude_rad) const;

 private:
  struct Proj;
  std::unique_ptr<Proj> proj_;
};

}  // namespace radar_emu::scene::geodata
