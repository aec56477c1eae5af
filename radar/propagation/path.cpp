#include "radar/propagation/path.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "radar/em/sbr.hpp"

namespace radar_emu::radar {

PathAttenuation::PathAttenuation(double carrier_hz, double tilt_rad,
                                 std::span<const MediumSpec> media) {
  db_per_m_.reserve(media.size());
  woodland_db_per_m_.assign(media.size(), 0.0);
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
      if (m.woodland) {
        woodland_db_per_m_[db_per_m_.size() - 1] =
            woodland_specific_attenuation_db_per_m(carrier_hz, m.in_leaf);
        woodland_max_db_ = woodland_max_attenuation_db(carrier_hz);
      }
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
  double woodland = 0.0;  // sum gamma d over woodland stretches, before saturation
  for (const PathSegment& s : segments) {
    if (s.medium >= db_per_m_.size() || !(s.length_m >= 0.0) || !std::isfinite(s.length_m)) {
      if (rejected != nullptr)
        ++*rejected;
      continue;
    }
    one_way += db_per_m_[s.medium] * s.length_m;
    woodland += woodland_db_per_m_[s.medium] * s.length_m;
  }
  if (woodland > 0.0)  // P.833 eq. (1) with d gamma summed over the woodland crossed
    one_way += woodland_max_db_ * -std::expm1(-woodland / woodland_max_db_);
  return 2.0 * one_way;
}

void apply_two_way_loss(std::span<Contribution> contributions, double one_way_db_per_m) noexcept {
  if (!(one_way_db_per_m > 0.0) || !std::isfinite(one_way_db_per_m))
    return;
  // Amplitude factor 10^(-2 gamma r / 20) = exp(-a r), a = gamma ln(10) / 10 (power ratio
  // 10^(-L/10) of the loss L in dB, amplitude its square root).
  const double a = one_way_db_per_m * std::numbers::ln10 / 10.0;
  for (Contribution& c : contributions) {
    if (!(c.range_m >= 0.0) || !std::isfinite(c.range_m))
      continue;
    c.amplitude *= std::exp(-a * c.range_m);
  }
}

}  // namespace radar_emu::radar
