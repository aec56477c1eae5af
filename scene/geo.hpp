#pragma once
// WGS84 geodesy: geodetic <-> ECEF <-> local East-North-Up (NIMA TR8350.2, 3rd ed., 2000,
// table 3.1 for the ellipsoid; ECEF/ENU rotations as in e.g. Farrell, Aided Navigation, 2008).

#include <glm/glm.hpp>

#include "scene/types.hpp"

namespace radar_emu::scene::wgs84 {

inline constexpr double kSemiMajorAxis_m = 6378137.0;
inline constexpr double kInverseFlattening = 298.257223563;
inline constexpr double kFlattening = 1.0 / kInverseFlattening;
inline constexpr double kFirstEccentricitySquared = kFlattening * (2.0 - kFlattening);

struct Geodetic {
  double latitude_rad = 0.0;
  double longitude_rad = 0.0;
  double height_m = 0.0;  ///< above the ellipsoid
};

[[nodiscard]] glm::dvec3 ecef_from_geodetic(const Geodetic& g) noexcept;
/// Exact to well below 1 mm for heights -10 km .. +100 km.
[[nodiscard]] Geodetic geodetic_from_ecef(const glm::dvec3& ecef_m) noexcept;

/// Local ENU frame anchored at a geodetic point.
class EnuFrame {
 public:
  explicit EnuFrame(const Geodetic& anchor) noexcept;
  explicit EnuFrame(const GeoAnchor& anchor) noexcept;
  [[nodiscard]] glm::dvec3 enu_from_geodetic(const Geodetic& g) const noexcept;
  [[nodiscard]] Geodetic geodetic_from_enu(const glm::dvec3& enu_m) const noexcept;
  [[nodiscard]] glm::dvec3 enu_from_ecef(const glm::dvec3& ecef_m) const noexcept;
  [[nodiscard]] glm::dvec3 ecef_from_enu(const glm::dvec3& enu_m) const noexcept;

 private:
  glm::dvec3 origin_ecef_m_{0.0};
  glm::dmat3 ecef_from_enu_{1.0};  ///< columns: east, north, up in ECEF
};

}  // namespace radar_emu::scene::wgs84
