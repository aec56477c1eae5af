// The plotting bridge (plot/charts.*): figures described in C++ come out as a PNG of the size
// asked (decoded with stb_image, independent of matplotlib) and an SVG beside it whose text holds
// the axis and colour-bar labels; bad data is refused before any drawing; a missing interpreter
// or matplotlib is one line naming the interpreter and the Debian package. What the figures
// show (colours through the colour map, every product's labels) is checked in Python by
// check_figures.py.

#include "plot/charts.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace plot = radar_emu::plot;
namespace fs = std::filesystem;

namespace {

plot::LineChart two_series_chart() {
  plot::LineChart c;
  c.title = "two series";
  c.x_label = "frequency [GHz]";
  c.y_label = "RCS [dBsm]";
  c.series = {{"HH", {0, 1, 2, 3}, {-10, 0, 5, -3}}, {"VV, a longer label", {0, 3}, {2, 2}}};
  return c;
}

plot::Heatmap ramp_map() {
  plot::Heatmap m;
  m.title = "ramp";
  m.x_label = "range [m]";
  m.y_label = "cross-range [m]";
  m.value_label = "amplitude [dBsm]";
  for (int i = 0; i < 20; ++i)
    m.x.push_back(i);
  for (int j = 0; j < 10; ++j)
    m.y.push_back(j);
  for (int j = 0; j < 10; ++j)
    for (int i = 0; i < 20; ++i)
      m.values.push_back(-2.0 * i);
  m.value_max = 0.0;
  m.value_range = 40.0;
  m.scale_bar = 0.0;
  return m;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Sets an environment variable for the scope of a test.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name))
      old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;
  ~ScopedEnv() {
    if (old_.empty())
      ::unsetenv(name_);
    else
      ::setenv(name_, old_.c_str(), 1);
  }

 private:
  const char* name_;
  std::string old_;
};

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("radar_emu_charts_test_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(Charts, BatchWritesPngOfTheAskedSizeAndSvgWithTheLabels) {
  const fs::path d = temp_dir("batch");
  plot::FigureBatch batch;
  batch.add(plot::single(two_series_chart()), d / "line.png");
  plot::Figure panels;
  panels.width = 900;
  panels.height = 700;
  panels.columns = 1;
  panels.title = "two panels";
  panels.panels = {ramp_map(), two_series_chart()};
  batch.add(std::move(panels), d / "panels.png");
  batch.write();
  EXPECT_TRUE(batch.empty());
  struct Want {
    const char* stem;
    int w, h;
    std::vector<std::string> texts;
  };
  for (const Want& want :
       {Want{"line", 1000, 640, {"frequency [GHz]", "RCS [dBsm]", "HH"}},
        Want{"panels", 900, 700, {"range [m]", "cross-range [m]", "amplitude [dBsm]", "2 m"}}}) {
    int w = 0, h = 0, ch = 0;
    unsigned char* px = stbi_load((d / (std::string(want.stem) + ".png")).c_str(), &w, &h, &ch, 3);
    ASSERT_NE(px, nullptr) << want.stem;
    EXPECT_EQ(w, want.w) << want.stem;
    EXPECT_EQ(h, want.h) << want.stem;
    stbi_image_free(px);
    const std::string svg = read_text(d / (std::string(want.stem) + ".svg"));
    for (const std::string& t : want.texts)
      EXPECT_NE(svg.find(">" + t + "<"), std::string::npos) << want.stem << ": no text " << t;
  }
  fs::remove_all(d);
}

TEST(Charts, BadInputIsAClearErrorBeforeAnyDrawing) {
  plot::FigureBatch batch;
  plot::LineChart c = two_series_chart();
  c.series[0].y.pop_back();
  EXPECT_THROW(batch.add(plot::single(c), "x.png"), std::invalid_argument);
  c = two_series_chart();
  c.log_y = true;
  for (auto& s : c.series)
    for (double& y : s.y)
      y = -1.0;
  EXPECT_THROW(batch.add(plot::single(c), "x.png"), std::invalid_argument);
  plot::Heatmap m = ramp_map();
  m.values.pop_back();
  EXPECT_THROW(batch.add(plot::single(m), "x.png"), std::invalid_argument);
  m = ramp_map();
  m.x[3] = m.x[2];
  EXPECT_THROW(batch.add(plot::single(m), "x.png"), std::invalid_argument);
  c = two_series_chart();
  c.series[0].y_lo = {1.0};
  EXPECT_THROW(batch.add(plot::single(c), "x.png"), std::invalid_argument);
  c = two_series_chart();
  c.width = 50;
  EXPECT_THROW(batch.add(plot::single(c), "x.png"), std::invalid_argument);
  EXPECT_TRUE(batch.empty());
}

TEST(Charts, MissingInterpreterIsOneLineNamingItAndThePackage) {
  const ScopedEnv env("RADAR_EMU_PYTHON", "/nonexistent/python3");
  const fs::path d = temp_dir("nopython");
  try {
    plot::write_line_chart_png(two_series_chart(), d / "line.png");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/nonexistent/python3"), std::string::npos) << what;
    EXPECT_NE(what.find("python3-matplotlib"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(d / "line.png"));
  fs::remove_all(d);
}

TEST(Charts, MissingMatplotlibIsOneLineNamingTheInterpreterAndThePackage) {
  // A stand-in interpreter that behaves as render.py does when `import matplotlib` fails.
  const fs::path d = temp_dir("nompl");
  const fs::path fake = d / "python-without-matplotlib";
  {
    std::ofstream f(fake);
    f << "#!/bin/sh\necho 'missing-matplotlib: No module named matplotlib' >&2\nexit 3\n";
  }
  ::chmod(fake.c_str(), 0755);
  const ScopedEnv env("RADAR_EMU_PYTHON", fake.string());
  try {
    plot::write_line_chart_png(two_series_chart(), d / "line.png");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(fake.string() + " has no matplotlib"), std::string::npos) << what;
    EXPECT_NE(what.find("apt-get install python3-matplotlib"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  fs::remove_all(d);
}
