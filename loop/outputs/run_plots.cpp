#include "loop/outputs/run_plots.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "plot/charts.hpp"

namespace radar_emu::loop {

using plot::Figure;
using plot::LineChart;
using plot::RefLine;
using plot::Rgb;
using plot::Series;

BScope::BScope(const Scenario& s, std::uint64_t /*frames_planned*/)
    : azimuth_min_deg_(common::degrees(s.sbr.azimuth_min_rad)),
      azimuth_max_deg_(common::degrees(s.sbr.azimuth_max_rad)),
      range_max_m_(s.sensor.max_range_m),
      period_s_(1.0 / s.rate_hz),
      last_frame_(kAzimuthCells * kRangeCells, -1.0f) {}

void BScope::add_frame(std::span<const io::icd::Detection> detections) noexcept {
  const double az_span = azimuth_max_deg_ - azimuth_min_deg_;
  for (const io::icd::Detection& d : detections) {
    const double fa = (d.azimuth_deg - azimuth_min_deg_) / az_span, fr = d.range_m / range_max_m_;
    if (!(fa >= 0.0 && fa <= 1.0 && fr >= 0.0 && fr <= 1.0))
      continue;  // outside the plotted field (counted all the same)
    const auto ia = std::min(kAzimuthCells - 1, static_cast<std::size_t>(fa * kAzimuthCells));
    const auto ir = std::min(kRangeCells - 1, static_cast<std::size_t>(fr * kRangeCells));
    last_frame_[ir * kAzimuthCells + ia] = static_cast<float>(frames_);
  }
  ++frames_;
  detections_ += detections.size();
}

void BScope::write_png(const std::filesystem::path& path) {
  LineChart c;
  c.title = "radar-emu B-scope: " + std::to_string(frames_) + " frames, " +
            std::to_string(detections_) + " detections (colour: time of the last detection)";
  c.x_label = "azimuth [deg], right of boresight";
  c.y_label = "range [km]";
  c.colour_label = "time from the first frame [s]";
  c.colour_map = "plasma";
  c.colour_min = 0.0;
  c.colour_max = std::max(1.0, static_cast<double>(frames_) - 1.0) * period_s_;
  c.x_min = azimuth_min_deg_;
  c.x_max = azimuth_max_deg_;
  c.y_min = 0.0;
  c.y_max = range_max_m_ * 1e-3;
  c.width = kWidth;
  c.height = kHeight;
  Series s;
  const double da = (azimuth_max_deg_ - azimuth_min_deg_) / kAzimuthCells;
  const double dr_km = range_max_m_ * 1e-3 / kRangeCells;
  for (std::size_t ir = 0; ir < kRangeCells; ++ir) {
    for (std::size_t ia = 0; ia < kAzimuthCells; ++ia) {
      const float f = last_frame_[ir * kAzimuthCells + ia];
      if (f < 0.0f)
        continue;
      s.x.push_back(azimuth_min_deg_ + (static_cast<double>(ia) + 0.5) * da);
      s.y.push_back((static_cast<double>(ir) + 0.5) * dr_km);
      s.colour_values.push_back(static_cast<double>(f) * period_s_);
    }
  }
  s.marker_size = 10.0;
  if (s.x.empty()) {  // nothing detected: an empty field, still with its axes
    s.x = {azimuth_min_deg_};
    s.y = {-1.0};  // below the axis: not drawn
    s.colour_values = {0.0};
  }
  c.series.push_back(std::move(s));
  plot::write_line_chart_png(c, path);
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
                      const GovernorTrace& governor, const std::filesystem::path& path) {
  using timing::Stage;
  const double budget_ms = period_s * 1e3;
  const std::vector<std::int64_t> frame_ns = profiler.history_ns(Stage::kFrame);
  const std::size_t n = frame_ns.size();
  // The ring keeps the last n frames of the run: their run frame indices.
  const std::uint64_t total = profiler.summary(Stage::kFrame).count;
  const double first = static_cast<double>(total >= n ? total - n : 0);
  const Rgb kBudget{200, 30, 30}, kDeadline{30, 30, 30};
  std::vector<RefLine> lines{{budget_ms, "frame period (budget)", false, false, kBudget}};
  if (governor.enabled)
    lines.push_back(
        {governor.deadline_ms, "governor deadline (trace + sensor)", false, true, kDeadline});

  LineChart stages;
  stages.title = "stage time per frame, stacked";
  stages.x_label = "frame [index in the run]";
  stages.y_label = "time [ms]";
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i)
    x[i] = first + static_cast<double>(i);
  for (Stage st :
       {Stage::kInput, Stage::kSceneUpdate, Stage::kTrace, Stage::kSensor, Stage::kOutput}) {
    const std::vector<std::int64_t> h = profiler.history_ns(st);
    Series s;
    s.label = st == Stage::kSceneUpdate ? "scene update" : std::string(timing::stage_name(st));
    s.x = x;
    s.y.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      s.y[i] = i < h.size() ? static_cast<double>(h[i]) * 1e-6 : 0.0;
    s.stacked = true;
    stages.series.push_back(std::move(s));
  }
  Series frame{"whole frame", x, std::vector<double>(n)};
  for (std::size_t i = 0; i < n; ++i)
    frame.y[i] = static_cast<double>(frame_ns[i]) * 1e-6;
  frame.colour = Rgb{0, 0, 0};
  stages.series.push_back(std::move(frame));
  stages.ref_lines = lines;
  stages.y_min = 0.0;
  stages.legend_below = false;
  if (n == 0)  // no frame: the axes and the lines alone
    stages.series = {Series{"", {first}, {0.0}}};

  // Histogram of frame times: 40 bins from 0 to the larger of the slowest frame and the budget,
  // drawn as a step outline.
  LineChart hist;
  hist.title = "frame-time histogram (" + std::to_string(n) + " frames)";
  hist.x_label = "frame time [ms]";
  hist.y_label = "frames per bin [count]";
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
  for (std::size_t b = 0; b < kBins; ++b) {
    const double lo = static_cast<double>(b) * bin_ms;
    steps.x.insert(steps.x.end(), {lo, lo + bin_ms});
    steps.y.insert(steps.y.end(), {counts[b], counts[b]});
  }
  steps.x.push_back(top_ms);
  steps.y.push_back(0.0);
  hist.series.push_back(std::move(steps));
  for (RefLine r : lines) {
    r.vertical = true;
    hist.ref_lines.push_back(r);
  }
  hist.y_min = 0.0;
  hist.legend_below = false;

  Figure fig;
  fig.width = kTimingPngWidth;
  fig.height = kTimingPngHeight;
  fig.panels = {stages, hist};
  fig.height_ratios = {1.4, 1.0};
  // The governor's level per frame (0: the scenario's fidelity; higher: coarser).
  std::vector<double> gx, gy;
  for (std::size_t i = 0; i < governor.levels.size(); ++i) {
    if (governor.levels[i] < 0)
      continue;
    gx.push_back(static_cast<double>(i));
    gy.push_back(static_cast<double>(governor.levels[i]));
  }
  if (!gx.empty()) {
    LineChart gov;
    gov.title = std::string("fidelity governor") + (governor.enabled ? "" : " (disabled)");
    gov.x_label = "frame [index in the run]";
    gov.y_label = "level [0 = the scenario's fidelity]";
    gov.series.push_back(Series{"level chosen", gx, gy, gx.size() < 60});
    gov.y_min = -0.5;
    gov.y_max = std::max(3.0, *std::max_element(gy.begin(), gy.end()) + 0.5);
    gov.legend_below = false;
    fig.panels.emplace_back(std::move(gov));
    fig.height_ratios.push_back(0.7);
  }
  plot::write_figure(std::move(fig), path);
}

}  // namespace radar_emu::loop
