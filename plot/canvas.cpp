#include "plot/canvas.hpp"

#include <stb/stb_easy_font.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace radar_emu::plot {

Canvas::Canvas(int width, int height, Rgb background)
    : w_(width), h_(height), px_(static_cast<std::size_t>(width * height) * 3) {
  for (int y = 0; y < h_; ++y) {
    for (int x = 0; x < w_; ++x)
      put(x, y, background);
  }
}

void Canvas::blit(const Canvas& src, int x, int y) noexcept {
  for (int sy = 0; sy < src.h_; ++sy) {
    for (int sx = 0; sx < src.w_; ++sx) {
      const std::size_t i = (static_cast<std::size_t>(sy) * static_cast<std::size_t>(src.w_) +
                             static_cast<std::size_t>(sx)) *
                            3;
      put(x + sx, y + sy, Rgb{src.px_[i], src.px_[i + 1], src.px_[i + 2]});
    }
  }
}

void Canvas::put(int x, int y, Rgb c) noexcept {
  if (x < 0 || y < 0 || x >= w_ || y >= h_)
    return;
  const std::size_t i =
      (static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x)) *
      3;
  px_[i] = c.r;
  px_[i + 1] = c.g;
  px_[i + 2] = c.b;
}

void Canvas::rect(int x0, int y0, int x1, int y1, Rgb c) noexcept {
  for (int y = std::max(0, y0); y <= std::min(h_ - 1, y1); ++y) {
    for (int x = std::max(0, x0); x <= std::min(w_ - 1, x1); ++x)
      put(x, y, c);
  }
}

void Canvas::line(int x0, int y0, int x1, int y1, Rgb c) noexcept {
  const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  for (int guard = 0; guard < 100000; ++guard) {
    put(x0, y0, c);
    if (x0 == x1 && y0 == y1)
      break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y0 += sy;
    }
  }
}

namespace {

// The glyph quads of `s` (stb_easy_font: 4 vertices of 16 bytes, x, y, z floats and RGBA; vertex
// 0 is the top-left corner, vertex 2 the bottom-right), as (x0, y0, x1, y1) at scale 1.
template <class F>
void for_each_quad(const std::string& s, F&& f) {
  std::array<char, 40000> buf{};
  std::array<char, 256> str{};
  std::strncpy(str.data(), s.c_str(), str.size() - 1);
  const int quads = stb_easy_font_print(0.0f, 0.0f, str.data(), nullptr, buf.data(),
                                        static_cast<int>(buf.size()));
  for (int q = 0; q < quads; ++q) {
    float v[12];
    std::memcpy(v, buf.data() + static_cast<std::size_t>(q) * 64, sizeof v);
    f(static_cast<int>(v[0]), static_cast<int>(v[1]), static_cast<int>(v[8]),
      static_cast<int>(v[9]));
  }
}

}  // namespace

void Canvas::text(int x, int y, const std::string& s, Rgb c, int scale) {
  for_each_quad(s, [&](int x0, int y0, int x1, int y1) {
    rect(x + scale * x0, y + scale * y0, x + scale * x1 - 1, y + scale * y1 - 1, c);
  });
}

void Canvas::text_up(int x, int y, const std::string& s, Rgb c, int scale) {
  // Text point (u, v) (u along the line, v down) goes to (x + v, y + width - u).
  const int w = text_width(s, scale);
  for_each_quad(s, [&](int x0, int y0, int x1, int y1) {
    rect(x + scale * y0, y + w - scale * x1, x + scale * y1 - 1, y + w - scale * x0 - 1, c);
  });
}

int Canvas::text_width(const std::string& s, int scale) {
  std::array<char, 256> str{};
  std::strncpy(str.data(), s.c_str(), str.size() - 1);
  return scale * stb_easy_font_width(str.data());
}

void Canvas::write_png(const std::filesystem::path& path) const {
  if (stbi_write_png(path.c_str(), w_, h_, 3, px_.data(), w_ * 3) == 0)
    throw std::runtime_error(path.string() + ": cannot write PNG");
}

Rgb colour_map(double f) noexcept {
  // Piecewise-linear through five anchors sampled from matplotlib's viridis (van der Walt &
  // Smith, 2015): perceptually ordered, readable in grey scale.
  static constexpr std::array<std::array<double, 3>, 5> kAnchors{
      {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}}};
  if (!(f > 0.0))
    f = 0.0;
  f = std::min(f, 1.0) * 4.0;
  const auto i = std::min<std::size_t>(3, static_cast<std::size_t>(f));
  const double t = f - static_cast<double>(i);
  auto mix = [&](std::size_t ch) {
    return static_cast<std::uint8_t>(
        std::lround(kAnchors[i][ch] + t * (kAnchors[i + 1][ch] - kAnchors[i][ch])));
  };
  return {mix(0), mix(1), mix(2)};
}

}  // namespace radar_emu::plot
