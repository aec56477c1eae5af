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

struct Contribution;  // radar/em/sbr.hpp

/// What fills a stretch of the path, at setup.
struct MediumSpec {
  std::string name;
  Atmosphere atmosphere{};        ///< gases (P.676)
  double rain_mm_per_h = 0.0;     ///< P.838 (horizontal path)
  double liquid_water_gm3 = 0.0;  ///< fog or cloud (P.840), at the atmosphere's temperature
  /// Woodland (P.833 sec. 2): the stretch is inside trees. Its attenuation saturates with the
  /// depth crossed, so woodland segments are summed first, then A_m [1 - exp(-sum gamma d /
  /// A_m)] is taken (eq. (1)); 1-30 GHz.
  bool woodland = false;
  bool in_leaf = true;
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

  /// One-way specific attenuation of medium i [dB/m] (for woodland: gamma, before saturation).
  [[nodiscard]] double specific_db_per_m(std::uint32_t medium) const noexcept;
  /// Two-way loss [dB] over the segments: 2 sum gamma_i L_i. Unknown media and negative or
  /// non-finite lengths count as 0 (and are counted in `rejected` when given). Real-time safe.
  [[nodiscard]] double two_way_loss_db(std::span<const PathSegment> segments,
                                       std::uint64_t* rejected = nullptr) const noexcept;

 private:
  std::vector<double> db_per_m_;
  std::vector<double> woodland_db_per_m_;
  double woodland_max_db_ = 0.0;
};

/// Two-way loss of a uniform medium applied to scattering returns: each contribution's amplitude
/// (sqrt of its RCS-like power, radar/em/sbr.hpp) is multiplied by 10^(-L/20) with
/// L = 2 gamma r [dB] the loss over the two-way path 2 r (r = range_m, the centre of a diffuse
/// footprint), gamma the one-way specific attenuation [dB/m] (PathAttenuation). Returns with a
/// non-finite, negative or zero gamma, or a negative or non-finite range, are left as they are.
/// Real-time safe: no allocation, no throw.
void apply_two_way_loss(std::span<Contribution> contributions, double one_way_db_per_m) noexcept;

}  // namespace radar_emu::radar
