#pragma once
// The one plotting layer of the tools (docs/plotting.md): the tools describe their figures here
// (line charts, stacked areas, polar cuts, heat maps and pictures, panels of them) and matplotlib
// draws them: an anti-aliased PNG and an SVG beside it (same stem), real fonts, log ticks,
// colour bars with units, perceptual colour maps, legends outside the data.
//
// How: the figures are written as JSON (arrays of heat maps as raw little-endian doubles beside
// it) to a temporary folder with the renderer plot/render.py (embedded in the binary at build
// time), and one Python process draws them all: the interpreter CMake found at configure time
// (Debian's /usr/bin/python3 with python3-matplotlib), or $RADAR_EMU_PYTHON. Setup-time code
// only: it allocates, writes files and waits for a child process.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace radar_emu::plot {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

struct Series {
  std::string label;         ///< legend entry; empty: not in the legend
  std::vector<double> x, y;  ///< same length; non-finite y values break the line
  bool markers = false;      ///< a marker at every point as well as the line
  bool dashed = false;       ///< closed forms, references, values outside a model's validity
  std::optional<Rgb> colour = std::nullopt;  ///< default: series_colour(index of the series)
  /// Markers only, no line between them (measured points).
  bool no_line = false;
  /// A stacked area: this series' y is drawn on top of the previous stacked series' (all the
  /// chart's stacked series share the first one's x).
  bool stacked = false;
  /// The spread of each point (error bars), empty or one per point: y_lo <= y <= y_hi, and the
  /// same across for x.
  std::vector<double> y_lo{}, y_hi{}, x_lo{}, x_hi{};
  /// Text beside each point (a knob's value), empty or one per point ("" for none).
  std::vector<std::string> point_labels{};
  /// A scatter coloured by these values (one per point) through the chart's colour map, with a
  /// colour bar labelled LineChart::colour_label.
  std::vector<double> colour_values{};
  double marker_size = 12.0;  ///< scatter marker area [pt^2]
};

/// The colour of the k-th series when it sets none (matplotlib's tab10, repeating).
[[nodiscard]] Rgb series_colour(std::size_t k) noexcept;

/// A horizontal (or vertical) reference line across the data: a budget, a deadline.
struct RefLine {
  double value = 0.0;
  std::string label;  ///< legend entry
  bool vertical = false;
  bool dashed = true;
  std::optional<Rgb> colour = std::nullopt;  ///< default: near black
};

struct LineChart {
  /// Axis labels carry the unit in brackets, "range [m]" (docs/plotting.md).
  std::string title, x_label, y_label;
  std::vector<Series> series;
  std::vector<RefLine> ref_lines;
  std::optional<double> y_min, y_max;  ///< default: the data range, padded
  std::optional<double> x_min, x_max;  ///< default: the data range, padded
  /// Log axes: non-positive values are left out; decade ticks, minor ticks at 2..9.
  bool log_x = false, log_y = false;
  /// Polar axes: x is the angle [deg] (0 up, clockwise), y the radius (y_min at the centre).
  bool polar = false;
  /// Equal x and y scale (a map of positions in metres).
  bool equal_aspect = false;
  /// Scatter series with colour_values: the colour bar's label (unit included), the map and
  /// its limits (default: the values' range).
  std::string colour_label;
  std::string colour_map = "viridis";
  std::optional<double> colour_min, colour_max;
  /// The legend under the data instead of right of it (default: chosen by the labels' length).
  std::optional<bool> legend_below;
  bool legend = true;  ///< false: no legend (a panel beside another with the same series)
  int width = 1000, height = 640;  ///< pixels of the whole picture when drawn alone
};

struct Heatmap {
  std::string title, x_label, y_label;
  /// The colour bar's label, the unit included ("RCS [dBsm]", "|chi| [dB]").
  std::string value_label;
  std::vector<double> x, y;    ///< pixel centres, ascending (need not be evenly spaced)
  std::vector<double> values;  ///< row-major [y][x]; non-finite values are drawn grey
  double value_max = 0.0;      ///< top of the colour scale
  double value_range = 40.0;   ///< the scale spans [value_max - range, value_max]
  /// Equal x and y scale. Default: when the x and y labels carry the same unit in brackets
  /// ("range [m]", "cross-range [m]").
  std::optional<bool> equal_aspect;
  /// A scale bar in the image's lower left, this long in x units (0: a 1-2-5 length near a
  /// fifth of the x span), labelled with the x unit. Default: none.
  std::optional<double> scale_bar;
  int width = 1000, height = 640;  ///< pixels of the whole picture when drawn alone
  /// Grey scale (black at the bottom of the scale, white at the top) instead of viridis.
  bool grey = false;
  /// A picture instead of values (an optical view beside a radar image): x.size() * y.size()
  /// RGB triplets, row-major [y][x] like `values` (which may then be empty); no colour bar.
  std::vector<std::uint8_t> rgb;
};

using Panel = std::variant<LineChart, Heatmap>;

/// Panels in a grid, filled row by row.
struct Figure {
  std::string title;  ///< above all panels (each panel may have its own too)
  std::vector<Panel> panels;
  int columns = 1;
  int width = 1000, height = 640;     ///< pixels of the PNG
  std::vector<double> height_ratios;  ///< of the rows; empty: equal
};

/// A figure of one panel at the panel's own size.
[[nodiscard]] Figure single(LineChart chart);
[[nodiscard]] Figure single(Heatmap map);

/// Figures drawn together by one renderer process (matplotlib's import costs ~0.5 s).
class FigureBatch {
 public:
  /// `png`: the PNG's path; the SVG goes beside it (same stem, .svg). Checks the data
  /// (std::invalid_argument naming the figure: empty or inconsistent data, a log axis with no
  /// positive value).
  void add(Figure figure, const std::filesystem::path& png);
  /// Draws every figure added, then forgets them. Throws std::runtime_error with one line:
  /// the interpreter cannot be run, matplotlib is missing (naming the interpreter and the
  /// Debian package), or the renderer's own error naming the figure.
  void write();
  [[nodiscard]] bool empty() const noexcept { return figures_.empty(); }

 private:
  std::vector<std::pair<Figure, std::filesystem::path>> figures_;
};

/// One figure drawn at once (a batch of one).
void write_figure(Figure figure, const std::filesystem::path& png);
void write_line_chart_png(const LineChart& chart, const std::filesystem::path& png);
void write_heatmap_png(const Heatmap& map, const std::filesystem::path& png);

/// The SVG written beside a PNG.
[[nodiscard]] std::filesystem::path svg_path(const std::filesystem::path& png);

/// The interpreter that draws: $RADAR_EMU_PYTHON, else the one CMake found.
[[nodiscard]] std::string plot_interpreter();

/// The unit in the last "[...]" of an axis label ("range [m]" -> "m"); empty when none.
[[nodiscard]] std::string unit_of(const std::string& label);

}  // namespace radar_emu::plot
