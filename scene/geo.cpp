#include "scene/geo.hpp"

#include <cmath>

namespace radar_emu::scene::wgs84 {

glm::dvec3 ecef_from_geodetic(const Geodetic& g) noexcept {
  // Prime vertical radius of curvature N = a / sqrt(1 - e^2 sin^2 phi) (TR8350.2 eq. 4-15).
  const double s = std::sin(g.latitude_rad), c = std::cos(g.latitude_rad);
  const double n = kSemiMajorAxis_m / std::sqrt(1.0 - kFirstEccentricitySquared * s * s);
  return {(n + g.height_m) * c * std::cos(g.longitude_rad),
          (n + g.height_m) * c * std::sin(g.longitude_rad),
          (n * (1.0 - kFirstEccentricitySquared) + g.height_m) * s};
}

Geodetic geodetic_from_ecef(const glm::dvec3& e) noexcept {
  // Fixed-point iteration on latitude (Hofmann-Wellenhof et al., GNSS, 2008, sec. 10.2.1):
  // converges to below 1e-12 rad in a few steps for heights well below the Earth's radius.
  Geodetic g;
  const double p = std::hypot(e.x, e.y);
  g.longitude_rad = std::atan2(e.y, e.x);
  double lat = std::atan2(e.z, p * (1.0 - kFirstEccentricitySquared));
  double h = 0.0;
  for (int i = 0; i < 10; ++i) {
    const double s = std::sin(lat);
    const double n = kSemiMajorAxis_m / std::sqrt(1.0 - kFirstEccentricitySquared * s * s);
    const double c = std::cos(lat);
    h = std::abs(c) > 1e-12 ? p / c - n : std::abs(e.z) - n * (1.0 - kFirstEccentricitySquared);
    const double next = std::atan2(e.z, p * (1.0 - kFirstEccentricitySquared * n / (n + h)));
    if (std::abs(next - lat) < 1e-14) {
      lat = next;
      break;
    }
    lat = next;
  }
  const double s = std::sin(lat), c = std::cos(lat);
  const double n = kSemiMajorAxis_m / std::sqrt(1.0 - kFirstEccentricitySquared * s * s);
  // Height from the converged latitude, robust near the poles (projection onto the normal).
  h = p * c + e.z * s - kSemiMajorAxis_m * kSemiMajorAxis_m / n;
  g.latitude_rad = lat;
  g.height_m = h;
  return g;
}

EnuFrame::EnuFrame(const Geodetic& anchor) noexcept : origin_ecef_m_(ecef_from_geodetic(anchor)) {
  const double sl = std::sin(anchor.latitude_rad), cl = std::cos(anchor.latitude_rad);
  const double so = std::sin(anchor.longitude_rad), co = std::cos(anchor.longitude_rad);
  const glm::dvec3 east(-so, co, 0.0);
  const glm::dvec3 north(-sl * co, -sl * so, cl);
  const glm::dvec3 up(cl * co, cl * so, sl);
  ecef_from_enu_ = glm::dmat3(east, north, up);
}

EnuFrame::EnuFrame(const GeoAnchor& a) noexcept
    : EnuFrame(Geodetic{a.latitude_rad, a.longitude_rad, a.height_m}) {}

glm::dvec3 EnuFrame::enu_from_ecef(const glm::dvec3& ecef_m) const noexcept {
  return glm::transpose(ecef_from_enu_) * (ecef_m - origin_ecef_m_);
}

glm::dvec3 EnuFrame::ecef_from_enu(const glm::dvec3& enu_m) const noexcept {
  return origin_ecef_m_ + ecef_from_enu_ * enu_m;
}

glm::dvec3 EnuFrame::enu_from_geodetic(const Geodetic& g) const noexcept {
  return enu_from_ecef(ecef_from_geodetic(g));
}

Geodetic EnuFrame::geodetic_from_enu(const glm::dvec3& enu_m) const noexcept {
  return geodetic_from_ecef(ecef_from_enu(enu_m));
}

}  // namespace radar_emu::scene::wgs84
