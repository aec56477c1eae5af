#pragma once
// Pictures of a run, for people who would rather look than read: a B-scope (azimuth across,
// range up) of every detection the radar sent, coloured by time; the stage times per frame.

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "loop/frame_record.hpp"
#include "loop/scenario.hpp"
#include "timing/profiler.hpp"

namespace radar_emu::loop {

/// What the fidelity governor did, for timing.png's governor panel.
struct GovernorTrace {
  bool enabled = false;
  double deadline_ms = 0.0;             ///< its deadline of trace + sensor [ms]
  std::span<const std::int8_t> levels;  ///< level per frame from the first (-1: no state)
};

/// timing.png (and timing.svg), 1000 x 1280 (matplotlib, plot/charts.hpp): above, each stage's
/// time per frame as stacked areas (input, scene update, trace, sensor, output) with the whole
/// frame as a line, the frame period (budget) and the governor's deadline drawn [ms]; below it,
/// the histogram of frame times with the same lines; last, the governor's level per frame.
/// Throws std::runtime_error naming the path on failure.
inline constexpr int kTimingPngWidth = 1000, kTimingPngHeight = 1280;
void write_timing_png(const timing::StageProfiler& profiler, double period_s,
                      const GovernorTrace& governor, const std::filesystem::path& path);

/// The B-scope of a run, as its outputs stream (loop/outputs/output_stream.hpp): each frame's
/// detections binned as they come into a fixed grid of azimuth x range cells holding the last
/// frame that had a detection there (add_frame(): no allocation), drawn when written as a
/// scatter of the occupied cells coloured by time, with a colour bar [s] (detections.png and
/// detections.svg, kWidth x kHeight pixels).
class BScope {
 public:
  static constexpr int kWidth = 1000, kHeight = 760;  ///< pixels of detections.png
  static constexpr std::size_t kAzimuthCells = 400, kRangeCells = 400;
  /// Setup: allocates the grid. `frames_planned` is not needed by the picture (kept for the
  /// callers' symmetry with the streamed outputs).
  BScope(const Scenario& scenario, std::uint64_t frames_planned);
  /// Bins the detections of the next frame. Real-time safe.
  void add_frame(std::span<const io::icd::Detection> detections) noexcept;
  /// Titles the picture with the frames and detections drawn and writes it (the renderer runs
  /// here). Throws std::runtime_error naming the path on failure.
  void write_png(const std::filesystem::path& path);
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }
  [[nodiscard]] std::uint64_t detections() const noexcept { return detections_; }

 private:
  double azimuth_min_deg_, azimuth_max_deg_, range_max_m_, period_s_;
  std::vector<float> last_frame_;  ///< [range cell][azimuth cell]; < 0: no detection
  std::uint64_t frames_ = 0;
  std::uint64_t detections_ = 0;
};

/// Writes the B-scope of the frames `result` keeps in memory as PNG. Throws std::runtime_error
/// naming the path on failure.
void write_bscope_png(const RunResult& result, const Scenario& scenario,
                      const std::filesystem::path& path);

}  // namespace radar_emu::loop
