#include "plot/charts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <utility>

namespace radar_emu::plot {

namespace {

constexpr int kMargin = 10;  // picture edge to anything drawn
constexpr int kTick = 6, kMinorTick = 3;
constexpr int kScale = 2;           // text scale of titles, labels and legends
constexpr int kLine = 12 * kScale;  // text line pitch
constexpr int kSwatch = 30;         // legend: line sample before the label
const Rgb kBackground{255, 255, 255}, kInk{30, 30, 30}, kGrid{222, 222, 222},
    kMinorGrid{242, 242, 242}, kMissing{170, 170, 170};
// Ten well separated colours (the "tab10" list of Vega/matplotlib, a fact about colours); past
// ten series the marker shape changes.
constexpr std::array<Rgb, 10> kPalette{{{31, 119, 180},
                                        {214, 39, 40},
                                        {44, 160, 44},
                                        {255, 127, 14},
                                        {148, 103, 189},
                                        {23, 190, 207},
                                        {140, 86, 75},
                                        {227, 119, 194},
                                        {127, 127, 127},
                                        {188, 189, 34}}};

// Labels "B^E" are drawn as B with E as a superscript (one scale smaller, raised).
int sup_scale(int scale) {
  return std::max(1, scale - 1);
}

int label_width(const std::string& s, int scale) {
  const std::size_t caret = s.find('^');
  if (caret == std::string::npos)
    return Canvas::text_width(s, scale);
  return Canvas::text_width(s.substr(0, caret), scale) + 1 +
         Canvas::text_width(s.substr(caret + 1), sup_scale(scale));
}

void draw_label(Canvas& c, int x, int y, const std::string& s, Rgb ink, int scale) {
  const std::size_t caret = s.find('^');
  if (caret == std::string::npos) {
    c.text(x, y, s, ink, scale);
    return;
  }
  const std::string base = s.substr(0, caret);
  c.text(x, y, base, ink, scale);
  c.text(x + Canvas::text_width(base, scale) + 1, y - 3 * scale, s.substr(caret + 1), ink,
         sup_scale(scale));
}

int max_label_width(const std::vector<std::string>& labels, int scale) {
  int w = 0;
  for (const std::string& s : labels)
    w = std::max(w, label_width(s, scale));
  return w;
}

std::vector<TextLine> layout_title(const std::string& title, int width, int& bottom) {
  std::vector<TextLine> out;
  bottom = kMargin;
  if (title.empty())
    return out;
  for (const std::string& line : wrap_text(title, width - 2 * kMargin, kScale)) {
    const int w = Canvas::text_width(line, kScale);
    out.push_back(TextLine{line, std::max(kMargin, (width - w) / 2), bottom, kScale});
    bottom += kLine;
  }
  return out;
}

// Axis transform: log10 on a log axis.
double axis_t(double v, bool log_axis) {
  return log_axis ? std::log10(v) : v;
}

// 1, 2 or 5 times a power of ten: the largest at most v (down) or the smallest at least v (up).
double nice_125(double v, bool up) {
  const double mag = std::pow(10.0, std::floor(std::log10(v)));
  if (up) {
    for (double m : {1.0, 2.0, 5.0, 10.0}) {
      if (m * mag >= v * (1 - 1e-12))
        return m * mag;
    }
    return 10.0 * mag;
  }
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * mag <= v * (1 + 1e-12))
      return m * mag;
  }
  return mag;
}

struct Range {
  double lo = std::numeric_limits<double>::max(), hi = -std::numeric_limits<double>::max();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  [[nodiscard]] bool empty() const { return !(hi >= lo); }
};

// Final axis range from the data range and the chart's limits.
void settle_range(double& lo, double& hi, std::optional<double> given_lo,
                  std::optional<double> given_hi, bool log_axis, double linear_pad,
                  const char* which) {
  if (log_axis && ((given_lo && !(*given_lo > 0.0)) || (given_hi && !(*given_hi > 0.0))))
    throw std::invalid_argument(std::string("chart: a log ") + which +
                                " axis needs positive limits");
  if (given_lo)
    lo = *given_lo;
  if (given_hi)
    hi = *given_hi;
  if (!(hi > lo)) {
    if (log_axis) {
      lo = lo / 2.0;
      hi = lo * 4.0;
    } else {
      const double half = lo == 0.0 ? 1.0 : 0.5 * std::abs(lo);
      lo -= given_lo ? 0.0 : half;
      hi = lo + 2.0 * half;
    }
    return;
  }
  if (log_axis) {
    if (!given_lo)
      lo = nice_125(lo, false);
    if (!given_hi)
      hi = nice_125(hi, true);
  } else {
    const double pad = linear_pad * (hi - lo);
    if (!given_lo)
      lo -= pad;
    if (!given_hi)
      hi += pad;
  }
}

void check_size(int w, int h) {
  if (w < 200 || h < 150 || w > 8000 || h > 8000)
    throw std::invalid_argument("chart: size " + std::to_string(w) + " x " + std::to_string(h) +
                                " is outside 200 x 150 .. 8000 x 8000 pixels");
}

// A 2-pixel line from (ax, ay) to (bx, by) (fractional pixels), clipped to `r` (Liang-Barsky);
// `dash` carries the dash phase along a polyline.
void draw_segment(Canvas& c, const PixelRect& r, double ax, double ay, double bx, double by,
                  Rgb col, bool dashed, double& dash) {
  double t0 = 0.0, t1 = 1.0;
  const double dx = bx - ax, dy = by - ay;
  const double xmin = r.x0, xmax = r.x1 - 1, ymin = r.y0, ymax = r.y1 - 1;
  const std::array<std::pair<double, double>, 4> pq{
      {{-dx, ax - xmin}, {dx, xmax - ax}, {-dy, ay - ymin}, {dy, ymax - ay}}};
  for (const auto& [p, q] : pq) {
    if (p == 0.0) {
      if (q < 0.0)
        return;
      continue;
    }
    const double t = q / p;
    if (p < 0.0)
      t0 = std::max(t0, t);
    else
      t1 = std::min(t1, t);
    if (t0 > t1)
      return;
  }
  const double len = std::hypot(dx, dy) * (t1 - t0);
  const int steps = std::max(1, static_cast<int>(std::ceil(len * 2.0)));
  for (int i = 0; i <= steps; ++i) {
    const double t = t0 + (t1 - t0) * i / steps;
    const double d = dash + len * i / steps;
    if (dashed && std::fmod(d, 14.0) > 8.0)
      continue;
    const int x = static_cast<int>(std::lround(ax + t * dx));
    const int y = static_cast<int>(std::lround(ay + t * dy));
    c.rect(x, y, x + 1, y + 1, col);
  }
  dash += len;
}

void draw_marker(Canvas& c, int x, int y, int shape, Rgb col) {
  if (shape == 0) {
    c.rect(x - 3, y - 3, x + 3, y + 3, col);
  } else if (shape == 1) {
    c.line(x - 4, y - 4, x + 4, y - 4, col);
    c.line(x - 4, y + 4, x + 4, y + 4, col);
    c.line(x - 4, y - 4, x - 4, y + 4, col);
    c.line(x + 4, y - 4, x + 4, y + 4, col);
  } else {
    c.line(x - 4, y - 4, x + 4, y + 4, col);
    c.line(x - 4, y + 4, x + 4, y - 4, col);
  }
}

void draw_frame(Canvas& c, const PixelRect& r) {
  c.line(r.x0 - 1, r.y0 - 1, r.x1 + 1, r.y0 - 1, kInk);
  c.line(r.x0 - 1, r.y1 + 1, r.x1 + 1, r.y1 + 1, kInk);
  c.line(r.x0 - 1, r.y0 - 1, r.x0 - 1, r.y1 + 1, kInk);
  c.line(r.x1 + 1, r.y0 - 1, r.x1 + 1, r.y1 + 1, kInk);
}

// Ticks and labels of both axes outside `r`; x(v) / y(v) give the pixel of a data value.
template <class FX, class FY>
void draw_ticks(Canvas& c, const PixelRect& r, const AxisTicks& xt, const AxisTicks& yt, FX x_of,
                FY y_of, bool grid) {
  if (grid) {
    for (double t : xt.minor)
      c.line(x_of(t), r.y0, x_of(t), r.y1, kMinorGrid);
    for (double t : yt.minor)
      c.line(r.x0, y_of(t), r.x1, y_of(t), kMinorGrid);
    for (double t : xt.major)
      c.line(x_of(t), r.y0, x_of(t), r.y1, kGrid);
    for (double t : yt.major)
      c.line(r.x0, y_of(t), r.x1, y_of(t), kGrid);
  }
  for (double t : xt.minor)
    c.line(x_of(t), r.y1 + 1, x_of(t), r.y1 + 1 + kMinorTick, kInk);
  for (double t : yt.minor)
    c.line(r.x0 - 1 - kMinorTick, y_of(t), r.x0 - 1, y_of(t), kInk);
  for (std::size_t i = 0; i < xt.major.size(); ++i) {
    const int x = x_of(xt.major[i]);
    c.line(x, r.y1 + 1, x, r.y1 + 1 + kTick, kInk);
    const int w = label_width(xt.labels[i], kScale);
    draw_label(c, x - w / 2, r.y1 + kTick + 8, xt.labels[i], kInk, kScale);
  }
  for (std::size_t i = 0; i < yt.major.size(); ++i) {
    const int y = y_of(yt.major[i]);
    c.line(r.x0 - 1 - kTick, y, r.x0 - 1, y, kInk);
    const int w = label_width(yt.labels[i], kScale);
    draw_label(c, r.x0 - kTick - 6 - w, y - 7, yt.labels[i], kInk, kScale);
  }
}

// Space under the plot: tick, tick labels, axis label.
int space_below(bool has_x_label) {
  return kTick + 8 + 2 * 10 + 8 + (has_x_label ? kLine : 0);
}
// Space left of the plot: the rotated y label and the tick labels.
int space_left(bool has_y_label, int tick_label_width) {
  return kMargin + (has_y_label ? Canvas::text_height(kScale) + 10 : 0) + tick_label_width + 6 +
         kTick;
}

void draw_axis_labels(Canvas& c, const PixelRect& r, const std::string& xl, const std::string& yl) {
  if (!xl.empty()) {
    const int w = Canvas::text_width(xl, kScale);
    c.text(std::max(kMargin, (r.x0 + r.x1 - w) / 2), r.y1 + kTick + 8 + 2 * 10 + 8, xl, kInk,
           kScale);
  }
  if (!yl.empty()) {
    const int h = Canvas::text_width(yl, kScale);
    c.text_up(kMargin, std::max(kMargin, (r.y0 + r.y1 - h) / 2), yl, kInk, kScale);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

Rgb series_colour(std::size_t k) noexcept {
  return kPalette[k % kPalette.size()];
}

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> out;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi))
    return out;
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * mag;
    if (step >= raw)
      break;
  }
  // (At most 1000 ticks: a span far below the values' precision would not advance k.)
  double k = std::ceil(lo / step - 1e-9);
  for (int n = 0; n < 1000 && k * step <= hi + 1e-9 * step; ++n, k += 1.0)
    out.push_back(k == 0.0 ? 0.0 : k * step);
  return out;
}

std::string format_tick(double v, double step) {
  char buf[40];
  if (!(step > 0.0) || !std::isfinite(step))
    step = std::abs(v) > 0.0 ? std::abs(v) : 1.0;
  if (std::abs(v) < 1e-9 * step)
    return "0";
  if (std::abs(v) >= 1e6 || step < 1e-4) {
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
  }
  const int decimals =
      step >= 1.0 ? 0 : std::min(10, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

AxisTicks axis_ticks(double lo, double hi, bool log_axis, int target) {
  AxisTicks t;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi))
    return t;
  if (!log_axis || !(lo > 0.0)) {
    t.major = nice_ticks(lo, hi, target);
    const double step = t.major.size() > 1 ? t.major[1] - t.major[0] : hi - lo;
    for (double v : t.major)
      t.labels.push_back(format_tick(v, step));
    return t;
  }
  const double span = std::log10(hi / lo);
  const int stride = std::max(1, static_cast<int>(std::ceil(span / 12.0)));
  const int k_lo = static_cast<int>(std::floor(std::log10(lo))) - 1;
  const int k_hi = static_cast<int>(std::ceil(std::log10(hi))) + 1;
  auto inside = [&](double v) { return v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9); };
  struct Mk {
    int m, k;
  };
  std::vector<Mk> major, minor;
  for (int k = k_lo; k <= k_hi; ++k) {
    for (int m = 1; m <= 9; ++m) {
      if (!inside(m * std::pow(10.0, k)))
        continue;
      if (m == 1 && k % stride == 0)
        major.push_back({m, k});
      else if (span <= 8.0 && m > 1)
        minor.push_back({m, k});
    }
  }
  if (major.size() < 3) {  // few decades: 2 and 5 get labels too
    std::vector<Mk> keep;
    for (const Mk& x : minor) {
      if (x.m == 2 || x.m == 5)
        major.push_back(x);
      else
        keep.push_back(x);
    }
    minor = std::move(keep);
    std::sort(major.begin(), major.end(), [](const Mk& a, const Mk& b) {
      return a.m * std::pow(10.0, a.k) < b.m * std::pow(10.0, b.k);
    });
  }
  if (major.size() < 2) {  // less than a 1-2-5 step: linear labels, mantissa ticks kept as minor
    t.major = nice_ticks(lo, hi, 4);
    const double step = t.major.size() > 1 ? t.major[1] - t.major[0] : hi - lo;
    for (double v : t.major)
      t.labels.push_back(format_tick(v, step));
    for (const Mk& x : minor)
      t.minor.push_back(x.m * std::pow(10.0, x.k));
    return t;
  }
  const bool plain =
      std::all_of(major.begin(), major.end(), [](const Mk& x) { return x.k >= -3 && x.k <= 4; });
  for (const Mk& x : major) {
    t.major.push_back(x.m * std::pow(10.0, x.k));
    if (plain) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.*f", std::max(0, -x.k), x.m * std::pow(10.0, x.k));
      t.labels.push_back(buf);
    } else {
      t.labels.push_back((x.m == 1 ? std::string() : std::to_string(x.m) + "x") + "10^" +
                         std::to_string(x.k));
    }
  }
  for (const Mk& x : minor)
    t.minor.push_back(x.m * std::pow(10.0, x.k));
  return t;
}

std::string unit_of(const std::string& label) {
  const std::size_t open = label.rfind('[');
  if (open == std::string::npos)
    return {};
  const std::size_t close = label.find(']', open);
  if (close == std::string::npos)
    return {};
  return label.substr(open + 1, close - open - 1);
}

std::vector<std::string> wrap_text(const std::string& text, int max_width_px, int scale) {
  std::vector<std::string> lines;
  std::string line;
  auto fits = [&](const std::string& s) { return Canvas::text_width(s, scale) <= max_width_px; };
  std::size_t i = 0;
  while (i < text.size()) {
    const std::size_t sp = std::min(text.find(' ', i), text.size());
    std::string word = text.substr(i, sp - i);
    i = sp + 1;
    const std::string joined = line.empty() ? word : line + " " + word;
    if (fits(joined)) {
      line = joined;
      continue;
    }
    if (!line.empty())
      lines.push_back(line);
    line.clear();
    while (!word.empty() && !fits(word)) {  // a word wider than a line: cut it
      std::size_t n = word.size();
      while (n > 1 && !fits(word.substr(0, n)))
        --n;
      lines.push_back(word.substr(0, n));
      word.erase(0, n);
    }
    line = word;
  }
  if (!line.empty())
    lines.push_back(line);
  return lines;
}

// ---------------------------------------------------------------------------------------------
// Line charts

double ChartLayout::fx(double x) const noexcept {
  return plot.x0 + (axis_t(x, log_x) - axis_t(x0, log_x)) /
                       (axis_t(x1, log_x) - axis_t(x0, log_x)) * (plot.width() - 1);
}

double ChartLayout::fy(double y) const noexcept {
  return plot.y1 - (axis_t(y, log_y) - axis_t(y0, log_y)) /
                       (axis_t(y1, log_y) - axis_t(y0, log_y)) * (plot.height() - 1);
}

ChartLayout line_chart_layout(const LineChart& chart) {
  check_size(chart.width, chart.height);
  ChartLayout L;
  L.width = chart.width;
  L.height = chart.height;
  L.log_x = chart.log_x;
  L.log_y = chart.log_y;
  Range xr, yr;
  for (const Series& s : chart.series) {
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("chart: series '" + s.label + "' has mismatched x and y");
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || (chart.log_x && !(s.x[i] > 0.0)) ||
          (chart.log_y && !(s.y[i] > 0.0)))
        continue;
      xr.add(s.x[i]);
      yr.add(s.y[i]);
    }
  }
  if (xr.empty())
    throw std::invalid_argument("chart '" + chart.title + "': no finite data" +
                                (chart.log_x || chart.log_y ? " (> 0 on a log axis)" : ""));
  L.x0 = xr.lo;
  L.x1 = xr.hi;
  L.y0 = yr.lo;
  L.y1 = yr.hi;
  settle_range(L.x0, L.x1, chart.x_min, chart.x_max, chart.log_x, 0.0, "x");
  settle_range(L.y0, L.y1, chart.y_min, chart.y_max, chart.log_y, 0.04, "y");
  L.x_ticks = axis_ticks(L.x0, L.x1, chart.log_x);
  L.y_ticks = axis_ticks(L.y0, L.y1, chart.log_y);

  int top = 0;
  L.title = layout_title(chart.title, chart.width, top);
  top += 14;

  // Legend: a column right of the plot when the labels are short, else rows of columns below.
  std::vector<int> entry_w;
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    if (chart.series[k].label.empty())
      continue;
    L.legend_series.push_back(k);
    entry_w.push_back(kSwatch + 8 + Canvas::text_width(chart.series[k].label, kScale));
  }
  const int legend_w = entry_w.empty() ? 0 : *std::max_element(entry_w.begin(), entry_w.end());
  const bool right = !entry_w.empty() && legend_w <= chart.width * 3 / 10 &&
                     static_cast<int>(entry_w.size()) * kLine <= chart.height / 2;
  const bool below = !entry_w.empty() && !right;
  int columns = 1, rows = 0;
  if (below) {
    columns = std::max(1, (chart.width - 2 * kMargin) / (legend_w + 20));
    rows = (static_cast<int>(entry_w.size()) + columns - 1) / columns;
  }
  const int left = space_left(!chart.y_label.empty(), max_label_width(L.y_ticks.labels, kScale));
  const int last_x_label =
      L.x_ticks.labels.empty() ? 0 : label_width(L.x_ticks.labels.back(), kScale);
  int right_space = std::max(kMargin + 4, last_x_label / 2 + kMargin);
  if (right)
    right_space = std::max(right_space, legend_w + 16 + kMargin);
  const int bottom =
      space_below(!chart.x_label.empty()) + (below ? rows * kLine + 10 : 0) + kMargin;
  L.plot = PixelRect{left, top, chart.width - right_space - 1, chart.height - bottom - 1};
  if (L.plot.width() < 80 || L.plot.height() < 60)
    throw std::invalid_argument("chart '" + chart.title +
                                "': no room left for the data beside its title and legend");
  for (std::size_t e = 0; e < entry_w.size(); ++e) {
    const int i = static_cast<int>(e);
    if (right) {
      const int x = L.plot.x1 + 16, y = L.plot.y0 + i * kLine;
      L.legend.push_back(PixelRect{x, y, x + entry_w[e] - 1, y + kLine - 4});
    } else {
      const int x = L.plot.x0 + (i % columns) * (legend_w + 20);
      const int y = L.plot.y1 + space_below(!chart.x_label.empty()) + 6 + (i / columns) * kLine;
      L.legend.push_back(PixelRect{x, y, x + entry_w[e] - 1, y + kLine - 4});
    }
  }
  L.legend_scale = kScale;
  return L;
}

Canvas render_line_chart(const LineChart& chart) {
  const ChartLayout L = line_chart_layout(chart);
  Canvas c(L.width, L.height, kBackground);
  auto x_of = [&](double v) { return static_cast<int>(std::lround(L.fx(v))); };
  auto y_of = [&](double v) { return static_cast<int>(std::lround(L.fy(v))); };
  draw_ticks(c, L.plot, L.x_ticks, L.y_ticks, x_of, y_of, true);
  auto ok = [&](double x, double y) {
    return std::isfinite(x) && std::isfinite(y) && (!L.log_x || x > 0.0) && (!L.log_y || y > 0.0);
  };
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    const Series& s = chart.series[k];
    const Rgb col = s.colour.value_or(series_colour(k));
    const int shape = static_cast<int>(k / kPalette.size()) % 3;
    bool have_prev = false;
    double xp = 0, yp = 0, dash = 0;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!ok(s.x[i], s.y[i])) {
        have_prev = false;
        continue;
      }
      const double x = L.fx(s.x[i]), y = L.fy(s.y[i]);
      if (have_prev)
        draw_segment(c, L.plot, xp, yp, x, y, col, s.dashed, dash);
      const bool in = x >= L.plot.x0 && x <= L.plot.x1 && y >= L.plot.y0 && y <= L.plot.y1;
      if (in && (s.markers || s.x.size() == 1))
        draw_marker(c, static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)), shape,
                    col);
      have_prev = true;
      xp = x;
      yp = y;
    }
  }
  draw_frame(c, L.plot);
  for (const TextLine& t : L.title)
    c.text(t.x, t.y, t.text, kInk, t.scale);
  draw_axis_labels(c, L.plot, chart.x_label, chart.y_label);
  for (std::size_t e = 0; e < L.legend.size(); ++e) {
    const std::size_t k = L.legend_series[e];
    const Series& s = chart.series[k];
    const Rgb col = s.colour.value_or(series_colour(k));
    const PixelRect& r = L.legend[e];
    const int ym = r.y0 + 7;
    double dash = 0;
    PixelRect whole{0, 0, L.width - 1, L.height - 1};
    draw_segment(c, whole, r.x0, ym, r.x0 + kSwatch - 4, ym, col, s.dashed, dash);
    if (s.markers)
      draw_marker(c, r.x0 + (kSwatch - 4) / 2, ym, static_cast<int>(k / kPalette.size()) % 3, col);
    c.text(r.x0 + kSwatch + 8, r.y0, s.label, kInk, L.legend_scale);
  }
  return c;
}

void write_line_chart_png(const LineChart& chart, const std::filesystem::path& path) {
  render_line_chart(chart).write_png(path);
}

// ---------------------------------------------------------------------------------------------
// Heat maps

namespace {

// Cell edges of pixel centres: midpoints, the ends half a spacing out.
std::vector<double> cell_edges(const std::vector<double>& c) {
  std::vector<double> e(c.size() + 1);
  if (c.size() == 1) {
    e[0] = c[0] - 0.5;
    e[1] = c[0] + 0.5;
    return e;
  }
  for (std::size_t i = 1; i < c.size(); ++i)
    e[i] = 0.5 * (c[i - 1] + c[i]);
  e[0] = c[0] - (e[1] - c[0]);
  e.back() = c.back() + (c.back() - e[c.size() - 1]);
  return e;
}

Rgb scale_colour(const Heatmap& m, double f) noexcept {
  if (!m.grey)
    return colour_map(f);
  const auto g = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(f, 0.0, 1.0)));
  return Rgb{g, g, g};
}

std::size_t cell_of(const std::vector<double>& edges, double v) {
  const auto it = std::upper_bound(edges.begin() + 1, edges.end() - 1, v);
  return static_cast<std::size_t>(it - (edges.begin() + 1));
}

void check_axis(const std::vector<double>& a, const std::string& title, const char* which) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i]) || (i > 0 && !(a[i] > a[i - 1])))
      throw std::invalid_argument("heat map '" + title + "': " + which +
                                  " centres must be finite and ascending");
  }
}

}  // namespace

int HeatmapLayout::px(double x) const noexcept {
  const double r = (x - x0) / (x1 - x0);
  const double f = std::isfinite(r) ? std::clamp(r, -1.0, 2.0) : 0.0;
  return std::clamp(image.x0 + static_cast<int>(std::floor(f * image.width())), image.x0, image.x1);
}

int HeatmapLayout::py(double y) const noexcept {
  const double r = (y - y0) / (y1 - y0);
  const double f = std::isfinite(r) ? std::clamp(r, -1.0, 2.0) : 0.0;
  return std::clamp(image.y1 - static_cast<int>(std::floor(f * image.height())), image.y0,
                    image.y1);
}

int HeatmapLayout::bar_row(double value) const noexcept {
  const double r = (value - value_lo) / (value_hi - value_lo);
  const double f = std::isfinite(r) ? std::clamp(r, 0.0, 1.0) : 0.0;
  return colour_bar.y1 - static_cast<int>(std::lround(f * (colour_bar.height() - 1)));
}

HeatmapLayout heatmap_layout(const Heatmap& m) {
  check_size(m.width, m.height);
  const bool picture = !m.rgb.empty();
  if (m.x.empty() || m.y.empty() ||
      (picture ? m.rgb.size() != m.x.size() * m.y.size() * 3
               : m.values.size() != m.x.size() * m.y.size()))
    throw std::invalid_argument("heat map '" + m.title + "': empty or inconsistent data");
  check_axis(m.x, m.title, "x");
  check_axis(m.y, m.title, "y");
  if (!(m.value_range > 0.0) || !std::isfinite(m.value_range) || !std::isfinite(m.value_max))
    throw std::invalid_argument("heat map '" + m.title +
                                "': the colour scale needs a finite top "
                                "and a range > 0");
  HeatmapLayout L;
  L.width = m.width;
  L.height = m.height;
  const std::vector<double> ex = cell_edges(m.x), ey = cell_edges(m.y);
  L.x0 = ex.front();
  L.x1 = ex.back();
  L.y0 = ey.front();
  L.y1 = ey.back();
  L.value_hi = m.value_max;
  L.value_lo = m.value_max - m.value_range;
  L.x_ticks = axis_ticks(L.x0, L.x1, false);
  L.y_ticks = axis_ticks(L.y0, L.y1, false);
  L.bar_ticks = axis_ticks(L.value_lo, L.value_hi, false, 5);
  const std::string xu = unit_of(m.x_label);
  L.equal_aspect = m.equal_aspect.value_or(!xu.empty() && xu == unit_of(m.y_label));

  int top = 0;
  L.title = layout_title(m.title, m.width, top);
  top += 14;
  const int left = space_left(!m.y_label.empty(), max_label_width(L.y_ticks.labels, kScale));
  const int bottom = space_below(!m.x_label.empty()) + kMargin;
  const int last_x_label =
      L.x_ticks.labels.empty() ? 0 : label_width(L.x_ticks.labels.back(), kScale);
  constexpr int kBarGap = 18, kBarWidth = 20;
  const int bar_space =
      picture ? kMargin
              : kBarGap + kBarWidth + kTick + 6 + max_label_width(L.bar_ticks.labels, kScale) +
                    (m.value_label.empty() ? 0 : 10 + Canvas::text_height(kScale)) + kMargin;
  const int right_space = std::max(bar_space, last_x_label / 2 + kMargin);
  const PixelRect avail{left, top, m.width - right_space - 1, m.height - bottom - 1};
  if (avail.width() < 60 || avail.height() < 60)
    throw std::invalid_argument("heat map '" + m.title + "': no room left for the image");
  L.image = avail;
  if (L.equal_aspect) {
    const double sx = avail.width() / (L.x1 - L.x0), sy = avail.height() / (L.y1 - L.y0);
    const double s = std::min(sx, sy);
    const int w = std::max(1, static_cast<int>(std::floor((L.x1 - L.x0) * s + 1e-9)));
    const int h = std::max(1, static_cast<int>(std::floor((L.y1 - L.y0) * s + 1e-9)));
    L.image.x0 = avail.x0 + (avail.width() - w) / 2;
    L.image.x1 = L.image.x0 + w - 1;
    L.image.y0 = avail.y0 + (avail.height() - h) / 2;
    L.image.y1 = L.image.y0 + h - 1;
  }
  L.colour_bar =
      PixelRect{L.image.x1 + kBarGap, L.image.y0, L.image.x1 + kBarGap + kBarWidth - 1, L.image.y1};
  if (picture) {
    L.colour_bar = PixelRect{L.image.x1 + 1, L.image.y0, L.image.x1, L.image.y1};
  } else if (L.colour_bar.height() < 60) {  // a flat image: the bar keeps a readable height
    const int mid = (L.image.y0 + L.image.y1) / 2;
    L.colour_bar.y0 = std::max(avail.y0, mid - 30);
    L.colour_bar.y1 = std::min(avail.y1, L.colour_bar.y0 + 59);
  }
  return L;
}

Canvas render_heatmap(const Heatmap& m) {
  const HeatmapLayout L = heatmap_layout(m);
  Canvas c(L.width, L.height, kBackground);
  const std::vector<double> ex = cell_edges(m.x), ey = cell_edges(m.y);
  const double range = L.value_hi - L.value_lo;
  // Each image pixel from the cell holding its centre.
  for (int py = L.image.y0; py <= L.image.y1; ++py) {
    const double y = L.y0 + (L.image.y1 - py + 0.5) / L.image.height() * (L.y1 - L.y0);
    const std::size_t iy = cell_of(ey, y);
    for (int px = L.image.x0; px <= L.image.x1; ++px) {
      const double x = L.x0 + (px - L.image.x0 + 0.5) / L.image.width() * (L.x1 - L.x0);
      const std::size_t i = iy * m.x.size() + cell_of(ex, x);
      if (!m.rgb.empty()) {
        c.put(px, py, Rgb{m.rgb[3 * i], m.rgb[3 * i + 1], m.rgb[3 * i + 2]});
        continue;
      }
      const double v = m.values[i];
      c.put(px, py, std::isfinite(v) ? scale_colour(m, (v - L.value_lo) / range) : kMissing);
    }
  }
  // Axes: ticks at the cells' data coordinates (the centre of the pixel holding the value).
  const double wx = (L.x1 - L.x0) / L.image.width(), wy = (L.y1 - L.y0) / L.image.height();
  auto x_of = [&](double v) { return L.px(std::min(v, L.x1 - 0.5 * wx)); };
  auto y_of = [&](double v) { return L.py(std::min(v, L.y1 - 0.5 * wy)); };
  draw_ticks(c, L.image, L.x_ticks, L.y_ticks, x_of, y_of, false);
  draw_frame(c, L.image);
  for (const TextLine& t : L.title)
    c.text(t.x, t.y, t.text, kInk, t.scale);
  draw_axis_labels(c, L.image, m.x_label, m.y_label);

  // Colour bar: ticks and labels on its right, the label (unit) beyond them, read upward.
  const PixelRect& b = L.colour_bar;
  for (int row = b.y0; row <= b.y1; ++row) {
    c.rect(b.x0, row, b.x1, row,
           scale_colour(m, static_cast<double>(b.y1 - row) / (b.height() - 1)));
  }
  if (b.width() > 0)
    draw_frame(c, b);
  int label_right = b.x1 + 2 + kTick;
  for (std::size_t i = 0; b.width() > 0 && i < L.bar_ticks.major.size(); ++i) {
    const int row = L.bar_row(L.bar_ticks.major[i]);
    c.line(b.x1 + 2, row, b.x1 + 1 + kTick, row, kInk);
    draw_label(c, b.x1 + kTick + 6, row - 7, L.bar_ticks.labels[i], kInk, kScale);
    label_right =
        std::max(label_right, b.x1 + kTick + 6 + label_width(L.bar_ticks.labels[i], kScale));
  }
  if (!m.value_label.empty() && b.width() > 0) {
    const int h = Canvas::text_width(m.value_label, kScale);
    c.text_up(label_right + 10, std::max(kMargin, (b.y0 + b.y1 - h) / 2), m.value_label, kInk,
              kScale);
  }

  // Scale bar, lower left inside the image.
  if (m.scale_bar) {
    const double span = L.x1 - L.x0;
    const double len = *m.scale_bar > 0.0 ? *m.scale_bar : nice_125(span / 5.0, false);
    const int n = static_cast<int>(std::lround(len / span * L.image.width()));
    const int x = L.image.x0 + 14, y = L.image.y1 - 16;
    char buf[48];
    std::snprintf(buf, sizeof buf, "%g %s", len, unit_of(m.x_label).c_str());
    c.rect(x - 2, y - 2, x + n + 1, y + 5, kInk);
    c.rect(x, y, x + n - 1, y + 3, kBackground);
    c.text(x + 1, y - 24 + 1, buf, kInk, kScale);
    c.text(x, y - 24, buf, kBackground, kScale);
  }
  return c;
}

void write_heatmap_png(const Heatmap& map, const std::filesystem::path& path) {
  render_heatmap(map).write_png(path);
}

Canvas join_panels(const std::vector<Canvas>& panels) {
  if (panels.empty())
    throw std::invalid_argument("join_panels: no panels");
  int w = 0, h = 0;
  for (const Canvas& p : panels) {
    w += p.width();
    h = std::max(h, p.height());
  }
  Canvas out(w, h, kBackground);
  int x = 0;
  for (const Canvas& p : panels) {
    out.blit(p, x, 0);
    x += p.width();
  }
  return out;
}

Canvas stack_panels(const std::vector<Canvas>& panels) {
  if (panels.empty())
    throw std::invalid_argument("stack_panels: no panels");
  int w = 0, h = 0;
  for (const Canvas& p : panels) {
    w = std::max(w, p.width());
    h += p.height();
  }
  Canvas out(w, h, kBackground);
  int y = 0;
  for (const Canvas& p : panels) {
    out.blit(p, 0, y);
    y += p.height();
  }
  return out;
}

}  // namespace radar_emu::plot
