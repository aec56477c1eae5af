// radar_emu: the Python module (pybind11 + NumPy). Thin bindings over the libraries the CLI
// uses, in the CLI's units and conventions (docs/python.md): the same loaders (load_target,
// make_target, scene_description, parse_scenario), the same engines (radar::RcsEngine,
// radar::range_profile / isar_image), the same tools for sigma0 and atten (run through their
// CSV), and the closed loop stepped frame by frame (ClosedLoop::step). Nothing is computed
// here that the CLI computes elsewhere: this file converts arguments and results.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "common/units.hpp"
#include "config/cli_args.hpp"
#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "radar/constants.hpp"
#include "radar/em/rcs.hpp"
#include "radar/products/range_profile.hpp"
#include "radar/sensor/window.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "scene/scene.hpp"
#include "scene/scene_info.hpp"
#include "scene/targets.hpp"
#include "tools/atten.hpp"
#include "tools/rcs.hpp"
#include "tools/scene.hpp"
#include "tools/sigma0.hpp"

namespace py = pybind11;
namespace common = radar_emu::common;
namespace config = radar_emu::config;
namespace loop = radar_emu::loop;
namespace tools = radar_emu::tools;
namespace radar = radar_emu::radar;
namespace sc = radar_emu::scene;

namespace {

// ---- NumPy structured arrays ----------------------------------------------------------------

// Columns of a packed structured array: 'd' float64, 'q' int64, 'Q' uint64, '?' bool.
class Table {
 public:
  Table& col(std::string name, char kind) {
    columns_.push_back({std::move(name), kind, size_});
    size_ += kind == '?' ? 1 : 8;
    return *this;
  }
  [[nodiscard]] py::dtype dtype() const {
    py::list fields;
    for (const Column& c : columns_) {
      const char* fmt = c.kind == 'd' ? "<f8" : c.kind == 'q' ? "<i8" : c.kind == 'Q' ? "<u8" : "?";
      fields.append(py::make_tuple(c.name, fmt));
    }
    return py::dtype::from_args(fields);
  }
  [[nodiscard]] py::array make(std::size_t rows) const {
    py::array a(dtype(), std::vector<py::ssize_t>{static_cast<py::ssize_t>(rows)});
    if (rows > 0)
      std::memset(a.mutable_data(), 0, rows * size_);
    return a;
  }
  // Writes row `row`, column `c` of `a` (made by make()).
  template <typename T>
  void set(py::array& a, std::size_t row, std::size_t c, T value) const {
    auto* base = static_cast<char*>(a.mutable_data()) + row * size_ + columns_[c].offset;
    switch (columns_[c].kind) {
      case 'd': {
        const auto v = static_cast<double>(value);
        std::memcpy(base, &v, 8);
        break;
      }
      case 'q': {
        const auto v = static_cast<std::int64_t>(value);
        std::memcpy(base, &v, 8);
        break;
      }
      case 'Q': {
        const auto v = static_cast<std::uint64_t>(value);
        std::memcpy(base, &v, 8);
        break;
      }
      default: {
        const bool v = static_cast<bool>(value);
        std::memcpy(base, &v, 1);
      }
    }
  }
  [[nodiscard]] std::size_t columns() const noexcept { return columns_.size(); }

 private:
  struct Column {
    std::string name;
    char kind;
    std::size_t offset;
  };
  std::vector<Column> columns_;
  std::size_t size_ = 0;
};

// ---- argument conversion ---------------------------------------------------------------------

// A sweep as the CLI takes it: "X" or "START:STOP:N" (config::parse_sweep, same errors), or
// a number, or a sequence / array of numbers.
using SweepArg = std::variant<std::string, double, std::vector<double>>;

std::vector<double> sweep(const SweepArg& arg, const char* option) {
  if (const auto* text = std::get_if<std::string>(&arg))
    return config::parse_sweep(*text, option);
  if (const auto* x = std::get_if<double>(&arg))
    return {*x};
  const auto& v = std::get<std::vector<double>>(arg);
  if (v.empty())
    throw std::invalid_argument(std::string(option) + ": no values");
  return v;
}

std::string path_text(const std::filesystem::path& p) {
  return p.string();
}

void warn(const std::string& text) {
  py::module_::import("warnings").attr("warn")(text);
}

// ---- targets ---------------------------------------------------------------------------------

// A loaded target with its engine, as `radar-emu rcs` and `profile` set it up (rcs_tool.cpp):
// tools::load_target, a scene over it, radar::RcsEngine with tools::rcs_config (bounce
// cap, ray density, edge diffraction), checked as the CLI checks them.
struct Target {
  Target(const std::filesystem::path& mesh, double scale, const std::vector<std::string>& materials,
         int bounces, double rays_per_wavelength, bool edges, double edge_turn_deg)
      : path(path_text(mesh)),
        config(tools::rcs_config(bounces, rays_per_wavelength, edges, edge_turn_deg,
                                 tools::OptionSpelling::kPython)),
        loaded(tools::load_target(path, scale, materials)),
        scene(loaded.description),
        engine(scene, loaded.surfaces, config) {}
  std::string path;
  radar::RcsConfig config;  // checked before the mesh is loaded: bad settings fail fast
  tools::LoadedTarget loaded;
  sc::Scene scene;
  radar::RcsEngine engine;  // keeps a pointer to `scene`: Target is never moved
};

std::shared_ptr<Target> make_loaded_target(const std::filesystem::path& mesh, double scale,
                                           const std::vector<std::string>& materials, int bounces,
                                           double rays_per_wavelength, bool edges,
                                           double edge_turn_deg) {
  auto t = std::make_shared<Target>(mesh, scale, materials, bounces, rays_per_wavelength, edges,
                                    edge_turn_deg);
  for (const std::string& w : t->loaded.warnings)
    warn(w);
  return t;
}

// `radar-emu rcs`: one row per CSV row (theta outer, then phi, then frequency), the CSV's
// columns: freq_hz, theta_deg, phi_deg, then per polarisation rcs_P_dbsm (radar::dbsm of the
// amplitude), re_P, im_P (scattering amplitude [m]), then facets_lit, facets_partial,
// tubes_cut_off of the direction, edges (edge diffraction on) and edges_used (the direction's
// edge terms). Full double precision (the CSV prints %.6f / %.9e).
py::array rcs_sweep(const Target& t, const SweepArg& freq_hz, const SweepArg& theta_deg,
                    const SweepArg& phi_deg, const std::string& pol,
                    std::optional<double> bistatic_theta_deg,
                    std::optional<double> bistatic_phi_deg) {
  const std::vector<double> freqs = sweep(freq_hz, "freq_hz");
  const std::vector<double> theta = sweep(theta_deg, "theta_deg");
  const std::vector<double> phi = sweep(phi_deg, "phi_deg");
  const std::vector<common::Polarisation> pols = tools::parse_pols(pol);
  for (double f : freqs) {
    if (!(f > 0.0))
      throw std::invalid_argument("frequencies must be > 0 Hz");
  }
  if (pols.empty())
    throw std::invalid_argument("pol: no polarisation");
  if (bistatic_theta_deg.has_value() != bistatic_phi_deg.has_value())
    throw std::invalid_argument("give both bistatic_theta_deg and bistatic_phi_deg");
  const std::size_t nt = theta.size(), np = phi.size(), nf = freqs.size();
  std::vector<radar::ScatteringMatrix> s(nt * np * nf);
  std::vector<tools::RcsDirectionStats> per_direction(nt * np);
  std::optional<std::pair<double, double>> bistatic;
  if (bistatic_theta_deg)
    bistatic.emplace(*bistatic_theta_deg, *bistatic_phi_deg);
  {
    py::gil_scoped_release release;
    radar::RcsStats total;
    tools::sweep_rcs(t.engine, theta, phi, freqs, bistatic, s, per_direction, total);
  }
  Table table;
  table.col("freq_hz", 'd').col("theta_deg", 'd').col("phi_deg", 'd');
  for (common::Polarisation p : pols) {
    const std::string n(common::polarisation_name(p));
    table.col("rcs_" + n + "_dbsm", 'd').col("re_" + n, 'd').col("im_" + n, 'd');
  }
  table.col("facets_lit", 'Q').col("facets_partial", 'Q').col("tubes_cut_off", 'Q');
  table.col("edges", '?').col("edges_used", 'Q');
  py::array out = table.make(nt * np * nf);
  std::size_t row = 0;
  for (std::size_t it = 0; it < nt; ++it) {
    for (std::size_t ip = 0; ip < np; ++ip) {
      const tools::RcsDirectionStats& ds = per_direction[it * np + ip];
      for (std::size_t k = 0; k < nf; ++k, ++row) {
        const radar::ScatteringMatrix& m = s[(it * np + ip) * nf + k];
        std::size_t c = 0;
        table.set(out, row, c++, freqs[k]);
        table.set(out, row, c++, theta[it]);
        table.set(out, row, c++, phi[ip]);
        for (common::Polarisation p : pols) {
          const std::complex<double> a = tools::component(m, p);
          table.set(out, row, c++, radar::dbsm(a));
          table.set(out, row, c++, a.real());
          table.set(out, row, c++, a.imag());
        }
        table.set(out, row, c++, ds.facets_lit);
        table.set(out, row, c++, ds.facets_partial);
        table.set(out, row, c++, ds.tubes_cut_off);
        table.set(out, row, c++, t.config.edges);
        table.set(out, row, c++, ds.edges_used);
      }
    }
  }
  return out;
}

// `radar-emu profile`: the range profile(s) as the CSV (theta_deg, phi_deg, range_m,
// amplitude_dbsm, re_m, im_m, edges, edges_used) and, over an angle sweep, the ISAR image
// (cross_range_m, range_m, amplitude_dbsm), from radar::range_profile and radar::isar_image on the
// engine's samples, with the tool's checks.
py::dict profile_sweep(const Target& t, const SweepArg& freq_hz, const SweepArg& theta_deg,
                       const SweepArg& phi_deg, const std::string& pol, const std::string& window,
                       std::size_t oversample) {
  const std::vector<double> freqs = sweep(freq_hz, "freq_hz");
  const std::vector<double> theta = sweep(theta_deg, "theta_deg");
  const std::vector<double> phi = sweep(phi_deg, "phi_deg");
  const std::vector<common::Polarisation> pols = tools::parse_pols(pol);
  if (pols.size() != 1)
    throw std::invalid_argument("pol: a profile takes one polarisation");
  const std::size_t nf = freqs.size();
  if (nf < 2)
    throw std::invalid_argument("a range profile needs freq_hz START:STOP:N with N >= 2");
  const double df = (freqs.back() - freqs.front()) / static_cast<double>(nf - 1);
  if (!(df > 0.0) || !(freqs.front() > 0.0))
    throw std::invalid_argument("freq_hz: frequencies must be positive and increasing");
  const std::size_t nt = theta.size(), np = phi.size();
  if (nt > 1 && np > 1)
    throw std::invalid_argument("sweep theta or phi, not both (ISAR uses one angle)");
  const auto kind = radar::parse_window_kind(window);
  if (!kind)
    throw std::invalid_argument("window: '" + window +
                                "' is not none, hann, hamming, blackman or taylor");
  if (oversample < 1 || oversample > 64)
    throw std::invalid_argument("oversample must be in 1..64");
  const std::size_t na = nt * np;
  std::vector<radar::ScatteringMatrix> s(na * nf);
  std::vector<std::uint64_t> edges_used(na);
  std::vector<radar::RangeProfile> profiles;
  std::optional<radar::IsarImage> image;
  const radar::FrequencyGrid grid{freqs.front(), df, nf};
  {
    py::gil_scoped_release release;
    radar::RcsStats stats;
    tools::sweep_profile(t.engine, theta, phi, freqs, s, edges_used, stats);
    std::vector<std::complex<double>> samples(na * nf);
    for (std::size_t i = 0; i < na * nf; ++i)
      samples[i] = tools::component(s[i], pols[0]);
    for (std::size_t a = 0; a < na; ++a) {
      profiles.push_back(
          radar::range_profile(std::span<const std::complex<double>>(samples.data() + a * nf, nf),
                               grid, *kind, oversample));
    }
    if (na > 1) {
      std::vector<double> angles(na);
      for (std::size_t a = 0; a < na; ++a)
        angles[a] = common::radians(nt > 1 ? theta[a] : phi[a]);
      double step = (angles.back() - angles.front()) / static_cast<double>(na - 1);
      std::vector<std::complex<double>> ordered = samples;
      if (step < 0.0) {  // descending sweep: imaged in ascending angle, as the tool does
        step = -step;
        for (std::size_t a = 0; a < na; ++a) {
          std::copy_n(samples.begin() + static_cast<std::ptrdiff_t>((na - 1 - a) * nf), nf,
                      ordered.begin() + static_cast<std::ptrdiff_t>(a * nf));
        }
      }
      image = radar::isar_image(ordered, grid, step, na, *kind, oversample);
    }
  }
  Table pt;
  pt.col("theta_deg", 'd')
      .col("phi_deg", 'd')
      .col("range_m", 'd')
      .col("amplitude_dbsm", 'd')
      .col("re_m", 'd')
      .col("im_m", 'd')
      .col("edges", '?')
      .col("edges_used", 'Q');
  std::size_t rows = 0;
  for (const auto& p : profiles)
    rows += p.range_m.size();
  py::array prof = pt.make(rows);
  std::size_t row = 0;
  for (std::size_t a = 0; a < na; ++a) {
    const std::size_t it = nt > 1 ? a : 0, ip = np > 1 ? a : 0;
    const radar::RangeProfile& p = profiles[a];
    for (std::size_t i = 0; i < p.range_m.size(); ++i, ++row) {
      pt.set(prof, row, 0, theta[it]);
      pt.set(prof, row, 1, phi[ip]);
      pt.set(prof, row, 2, p.range_m[i]);
      pt.set(prof, row, 3, radar::dbsm(p.amplitude_m[i]));
      pt.set(prof, row, 4, p.amplitude_m[i].real());
      pt.set(prof, row, 5, p.amplitude_m[i].imag());
      pt.set(prof, row, 6, t.config.edges);
      pt.set(prof, row, 7, edges_used[a]);
    }
  }
  const radar::RangeProfile& centre = profiles[na / 2];
  py::dict out;
  out["profile"] = prof;
  out["resolution_m"] = centre.resolution_m;
  out["bin_m"] = centre.bin_m;
  out["unambiguous_m"] = centre.unambiguous_m;
  if (image) {
    Table it;
    it.col("cross_range_m", 'd').col("range_m", 'd').col("amplitude_dbsm", 'd');
    py::array isar = it.make(image->pixels_m.size());
    std::size_t k = 0;
    for (std::size_t r = 0; r < image->cross_range_m.size(); ++r) {
      for (std::size_t c = 0; c < image->range_m.size(); ++c, ++k) {
        it.set(isar, k, 0, image->cross_range_m[r]);
        it.set(isar, k, 1, image->range_m[c]);
        it.set(isar, k, 2, radar::dbsm(image->pixels_m[r * image->range_m.size() + c]));
      }
    }
    out["isar"] = isar;
    out["isar_shape"] = py::make_tuple(image->cross_range_m.size(), image->range_m.size());
    out["cross_range_resolution_m"] = image->cross_range_resolution_m;
  } else {
    out["isar"] = py::none();
  }
  return out;
}

// ---- sigma0 and atten: the tools themselves, through their CSV -------------------------------

// A temporary CSV path, removed when this goes out of scope.
struct TempCsv {
  TempCsv() {
    static std::atomic<unsigned> counter{0};
    path = std::filesystem::temp_directory_path() / ("radar_emu_py_" + std::to_string(::getpid()) +
                                                     "_" + std::to_string(counter++) + ".csv");
  }
  ~TempCsv() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
  TempCsv(const TempCsv&) = delete;
  TempCsv& operator=(const TempCsv&) = delete;
  std::filesystem::path path;
};

// Reads a tool's CSV (header line, then numbers; an empty field is NaN) into a structured
// array; columns named in `bool_columns` become bool.
py::array read_csv(const std::filesystem::path& path,
                   const std::vector<std::string>& bool_columns) {
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line))
    throw std::runtime_error(path.string() + ": empty output");
  auto split = [](const std::string& l) {
    std::vector<std::string> out;
    std::stringstream ss(l);
    std::string f;
    while (std::getline(ss, f, ','))
      out.push_back(f);
    if (!l.empty() && l.back() == ',')
      out.emplace_back();
    return out;
  };
  const std::vector<std::string> names = split(line);
  Table t;
  for (const std::string& n : names)
    t.col(n,
          std::find(bool_columns.begin(), bool_columns.end(), n) != bool_columns.end() ? '?' : 'd');
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    if (!line.empty())
      rows.push_back(split(line));
  }
  py::array a = t.make(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t c = 0; c < names.size(); ++c) {
      const std::string f = c < rows[r].size() ? rows[r][c] : std::string();
      t.set(a, r, c, f.empty() ? std::nan("") : std::strtod(f.c_str(), nullptr));
    }
  }
  return a;
}

py::array sigma0(double freq_hz, const std::string& material, std::optional<double> eps_real,
                 std::optional<double> eps_loss, std::optional<double> rms_height_m,
                 std::optional<double> corr_length_m, const std::string& corr, double x_power,
                 const std::string& model, const SweepArg& theta_deg,
                 const std::optional<SweepArg>& theta_s_deg, double phi_s_deg,
                 const std::string& pol) {
  tools::Sigma0ToolOptions o;
  o.material = material;
  o.eps_real = eps_real;
  o.eps_loss = eps_loss;
  o.rms_height_m = rms_height_m;
  o.corr_length_m = corr_length_m;
  o.correlation = corr;
  o.x_power = x_power;
  o.freq_hz = freq_hz;
  o.model = model;
  o.theta_deg = sweep(theta_deg, "theta_deg");
  if (theta_s_deg)
    o.theta_s_deg = sweep(*theta_s_deg, "theta_s_deg");
  o.phi_s_deg = phi_s_deg;
  o.pols = pol;
  TempCsv csv;
  o.out_csv = csv.path.string();
  o.quiet = true;
  (void)tools::run_sigma0_tool(o);
  return read_csv(csv.path, {"valid"});
}

py::array atten(const SweepArg& freq_hz, double pressure_hpa, double temp_c, double rho_gm3,
                double rain_mmh, double fog_gm3, double veg_depth_m, bool out_of_leaf) {
  tools::AttenToolOptions o;
  o.freqs_hz = sweep(freq_hz, "freq_hz");
  o.dry_pressure_hpa = pressure_hpa;
  o.temperature_c = temp_c;
  o.water_vapour_gm3 = rho_gm3;
  o.rain_mm_per_h = rain_mmh;
  o.fog_gm3 = fog_gm3;
  o.veg_depth_m = veg_depth_m;
  o.out_of_leaf = out_of_leaf;
  TempCsv csv;
  o.out_csv = csv.path.string();
  o.quiet = true;
  (void)tools::run_atten_tool(o);
  return read_csv(csv.path, {});
}

// ---- scenes ----------------------------------------------------------------------------------

// A scene database summary: what `radar-emu scene info --json` prints, as a dict.
py::object scene_info(const std::filesystem::path& file) {
  std::vector<std::string> warnings;
  const sc::SceneDescription desc = sc::load_gltf(file, &warnings);
  for (const std::string& w : warnings)
    warn(w);
  const std::string json =
      tools::scene_info_json(sc::scene_info(desc), file.string(), warnings.size());
  return py::module_::import("json").attr("loads")(json);
}

// The objects of a description: name, triangle count, material names.
py::list objects_of(const sc::SceneDescription& d) {
  py::list out;
  for (const sc::ObjectDesc& o : d.objects) {
    py::dict e;
    e["name"] = o.name;
    e["triangles"] = o.mesh.triangles.size();
    e["vertices"] = o.mesh.positions_m.size();
    e["moving"] = o.motion.has_value() || o.trajectory.has_value();
    out.append(e);
  }
  return out;
}

// `radar-emu scene target`: writes a canonical target (.glb/.gltf/.obj/.stl by extension).
std::size_t write_target(const std::string& kind_name, const std::filesystem::path& out,
                         std::optional<double> a_m, std::optional<double> b_m,
                         std::optional<double> c_m, double facet_m) {
  const auto kind = sc::target_kind_from_name(kind_name);
  if (!kind) {
    throw std::invalid_argument("unknown target '" + kind_name + "' (known: " + sc::target_names() +
                                ")");
  }
  // The kind's default size (the table `scene target` and [[target]] read); none for shapes.
  const sc::TargetKindSize size = sc::target_kind_size(*kind);
  sc::TargetSpec spec;
  spec.kind = *kind;
  const std::optional<double> given[3] = {a_m, b_m, c_m};
  double* dim[3] = {&spec.a_m, &spec.b_m, &spec.c_m};
  static const char* const kName[3] = {"a_m", "b_m", "c_m"};
  for (int d = 0; d < 3; ++d) {
    if (given[d] && d >= size.dims)
      throw std::invalid_argument(std::string(kName[d]) + ": a " + kind_name + " takes " +
                                  std::to_string(size.dims) + " dimension(s) " +
                                  std::string(size.meaning));
    if (given[d])
      *dim[d] = *given[d];
    else if (d < size.dims && size.default_m)
      *dim[d] = (*size.default_m)[static_cast<std::size_t>(d)];
    else if (d < size.dims)
      throw std::invalid_argument(std::string(kName[d]) + ": a " + kind_name +
                                  " has no default size: give " + std::string(size.meaning) +
                                  " in metres");
  }
  spec.facet_m = facet_m;
  return sc::write_target_file(spec, out);
}

// ---- the closed loop -------------------------------------------------------------------------

loop::Scenario scenario_from(const std::optional<std::filesystem::path>& file,
                             const std::optional<std::string>& toml) {
  if (file && toml)
    throw std::invalid_argument("give a scenario file or TOML text, not both");
  if (file)
    return loop::load_scenario(*file);
  if (toml)
    return loop::parse_scenario(*toml, "<python>");
  return loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
}

const Table& detection_table() {
  static const Table t = [] {
    Table d;
    d.col("range_m", 'd')
        .col("azimuth_deg", 'd')
        .col("elevation_deg", 'd')
        .col("radial_velocity_mps", 'd')
        .col("snr_db", 'd')
        .col("rcs_dbsm", 'd')
        .col("range_std_m", 'd')
        .col("azimuth_std_deg", 'd')
        .col("elevation_std_deg", 'd')
        .col("radial_velocity_std_mps", 'd')
        .col("range_ambiguous", '?')
        .col("velocity_ambiguous", '?')
        .col("object_id", 'q');
    return d;
  }();
  return t;
}

const Table& truth_table() {
  static const Table t = [] {
    Table d;
    d.col("object_id", 'q')
        .col("range_m", 'd')
        .col("azimuth_deg", 'd')
        .col("elevation_deg", 'd')
        .col("radial_velocity_mps", 'd');
    return d;
  }();
  return t;
}

// `radar-emu run` stepped from Python: the scenario's loop on the simulated clock, the bus
// "sim"; each step() one frame, with the ownship state from the bus (the scenario's scripted
// INS) or given by the caller.
class Loop {
 public:
  Loop(const std::optional<std::filesystem::path>& file, const std::optional<std::string>& toml,
       std::optional<std::uint64_t> frames, const std::optional<std::filesystem::path>& out_dir,
       const std::optional<std::filesystem::path>& cube,
       const std::optional<std::string>& cube_frames)
      : scenario_(scenario_from(file, toml)) {
    if (frames) {
      if (*frames < 1 || *frames > 100'000'000)
        throw std::invalid_argument("frames must be in 1..100000000");
      scenario_.frames = *frames;
    }
    loop::RunOptions o;
    o.record_frames_max = 0;  // each step hands its frame to Python; nothing kept in memory
    if (out_dir)
      o.out_dir = *out_dir;
    has_outputs_ = out_dir.has_value();
    // Data cubes (docs/cube.md): the scenario's [output] cube and cube_frames, each replaced by
    // the argument when given, as `radar-emu run --cube --cube-frames` replaces them.
    try {
      loop::choose_cube(scenario_, cube ? cube->string() : std::string(), cube_frames.value_or(""),
                        o, "cube=", "cube_frames=");
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(e.what());
    }
    loop_ = std::make_unique<loop::ClosedLoop>(scenario_, o);
    for (const std::string& w : loop_->setup_warnings())
      warn(w);
  }

  // The next frame as a dict, or None once the scenario's frames are done.
  py::object step(const std::optional<py::dict>& ownship) {
    if (finished_)
      throw std::runtime_error("the loop has finished");
    loop::OwnshipInput in;
    const loop::OwnshipInput* given = nullptr;
    if (ownship) {
      in = ownship_from(*ownship);
      given = &in;
    }
    loop::FrameOutput f;
    bool ran = false;
    {
      py::gil_scoped_release release;
      ran = loop_->step(f, given);
    }
    if (!ran)
      return py::none();
    ++frames_done_;
    return frame_dict(f);
  }

  // Ends the run: the summary (and, with out_dir, every output file written as `radar-emu run`
  // writes them).
  py::dict finish() {
    if (finished_)
      throw std::runtime_error("the loop has finished");
    finished_ = true;
    const loop::RunResult r = loop_->finish();
    if (has_outputs_)
      loop_->write_outputs(r);
    py::dict d;
    d["frames"] = r.frames;
    d["frames_planned"] = r.frames_planned;
    d["frames_valid"] = r.frames_valid;
    d["detections_total"] = r.detections_total;
    d["detections_min"] = r.detections_min;
    d["detections_max"] = r.detections_max;
    d["bus_frames_in"] = r.bus_frames_in;
    d["bus_frames_out"] = r.bus_frames_out;
    d["sink_lists"] = r.sink_lists;
    d["frames_over_budget"] = r.frames_over_budget;
    d["frames_degraded"] = r.governor.frames_degraded;
    // The outcome per target (loop/outcome.hpp, docs/outcome.md), in report.json's units.
    const loop::RunReport rep = loop_->report(r);
    const loop::OutcomeTotals& o = r.outcome;
    d["frames_scored"] = o.frames_scored;
    d["false_alarms"] = o.false_alarms;
    d["false_alarms_on_objects"] = o.false_alarms_on_objects;
    d["false_alarms_per_frame"] = o.false_alarms_per_frame();
    py::list targets;
    for (const loop::TargetOutcome& t : o.targets) {
      py::dict e;
      e["object_id"] = t.object_id;
      e["object"] =
          t.object_id < rep.object_names.size() ? rep.object_names[t.object_id] : std::string();
      e["frames_in_beam"] = t.frames_in_beam;
      e["frames_detected"] = t.frames_detected;
      e["pd"] = t.frames_in_beam > 0 ? py::object(py::float_(t.pd())) : py::object(py::none());
      e["detections_associated"] = t.detections_associated;
      auto error = [](const loop::ErrorStats& x, double scale) -> py::object {
        if (x.count == 0)
          return py::none();
        py::dict s;
        s["mean"] = x.mean * scale;
        s["std"] = x.std_dev() * scale;
        s["stated_sigma_rms"] = x.stated_sigma_rms() * scale;
        return s;
      };
      e["range_error_m"] = error(t.range_m, 1.0);
      e["azimuth_error_deg"] = error(t.azimuth_rad, common::degrees(1.0));
      e["elevation_error_deg"] = error(t.elevation_rad, common::degrees(1.0));
      e["radial_velocity_error_mps"] = error(t.radial_velocity_mps, 1.0);
      targets.append(e);
    }
    d["targets"] = targets;
    // The cube file, when the run wrote one: what it holds and what it lost (docs/cube.md).
    if (const std::optional<loop::CubeCounters> c = loop_->cube_counters()) {
      py::dict e;
      e["file"] = c->file;
      e["first_frame"] = c->first_frame;
      e["last_frame"] = c->last_frame;
      e["frames_written"] = c->frames_written;
      e["frames_dropped"] = c->frames_dropped;
      e["frames_without_state"] = c->frames_without_state;
      e["capture_dropped"] = c->capture_dropped;
      e["write_errors"] = c->write_errors;
      e["bytes_written"] = c->bytes_written;
      e["first_error"] = c->first_error;
      d["cube"] = e;
    } else {
      d["cube"] = py::none();
    }
    return d;
  }

  [[nodiscard]] const loop::Scenario& scenario() const noexcept { return scenario_; }
  [[nodiscard]] std::uint64_t frames_done() const noexcept { return frames_done_; }
  // The scene objects' names (detections' and truth's object_id index them), as
  // detections.json names them: the scenario's scene description, built on first use.
  [[nodiscard]] const std::vector<std::string>& object_names() {
    if (!names_) {
      names_.emplace();
      for (const auto& o : loop::scene_description(loop_->scenario()).objects)
        names_->push_back(o.name);
    }
    return *names_;
  }

 private:
  static glm::dvec3 vec3(const py::dict& d, const char* key) {
    if (!d.contains(key))
      return glm::dvec3(0.0);
    const auto v = d[key].cast<std::vector<double>>();
    if (v.size() != 3)
      throw std::invalid_argument(std::string("ownship ") + key + ": three numbers (E, N, U)");
    return {v[0], v[1], v[2]};
  }
  static double number(const py::dict& d, const char* key) {
    return d.contains(key) ? d[key].cast<double>() : 0.0;
  }
  static loop::OwnshipInput ownship_from(const py::dict& d) {
    static const char* const kKeys[] = {"position_enu_m", "velocity_enu_mps", "heading_deg",
                                        "pitch_deg", "roll_deg"};
    for (const auto& item : d) {
      const auto key = item.first.cast<std::string>();
      if (std::find_if(std::begin(kKeys), std::end(kKeys),
                       [&](const char* k) { return key == k; }) == std::end(kKeys)) {
        throw std::invalid_argument("ownship: unknown key '" + key +
                                    "' (position_enu_m, velocity_enu_mps, heading_deg, "
                                    "pitch_deg, roll_deg)");
      }
    }
    if (!d.contains("position_enu_m"))
      throw std::invalid_argument("ownship: position_enu_m is required");
    loop::OwnshipInput in;
    in.position_enu_m = vec3(d, "position_enu_m");
    in.velocity_enu_mps = vec3(d, "velocity_enu_mps");
    in.heading_rad = common::radians(number(d, "heading_deg"));
    in.pitch_rad = common::radians(number(d, "pitch_deg"));
    in.roll_rad = common::radians(number(d, "roll_deg"));
    for (double x : {in.position_enu_m.x, in.position_enu_m.y, in.position_enu_m.z,
                     in.velocity_enu_mps.x, in.velocity_enu_mps.y, in.velocity_enu_mps.z,
                     in.heading_rad, in.pitch_rad, in.roll_rad}) {
      if (!std::isfinite(x))
        throw std::invalid_argument("ownship: values must be finite");
    }
    return in;
  }

  py::dict frame_dict(const loop::FrameOutput& f) const {
    const loop::FrameRecord& rec = f.record;
    py::dict d;
    d["frame_index"] = rec.frame_index;
    d["frame_counter"] = rec.header.frame_counter;
    d["time_s"] = rec.time_s;
    d["status"] = rec.header.status;
    d["ownship_valid"] = rec.ownship_valid;
    d["sent"] = rec.sent;
    d["late"] = rec.late;
    py::array_t<double> own(3);
    own.mutable_at(0) = rec.ownship_enu_m.x;
    own.mutable_at(1) = rec.ownship_enu_m.y;
    own.mutable_at(2) = rec.ownship_enu_m.z;
    d["ownship_enu_m"] = own;
    d["governor_level"] = rec.governor_level;
    d["rays"] = rec.rays;
    const Table& dt = detection_table();
    py::array dets = dt.make(f.detections.size());
    for (std::size_t i = 0; i < f.detections.size(); ++i) {
      const radar_emu::io::icd::Detection& x = f.detections[i];
      const std::uint32_t id = f.sensor_detections[i].object_id;
      std::size_t c = 0;
      dt.set(dets, i, c++, x.range_m);
      dt.set(dets, i, c++, x.azimuth_deg);
      dt.set(dets, i, c++, x.elevation_deg);
      dt.set(dets, i, c++, x.radial_velocity_mps);
      dt.set(dets, i, c++, x.snr_db);
      dt.set(dets, i, c++, x.rcs_dbsm);
      dt.set(dets, i, c++, x.range_std_m);
      dt.set(dets, i, c++, x.azimuth_std_deg);
      dt.set(dets, i, c++, x.elevation_std_deg);
      dt.set(dets, i, c++, x.radial_velocity_std_mps);
      dt.set(dets, i, c++, x.range_ambiguous);
      dt.set(dets, i, c++, x.velocity_ambiguous);
      dt.set(dets, i, c++,
             id == radar::kNoObject ? std::int64_t{-1} : static_cast<std::int64_t>(id));
    }
    d["detections"] = dets;
    const Table& tt = truth_table();
    py::array truth = tt.make(f.truth.size());
    for (std::size_t i = 0; i < f.truth.size(); ++i) {
      const loop::ObjectTruth& o = f.truth[i];
      tt.set(truth, i, 0, o.object_id);
      tt.set(truth, i, 1, o.range_m);
      tt.set(truth, i, 2, common::degrees(o.azimuth_rad));
      tt.set(truth, i, 3, common::degrees(o.elevation_rad));
      tt.set(truth, i, 4, o.radial_velocity_mps);
    }
    d["truth"] = truth;
    // Per detection: the index into "truth" of the object it was associated with, -1 for a
    // false alarm (docs/outcome.md).
    py::array_t<std::int64_t> association(static_cast<py::ssize_t>(f.detections.size()));
    for (std::size_t i = 0; i < f.detections.size(); ++i) {
      association.mutable_at(static_cast<py::ssize_t>(i)) =
          i < f.association.size() ? f.association[i] : -1;
    }
    d["association"] = association;
    return d;
  }

  loop::Scenario scenario_;
  std::unique_ptr<loop::ClosedLoop> loop_;
  std::optional<std::vector<std::string>> names_;
  bool has_outputs_ = false;
  bool finished_ = false;
  std::uint64_t frames_done_ = 0;
};

}  // namespace

PYBIND11_MODULE(radar_emu, m) {
  m.doc() =
      "radar-emu from Python: RCS, range profiles, sigma0, ITU attenuation and the closed loop, "
      "through the same C++ code as the radar-emu CLI, in its units (docs/python.md)";
  m.attr("__version__") = "0.1.0";
  m.attr("built_for_python") = RADAR_EMU_PYTHON_EXECUTABLE;

  // NumPy at import, with the interpreter to use when it is missing: the module is built for
  // one interpreter (CMake's Python3_EXECUTABLE, Debian's /usr/bin/python3 by default, which
  // has python3-numpy), and another one on PATH (a pyenv or venv build) may lack NumPy, which
  // would otherwise surface later as a bare "No module named 'numpy'" from the first array.
  try {
    py::module_::import("numpy");
  } catch (py::error_already_set& e) {
    const std::string here = py::str(py::module_::import("sys").attr("executable"));
    throw py::import_error("radar_emu: this interpreter (" + here + ") cannot import NumPy (" +
                           std::string(e.what()) +
                           "); the module was built for " RADAR_EMU_PYTHON_EXECUTABLE
                           ": run it with that interpreter, or install NumPy for this one");
  }

  // Errors: std::invalid_argument -> ValueError, std::runtime_error -> RuntimeError (pybind11's
  // defaults), with the CLI's one-line messages.

  m.def("target_names", [] {
    std::vector<std::string> out;
    const std::string all = sc::target_names();
    std::size_t start = 0;
    for (;;) {
      const std::size_t bar = all.find('|', start);
      out.push_back(all.substr(start, bar == std::string::npos ? bar : bar - start));
      if (bar == std::string::npos)
        return out;
      start = bar + 1;
    }
  });
  m.def("write_target", &write_target, py::arg("kind"), py::arg("out"), py::arg("a_m") = py::none(),
        py::arg("b_m") = py::none(), py::arg("c_m") = py::none(), py::arg("facet_m") = 0.0,
        "Writes a canonical target (radar-emu scene target KIND --out OUT ...); returns its "
        "triangle count.");
  m.def("scene_info", &scene_info, py::arg("file"),
        "Summary of a glTF scene database, as radar-emu scene info --json.");
  m.def(
      "scenario_scene",
      [](const std::optional<std::filesystem::path>& file, const std::optional<std::string>& toml) {
        const loop::Scenario s = scenario_from(file, toml);
        const sc::SceneDescription d = loop::scene_description(s);
        py::dict out;
        out["objects"] = objects_of(d);
        py::list mats;
        for (const auto& mat : d.materials)
          mats.append(mat.name);
        out["materials"] = mats;
        out["anchor_deg_m"] =
            py::make_tuple(common::degrees(d.anchor.latitude_rad),
                           common::degrees(d.anchor.longitude_rad), d.anchor.height_m);
        return out;
      },
      py::arg("scenario") = py::none(), py::kw_only(), py::arg("toml") = py::none(),
      "The scene a scenario names (builtin or glTF, with its [[target]] tables), as the loop "
      "builds it: objects and materials.");
  m.def(
      "default_scenario_toml", [] { return std::string(loop::default_scenario_toml()); },
      "The embedded default scenario (radar-emu run --print-scenario).");

  py::class_<Target, std::shared_ptr<Target>>(
      m, "Target",
      "A target mesh (.glb, .gltf, .obj, .stl) with its RCS engine, as radar-emu rcs / profile "
      "load it (--mesh, --scale, --material, --bounces, --rays-per-wavelength, --no-edges, "
      "--edge-turn-deg).")
      .def(py::init(&make_loaded_target), py::arg("mesh"), py::arg("scale") = 1.0,
           py::arg("materials") = std::vector<std::string>{}, py::arg("bounces") = 3,
           py::arg("rays_per_wavelength") = 4.0, py::arg("edges") = true,
           py::arg("edge_turn_deg") = 30.0)
      .def_property_readonly("edges", [](const Target& t) { return t.config.edges; })
      .def_property_readonly("edge_count", [](const Target& t) { return t.engine.edges().size(); })
      .def_property_readonly("path", [](const Target& t) { return t.path; })
      .def_property_readonly("facet_count", [](const Target& t) { return t.engine.facet_count(); })
      .def_property_readonly("degenerate_facets",
                             [](const Target& t) { return t.engine.degenerate_facets(); })
      .def_property_readonly("bounding_radius_m",
                             [](const Target& t) { return t.engine.bounding_radius_m(); })
      .def_property_readonly("warnings", [](const Target& t) { return t.loaded.warnings; })
      .def("rcs", &rcs_sweep, py::arg("freq_hz"), py::arg("theta_deg") = SweepArg(0.0),
           py::arg("phi_deg") = SweepArg(0.0), py::arg("pol") = "HH,VV",
           py::arg("bistatic_theta_deg") = py::none(), py::arg("bistatic_phi_deg") = py::none(),
           "RCS sweep (radar-emu rcs): a structured array with the CSV's columns and rows.")
      .def("profile", &profile_sweep, py::arg("freq_hz"), py::arg("theta_deg") = SweepArg(0.0),
           py::arg("phi_deg") = SweepArg(0.0), py::arg("pol") = "VV", py::arg("window") = "hann",
           py::arg("oversample") = 4,
           "Range profile, and ISAR over an angle sweep (radar-emu profile).");

  m.def(
      "rcs",
      [](const std::filesystem::path& mesh, const SweepArg& freq_hz, const SweepArg& theta_deg,
         const SweepArg& phi_deg, const std::string& pol, std::optional<double> bt,
         std::optional<double> bp, double scale, const std::vector<std::string>& materials,
         int bounces, double rpw, bool edges, double edge_turn_deg) {
        const auto t =
            make_loaded_target(mesh, scale, materials, bounces, rpw, edges, edge_turn_deg);
        return rcs_sweep(*t, freq_hz, theta_deg, phi_deg, pol, bt, bp);
      },
      py::arg("mesh"), py::arg("freq_hz"), py::arg("theta_deg") = SweepArg(0.0),
      py::arg("phi_deg") = SweepArg(0.0), py::arg("pol") = "HH,VV",
      py::arg("bistatic_theta_deg") = py::none(), py::arg("bistatic_phi_deg") = py::none(),
      py::arg("scale") = 1.0, py::arg("materials") = std::vector<std::string>{},
      py::arg("bounces") = 3, py::arg("rays_per_wavelength") = 4.0, py::arg("edges") = true,
      py::arg("edge_turn_deg") = 30.0,
      "radar-emu rcs: loads the mesh and sweeps; a structured array with the CSV's columns.");
  m.def(
      "profile",
      [](const std::filesystem::path& mesh, const SweepArg& freq_hz, const SweepArg& theta_deg,
         const SweepArg& phi_deg, const std::string& pol, const std::string& window,
         std::size_t oversample, double scale, const std::vector<std::string>& materials,
         int bounces, double rpw, bool edges, double edge_turn_deg) {
        const auto t =
            make_loaded_target(mesh, scale, materials, bounces, rpw, edges, edge_turn_deg);
        return profile_sweep(*t, freq_hz, theta_deg, phi_deg, pol, window, oversample);
      },
      py::arg("mesh"), py::arg("freq_hz"), py::arg("theta_deg") = SweepArg(0.0),
      py::arg("phi_deg") = SweepArg(0.0), py::arg("pol") = "VV", py::arg("window") = "hann",
      py::arg("oversample") = 4, py::arg("scale") = 1.0,
      py::arg("materials") = std::vector<std::string>{}, py::arg("bounces") = 3,
      py::arg("rays_per_wavelength") = 4.0, py::arg("edges") = true,
      py::arg("edge_turn_deg") = 30.0, "radar-emu profile: range profile and ISAR image.");
  m.def("sigma0", &sigma0, py::arg("freq_hz"), py::kw_only(), py::arg("material") = "",
        py::arg("eps_real") = py::none(), py::arg("eps_loss") = py::none(),
        py::arg("rms_height_m") = py::none(), py::arg("corr_length_m") = py::none(),
        py::arg("corr") = "exponential", py::arg("x_power") = 1.5, py::arg("model") = "total",
        py::arg("theta_deg") = SweepArg(std::string("0:85:86")),
        py::arg("theta_s_deg") = py::none(), py::arg("phi_s_deg") = 0.0,
        py::arg("pol") = "HH,VV,HV,VH",
        "radar-emu sigma0: the tool's CSV as a structured array (its printed precision).");
  m.def("atten", &atten, py::arg("freq_hz"), py::kw_only(), py::arg("pressure_hpa") = 1013.25,
        py::arg("temp_c") = 15.0, py::arg("rho_gm3") = 7.5, py::arg("rain_mmh") = 0.0,
        py::arg("fog_gm3") = 0.0, py::arg("veg_depth_m") = 0.0, py::arg("out_of_leaf") = false,
        "radar-emu atten: the tool's CSV as a structured array (its printed precision).");

  m.attr("detection_dtype") = detection_table().dtype();
  m.attr("truth_dtype") = truth_table().dtype();

  py::class_<Loop>(m, "Loop",
                   "The closed loop of radar-emu run, stepped frame by frame from Python.")
      .def(py::init<const std::optional<std::filesystem::path>&, const std::optional<std::string>&,
                    std::optional<std::uint64_t>, const std::optional<std::filesystem::path>&,
                    const std::optional<std::filesystem::path>&,
                    const std::optional<std::string>&>(),
           py::arg("scenario") = py::none(), py::kw_only(), py::arg("toml") = py::none(),
           py::arg("frames") = py::none(), py::arg("out_dir") = py::none(),
           py::arg("cube") = py::none(), py::arg("cube_frames") = py::none())
      .def("step", &Loop::step, py::arg("ownship") = py::none(),
           "Runs the next frame; a dict, or None once the scenario's frames are done.")
      .def("finish", &Loop::finish, "Ends the run: a summary dict (and the files in out_dir).")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__",
           [](Loop& l) {
             py::object f = l.step(std::nullopt);
             if (f.is_none())
               throw py::stop_iteration();
             return f;
           })
      .def_property_readonly("frames", [](const Loop& l) { return l.scenario().frames; })
      .def_property_readonly("rate_hz", [](const Loop& l) { return l.scenario().rate_hz; })
      .def_property_readonly("name", [](const Loop& l) { return l.scenario().name; })
      .def_property_readonly("frames_done", &Loop::frames_done)
      .def_property_readonly("object_names", &Loop::object_names);
}
