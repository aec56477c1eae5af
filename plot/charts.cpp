#include "plot/charts.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "plot/render_py.hpp"  // kRenderPy (generated from plot/render.py) and kPlotPython

extern char** environ;

namespace radar_emu::plot {

namespace {

using nlohmann::json;

// matplotlib's tab10 (Vega's category10), a fact about colours.
constexpr std::array<Rgb, 10> kPalette{{{31, 119, 180},
                                        {255, 127, 14},
                                        {44, 160, 44},
                                        {214, 39, 40},
                                        {148, 103, 189},
                                        {140, 86, 75},
                                        {227, 119, 194},
                                        {127, 127, 127},
                                        {188, 189, 34},
                                        {23, 190, 207}}};

std::string hex(Rgb c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

// Non-finite values become null (JSON has no NaN); the renderer reads them back as NaN.
json numbers(const std::vector<double>& v) {
  json a = json::array();
  for (double x : v)
    a.push_back(std::isfinite(x) ? json(x) : json(nullptr));
  return a;
}

void check_size(int w, int h, const std::string& what) {
  if (w < 200 || h < 150 || w > 8000 || h > 8000)
    throw std::invalid_argument(what + ": size " + std::to_string(w) + " x " + std::to_string(h) +
                                " is outside 200 x 150 .. 8000 x 8000 pixels");
}

void check_ascending(const std::vector<double>& a, const std::string& title, const char* which) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i]) || (i > 0 && !(a[i] > a[i - 1])))
      throw std::invalid_argument("heat map '" + title + "': " + which +
                                  " centres must be finite and ascending");
  }
}

void check(const LineChart& c) {
  bool any = false;
  const Series* first_stacked = nullptr;
  for (const Series& s : c.series) {
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("chart '" + c.title + "': series '" + s.label +
                                  "' has mismatched x and y");
    auto sized = [&](const auto& v, const char* what) {
      if (!v.empty() && v.size() != s.x.size())
        throw std::invalid_argument("chart '" + c.title + "': series '" + s.label + "': " + what +
                                    " needs one value per point");
    };
    sized(s.y_lo, "y_lo");
    sized(s.y_hi, "y_hi");
    sized(s.x_lo, "x_lo");
    sized(s.x_hi, "x_hi");
    sized(s.point_labels, "point_labels");
    sized(s.colour_values, "colour_values");
    if (s.y_lo.size() != s.y_hi.size() || s.x_lo.size() != s.x_hi.size())
      throw std::invalid_argument("chart '" + c.title + "': series '" + s.label +
                                  "': a spread needs both its low and high ends");
    if (s.stacked) {
      if (first_stacked == nullptr)
        first_stacked = &s;
      else if (s.x != first_stacked->x)
        throw std::invalid_argument("chart '" + c.title + "': stacked series '" + s.label +
                                    "' does not share the first stacked series' x");
    }
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!c.log_x || s.x[i] > 0.0) &&
          (!c.log_y || s.y[i] > 0.0))
        any = true;
    }
  }
  if (!any)
    throw std::invalid_argument("chart '" + c.title + "': no finite data" +
                                (c.log_x || c.log_y ? " (> 0 on a log axis)" : ""));
  if (c.log_x && ((c.x_min && !(*c.x_min > 0.0)) || (c.x_max && !(*c.x_max > 0.0))))
    throw std::invalid_argument("chart '" + c.title + "': a log x axis needs positive limits");
  if (c.log_y && ((c.y_min && !(*c.y_min > 0.0)) || (c.y_max && !(*c.y_max > 0.0))))
    throw std::invalid_argument("chart '" + c.title + "': a log y axis needs positive limits");
}

void check(const Heatmap& m) {
  const bool picture = !m.rgb.empty();
  if (m.x.empty() || m.y.empty() ||
      (picture ? m.rgb.size() != m.x.size() * m.y.size() * 3
               : m.values.size() != m.x.size() * m.y.size()))
    throw std::invalid_argument("heat map '" + m.title + "': empty or inconsistent data");
  check_ascending(m.x, m.title, "x");
  check_ascending(m.y, m.title, "y");
  if (!(m.value_range > 0.0) || !std::isfinite(m.value_range) || !std::isfinite(m.value_max))
    throw std::invalid_argument("heat map '" + m.title +
                                "': the colour scale needs a finite top and a range > 0");
}

template <class T>
void put_opt(json& j, const char* key, const std::optional<T>& v) {
  if (v)
    j[key] = *v;
}

json to_json(const LineChart& c) {
  json j{{"type", "line"},       {"title", c.title},
         {"x_label", c.x_label}, {"y_label", c.y_label},
         {"log_x", c.log_x},     {"log_y", c.log_y},
         {"polar", c.polar},     {"equal_aspect", c.equal_aspect}};
  put_opt(j, "x_min", c.x_min);
  put_opt(j, "x_max", c.x_max);
  put_opt(j, "y_min", c.y_min);
  put_opt(j, "y_max", c.y_max);
  put_opt(j, "colour_min", c.colour_min);
  put_opt(j, "colour_max", c.colour_max);
  put_opt(j, "legend_below", c.legend_below);
  j["legend"] = c.legend;
  j["colour_label"] = c.colour_label;
  j["colour_map"] = c.colour_map;
  json series = json::array();
  for (std::size_t k = 0; k < c.series.size(); ++k) {
    const Series& s = c.series[k];
    json js{{"label", s.label},     {"x", numbers(s.x)},           {"y", numbers(s.y)},
            {"markers", s.markers}, {"dashed", s.dashed},          {"no_line", s.no_line},
            {"stacked", s.stacked}, {"marker_size", s.marker_size}};
    if (s.colour)
      js["colour"] = hex(*s.colour);
    if (!s.y_lo.empty()) {
      js["y_lo"] = numbers(s.y_lo);
      js["y_hi"] = numbers(s.y_hi);
    }
    if (!s.x_lo.empty()) {
      js["x_lo"] = numbers(s.x_lo);
      js["x_hi"] = numbers(s.x_hi);
    }
    if (!s.point_labels.empty())
      js["point_labels"] = s.point_labels;
    if (!s.colour_values.empty())
      js["colour_values"] = numbers(s.colour_values);
    series.push_back(std::move(js));
  }
  j["series"] = std::move(series);
  json refs = json::array();
  for (const RefLine& r : c.ref_lines) {
    json jr{{"value", r.value},
            {"label", r.label},
            {"vertical", r.vertical},
            {"style", r.dashed ? "--" : "-"}};
    if (r.colour)
      jr["colour"] = hex(*r.colour);
    refs.push_back(std::move(jr));
  }
  j["ref_lines"] = std::move(refs);
  return j;
}

void write_binary(const std::filesystem::path& path, const void* data, std::size_t bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  if (!out.flush())
    throw std::runtime_error("plot: cannot write " + path.string());
}

json to_json(const Heatmap& m, const std::filesystem::path& dir, int& serial) {
  json j{{"type", "heatmap"},
         {"title", m.title},
         {"x_label", m.x_label},
         {"y_label", m.y_label},
         {"value_label", m.value_label},
         {"x", numbers(m.x)},
         {"y", numbers(m.y)},
         {"value_max", m.value_max},
         {"value_range", m.value_range},
         {"grey", m.grey}};
  put_opt(j, "equal_aspect", m.equal_aspect);
  put_opt(j, "scale_bar", m.scale_bar);
  const std::string name = "a" + std::to_string(serial++) + ".bin";
  if (!m.rgb.empty()) {
    write_binary(dir / name, m.rgb.data(), m.rgb.size());
    j["rgb_file"] = name;
  } else {
    // Raw doubles in the machine's order: the renderer reads them little-endian ("<f8").
    static_assert(std::endian::native == std::endian::little, "the renderer reads <f8");
    write_binary(dir / name, m.values.data(), m.values.size() * sizeof(double));
    j["values_file"] = name;
  }
  return j;
}

// A temporary folder, removed with everything in it when this goes out of scope.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "radar-emu-plot-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr)
      throw std::runtime_error("plot: cannot create a temporary folder in " +
                               std::filesystem::temp_directory_path().string() + ": " +
                               std::strerror(errno));
    path_ = tmpl;
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
};

std::string last_line(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty())
      last = line;
  }
  return last;
}

// Runs `python script spec` (no shell), its stdout and stderr to `log`; the exit status, or
// -1 with errno's text in `why` when it could not be started.
int run_renderer(const std::string& python, const std::filesystem::path& script,
                 const std::filesystem::path& spec, const std::filesystem::path& log,
                 std::string& why) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  std::string a0 = python, a1 = script.string(), a2 = spec.string();
  std::array<char*, 4> argv{a0.data(), a1.data(), a2.data(), nullptr};
  pid_t pid = 0;
  const int err = ::posix_spawnp(&pid, python.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (err != 0) {
    why = std::strerror(err);
    return -1;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      why = std::strerror(errno);
      return -1;
    }
  }
  if (WIFEXITED(status)) {
    if (WEXITSTATUS(status) == 127) {  // posix_spawnp's child could not exec
      why = "not found or not executable";
      return -1;
    }
    return WEXITSTATUS(status);
  }
  why = "killed by signal " + std::to_string(WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  return -1;
}

}  // namespace

Rgb series_colour(std::size_t k) noexcept {
  return kPalette[k % kPalette.size()];
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

std::filesystem::path svg_path(const std::filesystem::path& png) {
  std::filesystem::path p = png;
  return p.replace_extension(".svg");
}

std::string plot_interpreter() {
  const char* env = std::getenv("RADAR_EMU_PYTHON");
  return env != nullptr && *env != '\0' ? std::string(env) : std::string(kPlotPython);
}

Figure single(LineChart chart) {
  Figure f;
  f.width = chart.width;
  f.height = chart.height;
  f.panels.emplace_back(std::move(chart));
  return f;
}

Figure single(Heatmap map) {
  Figure f;
  f.width = map.width;
  f.height = map.height;
  f.panels.emplace_back(std::move(map));
  return f;
}

void FigureBatch::add(Figure figure, const std::filesystem::path& png) {
  check_size(figure.width, figure.height, png.string());
  if (figure.panels.empty())
    throw std::invalid_argument(png.string() + ": a figure with no panel");
  if (figure.columns < 1)
    throw std::invalid_argument(png.string() + ": columns must be >= 1");
  for (const Panel& p : figure.panels)
    std::visit([](const auto& x) { check(x); }, p);
  figures_.emplace_back(std::move(figure), png);
}

void FigureBatch::write() {
  if (figures_.empty())
    return;
  const TempDir tmp;
  int serial = 0;
  json figs = json::array();
  for (const auto& [f, png] : figures_) {
    json jf{{"png", std::filesystem::absolute(png).string()},
            {"svg", std::filesystem::absolute(svg_path(png)).string()},
            {"title", f.title},
            {"columns", f.columns},
            {"width", f.width},
            {"height", f.height},
            {"height_ratios", f.height_ratios}};
    json panels = json::array();
    for (const Panel& p : f.panels) {
      if (const auto* c = std::get_if<LineChart>(&p))
        panels.push_back(to_json(*c));
      else
        panels.push_back(to_json(std::get<Heatmap>(p), tmp.path(), serial));
    }
    jf["panels"] = std::move(panels);
    figs.push_back(std::move(jf));
  }
  const std::filesystem::path spec = tmp.path() / "spec.json", script = tmp.path() / "render.py",
                              log = tmp.path() / "render.log";
  {
    std::ofstream out(spec);
    out << json{{"figures", std::move(figs)}}.dump();
    std::ofstream py(script);
    py << kRenderPy;
    if (!out.flush() || !py.flush())
      throw std::runtime_error("plot: cannot write the figure spec in " + tmp.path().string());
  }
  std::string names;
  for (const auto& f : figures_)
    names += (names.empty() ? "" : ", ") + f.second.string();
  figures_.clear();
  const std::string python = plot_interpreter();
  std::string why;
  const int rc = run_renderer(python, script, spec, log, why);
  if (rc == 0)
    return;
  const std::string hint =
      "(Debian: apt-get install python3-matplotlib; or set RADAR_EMU_PYTHON "
      "to a Python 3 with matplotlib)";
  if (rc < 0)
    throw std::runtime_error("plot: cannot run " + python + " to draw " + names + ": " + why + " " +
                             hint);
  if (rc == 3)
    throw std::runtime_error("plot: " + python + " has no matplotlib to draw " + names + " " +
                             hint);
  throw std::runtime_error("plot: " + python + " failed drawing: " + last_line(log));
}

void write_figure(Figure figure, const std::filesystem::path& png) {
  FigureBatch b;
  b.add(std::move(figure), png);
  b.write();
}

void write_line_chart_png(const LineChart& chart, const std::filesystem::path& png) {
  write_figure(single(chart), png);
}

void write_heatmap_png(const Heatmap& map, const std::filesystem::path& png) {
  write_figure(single(map), png);
}

}  // namespace radar_emu::plot
