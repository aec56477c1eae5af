#pragma once
// "A realistic mean RCS coupled with its fluctuations" (seed paper): statistics of RCS samples
// over small aspect windows. Offline (allocates); throws std::invalid_argument for bad input.

#include <cstddef>
#include <span>
#include <vector>

namespace radar_emu::radar {

struct FluctuationStats {
  std::size_t count = 0;
  double mean_m2 = 0.0;    ///< mean of sigma (linear: the power average)
  double median_m2 = 0.0;  ///< 50 % point
  double p10_m2 = 0.0;     ///< 10 % and 90 % points; all percentiles interpolate linearly
  double p90_m2 = 0.0;  ///< between order statistics at (count - 1) p (Hyndman & Fan 1996, type 7)
  /// Standard deviation of 10 log10(sigma) (sigma floored at 1e-30 m^2), the "spread" [dB]
  /// (population form, divides by count).
  double std_db = 0.0;
};

/// Statistics of all samples (sigma >= 0, finite, at least one).
[[nodiscard]] FluctuationStats fluctuation_stats(std::span<const double> rcs_m2);

/// For each sample i, the statistics of the samples whose angle lies within +-half_window_rad
/// of angle i (angles in any order, same length as rcs_m2, half_window_rad >= 0).
[[nodiscard]] std::vector<FluctuationStats> sliding_window_stats(std::span<const double> angle_rad,
                                                                 std::span<const double> rcs_m2,
                                                                 double half_window_rad);

}  // namespace radar_emu::radar
