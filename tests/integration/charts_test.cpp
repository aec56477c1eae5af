// The plotting layer (plot/charts.*) against what a reader of a report checks: tick values
// where a 1-2-5 rule and decades put them, legends clear of the data, whole titles, square
// metres on an image, and colours that read back through the colour bar. The PNGs are decoded
// with stb_image, independent of the writer (stb_image_write).

#include "plot/charts.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace plot = radar_emu::plot;

namespace {

std::size_t pixel_index(int x, int y, int width) {
  return (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
          static_cast<std::size_t>(x)) *
         3;
}

void expect_values(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_NEAR(got[i], want[i], 1e-9 * std::max(1.0, std::abs(want[i]))) << "tick " << i;
}

plot::LineChart two_series_chart() {
  plot::LineChart c;
  c.title = "two series";
  c.x_label = "frequency [GHz]";
  c.y_label = "RCS [dBsm]";
  c.series = {{"HH", {0, 1, 2, 3}, {-10, 0, 5, -3}}, {"VV, a longer label", {0, 3}, {2, 2}}};
  return c;
}

}  // namespace

TEST(Charts, LinearTicksAreOneTwoFiveSteps) {
  // 0..10 in about 6 intervals: step 2 (10 / 6 = 1.67 -> the next of 1, 2, 5 is 2).
  expect_values(plot::nice_ticks(0.0, 10.0), {0, 2, 4, 6, 8, 10});
  // -43..3: raw step 7.7 -> 10; ticks at multiples of 10 inside.
  expect_values(plot::nice_ticks(-43.0, 3.0), {-40, -30, -20, -10, 0});
  // 0.013..0.047: raw 0.0057 -> 0.01.
  expect_values(plot::nice_ticks(0.013, 0.047), {0.02, 0.03, 0.04});
  const plot::AxisTicks t = plot::axis_ticks(-1.0, 1.0, false);
  expect_values(t.major, {-1.0, -0.5, 0.0, 0.5, 1.0});  // raw 2/6 = 0.33 -> step 0.5
}

TEST(Charts, LinearTickLabelsHaveTheStepsPrecision) {
  const plot::AxisTicks t = plot::axis_ticks(0.0, 0.5, false, 5);  // step 0.1
  ASSERT_EQ(t.labels.size(), 6u);
  EXPECT_EQ(t.labels[0], "0");
  EXPECT_EQ(t.labels[1], "0.1");
  EXPECT_EQ(t.labels[5], "0.5");
  const plot::AxisTicks z = plot::axis_ticks(-3.0, 3.0, false);  // no "-0" at zero
  EXPECT_NE(std::find(z.labels.begin(), z.labels.end(), "0"), z.labels.end());
}

TEST(Charts, LogAxisHasDecadesAndMinorTicks) {
  const plot::AxisTicks t = plot::axis_ticks(1e-3, 1e2, true);
  expect_values(t.major, {1e-3, 1e-2, 1e-1, 1, 10, 100});
  EXPECT_EQ(t.labels, (std::vector<std::string>{"0.001", "0.01", "0.1", "1", "10", "100"}));
  // 2..9 in each of the five decades.
  ASSERT_EQ(t.minor.size(), 5u * 8u);
  EXPECT_NEAR(t.minor.front(), 2e-3, 1e-15);
  EXPECT_NEAR(t.minor.back(), 90.0, 1e-9);
  // Far from 1: labelled 10^k.
  const plot::AxisTicks far = plot::axis_ticks(1e-9, 1e-3, true);
  EXPECT_EQ(far.labels.front(), "10^-9");
  EXPECT_EQ(far.labels.back(), "10^-3");
  EXPECT_EQ(far.major.size(), 7u);
  // Fewer than three decade ticks: 2 and 5 labelled as well, the rest minor.
  const plot::AxisTicks few = plot::axis_ticks(1.0, 50.0, true);
  expect_values(few.major, {1, 2, 5, 10, 20, 50});
  expect_values(few.minor, {3, 4, 6, 7, 8, 9, 30, 40});
}

TEST(Charts, LegendIsOutsideTheData) {
  plot::LineChart c = two_series_chart();
  const plot::ChartLayout L = plot::line_chart_layout(c);
  ASSERT_EQ(L.legend.size(), 2u);
  for (const plot::PixelRect& r : L.legend) {
    EXPECT_FALSE(r.overlaps(L.plot)) << "legend box at " << r.x0 << "," << r.y0;
    EXPECT_GE(r.x0, 0);
    EXPECT_LT(r.x1, L.width);
    EXPECT_LT(r.y1, L.height);
  }
  // Long labels (the tradeoff charts): the legend moves below the plot, still outside it.
  for (int k = 0; k < 12; ++k)
    c.series.push_back({"case vehicle, knob rays_per_wavelength number " + std::to_string(k),
                        {0, 1},
                        {double(k), double(k + 1)}});
  c.height = 900;
  const plot::ChartLayout B = plot::line_chart_layout(c);
  ASSERT_EQ(B.legend.size(), 14u);
  for (const plot::PixelRect& r : B.legend) {
    EXPECT_FALSE(r.overlaps(B.plot));
    EXPECT_GT(r.y0, B.plot.y1);
    EXPECT_LT(r.x1, B.width);
    EXPECT_LT(r.y1, B.height);
  }
  for (std::size_t i = 0; i < B.legend.size(); ++i) {
    for (std::size_t j = i + 1; j < B.legend.size(); ++j)
      EXPECT_FALSE(B.legend[i].overlaps(B.legend[j])) << i << " and " << j;
  }
}

TEST(Charts, LongTitleIsWrappedNotClipped) {
  plot::LineChart c = two_series_chart();
  std::string title;
  for (int i = 0; title.size() < 230; ++i)
    title += "word" + std::to_string(i) + " ";
  title.pop_back();
  c.title = title;
  const plot::ChartLayout L = plot::line_chart_layout(c);
  ASSERT_GE(L.title.size(), 2u);
  std::string joined;
  for (const plot::TextLine& t : L.title) {
    EXPECT_GE(t.x, 0);
    EXPECT_LE(t.x + plot::Canvas::text_width(t.text, t.scale), L.width) << t.text;
    EXPECT_LT(t.y + plot::Canvas::text_height(t.scale), L.plot.y0) << "title over the plot";
    joined += (joined.empty() ? "" : " ") + t.text;
  }
  EXPECT_EQ(joined, title);  // every character drawn
  // One unbroken word wider than the picture is cut, not lost.
  const std::vector<std::string> cut = plot::wrap_text(std::string(300, 'x'), 400, 2);
  std::size_t n = 0;
  for (const auto& s : cut) {
    EXPECT_LE(plot::Canvas::text_width(s, 2), 400);
    n += s.size();
  }
  EXPECT_EQ(n, 300u);
}

TEST(Charts, ImageInMetresHasEqualScales) {
  plot::Heatmap m;
  m.title = "ISAR";
  m.x_label = "range [m]";
  m.y_label = "cross-range [m]";
  m.value_label = "dBsm";
  // Cell centres so that the cells span exactly 10 m in x and 5 m in y.
  for (int i = 0; i < 100; ++i)
    m.x.push_back(-5.0 + 0.1 * (i + 0.5));
  for (int j = 0; j < 50; ++j)
    m.y.push_back(-2.5 + 0.1 * (j + 0.5));
  m.values.assign(m.x.size() * m.y.size(), 0.0);
  const plot::HeatmapLayout L = plot::heatmap_layout(m);
  EXPECT_TRUE(L.equal_aspect);
  EXPECT_NEAR(L.x1 - L.x0, 10.0, 1e-9);
  EXPECT_NEAR(L.y1 - L.y0, 5.0, 1e-9);
  // Pixels per metre: the 10 m span drawn at the y scale is the drawn width within 1 pixel.
  const double y_px_per_m = L.image.height() / 5.0;
  EXPECT_NEAR(10.0 * y_px_per_m, L.image.width(), 1.0)
      << L.image.width() << " x " << L.image.height();
  EXPECT_FALSE(L.colour_bar.overlaps(L.image));
  // Different units: the image fills the space.
  m.y_label = "Doppler [Hz]";
  const plot::HeatmapLayout F = plot::heatmap_layout(m);
  EXPECT_FALSE(F.equal_aspect);
  EXPECT_GT(F.image.height(), L.image.height());
}

TEST(Charts, PixelColoursReadBackThroughTheColourBar) {
  plot::Heatmap m;
  m.title = "ramp";
  m.x_label = "x [m]";
  m.y_label = "y [s]";
  m.value_label = "level [dB]";
  m.value_max = 10.0;
  m.value_range = 40.0;  // -30..10 dB
  const std::size_t nx = 8, ny = 5;
  for (std::size_t i = 0; i < nx; ++i)
    m.x.push_back(static_cast<double>(i));
  for (std::size_t j = 0; j < ny; ++j)
    m.y.push_back(100.0 + 10.0 * static_cast<double>(j));
  // value(i, j) = -30 + 40 * (i + nx j) / (nx ny - 1): every cell a different level.
  for (std::size_t j = 0; j < ny; ++j) {
    for (std::size_t i = 0; i < nx; ++i)
      m.values.push_back(-30.0 +
                         40.0 * static_cast<double>(i + nx * j) / static_cast<double>(nx * ny - 1));
  }
  const std::filesystem::path png =
      std::filesystem::temp_directory_path() / "radar_emu_charts_test_ramp.png";
  plot::write_heatmap_png(m, png);
  int w = 0, h = 0, ch = 0;
  unsigned char* px = stbi_load(png.c_str(), &w, &h, &ch, 3);
  ASSERT_NE(px, nullptr);
  const plot::HeatmapLayout L = plot::heatmap_layout(m);
  ASSERT_EQ(w, L.width);
  ASSERT_EQ(h, L.height);
  auto at = [&](int x, int y) {
    const unsigned char* p = px + pixel_index(x, y, w);
    return std::array<int, 3>{p[0], p[1], p[2]};
  };
  // The value of a bar row from two labelled ticks of the bar (linear between them).
  ASSERT_GE(L.bar_ticks.major.size(), 2u);
  const double v_a = L.bar_ticks.major.front(), v_b = L.bar_ticks.major.back();
  const int r_a = L.bar_row(v_a), r_b = L.bar_row(v_b);
  const int bar_x = (L.colour_bar.x0 + L.colour_bar.x1) / 2;
  for (std::size_t j = 0; j < ny; ++j) {
    for (std::size_t i = 0; i < nx; ++i) {
      const auto c = at(L.px(m.x[i]), L.py(m.y[j]));
      int best_row = L.colour_bar.y0, best = 1 << 30;
      for (int r = L.colour_bar.y0; r <= L.colour_bar.y1; ++r) {
        const auto b = at(bar_x, r);
        const int d = (b[0] - c[0]) * (b[0] - c[0]) + (b[1] - c[1]) * (b[1] - c[1]) +
                      (b[2] - c[2]) * (b[2] - c[2]);
        if (d < best) {
          best = d;
          best_row = r;
        }
      }
      const double v = v_a + (v_b - v_a) * (best_row - r_a) / double(r_b - r_a);
      // One bar row is 40 dB / (bar height) ~ 0.1 dB; colours are quantised to 8 bits.
      EXPECT_NEAR(v, m.values[j * nx + i], 0.6) << "cell " << i << "," << j;
    }
  }
  stbi_image_free(px);
  std::filesystem::remove(png);
}

TEST(Charts, LineIsDrawnWhereTheAxesSay) {
  // y from 0 to 4 fills the plot's height: a horizontal line at y = 2 is drawn half-way down,
  // in the first series' colour.
  plot::LineChart c;
  c.x_label = "x [m]";
  c.y_label = "y [m]";
  c.y_min = 0.0;
  c.y_max = 4.0;
  c.series = {{"", {0.0, 3.0}, {2.0, 2.0}}};
  const plot::ChartLayout L = plot::line_chart_layout(c);
  EXPECT_TRUE(L.legend.empty());
  const plot::Canvas canvas = plot::render_line_chart(c);
  const int row = static_cast<int>(std::lround(L.fy(2.0)));
  EXPECT_NEAR(row, 0.5 * (L.plot.y0 + L.plot.y1), 1.0);
  expect_values(L.y_ticks.major, {0, 1, 2, 3, 4});
  const std::uint8_t* d = canvas.data();
  const int x = (L.plot.x0 + L.plot.x1) / 2;
  const std::uint8_t* p = d + pixel_index(x, row, canvas.width());
  EXPECT_EQ(static_cast<int>(p[0]), 31);  // the first series' colour
  EXPECT_EQ(static_cast<int>(p[1]), 119);
  EXPECT_EQ(static_cast<int>(p[2]), 180);
}

TEST(Charts, BadInputIsAClearError) {
  plot::LineChart c;
  c.series = {{"neg", {1, 2}, {-1, -2}}};
  c.log_y = true;
  EXPECT_THROW((void)plot::render_line_chart(c), std::invalid_argument);
  plot::Heatmap m;
  m.x = {0, 1};
  m.y = {0};
  m.values = {1, 2};
  m.value_range = 0.0;
  EXPECT_THROW((void)plot::render_heatmap(m), std::invalid_argument);
  m.value_range = 10.0;
  m.x = {1, 0};
  EXPECT_THROW((void)plot::render_heatmap(m), std::invalid_argument);
}

TEST(Charts, PictureCellsKeepTheirColoursAndHaveNoColourBar) {
  // A 2 x 2 picture (rows ascending in y): each quarter of the image shows its RGB triplet.
  plot::Heatmap m;
  m.x_label = "azimuth [deg]";
  m.y_label = "elevation [deg]";
  m.x = {0.0, 1.0};
  m.y = {0.0, 1.0};
  m.rgb = {255, 0, 0, 0, 255, 0, 0, 0, 255, 250, 250, 10};
  const plot::HeatmapLayout L = plot::heatmap_layout(m);
  EXPECT_EQ(L.colour_bar.width(), 0);
  EXPECT_TRUE(L.equal_aspect);
  EXPECT_NEAR(L.image.width(), L.image.height(), 1.0);
  const plot::Canvas c = plot::render_heatmap(m);
  for (std::size_t j = 0; j < 2; ++j) {
    for (std::size_t i = 0; i < 2; ++i) {
      const std::uint8_t* p = c.data() + pixel_index(L.px(m.x[i]), L.py(m.y[j]), c.width());
      const std::size_t k = 3 * (j * 2 + i);
      EXPECT_EQ(p[0], m.rgb[k]) << i << "," << j;
      EXPECT_EQ(p[1], m.rgb[k + 1]);
      EXPECT_EQ(p[2], m.rgb[k + 2]);
    }
  }
  m.rgb.pop_back();
  EXPECT_THROW((void)plot::render_heatmap(m), std::invalid_argument);
}
