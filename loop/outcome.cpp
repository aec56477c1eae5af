#include "loop/outcome.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace radar_emu::loop {

void ErrorStats::add(double error, double stated_sigma) noexcept {
  ++count;
  const double delta = error - mean;
  mean += delta / static_cast<double>(count);
  m2 += delta * (error - mean);
  stated_variance_sum += stated_sigma * stated_sigma;
}

double ErrorStats::std_dev() const noexcept {
  return count > 1 ? std::sqrt(std::max(m2, 0.0) / static_cast<double>(count - 1)) : 0.0;
}

double ErrorStats::stated_sigma_rms() const noexcept {
  return count > 0 ? std::sqrt(stated_variance_sum / static_cast<double>(count)) : 0.0;
}

double fold_symmetric(double x, double period) noexcept {
  if (!(period > 0.0) || !std::isfinite(period))
    return x;
  return x - period * std::floor(x / period + 0.5);
}

OutcomeTally::OutcomeTally(const AssociationGate& gate, std::span<const std::uint32_t> object_ids,
                           std::size_t max_detections, std::size_t max_truth) {
  auto require = [](bool ok, const char* what) {
    if (!ok)
      throw std::invalid_argument(std::string("outcome: association gate ") + what);
  };
  require(std::isfinite(gate.range_cell_m) && gate.range_cell_m > 0.0, "range cell must be > 0");
  require(std::isfinite(gate.azimuth_cell_rad) && gate.azimuth_cell_rad > 0.0,
          "azimuth cell must be > 0");
  require(std::isfinite(gate.elevation_cell_rad) && gate.elevation_cell_rad > 0.0,
          "elevation cell must be > 0");
  require(std::isfinite(gate.sigmas) && gate.sigmas >= 0.0, "sigmas must be >= 0");
  totals_.gate = gate;
  std::uint32_t max_id = 0;
  for (std::uint32_t id : object_ids)
    max_id = std::max(max_id, id);
  index_of_.assign(object_ids.empty() ? 0 : static_cast<std::size_t>(max_id) + 1, -1);
  totals_.targets.resize(object_ids.size());
  for (std::size_t k = 0; k < object_ids.size(); ++k) {
    totals_.targets[k].object_id = object_ids[k];
    index_of_[object_ids[k]] = static_cast<int>(k);
  }
  association_.assign(max_detections, -1);
  best_detection_.assign(max_truth, -1);
  best_distance_.assign(max_truth, 0.0);
}

void OutcomeTally::frame(std::span<const ObjectTruth> truth, std::span<const double> size_m,
                         std::span<const radar::Detection> detections) noexcept {
  const AssociationGate& g = totals_.gate;
  const std::size_t n_truth = std::min({truth.size(), size_m.size(), best_detection_.size()});
  const std::size_t n_det = std::min(detections.size(), association_.size());
  last_detections_ = n_det;
  ++totals_.frames_scored;
  totals_.detections += n_det;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::fill_n(best_detection_.begin(), n_truth, -1);
  std::fill_n(best_distance_.begin(), n_truth, kInf);
  // Each detection to the nearest object (normalised distance) whose gate holds it.
  for (std::size_t i = 0; i < n_det; ++i) {
    const radar::Detection& d = detections[i];
    int best = -1;
    double best_d2 = kInf;
    for (std::size_t j = 0; j < n_truth; ++j) {
      const ObjectTruth& t = truth[j];
      if (t.object_id >= index_of_.size() || index_of_[t.object_id] < 0)
        continue;
      const double size = std::max(size_m[j], 0.0);
      const double angle_size = t.range_m > 0.0 ? size / t.range_m : 0.0;
      const double gr = g.range_cell_m + g.sigmas * d.range_std_m + size;
      const double ga = g.azimuth_cell_rad + g.sigmas * d.azimuth_std_rad + angle_size;
      const double ge = g.elevation_cell_rad + g.sigmas * d.elevation_std_rad + angle_size;
      const double nr = fold_symmetric(d.range_m - t.range_m, g.unambiguous_range_m) / gr;
      const double na = (d.azimuth_rad - t.azimuth_rad) / ga;
      const double ne = (d.elevation_rad - t.elevation_rad) / ge;
      // NaN fails every comparison: a non-finite detection is in no gate.
      if (!(std::abs(nr) <= 1.0 && std::abs(na) <= 1.0 && std::abs(ne) <= 1.0))
        continue;
      const double d2 = nr * nr + na * na + ne * ne;
      if (d2 < best_d2) {
        best_d2 = d2;
        best = static_cast<int>(j);
      }
    }
    association_[i] = best;
    if (best < 0) {
      ++totals_.false_alarms;
      if (d.object_id != radar::kNoObject)
        ++totals_.false_alarms_on_objects;
      continue;
    }
    const auto j = static_cast<std::size_t>(best);
    ++totals_.targets[static_cast<std::size_t>(index_of_[truth[j].object_id])]
          .detections_associated;
    if (best_d2 < best_distance_[j]) {
      best_distance_[j] = best_d2;
      best_detection_[j] = static_cast<int>(i);
    }
  }
  // Per object in the beam: in the beam, detected, and its detection's errors.
  for (std::size_t j = 0; j < n_truth; ++j) {
    const ObjectTruth& t = truth[j];
    if (t.object_id >= index_of_.size() || index_of_[t.object_id] < 0)
      continue;
    TargetOutcome& o = totals_.targets[static_cast<std::size_t>(index_of_[t.object_id])];
    ++o.frames_in_beam;
    if (best_detection_[j] < 0)
      continue;
    ++o.frames_detected;
    const radar::Detection& d = detections[static_cast<std::size_t>(best_detection_[j])];
    o.range_m.add(fold_symmetric(d.range_m - t.range_m, g.unambiguous_range_m), d.range_std_m);
    o.azimuth_rad.add(d.azimuth_rad - t.azimuth_rad, d.azimuth_std_rad);
    o.elevation_rad.add(d.elevation_rad - t.elevation_rad, d.elevation_std_rad);
    o.radial_velocity_mps.add(fold_symmetric(d.radial_velocity_mps - t.radial_velocity_mps,
                                             2.0 * g.unambiguous_velocity_mps),
                              d.velocity_std_mps);
  }
}

}  // namespace radar_emu::loop
