#include "radar/products/fluctuation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/units.hpp"

namespace radar_emu::radar {

namespace {

// Hyndman & Fan (1996), "Sample quantiles in statistical packages", type 7.
double quantile(const std::vector<double>& sorted, double p) {
  const double h = (static_cast<double>(sorted.size()) - 1.0) * p;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (h - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

}  // namespace

FluctuationStats fluctuation_stats(std::span<const double> rcs_m2) {
  if (rcs_m2.empty())
    throw std::invalid_argument("fluctuation statistics: no samples");
  std::vector<double> sorted(rcs_m2.begin(), rcs_m2.end());
  double sum = 0.0, sum_db = 0.0;
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    const double s = sorted[i];
    if (!std::isfinite(s) || s < 0.0) {
      throw std::invalid_argument("fluctuation statistics: sample " + std::to_string(i) +
                                  " is not a finite, non-negative RCS");
    }
    sum += s;
    sum_db += common::db_from_power(std::max(s, 1e-30));
  }
  const double n = static_cast<double>(sorted.size());
  const double mean_db = sum_db / n;
  double var_db = 0.0;
  for (double s : sorted) {
    const double d = common::db_from_power(std::max(s, 1e-30)) - mean_db;
    var_db += d * d;
  }
  std::sort(sorted.begin(), sorted.end());
  FluctuationStats st;
  st.count = sorted.size();
  st.mean_m2 = sum / n;
  st.median_m2 = quantile(sorted, 0.5);
  st.p10_m2 = quantile(sorted, 0.1);
  st.p90_m2 = quantile(sorted, 0.9);
  st.std_db = std::sqrt(var_db / n);
  return st;
}

std::vector<FluctuationStats> sliding_window_stats(std::span<const double> angle_rad,
                                                   std::span<const double> rcs_m2,
                                                   double half_window_rad) {
  if (angle_rad.size() != rcs_m2.size())
    throw std::invalid_argument("fluctuation statistics: angles and samples differ in number");
  if (!std::isfinite(half_window_rad) || half_window_rad < 0.0)
    throw std::invalid_argument("fluctuation statistics: the window must be >= 0");
  std::vector<FluctuationStats> out;
  out.reserve(rcs_m2.size());
  std::vector<double> window;
  for (std::size_t i = 0; i < angle_rad.size(); ++i) {
    window.clear();
    for (std::size_t j = 0; j < angle_rad.size(); ++j) {
      if (std::abs(angle_rad[j] - angle_rad[i]) <= half_window_rad * (1.0 + 1e-12))
        window.push_back(rcs_m2[j]);
    }
    out.push_back(fluctuation_stats(window));
  }
  return out;
}

}  // namespace radar_emu::radar
