#include "loop/outputs/run_plots.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "common/units.hpp"
#include "plot/canvas.hpp"
#include "plot/charts.hpp"

namespace radar_emu::loop {

using plot::Canvas;
using plot::format_tick;
using plot::LineChart;
using plot::nice_ticks;
using plot::render_line_chart;
using plot::Rgb;
using plot::Series;

namespace {

// Blue (start of the run) to red (end).
Rgb time_colour(double f) noexcept {
  f = std::clamp(f, 0.0, 1.0);
  return {static_cast<std::uint8_t>(40 + 215 * f),
          static_cast<std::uint8_t>(90 + 60 * (1 - std::abs(2 * f - 1))),
          static_cast<std::uint8_t>(255 - 215 * f)};
}

}  // namespace

int BScopeLayout::x_of(double azimuth_deg) const noexcept {
  const double f = (azimuth_deg - azimuth_min_deg) / (azimuth_max_deg - azimuth_min_deg);
  return kLeft + static_cast<int>(std::lround(f * (kWidth - kLeft - kRight - 1)));
}

int BScopeLayout::y_of(double range_m) const noexcept {
  const double f = range_m / range_max_m;
  return kHeight - kBottom - static_cast<int>(std::lround(f * (kHeight - kTop - kBottom - 1)));
}

namespace {
const Rgb kBScopeBackground{16, 20, 28}, kBScopeGrid{55, 62, 78}, kBScopeInk{210, 215, 225};
}  // namespace

BScope::BScope(const Scenario& s, std::uint64_t frames_planned)
    : canvas_(BScopeLayout::kWidth, BScopeLayout::kHeight, kBScopeBackground),
      colour_scale_(1.0 / std::max(1.0, static_cast<double>(frames_planned) - 1.0)) {
  BScopeLayout& L = layout_;
  L.azimuth_min_deg = common::degrees(s.sbr.azimuth_min_rad);
  L.azimuth_max_deg = common::degrees(s.sbr.azimuth_max_rad);
  L.range_max_m = s.sensor.max_range_m;
  Canvas& c = canvas_;
  char label[64];
  // Grids and labels at 1-2-5 steps (charts.hpp's ticks): range in km up the left, azimuth in
  // deg along the bottom; the axis titles with their units.
  const std::vector<double> range_km = nice_ticks(0.0, L.range_max_m / 1000.0, 6);
  for (double r : range_km) {
    const int y = L.y_of(r * 1000.0);
    c.rect(BScopeLayout::kLeft, y, BScopeLayout::kWidth - BScopeLayout::kRight - 1, y, kBScopeGrid);
    const std::string t = format_tick(r, range_km.size() > 1 ? range_km[1] - range_km[0] : 1.0);
    c.text(BScopeLayout::kLeft - 8 - Canvas::text_width(t, 2), y - 6, t, kBScopeInk, 2);
  }
  const std::string range_title = "range [km]";
  c.text_up(6,
            (BScopeLayout::kTop + BScopeLayout::kHeight - BScopeLayout::kBottom -
             Canvas::text_width(range_title, 2)) /
                2,
            range_title, kBScopeInk, 2);
  const std::vector<double> az = nice_ticks(L.azimuth_min_deg, L.azimuth_max_deg, 8);
  for (double a : az) {
    const int x = L.x_of(a);
    c.rect(x, BScopeLayout::kTop, x, BScopeLayout::kHeight - BScopeLayout::kBottom - 1,
           kBScopeGrid);
    std::snprintf(label, sizeof label, std::abs(a) < 1e-9 ? "0" : "%+g", a);
    c.text(x - Canvas::text_width(label, 2) / 2, BScopeLayout::kHeight - BScopeLayout::kBottom + 8,
           label, kBScopeInk, 2);
  }
  const std::string az_title = "azimuth [deg], right of boresight";
  c.text((BScopeLayout::kLeft + BScopeLayout::kWidth - BScopeLayout::kRight -
          Canvas::text_width(az_title, 2)) /
             2,
         BScopeLayout::kHeight - 24, az_title, kBScopeInk, 2);
}

void BScope::add_frame(std::span<const io::icd::Detection> detections) noexcept {
  const Rgb col = time_colour(static_cast<double>(frames_) * colour_scale_);
  for (const io::icd::Detection& d : detections) {
    const int x = layout_.x_of(d.azimuth_deg), y = layout_.y_of(d.range_m);
    canvas_.rect(x - 2, y - 2, x + 2, y + 2, col);
  }
  ++frames_;
  detections_ += detections.size();
}

void BScope::write_png(const std::filesystem::path& path) {
  // The title band (above kTop) is left free by the grid: the title is written last, once the
  // frames and detections are known.
  char label[96];
  std::snprintf(
      label, sizeof label, "radar-emu: %llu frames, %llu detections (blue: first, red: last)",
      static_cast<unsigned long long>(frames_), static_cast<unsigned long long>(detections_));
  canvas_.text(BScopeLayout::kLeft, 12, label, kBScopeInk, 2);
  canvas_.write_png(path);
}

void write_bscope_png(const RunResult& result, const Scenario& s,
                      const std::filesystem::path& path) {
  BScope b(s, result.records.size());
  for (const FrameRecord& rec : result.records) {
    b.add_frame(std::span<const io::icd::Detection>(result.detections)
                    .subspan(rec.first_detection, rec.detection_count));
  }
  b.write_png(path);
}

void write_timing_png(const timing::StageProfiler& profiler, double period_s,
                      const std::filesystem::path& path) {
  using timing::Stage;
  const double budget_ms = period_s * 1e3;
  const std::vector<std::int64_t> frame_ns = profiler.history_ns(Stage::kFrame);
  const std::size_t n = frame_ns.size();
  Canvas out(kTimingPngWidth, kTimingPngHeight, Rgb{255, 255, 255});

  LineChart stages;
  stages.title = "stage time per frame, stacked (budget = frame period)";
  stages.x_label = "frame (of the last " + std::to_string(n) + " kept)";
  stages.y_label = "time [ms]";
  std::vector<double> x(n), cumulative(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    x[i] = static_cast<double>(i);
  for (Stage st :
       {Stage::kInput, Stage::kSceneUpdate, Stage::kTrace, Stage::kSensor, Stage::kOutput}) {
    const std::vector<std::int64_t> h = profiler.history_ns(st);
    Series s;
    s.label = st == Stage::kInput         ? "input"
              : st == Stage::kSceneUpdate ? "+scene"
                                          : "+" + std::string(timing::stage_name(st));
    s.x = x;
    s.y.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      cumulative[i] += i < h.size() ? static_cast<double>(h[i]) * 1e-6 : 0.0;
      s.y[i] = cumulative[i];
    }
    stages.series.push_back(std::move(s));
  }
  Series frame{"frame", x, std::vector<double>(n)};
  for (std::size_t i = 0; i < n; ++i)
    frame.y[i] = static_cast<double>(frame_ns[i]) * 1e-6;
  stages.series.push_back(std::move(frame));
  stages.series.push_back(Series{"budget",
                                 {0.0, n > 1 ? static_cast<double>(n - 1) : 1.0},
                                 {budget_ms, budget_ms},
                                 false,
                                 true});
  stages.y_min = 0.0;
  out.blit(render_line_chart(stages), 0, 0);

  // Histogram of frame times: 40 bins from 0 to the larger of the slowest frame and the budget,
  // drawn as a step outline.
  LineChart hist;
  hist.title = "frame-time histogram (" + std::to_string(n) + " frames)";
  hist.x_label = "frame time [ms]";
  hist.y_label = "frames";
  constexpr std::size_t kBins = 40;
  double top_ms = budget_ms;
  for (std::int64_t v : frame_ns)
    top_ms = std::max(top_ms, static_cast<double>(v) * 1e-6);
  top_ms *= 1.05;  // the budget line clear of the frame
  const double bin_ms = top_ms / static_cast<double>(kBins);
  std::array<double, kBins> counts{};
  for (std::int64_t v : frame_ns) {
    const auto b = static_cast<std::size_t>(static_cast<double>(v) * 1e-6 / bin_ms);
    counts[std::min(b, kBins - 1)] += 1.0;
  }
  Series steps;
  steps.label = "frames";
  steps.x.push_back(0.0);
  steps.y.push_back(0.0);
  double count_max = 1.0;
  for (std::size_t b = 0; b < kBins; ++b) {
    const double lo = static_cast<double>(b) * bin_ms;
    steps.x.insert(steps.x.end(), {lo, lo + bin_ms});
    steps.y.insert(steps.y.end(), {counts[b], counts[b]});
    count_max = std::max(count_max, counts[b]);
  }
  steps.x.push_back(top_ms);
  steps.y.push_back(0.0);
  hist.series.push_back(std::move(steps));
  hist.series.push_back(Series{"budget", {budget_ms, budget_ms}, {0.0, count_max}, false, true});
  hist.y_min = 0.0;
  out.blit(render_line_chart(hist), 0, kTimingPngHeight / 2);
  out.write_png(path);
}

}  // namespace radar_emu::loop
