#include "radar/propagation/path.hpp"

#include <cmath>
#include <stdexcept>

namespace radar_emu::radar {

PathAttenuation::PathAttenuation(double carrier_hz, double tilt_rad,
                                 std::span<const MediumSpec> media) {
  db_per_m_.reserve(media.size());
  for (const MediumSpec& m : media) {
    try {
      double db_per_km = gaseous_specific_attenuation(carrier_hz, m.atmosphere).total_db_per_km();
      if (m.rain_mm_per_h > 0.0)
        db_per_km +=
            rain_specific_attenuation_db_per_km(carrier_hz, m.rain_mm_per_h, 0.0, tilt_rad);
      if (m.liquid_water_gm3 > 0.0) {
        db_per_km += cloud_fog_specific_attenuation_db_per_km(carrier_hz, m.liquid_water_gm3,
                                                              m.atmosphere.temperature_k);
      }
      db_per_m_.push_back(db_per_km * 1e-3);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("medium '" + m.name + "': " + e.what());
    }
  }
}

double PathAttenuation::specific_db_per_m(std::uint32_t medium) const noexcept {
  return medium < db_per_m_.size() ? db_per_m_[medium] : 0.0;
}

double PathAttenuation::two_way_loss_db(std::span<const PathSegment> segments,
                                        std::uint64_t* rejected) const noexcept {
  double one_way = 0.0;
  for (const PathSegment& s : segments) {
    if (s.medium >= db_per_m_.size() || !(s.length_m >= 0.0) || !std::isfinite(s.length_m)) {
      if (rejected != nullptr)
        ++*rejected;
      continue;
    }
    one_way += db_per_m_[s.medium] * s.length_m;
  }
  return 2.0 * one_way;
}

}  // namespace radar_emu::radar
