#include "emulator/plot.hpp"

#include <stb/stb_easy_font.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace radar_emu::emulator {

namespace {

struct Rgb {
  std::uint8_t r, g, b;
};

class Canvas {
 public:
  Canvas(int w, int h, Rgb background) : w_(w), h_(h), px_(static_cast<std::size_t>(w * h) * 3) {
    for (int i = 0; i < w * h; ++i)
      set_index(i, background);
  }
  void put(int x, int y, Rgb c) {
    if (x >= 0 && y >= 0 && x < w_ && y < h_)
      set_index(y * w_ + x, c);
  }
  void rect(int x0, int y0, int x1, int y1, Rgb c) {
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x)
        put(x, y, c);
    }
  }
  // Text with stb_easy_font: it returns quads (4 vertices of x, y, z, colour each).
  void text(int x, int y, const char* s, Rgb c, int scale = 1) {
    std::array<char, 20000> buf{};
    std::array<char, 128> str{};
    std::strncpy(str.data(), s, str.size() - 1);
    const int quads = stb_easy_font_print(0.0f, 0.0f, str.data(), nullptr, buf.data(),
                                          static_cast<int>(buf.size()));
    for (int q = 0; q < quads; ++q) {
      // Each quad is 4 vertices of 16 bytes (x, y, z floats and an RGBA colour); vertex 0 is
      // the top-left corner, vertex 2 the bottom-right.
      float v[12];
      std::memcpy(v, buf.data() + static_cast<std::size_t>(q) * 64, sizeof v);
      const int qx0 = x + scale * static_cast<int>(v[0]), qy0 = y + scale * static_cast<int>(v[1]);
      const int qx1 = x + scale * static_cast<int>(v[8]) - 1;
      const int qy1 = y + scale * static_cast<int>(v[9]) - 1;
      rect(qx0, qy0, qx1, qy1, c);
    }
  }
  [[nodiscard]] const std::uint8_t* data() const { return px_.data(); }

 private:
  void set_index(int i, Rgb c) {
    px_[static_cast<std::size_t>(i) * 3 + 0] = c.r;
    px_[static_cast<std::size_t>(i) * 3 + 1] = c.g;
    px_[static_cast<std::size_t>(i) * 3 + 2] = c.b;
  }
  int w_, h_;
  std::vector<std::uint8_t> px_;
};

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
  L.azimuth_min_deg = s.sensor.azimuth_min_rad * kDeg;
  L.azimuth_max_deg = s.sensor.azimuth_max_rad * kDeg;
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
  if (stbi_write_png(path.c_str(), BScopeLayout::kWidth, BScopeLayout::kHeight, 3, c.data(),
                     BScopeLayout::kWidth * 3) == 0) {
    throw std::runtime_error(path.string() + ": cannot write PNG");
  }
}

}  // namespace radar_emu::emulator
