#pragma once
// Two-way attenuation along a ray through segments of different media, from specific
// attenuations built once at setup (ITU-R models in radar/propagation/itu.hpp): the frame path
// only multiplies and adds.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "radar/propagation/itu.hpp"

namespace radar_emu::radar {

/// What fills a stretch of the path, at setup.
struct MediumSpec {
  std::string name;
  Atmosphere atmosphere{};        ///< gases (P.676)
  double rain_mm_per_h = 0.0;     ///< P.838 (horizontal path)
  double liquid_water_gm3 = 0.0;  ///< fog or cloud (P.840), at the atmosphere's temperature
};

/// One stretch of a ray: which medium (index into the table) and how long [m].
struct PathSegment {
  std::uint32_t medium = 0;
  double length_m = 0.0;
};

class PathAttenuation {
 public:
  /// Setup: specific attenuation of every medium at `carrier_hz` for a wave of polarisation tilt
  /// `tilt_rad` (0: horizontal, pi/2: vertical) on a near-horizontal path. Throws
  /// std::invalid_argument (with the medium's name) for inputs outside the models' ranges.
  PathAttenuation(double carrier_hz, double tilt_rad, std::span<const MediumSpec> media);

  /// One-way specific attenuation of medium i [dB/m].
  [[nodiscard]] double specific_db_per_m(std::uint32_t medium) const noexcept;
  /// Two-way loss [dB] over the segments: 2 sum gamma_i L_i. Unknown media and negative or
  /// non-finite lengths count as 0 (and are counted in `rejected` when given). Real-time safe.
  [[nodiscard]] double two_way_loss_db(std::span<const PathSegment> segments,
                                       std::uint64_t* rejected = nullptr) const noexcept;

 private:
  std::vector<double> db_per_m_;
};

}  // namespace radar_emu::radar
