#pragma once
// The one plotting layer of the tools: line charts and heat maps (images) as PNG, drawn to the
// conventions of a report (docs/plotting.md): axis labels with units, 1-2-5 ticks on linear axes,
// decade and 2..9 minor ticks on log axes, colour bars with ticks and a label, legends outside
// the data, titles wrapped rather than clipped, images in metres at equal x and y scale.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "plot/canvas.hpp"

namespace radar_emu::plot {

struct Series {
  std::string label;         ///< legend entry; empty: not in the legend
  std::vector<double> x, y;  ///< same length; non-finite y values break the line
  bool markers = false;      ///< a marker at every point as well as the line
  bool dashed = false;
  std::optional<Rgb> colour = std::nullopt;  ///< default: series_colour(index of the series)
};

/// The colour of the k-th series when it sets none (ten well separated colours, repeating).
[[nodiscard]] Rgb series_colour(std::size_t k) noexcept;

struct LineChart {
  /// Axis labels carry the unit in brackets, "range [m]" (docs/plotting.md).
  std::string title, x_label, y_label;
  std::vector<Series> series;
  std::optional<double> y_min, y_max;  ///< default: the data range (finite values), padded
  std::optional<double> x_min, x_max;  ///< default: the data range
  /// Log axes: non-positive values are left out; decade ticks, minor ticks at 2..9.
  bool log_x = false, log_y = false;
  int width = 1000, height = 640;  ///< pixels of the whole picture
};

struct Heatmap {
  std::string title, x_label, y_label;
  /// The colour bar's label, the unit included ("dBsm", "|chi| [dB]").
  std::string value_label;
  std::vector<double> x, y;    ///< pixel centres, ascending (need not be evenly spaced)
  std::vector<double> values;  ///< row-major [y][x]; non-finite values are drawn grey
  double value_max = 0.0;      ///< top of the colour scale
  double value_range = 40.0;   ///< the scale spans [value_max - range, value_max]
  /// Equal x and y scale (square data units, letterboxed). Default: when the x and y labels
  /// carry the same unit in brackets ("range [m]", "cross-range [m]").
  std::optional<bool> equal_aspect;
  /// A scale bar in the image's lower left, this long in x units (0: a 1-2-5 length near a
  /// fifth of the x span), labelled with the x unit. Default: none.
  std::optional<double> scale_bar;
  int width = 1000, height = 640;  ///< pixels of the whole picture
  /// Grey scale (black at the bottom of the scale, white at the top) instead of viridis.
  bool grey = false;
  /// A picture instead of values (an optical view beside a radar image): x.size() * y.size()
  /// RGB triplets, row-major [y][x] like `values` (which may then be empty); no colour bar.
  std::vector<std::uint8_t> rgb;
};

/// Panels side by side (height: the tallest).
[[nodiscard]] Canvas join_panels(const std::vector<Canvas>& panels);

/// Throw std::runtime_error naming the path on write failure, std::invalid_argument for empty or
/// inconsistent data.
void write_line_chart_png(const LineChart& chart, const std::filesystem::path& path);
/// The same chart as a canvas (chart.width x chart.height, to combine several in one picture).
[[nodiscard]] Canvas render_line_chart(const LineChart& chart);
void write_heatmap_png(const Heatmap& map, const std::filesystem::path& path);
[[nodiscard]] Canvas render_heatmap(const Heatmap& map);
/// Panels one under the other (width: the widest), e.g. one heat map per slice of a sweep.
[[nodiscard]] Canvas stack_panels(const std::vector<Canvas>& panels);

/// Tick positions at 1, 2 or 5 times a power of ten covering [lo, hi] with about `target`
/// intervals.
[[nodiscard]] std::vector<double> nice_ticks(double lo, double hi, int target = 6);

struct AxisTicks {
  std::vector<double> major;        ///< labelled
  std::vector<std::string> labels;  ///< one per major tick; "10^k" is drawn with a superscript
  std::vector<double> minor;        ///< unlabelled (log axes: 2..9 x 10^k)
};
/// Linear: nice_ticks. Log (lo > 0): every decade in range (every other one past 12 decades),
/// minor ticks at 2..9 (up to 8 decades); 2 and 5 labelled too when fewer than 3 decade ticks show;
/// labels plain between 0.001 and 10^4, 10^k outside.
[[nodiscard]] AxisTicks axis_ticks(double lo, double hi, bool log_axis, int target = 6);
/// "%g"-like label at the precision the tick step needs ("0.25", "1500", "-3").
[[nodiscard]] std::string format_tick(double value, double step);

/// Pixel rectangle, inclusive.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  [[nodiscard]] int width() const noexcept { return x1 - x0 + 1; }
  [[nodiscard]] int height() const noexcept { return y1 - y0 + 1; }
  [[nodiscard]] bool overlaps(const PixelRect& o) const noexcept {
    return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1;
  }
};

struct TextLine {
  std::string text;
  int x = 0, y = 0, scale = 2;  ///< top-left
};

/// Where render_line_chart puts things (shared with tests).
struct ChartLayout {
  int width = 0, height = 0;
  PixelRect plot;                          ///< the data area, inside the axes' frame
  std::vector<TextLine> title;             ///< wrapped to the picture's width
  std::vector<PixelRect> legend;           ///< one box (swatch + label) per labelled series
  std::vector<std::size_t> legend_series;  ///< the series of each legend box
  int legend_scale = 2;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  ///< axis ranges (data units)
  bool log_x = false, log_y = false;
  AxisTicks x_ticks, y_ticks;
  [[nodiscard]] double fx(double x) const noexcept;  ///< fractional pixel column
  [[nodiscard]] double fy(double y) const noexcept;  ///< fractional pixel row
};
[[nodiscard]] ChartLayout line_chart_layout(const LineChart& chart);

/// Where render_heatmap puts things (shared with tests).
struct HeatmapLayout {
  int width = 0, height = 0;
  PixelRect image;       ///< the data area (letterboxed when equal_aspect)
  PixelRect colour_bar;  ///< top row: value_max, bottom row: value_max - value_range; empty
                         ///< (width 0) for a picture
  std::vector<TextLine> title;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  ///< extents of the cells (data units)
  bool equal_aspect = false;
  AxisTicks x_ticks, y_ticks, bar_ticks;
  double value_lo = 0, value_hi = 1;
  /// The pixel column / row whose cell holds data coordinate x / y.
  [[nodiscard]] int px(double x) const noexcept;
  [[nodiscard]] int py(double y) const noexcept;
  /// The colour-bar row of a value (clamped to the bar).
  [[nodiscard]] int bar_row(double value) const noexcept;
};
[[nodiscard]] HeatmapLayout heatmap_layout(const Heatmap& map);

/// The unit in the last "[...]" of an axis label ("range [m]" -> "m"); empty when none.
[[nodiscard]] std::string unit_of(const std::string& label);
/// Words of `text` in lines no wider than `max_width_px` at `scale` (a word wider than that is
/// cut); no character is lost.
[[nodiscard]] std::vector<std::string> wrap_text(const std::string& text, int max_width_px,
                                                 int scale);

}  // namespace radar_emu::plot
