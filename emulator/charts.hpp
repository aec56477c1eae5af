#pragma once
// Line charts and heat maps as PNG, for the offline tools (RCS patterns, range profiles, ISAR).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "emulator/canvas.hpp"

namespace radar_emu::emulator {

struct Series {
  std::string label;
  std::vector<double> x, y;  ///< same length; non-finite y values break the line
};

struct LineChart {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  std::optional<double> y_min, y_max;  ///< default: the data range (finite values)
};

struct Heatmap {
  std::string title, x_label, y_label, value_label;
  std::vector<double> x, y;    ///< pixel centres, ascending
  std::vector<double> values;  ///< row-major [y][x]
  double value_max = 0.0;      ///< top of the colour scale
  double value_range = 40.0;   ///< the scale spans [value_max - range, value_max]
};

/// Throw std::runtime_error naming the path on write failure, std::invalid_argument for empty or
/// inconsistent data.
void write_line_chart_png(const LineChart& chart, const std::filesystem::path& path);
/// The same chart as a 1000 x 640 canvas (to combine several charts into one picture).
[[nodiscard]] Canvas render_line_chart(const LineChart& chart);
void write_heatmap_png(const Heatmap& map, const std::filesystem::path& path);

/// Tick positions at 1, 2 or 5 times a power of ten covering [lo, hi] with about `target`
/// intervals.
[[nodiscard]] std::vector<double> nice_ticks(double lo, double hi, int target = 6);

}  // namespace radar_emu::emulator
