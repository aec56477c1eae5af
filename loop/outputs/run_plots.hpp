#pragma once
// Pictures of a run, for people who would rather look than read: a B-scope (azimuth across,
// range up) of every detection the radar sent, coloured by time.

#include <cstdint>
#include <filesystem>
#include <span>

#include "loop/frame_record.hpp"
#include "loop/scenario.hpp"
#include "plot/canvas.hpp"
#include "timing/profiler.hpp"

namespace radar_emu::loop {

/// Plot geometry, shared with tests: pixel of an (azimuth, range) point.
struct BScopeLayout {
  static constexpr int kWidth = 900, kHeight = 700;
  static constexpr int kLeft = 70, kRight = 20, kTop = 40, kBottom = 50;
  double azimuth_min_deg = -8.0, azimuth_max_deg = 8.0, range_max_m = 6000.0;
  [[nodiscard]] int x_of(double azimuth_deg) const noexcept;
  [[nodiscard]] int y_of(double range_m) const noexcept;
};

/// timing.png, 1000 x 1280: above, each stage's time per frame stacked in frame order (input,
/// + scene update, + trace, + sensor, + output) with the whole frame and the budget (the
/// period) as lines [ms]; below, the histogram of frame times with the budget marked. Throws
/// std::runtime_error naming the path on failure.
inline constexpr int kTimingPngWidth = 1000, kTimingPngHeight = 1280;
void write_timing_png(const timing::StageProfiler& profiler, double period_s,
                      const std::filesystem::path& path);

/// The B-scope drawn frame by frame, as a run's outputs stream (loop/outputs/output_stream.hpp):
/// the grid at construction (setup: allocates the canvas), each frame's detections as they come
/// (add_frame(): no allocation), the title when written.
class BScope {
 public:
  /// `frames_planned` sets the colour scale: frame k of n is drawn at k / (n - 1) from blue to
  /// red (an interrupted run stops short of red).
  BScope(const Scenario& scenario, std::uint64_t frames_planned);
  /// Draws the detections of the next frame. Real-time safe.
  void add_frame(std::span<const io::icd::Detection> detections) noexcept;
  /// Titles the picture with the frames and detections drawn and writes it. Throws
  /// std::runtime_error naming the path on failure.
  void write_png(const std::filesystem::path& path);
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }
  [[nodiscard]] std::uint64_t detections() const noexcept { return detections_; }

 private:
  BScopeLayout layout_;
  plot::Canvas canvas_;
  double colour_scale_;
  std::uint64_t frames_ = 0;
  std::uint64_t detections_ = 0;
};

/// Writes the B-scope of the frames `result` keeps in memory as PNG. Throws std::runtime_error
/// naming the path on failure.
void write_bscope_png(const RunResult& result, const Scenario& scenario,
                      const std::filesystem::path& path);

}  // namespace radar_emu::loop
