#pragma once
// A small RGB raster for the pictures the tools write (stb_easy_font text, stb_image_write PNG).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace radar_emu::plot {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

class Canvas {
 public:
  Canvas(int width, int height, Rgb background);
  void put(int x, int y, Rgb c) noexcept;                     ///< clipped to the canvas
  void rect(int x0, int y0, int x1, int y1, Rgb c) noexcept;  ///< filled, inclusive
  void line(int x0, int y0, int x1, int y1, Rgb c) noexcept;  ///< Bresenham
  void blit(const Canvas& src, int x, int y) noexcept;        ///< src's top-left at (x, y), clipped
  /// Text (stb_easy_font, about 6 x 12 pixels per character at scale 1), top-left at (x, y).
  void text(int x, int y, const std::string& s, Rgb c, int scale = 1);
  /// The same text turned a quarter counter-clockwise (read bottom to top), the top-left of its
  /// box at (x, y): text_height(scale) wide, text_width(s, scale) high.
  void text_up(int x, int y, const std::string& s, Rgb c, int scale = 1);
  [[nodiscard]] static int text_width(const std::string& s, int scale = 1);
  /// Height of a line of text, descenders included.
  [[nodiscard]] static int text_height(int scale = 1) noexcept { return 10 * scale; }
  [[nodiscard]] int width() const noexcept { return w_; }
  [[nodiscard]] int height() const noexcept { return h_; }
  [[nodiscard]] const std::uint8_t* data() const noexcept { return px_.data(); }
  /// Throws std::runtime_error naming the path when the file cannot be written.
  void write_png(const std::filesystem::path& path) const;

 private:
  int w_, h_;
  std::vector<std::uint8_t> px_;
};

/// Perceptually ordered colour map (dark blue - teal - yellow, viridis-like) for f in [0, 1].
[[nodiscard]] Rgb colour_map(double f) noexcept;

}  // namespace radar_emu::plot
