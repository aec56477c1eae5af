#pragma once
// The outcome per target: "did the radar see it, and how well". Each frame, the detections are
// associated with the objects in the beam (loop/truth.hpp), and per object the loop counts the
// frames it was in the beam and the frames it was detected in (Pd = detected / in beam), and
// accumulates the error of its associated detection (detection minus truth) in range, azimuth,
// elevation and radial velocity, next to the one-sigma accuracies the sensor stated for those
// detections. Detections associated with no object in the beam are false alarms.
//
// Association (docs/outcome.md). A detection is in an object's gate when, in range, azimuth and
// elevation each, |detection - truth| <= gate, with
//   gate = one resolution cell + sigmas x the detection's stated one-sigma + the object's size,
// the cell being the range resolution and the sum beam's 3 dB widths, the size half the
// diagonal of the object's world bounding box (in the angles: divided by its range). The
// radial velocity is not gated (it folds; the range and angles already separate the objects).
// Each detection goes to the object of smallest normalised distance sum((delta / gate)^2) among
// those whose gate holds it (at most one object); per object and frame, the detection of
// smallest normalised distance is "its" detection (the errors), the others count as associated
// (an extended object gives several) and are not false alarms. Range errors are taken modulo the
// unambiguous range and velocity errors modulo twice the unambiguous velocity (into
// [-v_ua, v_ua)), as the sensor folds them.
//
// Units: SI throughout (m, rad, m/s); degrees exist only in the outputs. Setup (the
// constructor) allocates; frame() is real-time safe.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "loop/truth.hpp"
#include "radar/sensor/sensor.hpp"

namespace radar_emu::loop {

/// The association gate (header): resolution cells, sigmas and the ambiguity intervals.
struct AssociationGate {
  double range_cell_m = 1.0;              ///< range resolution [m] (> 0)
  double azimuth_cell_rad = 0.01;         ///< sum beam's 3 dB width in azimuth [rad] (> 0)
  double elevation_cell_rad = 0.01;       ///< and in elevation [rad] (> 0)
  double sigmas = 3.0;                    ///< stated one-sigmas added to the cell (>= 0)
  double unambiguous_range_m = 0.0;       ///< range errors modulo this [m]; 0: not folded
  double unambiguous_velocity_mps = 0.0;  ///< velocity errors into [-v_ua, v_ua) [m/s]; 0: not
};

/// Mean and spread of one error (detection minus truth) over the frames an object was
/// detected, and the rms of the one-sigma accuracies the sensor stated for those detections.
/// Welford's running mean and sum of squared deviations (no cancellation).
struct ErrorStats {
  std::uint64_t count = 0;
  double mean = 0.0;                 ///< mean error, in the quantity's unit
  double m2 = 0.0;                   ///< sum of squared deviations from the mean
  double stated_variance_sum = 0.0;  ///< sum of the stated one-sigma squared

  void add(double error, double stated_sigma) noexcept;
  /// Sample standard deviation (n - 1); 0 below two samples.
  [[nodiscard]] double std_dev() const noexcept;
  /// Root mean square of the stated one-sigmas; 0 without samples.
  [[nodiscard]] double stated_sigma_rms() const noexcept;
};

/// One truth object over the run.
struct TargetOutcome {
  std::uint32_t object_id = 0;              ///< index into scene::Scene::objects()
  std::uint64_t frames_in_beam = 0;         ///< frames it was in the truth list
  std::uint64_t frames_detected = 0;        ///< of those, with a detection associated
  std::uint64_t detections_associated = 0;  ///< every detection associated with it
  ErrorStats range_m, azimuth_rad, elevation_rad, radial_velocity_mps;
  /// frames_detected / frames_in_beam (0 when never in the beam).
  [[nodiscard]] double pd() const noexcept {
    return frames_in_beam > 0
               ? static_cast<double>(frames_detected) / static_cast<double>(frames_in_beam)
               : 0.0;
  }
};

/// The outcome of a run so far: per truth object (in truth.json's order), and the false
/// alarms.
struct OutcomeTotals {
  AssociationGate gate{};
  std::vector<TargetOutcome> targets;
  std::uint64_t frames_scored = 0;  ///< frames with an ownship state (truth and detections)
  std::uint64_t detections = 0;     ///< detections of those frames
  std::uint64_t false_alarms = 0;   ///< associated with no object in the beam
  /// Of those, the ones whose cell a scene object's return dominates (Detection::object_id):
  /// objects truth does not cover (buildings: no conducting material) or whose box centre is
  /// outside the field of view; the rest are clutter or noise.
  std::uint64_t false_alarms_on_objects = 0;
  [[nodiscard]] double false_alarms_per_frame() const noexcept {
    return frames_scored > 0
               ? static_cast<double>(false_alarms) / static_cast<double>(frames_scored)
               : 0.0;
  }
};

/// The outcome so far, as the frame path hands it on (the live view): spans into the tally.
struct OutcomeSoFar {
  std::span<const TargetOutcome> targets;
  std::uint64_t frames_scored = 0;
  std::uint64_t false_alarms = 0;
};

/// Per-frame association and accumulation (header).
class OutcomeTally {
 public:
  /// Setup: one TargetOutcome per id of `object_ids` (in that order), scratch for
  /// `max_detections` detections and `max_truth` objects a frame. Throws std::invalid_argument
  /// when a cell is not > 0 or sigmas < 0.
  OutcomeTally(const AssociationGate& gate, std::span<const std::uint32_t> object_ids,
               std::size_t max_detections, std::size_t max_truth);

  /// One frame with an ownship state: `truth` the objects in the beam, `size_m` each one's size
  /// (half its bounding box diagonal, same index), `detections` the sensor's. Entries beyond
  /// the scratch sizes, and truth objects not in object_ids, are ignored. Real-time safe.
  void frame(std::span<const ObjectTruth> truth, std::span<const double> size_m,
             std::span<const radar::Detection> detections) noexcept;

  /// The detections of the last frame: the index into its `truth` each was associated with, -1
  /// for a false alarm (valid until the next frame()).
  [[nodiscard]] std::span<const int> association() const noexcept {
    return {association_.data(), last_detections_};
  }
  [[nodiscard]] const OutcomeTotals& totals() const noexcept { return totals_; }
  [[nodiscard]] OutcomeSoFar so_far() const noexcept {
    return {totals_.targets, totals_.frames_scored, totals_.false_alarms};
  }

 private:
  OutcomeTotals totals_;
  std::vector<int> index_of_;          ///< by object id: index into targets, -1 none
  std::vector<int> association_;       ///< per detection (max_detections)
  std::vector<int> best_detection_;    ///< per truth entry (max_truth)
  std::vector<double> best_distance_;  ///< per truth entry: its normalised distance squared
  std::size_t last_detections_ = 0;
};

/// `x` folded into [-period/2, period/2) (unchanged when period <= 0). Real-time safe.
[[nodiscard]] double fold_symmetric(double x, double period) noexcept;

}  // namespace radar_emu::loop
