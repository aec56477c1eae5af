#include "emulator/plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "emulator/canvas.hpp"

namespace radar_emu::emulator {

namespace {

// Blue (start of the run) to red (end).
Rgb time_colour(double f) {
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

void write_bscope_png(const RunResult& result, const Scenario& s,
                      const std::filesystem::path& path) {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  BScopeLayout L;
  L.azimuth_min_deg = s.sbr.azimuth_min_rad * kDeg;
  L.azimuth_max_deg = s.sbr.azimuth_max_rad * kDeg;
  L.range_max_m = s.sensor.max_range_m;
  const Rgb bg{16, 20, 28}, grid{55, 62, 78}, ink{210, 215, 225};
  Canvas c(BScopeLayout::kWidth, BScopeLayout::kHeight, bg);
  char label[64];
  // Range grid every 500 m (labelled every km), azimuth grid every 2 deg.
  for (double r = 0.0; r <= L.range_max_m + 1e-9; r += 500.0) {
    const int y = L.y_of(r);
    c.rect(BScopeLayout::kLeft, y, BScopeLayout::kWidth - BScopeLayout::kRight - 1, y, grid);
    if (std::fmod(r, 1000.0) < 1e-9) {
      std::snprintf(label, sizeof label, "%.0f km", r / 1000.0);
      c.text(8, y - 6, label, ink, 2);
    }
  }
  for (double a = std::ceil(L.azimuth_min_deg / 2.0) * 2.0; a <= L.azimuth_max_deg + 1e-9;
       a += 2.0) {
    const int x = L.x_of(a);
    c.rect(x, BScopeLayout::kTop, x, BScopeLayout::kHeight - BScopeLayout::kBottom - 1, grid);
    std::snprintf(label, sizeof label, "%+.0f", a);
    c.text(x - 12, BScopeLayout::kHeight - BScopeLayout::kBottom + 8, label, ink, 2);
  }
  c.text(BScopeLayout::kWidth / 2 - 120, BScopeLayout::kHeight - 18,
         "azimuth [deg], right of boresight", ink, 1);
  std::snprintf(label, sizeof label,
                "radar-emu: %llu frames, %llu detections (blue: first, red: last)",
                static_cast<unsigned long long>(result.records.size()),
                static_cast<unsigned long long>(result.detections_total));
  c.text(BScopeLayout::kLeft, 12, label, ink, 2);
  const double n = std::max<double>(1.0, static_cast<double>(result.records.size()) - 1.0);
  for (std::size_t k = 0; k < result.records.size(); ++k) {
    const FrameRecord& rec = result.records[k];
    const Rgb col = time_colour(static_cast<double>(k) / n);
    for (std::uint32_t i = 0; i < rec.detection_count; ++i) {
      const io::icd::Detection& d = result.detections[rec.first_detection + i];
      const int x = L.x_of(d.azimuth_deg), y = L.y_of(d.range_m);
      c.rect(x - 2, y - 2, x + 2, y + 2, col);
    }
  }
  c.write_png(path);
}

}  // namespace radar_emu::emulator
