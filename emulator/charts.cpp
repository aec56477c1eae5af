#include "emulator/charts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace radar_emu::emulator {

namespace {

constexpr int kWidth = 1000, kHeight = 640;
constexpr int kLeft = 90, kRight = 30, kTop = 50, kBottom = 70;
const Rgb kBackground{255, 255, 255}, kInk{30, 30, 30}, kGrid{225, 225, 225};
constexpr std::array<Rgb, 8> kPalette{{{31, 119, 180},
                                       {214, 39, 40},
                                       {44, 160, 44},
                                       {255, 127, 14},
                                       {148, 103, 189},
                                       {23, 190, 207},
                                       {30, 30, 30},
                                       {140, 86, 75}}};

std::string format_tick(double v) {
  char buf[32];
  if (std::abs(v) >= 1e5 || (std::abs(v) < 1e-3 && v != 0.0))
    std::snprintf(buf, sizeof buf, "%.3g", v);
  else
    std::snprintf(buf, sizeof buf, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

struct Frame {
  double x0, x1, y0, y1;
  int px(double x) const {
    return kLeft + static_cast<int>(std::lround((x - x0) / (x1 - x0) * (kWidth - kLeft - kRight)));
  }
  int py(double y) const {
    return kHeight - kBottom -
           static_cast<int>(std::lround((y - y0) / (y1 - y0) * (kHeight - kTop - kBottom)));
  }
};

void draw_axes(Canvas& c, const Frame& f, const std::string& title, const std::string& xl,
               const std::string& yl, bool grid) {
  for (double t : nice_ticks(f.x0, f.x1)) {
    const int x = f.px(t);
    if (grid)
      c.line(x, kTop, x, kHeight - kBottom, kGrid);
    c.line(x, kHeight - kBottom, x, kHeight - kBottom + 5, kInk);
    const std::string s = format_tick(t);
    c.text(x - Canvas::text_width(s, 2) / 2, kHeight - kBottom + 10, s, kInk, 2);
  }
  for (double t : nice_ticks(f.y0, f.y1)) {
    const int y = f.py(t);
    if (grid)
      c.line(kLeft, y, kWidth - kRight, y, kGrid);
    c.line(kLeft - 5, y, kLeft, y, kInk);
    const std::string s = format_tick(t);
    c.text(kLeft - 10 - Canvas::text_width(s, 2), y - 7, s, kInk, 2);
  }
  c.line(kLeft, kTop, kLeft, kHeight - kBottom, kInk);
  c.line(kLeft, kHeight - kBottom, kWidth - kRight, kHeight - kBottom, kInk);
  c.text(kLeft, 4, title, kInk, 2);
  c.text((kLeft + kWidth - kRight - Canvas::text_width(xl, 2)) / 2, kHeight - 28, xl, kInk, 2);
  c.text(6, kTop - 20, yl, kInk, 2);
}

}  // namespace

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
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    out.push_back(t);
  return out;
}

void write_line_chart_png(const LineChart& chart, const std::filesystem::path& path) {
  render_line_chart(chart).write_png(path);
}

Canvas render_line_chart(const LineChart& chart) {
  double x0 = std::numeric_limits<double>::max(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const Series& s : chart.series) {
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("chart: series '" + s.label + "' has mismatched x and y");
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]))
        continue;
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]);
      y1 = std::max(y1, s.y[i]);
    }
  }
  if (!(x1 >= x0))
    throw std::invalid_argument("chart '" + chart.title + "': no finite data");
  if (chart.y_min)
    y0 = *chart.y_min;
  if (chart.y_max)
    y1 = *chart.y_max;
  if (x1 == x0) {
    x0 -= 0.5;
    x1 += 0.5;
  }
  if (!(y1 > y0)) {
    y0 -= 1.0;
    y1 += 1.0;
  }
  const double pad = 0.04 * (y1 - y0);
  if (!chart.y_min)
    y0 -= pad;
  if (!chart.y_max)
    y1 += pad;
  const Frame f{x0, x1, y0, y1};
  Canvas c(kWidth, kHeight, kBackground);
  draw_axes(c, f, chart.title, chart.x_label, chart.y_label, true);
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    const Series& s = chart.series[k];
    const Rgb col = kPalette[k % kPalette.size()];
    bool have_prev = false;
    int px_prev = 0, py_prev = 0;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        have_prev = false;
        continue;
      }
      const int px = f.px(s.x[i]);
      const int py = std::clamp(f.py(std::clamp(s.y[i], y0, y1)), kTop, kHeight - kBottom);
      if (have_prev) {
        c.line(px_prev, py_prev, px, py, col);
        c.line(px_prev, py_prev + 1, px, py + 1, col);
      } else if (s.x.size() == 1) {
        c.rect(px - 3, py - 3, px + 3, py + 3, col);
      }
      have_prev = true;
      px_prev = px;
      py_prev = py;
    }
    // Legend, top right.
    const int ly = kTop + 8 + static_cast<int>(k) * 22;
    const int lx = kWidth - kRight - 150;
    c.rect(lx, ly + 5, lx + 24, ly + 7, col);
    c.text(lx + 32, ly, s.label, kInk, 2);
  }
  return c;
}

void write_heatmap_png(const Heatmap& m, const std::filesystem::path& path) {
  if (m.x.empty() || m.y.empty() || m.values.size() != m.x.size() * m.y.size())
    throw std::invalid_argument("heat map '" + m.title + "': empty or inconsistent data");
  const double dx = m.x.size() > 1 ? (m.x.back() - m.x.front()) / double(m.x.size() - 1) : 1.0;
  const double dy = m.y.size() > 1 ? (m.y.back() - m.y.front()) / double(m.y.size() - 1) : 1.0;
  const Frame f{m.x.front() - dx / 2, m.x.back() + dx / 2, m.y.front() - dy / 2,
                m.y.back() + dy / 2};
  Canvas c(kWidth, kHeight, kBackground);
  const double lo = m.value_max - m.value_range;
  // Paint each plot pixel from the nearest sample.
  for (int py = kTop; py <= kHeight - kBottom; ++py) {
    const double y =
        f.y0 + (kHeight - kBottom - py + 0.5) / (kHeight - kTop - kBottom) * (f.y1 - f.y0);
    const auto iy = static_cast<std::size_t>(
        std::clamp(std::floor((y - f.y0) / dy), 0.0, static_cast<double>(m.y.size() - 1)));
    for (int px = kLeft; px <= kWidth - kRight; ++px) {
      const double x = f.x0 + (px - kLeft + 0.5) / (kWidth - kLeft - kRight) * (f.x1 - f.x0);
      const auto ix = static_cast<std::size_t>(
          std::clamp(std::floor((x - f.x0) / dx), 0.0, static_cast<double>(m.x.size() - 1)));
      const double v = m.values[iy * m.x.size() + ix];
      c.put(px, py, colour_map((v - lo) / m.value_range));
    }
  }
  draw_axes(c, f, m.title, m.x_label, m.y_label, false);
  // Colour bar.
  const int bx = kWidth - kRight + 6;
  for (int py = kTop; py <= kHeight - kBottom; ++py) {
    const double t = double(kHeight - kBottom - py) / (kHeight - kTop - kBottom);
    c.rect(bx, py, bx + 12, py, colour_map(t));
  }
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.0f", m.value_max);
  c.text(bx - 30, kTop - 14, buf, kInk, 1);
  std::snprintf(buf, sizeof buf, "%.0f %s", lo, m.value_label.c_str());
  c.text(bx - 60, kHeight - kBottom + 30, buf, kInk, 1);
  c.write_png(path);
}

}  // namespace radar_emu::emulator
