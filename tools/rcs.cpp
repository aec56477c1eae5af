#include "tools/rcs.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>

#include "common/path.hpp"
#include "common/units.hpp"
#include "config/cli_args.hpp"
#include "config/memory_limit.hpp"
#include "config/progress.hpp"
#include "plot/charts.hpp"
#include "radar/constants.hpp"
#include "radar/em/mom.hpp"
#include "radar/em/surfaces.hpp"
#include "radar/products/fluctuation.hpp"
#include "radar/products/range_profile.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "tools/mpi_work.hpp"

namespace radar_emu::tools {

using common::Polarisation;

using config::parse_number;
using config::split;
using plot::Figure;
using plot::FigureBatch;
using plot::Heatmap;
using plot::LineChart;
using plot::Series;
using plot::write_line_chart_png;

using config::parse_sweep;

namespace {

std::filesystem::path sibling(const std::string& path, const std::string& suffix) {
  std::filesystem::path p(path);
  return p.parent_path() / (p.stem().string() + suffix);
}

FILE* open_or_throw(const std::filesystem::path& path) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr)
    throw std::runtime_error(path.string() + ": cannot open for writing");
  return f;
}

struct FileCloser {
  void operator()(FILE* f) const noexcept { std::fclose(f); }
};
using File = std::unique_ptr<FILE, FileCloser>;

// Flushes and closes a written file: an error buffered until then (a full disk, /dev/full) is a
// failed write, not a silent empty file.
void close_or_throw(File& f, const std::string& path) {
  const bool flushed = std::fflush(f.get()) == 0 && std::ferror(f.get()) == 0;
  const bool closed = std::fclose(f.release()) == 0;
  if (!flushed || !closed)
    throw std::runtime_error(path + ": write failed");
}

double db_of_power(double p) {
  return p > 0.0 ? common::db_from_power(p) : -400.0;
}

// Directions computed side by side per wave in the sweeps (sweep_in_waves).
constexpr std::size_t kDirectionWave = 8;

// A stop request, heard in one process only: under mpirun every rank must run its whole block
// (the gather waits for all of them), so a split sweep runs to its end.
bool stopped(const std::atomic<int>* stop) {
  return stop != nullptr && mpi_work::launched_size() <= 1 &&
         stop->load(std::memory_order_relaxed) != 0;
}

// Sums the counters of one compute() call into a run's total.
void add_stats(radar::RcsStats& total, const radar::RcsStats& one) {
  total.facets_lit += one.facets_lit;
  total.facets_partial += one.facets_partial;
  total.lit_subfacets += one.lit_subfacets;
  total.facets_shadowed += one.facets_shadowed;
  total.facets_edge_on += one.facets_edge_on;
  total.rays += one.rays;
  total.ray_hits += one.ray_hits;
  total.paths += one.paths;
  total.grazing_stops += one.grazing_stops;
  total.tubes_cut_off += one.tubes_cut_off;
  total.occlusion_queries += one.occlusion_queries;
  total.segments += one.segments;
  total.edges_used += one.edges_used;
  total.edges_shadowed += one.edges_shadowed;
  total.edges_skipped += one.edges_skipped;
  total.edges_guarded += one.edges_guarded;
  total.edges_double += one.edges_double;
  total.edges_reflected += one.edges_reflected;
  for (std::size_t b = 0; b <= static_cast<std::size_t>(radar::kMaxRcsBounces); ++b)
    total.paths_by_bounce[b] += one.paths_by_bounce[b];
}

// The directions of this rank's block in waves (kDirectionWave), the directions of a wave side by
// side, one TBB task each (compute() is parallel inside too): a direction's serial stages and
// joins then leave no core idle. `one(d, stats)` computes direction d whole; its result does not
// depend on the threading, so the output is that of one direction at a time. Progress and the
// stop signal are checked per wave. Returns the directions done (`all` unless stopped).
template <class ComputeOne>
std::size_t sweep_in_waves(const mpi_work::Block& mine, std::size_t all,
                           const std::atomic<int>* stop,
                           const std::function<void(std::size_t)>& progress,
                           radar::RcsStats& mine_total, ComputeOne&& one) {
  std::array<radar::RcsStats, kDirectionWave> wave{};
  for (std::size_t w = mine.begin; w < mine.end; w += kDirectionWave) {
    if (stopped(stop))
      return w;
    const std::size_t w_end = std::min(mine.end, w + kDirectionWave);
    tbb::parallel_for(w, w_end, [&](std::size_t d) {
      radar::RcsStats& st = wave[d - w];
      st = {};
      one(d, st);
    });
    for (std::size_t d = w; d < w_end; ++d) {
      add_stats(mine_total, wave[d - w]);
      if (progress)
        progress(d - mine.begin + 1);
    }
  }
  return all;
}

// Adds a sweep's counters to `total`: this rank's `mine`; on rank 0 of an MPI split, every
// rank's, gathered one record a rank and added in rank order (integers: the same sum as one
// process).
void add_gathered_stats(radar::RcsStats& total, const radar::RcsStats& mine) {
  std::vector<radar::RcsStats> per_rank(static_cast<std::size_t>(mpi_work::size()));
  per_rank[static_cast<std::size_t>(mpi_work::rank())] = mine;
  mpi_work::gather_blocks(std::span<radar::RcsStats>(per_rank));  // one item a rank
  if (!mpi_work::is_root()) {
    add_stats(total, mine);
    return;
  }
  for (const radar::RcsStats& one : per_rank)
    add_stats(total, one);
}

// Tubes still bouncing at the cap: the return may still be growing (a cavity).
void warn_cut_off(const radar::RcsStats& stats, int bounces) {
  if (stats.tubes_cut_off == 0 || stats.rays == 0)
    return;
  std::fprintf(stderr,
               "radar-emu: note: %llu of %llu ray tubes (%.2g %%) were still bouncing at the cap "
               "of %d bounces; raise --bounces (up to %d) if the return has not converged\n",
               static_cast<unsigned long long>(stats.tubes_cut_off),
               static_cast<unsigned long long>(stats.rays),
               100.0 * static_cast<double>(stats.tubes_cut_off) / static_cast<double>(stats.rays),
               bounces, radar::kMaxRcsBounces);
}

// Physical optics is an asymptotic (high-frequency) method: flag small electrical sizes. A
// warning: printed whatever -q says (-q silences progress and the summary only).
void warn_electrical_size(const radar::RcsEngine& engine, double f_min_hz) {
  const double ka =
      2.0 * radar::kPi * f_min_hz / radar::kSpeedOfLight_mps * engine.bounding_radius_m();
  if (ka < 10.0) {
    std::fprintf(stderr,
                 "radar-emu: warning: the target is only ka = %.2f (wavenumber times its bounding "
                 "radius) at %.4g Hz: physical optics is a high-frequency method and its error "
                 "grows below ka ~ 10 (a sphere against the exact Mie series: up to +-1.4 dB at "
                 "ka 5-10, more below; docs/validation.md); rcs --method mom solves such "
                 "targets up to the mesh\n",
                 ka, f_min_hz);
  }
}

void print_target(const LoadedTarget& t, const radar::RcsEngine& e, bool quiet) {
  for (const std::string& w : t.warnings)
    std::fprintf(stderr, "radar-emu: warning: %s\n", w.c_str());
  if (quiet)
    return;
  std::printf("target: %zu facets (%zu degenerate skipped), bounding radius %.4g m\n",
              e.facet_count(), e.degenerate_facets(), e.bounding_radius_m());
  if (!e.config().edges) {
    std::printf("edge diffraction: off (--no-edges)\n");
    return;
  }
  const radar::EdgeCensus& c = e.edge_census();
  std::printf(
      "edge diffraction: on, %zu edges (%llu open-sheet boundaries, %llu wedges turning > %.0f "
      "deg; %llu smoother edges left to PO, %llu not modelled: concave, non-PEC, shared by > 2 "
      "facets or inconsistently wound)\n",
      e.edges().size(), static_cast<unsigned long long>(c.half_planes),
      static_cast<unsigned long long>(c.wedges), e.config().edge_min_turn_rad / common::kRadPerDeg,
      static_cast<unsigned long long>(c.smooth), static_cast<unsigned long long>(c.unsupported));
  if (e.config().edge_order >= 2)
    std::printf(
        "double diffraction: %zu edge pairs across flat faces (hard polarisation; "
        "--edge-order 1 leaves it out)\n",
        e.edge_pairs().size());
  std::printf(
      "reflection-diffraction: %zu flat PEC faces light and relay edges by one reflection\n",
      e.reflecting_planes().size());
}

// The summary line of the edge terms over a run.
void print_edge_stats(const radar::RcsEngine& e, const radar::RcsStats& st) {
  if (!e.config().edges)
    return;
  std::printf(
      "edge terms: %llu used, %llu shadowed, %llu without a term (no lit face, along the edge, "
      "receiver inside the wedge), %llu boundary singularities stepped around, %llu "
      "double-diffraction terms, %llu terms by way of a reflection\n",
      static_cast<unsigned long long>(st.edges_used),
      static_cast<unsigned long long>(st.edges_shadowed),
      static_cast<unsigned long long>(st.edges_skipped),
      static_cast<unsigned long long>(st.edges_guarded),
      static_cast<unsigned long long>(st.edges_double),
      static_cast<unsigned long long>(st.edges_reflected));
}

radar::RcsConfig with_edge_order(radar::RcsConfig c, int edge_order) {
  if (edge_order != 1 && edge_order != 2)
    throw std::invalid_argument("--edge-order must be 1 or 2");
  c.edge_order = edge_order;
  return c;
}

// The target as both tools set it up: loaded, built, with the engine over it (in place: the
// engine keeps a pointer to the scene), and the loader's and the method's warnings printed.
struct ToolTarget {
  LoadedTarget loaded;
  scene::Scene scene;
  radar::RcsEngine engine;
  ToolTarget(const std::string& mesh, double scale, const std::vector<std::string>& materials,
             int bounces, double rays_per_wavelength, bool edges, double edge_turn_deg,
             int edge_order, double min_freq_hz, bool quiet)
      : loaded(load_target(mesh, scale, materials)),
        scene(loaded.description),
        engine(scene, loaded.surfaces,
               with_edge_order(rcs_config(bounces, rays_per_wavelength, edges, edge_turn_deg),
                               edge_order)) {
    if (!mpi_work::is_root())
      return;  // under mpirun, rank 0 alone prints (every rank loads the same target)
    print_target(loaded, engine, quiet);
    warn_electrical_size(engine, min_freq_hz);
  }
};

// Starts the MPI split of a sweep of `items` work items (nothing in one process) and says, on
// rank 0 unless quiet, how the ranks share them.
void start_split(std::size_t items, const char* what, bool quiet) {
  mpi_work::start();
  if (quiet || mpi_work::size() == 1 || !mpi_work::is_root())
    return;
  std::printf("MPI: %zu %s over %d ranks (%zu on rank 0), %d TBB thread(s) per rank\n", items, what,
              mpi_work::size(), mpi_work::my_block(items).size(), mpi_work::threads_per_rank());
}

// A plot overlay "FILE=LABEL" (RcsToolOptions::overlays): x and y from the last two numbers of
// each line.
Series read_overlay(const std::string& spec) {
  const std::size_t eq = spec.rfind('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
    throw std::invalid_argument("--overlay '" + spec + "': expected FILE=LABEL");
  const std::string path = spec.substr(0, eq);
  Series ser;
  ser.label = spec.substr(eq + 1);
  ser.dashed = true;  // a reference beside the computed curves (docs/plotting.md)
  FILE* f = std::fopen(path.c_str(), "r");
  if (f == nullptr)
    throw std::invalid_argument("--overlay: cannot read " + path);
  const File closer(f);
  char buf[4096];
  for (std::size_t line = 1; std::fgets(buf, sizeof buf, f) != nullptr; ++line) {
    std::string text(buf);
    std::replace(text.begin(), text.end(), ',', ' ');
    std::vector<double> v;
    bool numeric = true;
    for (std::string_view tok : split(text, ' ')) {
      while (!tok.empty() && std::isspace(static_cast<unsigned char>(tok.back())))
        tok.remove_suffix(1);
      if (tok.empty())
        continue;
      double x = 0.0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
      if (ec != std::errc() || ptr != tok.data() + tok.size()) {
        numeric = false;
        break;
      }
      v.push_back(x);
    }
    if (v.empty() && numeric)
      continue;  // blank line
    if (!numeric || v.size() < 2) {
      if (line == 1)
        continue;  // header
      throw std::invalid_argument("--overlay: " + path + ":" + std::to_string(line) +
                                  ": expected at least two numbers");
    }
    ser.x.push_back(v[v.size() - 2]);
    ser.y.push_back(v.back());
  }
  if (ser.x.empty())
    throw std::invalid_argument("--overlay: " + path + " has no data line");
  return ser;
}

// The sweep of `rcs --method mom`: one fill and factorisation per frequency, every direction
// solved from it (radar/em/mom.hpp). Writes s as sweep_rcs does; returns the seconds taken.
double sweep_mom(const RcsToolOptions& o, const std::optional<std::pair<double, double>>& bistatic,
                 std::vector<radar::ScatteringMatrix>& s, std::size_t& freqs_done) {
  if (mpi_work::launched_size() > 1)
    throw std::invalid_argument(
        "--method mom runs in one process (its LU uses every core); "
        "start it without mpirun");
  radar::MomConfig cfg;
  if (o.mom_equation == "efie")
    cfg.equation = radar::MomEquation::kEfie;
  else if (o.mom_equation == "mfie")
    cfg.equation = radar::MomEquation::kMfie;
  else if (o.mom_equation == "cfie")
    cfg.equation = radar::MomEquation::kCfie;
  else
    throw std::invalid_argument("--mom-equation must be efie, mfie or cfie (got '" +
                                o.mom_equation + "')");
  cfg.max_unknowns = o.mom_max_unknowns;
  const LoadedTarget loaded = load_target(o.mesh, o.scale, o.materials);
  for (const std::string& w : loaded.warnings) {
    // The loader's caution about open meshes is PO's (shadowing); the method of moments solves
    // sheets as they are and its summary counts their open edges.
    if (w.find(": open mesh: ") == std::string::npos)
      std::fprintf(stderr, "radar-emu: warning: %s\n", w.c_str());
  }
  radar::MomSolver solver(loaded.description, loaded.surfaces, cfg);
  const radar::MomMeshInfo& mi = solver.mesh_info();
  if (!o.quiet) {
    std::printf(
        "target: %zu triangles (%zu degenerate skipped), %zu vertices after welding, %zu "
        "surfaces (%zu closed%s), %zu open edges\nmethod of moments: %s, %zu unknowns (RWG), "
        "matrix %.2f GB, edges mean %.4g m, longest %.4g m\n",
        mi.triangles, mi.degenerate_skipped, mi.vertices, mi.components, mi.closed_components,
        mi.flipped_components > 0 ? ", some turned outward" : "", mi.boundary_edges,
        radar::equation_name(solver.equation()), mi.unknowns,
        16e-9 * static_cast<double>(mi.unknowns) * static_cast<double>(mi.unknowns), mi.mean_edge_m,
        mi.max_edge_m);
  }
  const std::size_t nt = o.theta_deg.size(), np = o.phi_deg.size(), nf = o.freqs_hz.size();
  {
    // Before the fill: the matrix (16 N^2 bytes) and the time a frequency takes, scaled from
    // docs/performance.md's reference machine (fill ~1.2e-7 s N^2, LU 8/3 N^3 flops at ~120
    // GFLOP/s); the progress line then measures the real pace.
    const double n = static_cast<double>(mi.unknowns);
    const double per_freq_s = 1.2e-7 * n * n + (8.0 / 3.0) * n * n * n / 120e9;
    o.control.tell_estimate("method of moments, " + std::to_string(mi.unknowns) +
                            " unknowns: matrix " + config::format_bytes(16.0 * n * n) +
                            ", fill + LU about " + config::format_duration(per_freq_s) +
                            " a frequency on a 2-core reference machine (more below ~5000 "
                            "unknowns, where the near-pair integrals dominate), " +
                            std::to_string(nf) + " frequencies: about " +
                            config::format_duration(per_freq_s * static_cast<double>(nf)));
    // The matrix (complex double, factored in place) is allocated at the first frequency.
    if (const auto over = config::over_memory_limit(
            16.0 * n * n, std::to_string(mi.unknowns) + " unknowns: the " +
                              std::to_string(mi.unknowns) + "^2 complex matrix")) {
      throw std::invalid_argument("--method mom: the method of moments " + *over +
                                  ": a coarser mesh or a smaller target");
    }
  }
  std::vector<radar::Direction> tx(nt * np), rx(nt * np);
  for (std::size_t it = 0; it < nt; ++it) {
    for (std::size_t ip = 0; ip < np; ++ip) {
      tx[it * np + ip] = {common::radians(o.theta_deg[it]), common::radians(o.phi_deg[ip])};
      rx[it * np + ip] = bistatic ? radar::Direction{common::radians(bistatic->first),
                                                     common::radians(bistatic->second)}
                                  : tx[it * np + ip];
    }
  }
  std::vector<radar::ScatteringMatrix> one(nt * np);
  const auto t0 = std::chrono::steady_clock::now();
  freqs_done = 0;
  for (std::size_t k = 0; k < nf; ++k) {
    // Between frequencies: one fill and LU is the work item (radar/ polls nothing).
    if (o.control.stop_signal() != 0)
      break;
    const double f = o.freqs_hz[k];
    const double lambda = radar::kSpeedOfLight_mps / f;
    if (mi.max_edge_m > 0.25 * lambda || mi.mean_edge_m > 0.15 * lambda) {
      std::fprintf(stderr,
                   "radar-emu: warning: at %.4g Hz the mesh's edges are %.2g (mean) and %.2g "
                   "(longest) wavelengths; the method of moments wants about 0.1 (results "
                   "degrade past ~0.2): refine the mesh\n",
                   f, mi.mean_edge_m / lambda, mi.max_edge_m / lambda);
    }
    if (!o.quiet) {
      std::printf("%.6g Hz: filling and factorising...", f);
      std::fflush(stdout);
    }
    const radar::MomFactorInfo fi = solver.factor(f);
    solver.scatter(tx, rx, one);
    if (!o.quiet)
      std::printf(" fill %.1f s (%zu near triangle pairs), LU %.1f s\n", fi.fill_s, fi.near_pairs,
                  fi.factor_s);
    for (std::size_t d = 0; d < nt * np; ++d)
      s[d * nf + k] = one[d];
    freqs_done = k + 1;
    o.control.report(freqs_done, nf);
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

LoadedTarget load_target(const std::string& mesh_path, double scale,
                         const std::vector<std::string>& material_definitions) {
  if (!std::isfinite(scale) || scale <= 0.0)
    throw std::invalid_argument("--scale must be a positive number");
  LoadedTarget t;
  const std::filesystem::path path(mesh_path);
  const std::string ext = common::lower_extension(path);
  if (ext == ".glb" || ext == ".gltf") {
    t.description = scene::load_gltf(path, &t.warnings);
    if (scale != 1.0) {
      for (scene::ObjectDesc& o : t.description.objects) {
        for (glm::vec3& p : o.mesh.positions_m)
          p *= static_cast<float>(scale);
        o.world_from_body[3] = glm::dvec4(glm::dvec3(o.world_from_body[3]) * scale, 1.0);
      }
    }
  } else if (ext == ".obj" || ext == ".stl") {
    scene::MeshFileOptions options;
    options.scale = scale;
    t.description = scene::load_mesh_file(path, options, &t.warnings);
  } else {
    throw std::invalid_argument(mesh_path + ": unknown mesh format '" + ext +
                                "' (expected .glb, .gltf, .obj or .stl)");
  }
  // Material definitions from the command line: overrides of the one resolver
  // (radar/em/surfaces.hpp). The tool sweeps frequencies, so it resolves without a carrier: the
  // catalogue gives only its frequency-independent conductors, the rest needs a definition.
  std::vector<radar::SurfaceOverride> defs;
  for (const std::string& text : material_definitions) {
    const std::size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw std::invalid_argument("--material '" + text +
                                  "': expected NAME=EPS_REAL,EPS_LOSS[,THICKNESS_M]");
    }
    radar::SurfaceOverride d;
    d.name = text.substr(0, eq);
    const auto v = split(std::string_view(text).substr(eq + 1), ',');
    if (v.size() != 2 && v.size() != 3) {
      throw std::invalid_argument("--material '" + text +
                                  "': expected NAME=EPS_REAL,EPS_LOSS[,THICKNESS_M]");
    }
    const double re = parse_number(v[0], "--material"), loss = parse_number(v[1], "--material");
    if (re < 1.0 || loss < 0.0) {
      throw std::invalid_argument("--material '" + text +
                                  "': EPS_REAL must be >= 1 and EPS_LOSS >= 0 (eps = EPS_REAL - "
                                  "j EPS_LOSS)");
    }
    d.model.relative_permittivity = {re, -loss};
    d.model.kind = radar::SurfaceModel::Kind::kDielectric;
    if (v.size() == 3) {
      d.model.kind = radar::SurfaceModel::Kind::kCoatedPec;
      d.model.thickness_m = parse_number(v[2], "--material");
      if (d.model.thickness_m <= 0.0)
        throw std::invalid_argument("--material '" + text + "': THICKNESS_M must be > 0");
    }
    defs.push_back(d);
  }
  try {
    const radar::SurfaceSet resolved =
        radar::resolve_surfaces(t.description.materials, {std::nullopt, {}, defs});
    for (const radar::Surface& s : resolved.surfaces)
      t.surfaces.push_back(s.specular);
  } catch (const radar::UnresolvedMaterial& e) {
    throw std::invalid_argument(mesh_path + ": " + e.what() + "; define it with --material " +
                                e.name() + "=EPS_REAL,EPS_LOSS[,THICKNESS_M]");
  }
  for (const radar::SurfaceOverride& d : defs) {
    if (std::none_of(t.description.materials.begin(), t.description.materials.end(),
                     [&](const scene::Material& m) { return m.name == d.name; }))
      t.warnings.push_back("--material " + d.name + ": the mesh has no material of that name");
  }
  return t;
}

std::vector<Polarisation> parse_pols(std::string_view text) {
  std::vector<Polarisation> out;
  for (std::string_view p : split(text, ',')) {
    Polarisation pol;
    try {
      pol = common::parse_polarisation(p);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("--pol: " + std::string(e.what()));
    }
    if (std::find(out.begin(), out.end(), pol) == out.end())
      out.push_back(pol);
  }
  return out;
}

std::complex<double> component(const radar::ScatteringMatrix& s, Polarisation p) noexcept {
  switch (p) {
    case Polarisation::kHH:
      return s.hh;
    case Polarisation::kHV:
      return s.hv;
    case Polarisation::kVH:
      return s.vh;
    case Polarisation::kVV:
      return s.vv;
  }
  return {};
}

radar::RcsConfig rcs_config(int bounces, double rays_per_wavelength, bool edges,
                            double edge_turn_deg, OptionSpelling spelling) {
  const auto name = [spelling](std::string cli) {
    if (spelling == OptionSpelling::kCli)
      return cli;
    cli.erase(0, 2);
    std::replace(cli.begin(), cli.end(), '-', '_');
    return cli;
  };
  // The command line checks --bounces and --rays-per-wavelength already (app/); these are
  // for the library's other callers (the Python module).
  if (bounces < 1 || bounces > radar::kMaxRcsBounces) {
    throw std::invalid_argument(name("--bounces") + " must be in 1.." +
                                std::to_string(radar::kMaxRcsBounces));
  }
  if (!(rays_per_wavelength > 0.0))
    throw std::invalid_argument(name("--rays-per-wavelength") + " must be > 0");
  if (!(edge_turn_deg >= 0.0 && edge_turn_deg < 180.0))
    throw std::invalid_argument(name("--edge-turn-deg") + " must be in [0, 180)");
  radar::RcsConfig c;
  c.max_bounces = bounces;
  c.rays_per_wavelength = rays_per_wavelength;
  c.edges = edges;
  c.edge_min_turn_rad = common::radians(edge_turn_deg);
  return c;
}

std::size_t sweep_rcs(const radar::RcsEngine& engine, std::span<const double> theta_deg,
                      std::span<const double> phi_deg, std::span<const double> freqs_hz,
                      std::optional<std::pair<double, double>> bistatic_deg,
                      std::span<radar::ScatteringMatrix> s,
                      std::span<RcsDirectionStats> per_direction, radar::RcsStats& total,
                      const std::function<void(std::size_t)>& progress,
                      const std::atomic<int>* stop) {
  const std::size_t nt = theta_deg.size(), np = phi_deg.size(), nf = freqs_hz.size();
  if (s.size() != nt * np * nf || per_direction.size() != nt * np)
    throw std::invalid_argument("sweep_rcs: output sizes do not match the sweep");
  // The work items are the directions d = it * np + ip, all frequencies each: one ray trace
  // serves every frequency (the tube density follows the highest), so a direction is computed
  // whole, exactly as in one process. MPI ranks take contiguous blocks (mpi_work.hpp).
  const mpi_work::Block mine = mpi_work::my_block(nt * np);
  radar::RcsStats mine_total;
  const std::size_t done = sweep_in_waves(
      mine, nt * np, stop, progress, mine_total, [&](std::size_t d, radar::RcsStats& one) {
        const std::size_t it = d / np, ip = d % np;
        const radar::Direction tx{common::radians(theta_deg[it]), common::radians(phi_deg[ip])};
        const radar::Direction rx = bistatic_deg
                                        ? radar::Direction{common::radians(bistatic_deg->first),
                                                           common::radians(bistatic_deg->second)}
                                        : tx;
        engine.compute(tx, rx, freqs_hz, s.subspan(d * nf, nf), one);
        per_direction[d] = {one.facets_lit, one.facets_partial, one.tubes_cut_off, one.edges_used};
      });
  mpi_work::gather_blocks(s, nf);
  mpi_work::gather_blocks(per_direction);
  add_gathered_stats(total, mine_total);
  return done;
}

std::size_t sweep_profile(const radar::RcsEngine& engine, std::span<const double> theta_deg,
                          std::span<const double> phi_deg, std::span<const double> freqs_hz,
                          std::span<radar::ScatteringMatrix> s, std::span<std::uint64_t> edges_used,
                          radar::RcsStats& total, const std::function<void(std::size_t)>& progress,
                          const std::atomic<int>* stop) {
  const std::size_t nt = theta_deg.size(), np = phi_deg.size(), nf = freqs_hz.size();
  const std::size_t na = nt * np;
  if (nt > 1 && np > 1)
    throw std::invalid_argument("sweep theta or phi, not both (ISAR uses one angle)");
  if (s.size() != na * nf || edges_used.size() != na)
    throw std::invalid_argument("sweep_profile: output sizes do not match the sweep");
  // The work items are the angles, all frequencies each (as sweep_rcs), split over MPI ranks.
  const mpi_work::Block mine = mpi_work::my_block(na);
  radar::RcsStats mine_total;
  const std::size_t done = sweep_in_waves(
      mine, na, stop, progress, mine_total, [&](std::size_t a, radar::RcsStats& one) {
        const std::size_t it = nt > 1 ? a : 0, ip = np > 1 ? a : 0;
        const radar::Direction dir{common::radians(theta_deg[it]), common::radians(phi_deg[ip])};
        engine.compute(dir, dir, freqs_hz, s.subspan(a * nf, nf), one);
        edges_used[a] = one.edges_used;
      });
  mpi_work::gather_blocks(s, nf);
  mpi_work::gather_blocks(edges_used);
  add_gathered_stats(total, mine_total);
  return done;
}

namespace {

// One swept dimension (theta, phi or frequency): RCS against it, a curve per polarisation, the
// overlays beside them; 60 dB under the peak kept (deep nulls would squash the pattern).
void write_rcs_chart(const RcsToolOptions& o, const std::vector<radar::ScatteringMatrix>& s,
                     const std::string& name, std::vector<Series> overlays) {
  const std::size_t nt = o.theta_deg.size(), np = o.phi_deg.size(), nf = o.freqs_hz.size();
  const bool sweep_theta = nt > 1, sweep_phi = np > 1;
  LineChart chart;
  chart.y_label = "RCS [dBsm]";
  char title[200];
  if (sweep_theta || sweep_phi) {
    chart.x_label = sweep_theta ? "theta [deg]" : "phi [deg]";
    std::snprintf(title, sizeof title, "%s: RCS at %.4g GHz%s, %s = %g deg", name.c_str(),
                  o.freqs_hz[0] / 1e9, o.bistatic_theta_deg ? " (bistatic)" : "",
                  sweep_theta ? "phi" : "theta", sweep_theta ? o.phi_deg[0] : o.theta_deg[0]);
  } else {
    chart.x_label = "frequency [GHz]";
    std::snprintf(title, sizeof title, "%s: RCS at theta %g deg, phi %g deg", name.c_str(),
                  o.theta_deg[0], o.phi_deg[0]);
  }
  chart.title = title;
  for (Polarisation p : o.pols) {
    Series ser;
    ser.label = std::string(common::polarisation_name(p));
    if (sweep_theta || sweep_phi) {
      const std::size_t n = sweep_theta ? nt : np;
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t it = sweep_theta ? i : 0, ip = sweep_theta ? 0 : i;
        ser.x.push_back(sweep_theta ? o.theta_deg[i] : o.phi_deg[i]);
        ser.y.push_back(radar::dbsm(component(s[(it * np + ip) * nf], p)));
      }
    } else {
      for (std::size_t k = 0; k < nf; ++k) {
        ser.x.push_back(o.freqs_hz[k] / 1e9);
        ser.y.push_back(radar::dbsm(component(s[k], p)));
      }
    }
    chart.series.push_back(std::move(ser));
  }
  for (Series& ser : overlays)
    chart.series.push_back(std::move(ser));
  double peak = -400.0;
  for (const Series& ser : chart.series) {
    for (double y : ser.y)
      peak = std::max(peak, y);
  }
  double low = peak;
  for (const Series& ser : chart.series) {
    for (double y : ser.y)
      low = std::min(low, y);
  }
  chart.y_min = std::max(low, peak - 60.0);
  // A cut over half a turn or more in phi is also drawn as the polar pattern an engineer
  // expects, beside the Cartesian one (the same curves).
  const double span = sweep_phi ? std::abs(o.phi_deg.back() - o.phi_deg.front()) : 0.0;
  if (!sweep_theta && sweep_phi && span >= 180.0) {
    Figure fig;
    fig.title = chart.title;
    chart.title.clear();
    LineChart polar = chart;
    polar.polar = true;
    polar.y_max = std::ceil(peak / 10.0) * 10.0;
    polar.legend = false;  // the Cartesian panel's legend names the same curves
    chart.legend_below = true;
    fig.panels = {chart, polar};
    fig.columns = 2;
    fig.width = 1500;
    fig.height = 700;
    plot::write_figure(std::move(fig), o.plot_png);
    return;
  }
  write_line_chart_png(chart, o.plot_png);
}

// Indices of `v` in ascending order (a map's axis must ascend).
std::vector<std::size_t> ascending(const std::vector<double>& v) {
  std::vector<std::size_t> idx(v.size());
  for (std::size_t i = 0; i < v.size(); ++i)
    idx[i] = i;
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  return idx;
}

// Two or three swept dimensions: a map (dBsm colour, 60 dB under the peak) of the first two
// swept of (theta, phi, frequency) per polarisation, and per value of the third one swept, as
// panels one under the other (at most kMaxPanels; the CSV has everything).
void write_rcs_maps(const RcsToolOptions& o, const std::vector<radar::ScatteringMatrix>& s,
                    const std::string& name) {
  constexpr std::size_t kMaxPanels = 12;
  const std::size_t np = o.phi_deg.size(), nf = o.freqs_hz.size();
  // Axes 0 theta, 1 phi, 2 frequency [GHz].
  std::vector<double> ghz(nf);
  for (std::size_t k = 0; k < nf; ++k)
    ghz[k] = o.freqs_hz[k] / 1e9;
  const std::array<const std::vector<double>*, 3> values{&o.theta_deg, &o.phi_deg, &ghz};
  const std::array<const char*, 3> labels{"theta [deg]", "phi [deg]", "frequency [GHz]"};
  const std::array<const char*, 3> names{"theta", "phi", "f"};
  const std::array<const char*, 3> units{"deg", "deg", "GHz"};
  std::vector<int> swept;
  for (int a = 0; a < 3; ++a) {
    if (values[static_cast<std::size_t>(a)]->size() > 1)
      swept.push_back(a);
  }
  // x: an angle (phi before theta when both are swept, the pattern's usual cut); y: the other.
  int ax = swept[0], ay = swept[1];
  if (ax == 0 && ay == 1)
    std::swap(ax, ay);
  const int slice_axis = swept.size() > 2 ? swept[2] : -1;
  auto idx3 = [&](std::array<std::size_t, 3> i) { return (i[0] * np + i[1]) * nf + i[2]; };
  const auto& xs = *values[static_cast<std::size_t>(ax)];
  const auto& ys = *values[static_cast<std::size_t>(ay)];
  const std::vector<std::size_t> ox = ascending(xs), oy = ascending(ys);
  for (std::size_t i = 1; i < ox.size(); ++i) {
    if (!(xs[ox[i]] > xs[ox[i - 1]]))
      throw std::invalid_argument(std::string("--plot: the map needs distinct ") +
                                  names[static_cast<std::size_t>(ax)] + " values");
  }
  for (std::size_t i = 1; i < oy.size(); ++i) {
    if (!(ys[oy[i]] > ys[oy[i - 1]]))
      throw std::invalid_argument(std::string("--plot: the map needs distinct ") +
                                  names[static_cast<std::size_t>(ay)] + " values");
  }
  const std::size_t n_slices =
      slice_axis < 0 ? 1 : values[static_cast<std::size_t>(slice_axis)]->size();
  double peak = -400.0;
  for (const radar::ScatteringMatrix& m : s) {
    for (Polarisation p : o.pols)
      peak = std::max(peak, radar::dbsm(component(m, p)));
  }
  Figure fig;
  std::size_t skipped = 0;
  for (std::size_t sl = 0; sl < n_slices; ++sl) {
    for (Polarisation p : o.pols) {
      if (fig.panels.size() == kMaxPanels) {
        ++skipped;
        continue;
      }
      Heatmap m;
      std::string fixed;
      char buf[64];
      for (int a = 0; a < 3; ++a) {
        if (a == ax || a == ay)
          continue;
        const auto ua = static_cast<std::size_t>(a);
        std::snprintf(buf, sizeof buf, ", %s %g %s", names[ua],
                      (*values[ua])[a == slice_axis ? sl : 0], units[ua]);
        fixed += buf;
      }
      m.title = name + ": RCS " + std::string(common::polarisation_name(p)) + fixed +
                (o.bistatic_theta_deg ? " (bistatic)" : "");
      m.x_label = labels[static_cast<std::size_t>(ax)];
      m.y_label = labels[static_cast<std::size_t>(ay)];
      m.value_label = "RCS [dBsm]";
      m.equal_aspect = false;
      for (std::size_t i : ox)
        m.x.push_back(xs[i]);
      for (std::size_t j : oy)
        m.y.push_back(ys[j]);
      for (std::size_t j : oy) {
        for (std::size_t i : ox) {
          std::array<std::size_t, 3> at{0, 0, 0};
          at[static_cast<std::size_t>(ax)] = i;
          at[static_cast<std::size_t>(ay)] = j;
          if (slice_axis >= 0)
            at[static_cast<std::size_t>(slice_axis)] = sl;
          m.values.push_back(radar::dbsm(component(s[idx3(at)], p)));
        }
      }
      m.value_max = std::ceil(peak);
      m.value_range = 60.0;
      fig.panels.emplace_back(std::move(m));
    }
  }
  if (skipped > 0) {
    std::fprintf(stderr,
                 "radar-emu: warning: --plot: drew the first %zu maps of %zu (the CSV has all)\n",
                 kMaxPanels, kMaxPanels + skipped);
  }
  // Panels one under the other, 560 pixels each.
  fig.width = 1000;
  fig.height = 560 * static_cast<int>(fig.panels.size());
  plot::write_figure(std::move(fig), o.plot_png);
}

}  // namespace

int run_rcs_tool(const RcsToolOptions& o) {
  if (o.freqs_hz.empty())
    throw std::invalid_argument("give --freq-hz F or --freq-sweep-hz START:STOP:N");
  for (double f : o.freqs_hz) {
    if (!(f > 0.0))
      throw std::invalid_argument("frequencies must be > 0 Hz");
  }
  if (o.pols.empty())
    throw std::invalid_argument("--pol: no polarisation");
  if (o.bistatic_theta_deg.has_value() != o.bistatic_phi_deg.has_value())
    throw std::invalid_argument("give both --bistatic-theta-deg and --bistatic-phi-deg");
  if (!o.overlays.empty() && o.plot_png.empty())
    throw std::invalid_argument("--overlay needs --plot");
  if (!o.overlays.empty() &&
      int(o.theta_deg.size() > 1) + int(o.phi_deg.size() > 1) + int(o.freqs_hz.size() > 1) > 1)
    throw std::invalid_argument(
        "--overlay: curves go on a plot of one swept dimension (with two swept, --plot is a map)");
  std::vector<Series> overlays;  // read before the sweep: a bad file fails fast
  if (mpi_work::is_root()) {     // under mpirun, rank 0 alone plots
    for (const std::string& spec : o.overlays)
      overlays.push_back(read_overlay(spec));
  }
  const bool mom = o.method == "mom";
  if (!mom && o.method != "po")
    throw std::invalid_argument("--method must be po or mom (got '" + o.method + "')");
  const std::size_t nt = o.theta_deg.size(), np = o.phi_deg.size(), nf = o.freqs_hz.size();
  std::vector<radar::ScatteringMatrix> s(nt * np * nf);  // [theta][phi][freq]
  radar::RcsStats stats;
  // Per direction, for the CSV: how bounce 1 was lit and how many tubes the bounce cap cut off.
  std::vector<RcsDirectionStats> per_direction(nt * np);
  std::optional<std::pair<double, double>> bistatic;
  if (o.bistatic_theta_deg)
    bistatic.emplace(*o.bistatic_theta_deg, *o.bistatic_phi_deg);
  std::optional<ToolTarget> target;
  double elapsed_s = 0.0;
  // How far the sweep got: every direction at the first freqs_done frequencies (MoM), or the
  // first dirs_done directions at every frequency (PO).
  std::size_t dirs_done = nt * np, freqs_done = nf;
  if (mom) {
    elapsed_s = sweep_mom(o, bistatic, s, freqs_done);
  } else {
    target.emplace(o.mesh, o.scale, o.materials, o.bounces, o.rays_per_wavelength, o.edges,
                   o.edge_turn_deg, o.edge_order,
                   *std::min_element(o.freqs_hz.begin(), o.freqs_hz.end()), o.quiet);
    start_split(nt * np, "directions", o.quiet);
    // Under mpirun: rank 0's block (the others keep pace), the others quiet.
    const std::size_t my_items = mpi_work::my_block(nt * np).size();
    const auto t0 = std::chrono::steady_clock::now();
    std::function<void(std::size_t)> progress;
    if (mpi_work::is_root() && o.control.progress)
      progress = [&o, my_items](std::size_t done) { o.control.report(done, my_items); };
    dirs_done = sweep_rcs(target->engine, o.theta_deg, o.phi_deg, o.freqs_hz, bistatic, s,
                          per_direction, stats, progress, o.control.stop);
    elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!mpi_work::is_root())
      return 0;  // rank 0 has gathered every direction: it alone writes
  }

  const bool interrupted = dirs_done < nt * np || freqs_done < nf;
  {
    File f(open_or_throw(o.out_csv));
    std::fprintf(f.get(), "freq_hz,theta_deg,phi_deg");
    for (Polarisation p : o.pols) {
      const std::string n(common::polarisation_name(p));
      std::fprintf(f.get(), ",rcs_%s_dbsm,re_%s,im_%s", n.c_str(), n.c_str(), n.c_str());
    }
    // edges: 1 when edge diffraction was on; edges_used: the edge terms of that direction.
    std::fprintf(f.get(), ",facets_lit,facets_partial,tubes_cut_off,edges,edges_used\n");
    for (std::size_t it = 0; it < nt; ++it) {
      for (std::size_t ip = 0; ip < np; ++ip) {
        if (it * np + ip >= dirs_done)
          break;
        const RcsDirectionStats& ds = per_direction[it * np + ip];
        for (std::size_t k = 0; k < freqs_done; ++k) {
          const radar::ScatteringMatrix& m = s[(it * np + ip) * nf + k];
          std::fprintf(f.get(), "%.10g,%.10g,%.10g", o.freqs_hz[k], o.theta_deg[it], o.phi_deg[ip]);
          for (Polarisation p : o.pols) {
            const std::complex<double> a = component(m, p);
            std::fprintf(f.get(), ",%.6f,%.9e,%.9e", radar::dbsm(a), a.real(), a.imag());
          }
          std::fprintf(f.get(), ",%llu,%llu,%llu,%d,%llu\n",
                       static_cast<unsigned long long>(ds.facets_lit),
                       static_cast<unsigned long long>(ds.facets_partial),
                       static_cast<unsigned long long>(ds.tubes_cut_off), o.edges && !mom ? 1 : 0,
                       static_cast<unsigned long long>(ds.edges_used));
        }
      }
    }
    if (interrupted) {
      // A comment line (numpy.loadtxt and pandas' comment="#" skip it) that says what is there.
      std::fprintf(f.get(),
                   "# incomplete: stopped by %s after %zu of %zu directions x %zu of %zu "
                   "frequencies (%zu rows)\n",
                   config::signal_name(o.control.stop_signal()).c_str(), dirs_done, nt * np,
                   freqs_done, nf, dirs_done * freqs_done);
    }
    close_or_throw(f, o.out_csv);
  }
  if (interrupted) {
    warn_cut_off(stats, o.bounces);
    return 128 + o.control.stop_signal();  // no statistics or plot of a partial sweep
  }

  // Fluctuation statistics over a sliding aspect window of the swept angle.
  const bool sweep_theta = nt > 1, sweep_phi = np > 1;
  std::string stats_path;
  if (o.window_deg > 0.0) {
    if (!sweep_theta && !sweep_phi)
      throw std::invalid_argument("--window-deg needs a sweep in theta or phi");
    stats_path = o.stats_csv.empty() ? sibling(o.out_csv, "_stats.csv").string() : o.stats_csv;
    File f(open_or_throw(stats_path));
    std::fprintf(f.get(), "freq_hz,theta_deg,phi_deg");
    for (Polarisation p : o.pols) {
      const std::string n(common::polarisation_name(p));
      std::fprintf(f.get(), ",mean_%s_dbsm,median_%s_dbsm,p10_%s_dbsm,p90_%s_dbsm,std_%s_db",
                   n.c_str(), n.c_str(), n.c_str(), n.c_str(), n.c_str());
    }
    std::fputc('\n', f.get());
    const std::size_t n_swept = sweep_theta ? nt : np, n_fixed = sweep_theta ? np : nt;
    std::vector<double> angles(n_swept), sigma(n_swept);
    for (std::size_t i = 0; i < n_swept; ++i)
      angles[i] = common::radians(sweep_theta ? o.theta_deg[i] : o.phi_deg[i]);
    for (std::size_t j = 0; j < n_fixed; ++j) {
      for (std::size_t k = 0; k < nf; ++k) {
        std::vector<std::vector<radar::FluctuationStats>> per_pol;
        for (Polarisation p : o.pols) {
          for (std::size_t i = 0; i < n_swept; ++i) {
            const std::size_t it = sweep_theta ? i : j, ip = sweep_theta ? j : i;
            sigma[i] = std::norm(component(s[(it * np + ip) * nf + k], p));
          }
          per_pol.push_back(
              radar::sliding_window_stats(angles, sigma, common::radians(0.5 * o.window_deg)));
        }
        for (std::size_t i = 0; i < n_swept; ++i) {
          const std::size_t it = sweep_theta ? i : j, ip = sweep_theta ? j : i;
          std::fprintf(f.get(), "%.10g,%.10g,%.10g", o.freqs_hz[k], o.theta_deg[it], o.phi_deg[ip]);
          for (const auto& st : per_pol) {
            const radar::FluctuationStats& x = st[i];
            std::fprintf(f.get(), ",%.4f,%.4f,%.4f,%.4f,%.4f", db_of_power(x.mean_m2),
                         db_of_power(x.median_m2), db_of_power(x.p10_m2), db_of_power(x.p90_m2),
                         x.std_db);
          }
          std::fputc('\n', f.get());
        }
      }
    }
    close_or_throw(f, stats_path);
  }

  if (!o.plot_png.empty()) {
    const std::string name = std::filesystem::path(o.mesh).filename().string();
    if (int(sweep_theta) + int(sweep_phi) + int(nf > 1) >= 2)
      write_rcs_maps(o, s, name);
    else
      write_rcs_chart(o, s, name, std::move(overlays));
  }

  if (!o.quiet) {
    if (mom) {
      std::printf("%zu directions x %zu frequencies in %.2f s (method of moments)\n", nt * np, nf,
                  elapsed_s);
    } else {
      std::printf(
          "%zu directions x %zu frequencies in %.2f s: %llu lit facets, %llu partly lit, %llu "
          "shadowed, %llu rays, %llu multi-bounce paths, %llu tubes cut off at the bounce cap "
          "(%d)\n",
          nt * np, nf, elapsed_s, static_cast<unsigned long long>(stats.facets_lit),
          static_cast<unsigned long long>(stats.facets_partial),
          static_cast<unsigned long long>(stats.facets_shadowed),
          static_cast<unsigned long long>(stats.rays), static_cast<unsigned long long>(stats.paths),
          static_cast<unsigned long long>(stats.tubes_cut_off), o.bounces);
      print_edge_stats(target->engine, stats);
    }
    std::printf("wrote %s", o.out_csv.c_str());
    if (!stats_path.empty())
      std::printf(", %s", stats_path.c_str());
    if (!o.plot_png.empty())
      std::printf(", %s", o.plot_png.c_str());
    std::printf("\n");
  }
  warn_cut_off(stats, o.bounces);  // whatever -q says (no tube traced with --method mom)
  return 0;
}

int run_profile_tool(const ProfileToolOptions& o) {
  const std::size_t nf = o.freqs_hz.size();
  if (nf < 2)
    throw std::invalid_argument("a range profile needs --freq-sweep-hz START:STOP:N with N >= 2");
  const double df = (o.freqs_hz.back() - o.freqs_hz.front()) / static_cast<double>(nf - 1);
  if (!(df > 0.0) || !(o.freqs_hz.front() > 0.0))
    throw std::invalid_argument("--freq-sweep-hz: frequencies must be positive and increasing");
  const std::size_t nt = o.theta_deg.size(), np = o.phi_deg.size();
  if (nt > 1 && np > 1)
    throw std::invalid_argument("sweep theta or phi, not both (ISAR uses one angle)");
  const auto window = radar::parse_window_kind(o.window);
  if (!window)
    throw std::invalid_argument("--window: '" + o.window +
                                "' is not none, hann, hamming, blackman or taylor");
  if (o.oversample < 1 || o.oversample > 64)
    throw std::invalid_argument("--oversample must be in 1..64");
  const ToolTarget target(o.mesh, o.scale, o.materials, o.bounces, o.rays_per_wavelength, o.edges,
                          o.edge_turn_deg, o.edge_order, o.freqs_hz.front(), o.quiet);
  const radar::RcsEngine& engine = target.engine;

  const std::size_t na = nt * np;
  std::vector<radar::ScatteringMatrix> s(na * nf);
  std::vector<std::uint64_t> edges_used(na);
  radar::RcsStats stats;
  start_split(na, "angles", o.quiet);
  const std::size_t my_items = mpi_work::my_block(na).size();
  const auto t0 = std::chrono::steady_clock::now();
  std::function<void(std::size_t)> progress;
  if (mpi_work::is_root() && o.control.progress)
    progress = [&o, my_items](std::size_t done) { o.control.report(done, my_items); };
  const std::size_t angles_done = sweep_profile(engine, o.theta_deg, o.phi_deg, o.freqs_hz, s,
                                                edges_used, stats, progress, o.control.stop);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!mpi_work::is_root())
    return 0;  // rank 0 has gathered every angle: it alone writes

  const radar::FrequencyGrid grid{o.freqs_hz.front(), df, nf};
  // Aliasing: the target must fit in the unambiguous windows (c / 2 df in range,
  // lambda_c / (2 dtheta) in cross-range), or its far parts fold over.
  const double extent_m = 2.0 * engine.bounding_radius_m();
  const double range_window_m = radar::kSpeedOfLight_mps / (2.0 * df);
  if (range_window_m < extent_m) {
    std::fprintf(stderr,
                 "radar-emu: warning: the unambiguous range window c/(2 df) = %.3g m is smaller "
                 "than the target (%.3g m across): its profile folds over; use a finer frequency "
                 "step\n",
                 range_window_m, extent_m);
  }
  if (na > 1) {
    const double a0 = nt > 1 ? o.theta_deg.front() : o.phi_deg.front();
    const double a1 = nt > 1 ? o.theta_deg.back() : o.phi_deg.back();
    const double step_rad = common::radians(std::abs(a1 - a0) / static_cast<double>(na - 1));
    const double f_c = 0.5 * (o.freqs_hz.front() + o.freqs_hz.back());
    const double cross_window_m = radar::kSpeedOfLight_mps / f_c / (2.0 * step_rad);
    if (cross_window_m < extent_m) {
      std::fprintf(stderr,
                   "radar-emu: warning: the unambiguous cross-range window lambda/(2 dtheta) = "
                   "%.3g m is smaller than the target (%.3g m across): the ISAR image folds over; "
                   "use a finer angle step\n",
                   cross_window_m, extent_m);
    }
  }
  std::vector<std::complex<double>> samples(na * nf);
  for (std::size_t i = 0; i < na * nf; ++i)
    samples[i] = component(s[i], o.pol);
  std::vector<radar::RangeProfile> profiles;
  for (std::size_t a = 0; a < angles_done; ++a) {
    profiles.push_back(
        radar::range_profile(std::span<const std::complex<double>>(samples.data() + a * nf, nf),
                             grid, *window, o.oversample));
  }
  {
    File f(open_or_throw(o.out_csv));
    // edges: 1 when edge diffraction was on; edges_used: the edge terms of that angle.
    std::fprintf(f.get(), "theta_deg,phi_deg,range_m,amplitude_dbsm,re_m,im_m,edges,edges_used\n");
    for (std::size_t a = 0; a < angles_done; ++a) {
      const std::size_t it = nt > 1 ? a : 0, ip = np > 1 ? a : 0;
      const radar::RangeProfile& p = profiles[a];
      for (std::size_t i = 0; i < p.range_m.size(); ++i) {
        std::fprintf(f.get(), "%.10g,%.10g,%.6f,%.4f,%.9e,%.9e,%d,%llu\n", o.theta_deg[it],
                     o.phi_deg[ip], p.range_m[i], radar::dbsm(p.amplitude_m[i]),
                     p.amplitude_m[i].real(), p.amplitude_m[i].imag(), o.edges ? 1 : 0,
                     static_cast<unsigned long long>(edges_used[a]));
      }
    }
    if (angles_done < na) {
      std::fprintf(f.get(), "# incomplete: stopped by %s after %zu of %zu angles (%zu rows)\n",
                   config::signal_name(o.control.stop_signal()).c_str(), angles_done, na,
                   angles_done * (profiles.empty() ? 0 : profiles.front().range_m.size()));
    }
    close_or_throw(f, o.out_csv);
  }
  if (angles_done < na)
    return 128 + o.control.stop_signal();  // no plot or ISAR image of a partial sweep
  const radar::RangeProfile& centre = profiles[na / 2];
  const std::string name = std::filesystem::path(o.mesh).filename().string();
  FigureBatch figures;  // the profile and the ISAR image by one renderer
  if (!o.plot_png.empty()) {
    LineChart chart;
    char title[200];
    std::snprintf(title, sizeof title,
                  "%s: %s range profile, %.4g-%.4g GHz, %s window, resolution %.3g m", name.c_str(),
                  std::string(common::polarisation_name(o.pol)).c_str(), o.freqs_hz.front() / 1e9,
                  o.freqs_hz.back() / 1e9, o.window.c_str(), centre.resolution_m);
    chart.title = title;
    chart.x_label = "range from the target origin [m], + away from the radar";
    chart.y_label = "|profile| [dBsm]";
    Series ser;
    ser.label = std::string(common::polarisation_name(o.pol));
    double peak = -400.0;
    for (std::size_t i = 0; i < centre.range_m.size(); ++i) {
      ser.x.push_back(centre.range_m[i]);
      ser.y.push_back(radar::dbsm(centre.amplitude_m[i]));
      peak = std::max(peak, ser.y.back());
    }
    chart.series.push_back(std::move(ser));
    chart.y_min = peak - o.dynamic_range_db;
    chart.y_max = peak + 3.0;
    figures.add(plot::single(std::move(chart)), o.plot_png);
  }
  std::string isar_csv, isar_png;
  double cross_res = 0.0;
  if (na > 1) {
    std::vector<double> angles(na);
    for (std::size_t a = 0; a < na; ++a)
      angles[a] = common::radians(nt > 1 ? o.theta_deg[a] : o.phi_deg[a]);
    double step = (angles.back() - angles.front()) / static_cast<double>(na - 1);
    std::vector<std::complex<double>> ordered = samples;
    if (step < 0.0) {  // descending sweep: image it in ascending angle
      step = -step;
      for (std::size_t a = 0; a < na; ++a) {
        std::copy_n(samples.begin() + static_cast<std::ptrdiff_t>((na - 1 - a) * nf), nf,
                    ordered.begin() + static_cast<std::ptrdiff_t>(a * nf));
      }
    }
    const radar::IsarImage img = radar::isar_image(ordered, grid, step, na, *window, o.oversample);
    cross_res = img.cross_range_resolution_m;
    isar_csv = o.isar_csv.empty() ? sibling(o.out_csv, "_isar.csv").string() : o.isar_csv;
    File f(open_or_throw(isar_csv));
    std::fprintf(f.get(), "cross_range_m,range_m,amplitude_dbsm\n");
    double peak = -400.0;
    std::vector<double> values(img.pixels_m.size());
    for (std::size_t i = 0; i < img.pixels_m.size(); ++i) {
      values[i] = radar::dbsm(img.pixels_m[i]);
      peak = std::max(peak, values[i]);
    }
    for (std::size_t r = 0; r < img.cross_range_m.size(); ++r) {
      for (std::size_t c = 0; c < img.range_m.size(); ++c) {
        std::fprintf(f.get(), "%.6f,%.6f,%.4f\n", img.cross_range_m[r], img.range_m[c],
                     values[r * img.range_m.size() + c]);
      }
    }
    close_or_throw(f, isar_csv);
    isar_png = o.isar_png;
    if (isar_png.empty() && !o.plot_png.empty())
      isar_png = sibling(o.plot_png, "_isar.png").string();
    if (!isar_png.empty()) {
      Heatmap m;
      char title[200];
      std::snprintf(title, sizeof title, "%s: ISAR (%s), resolution %.3g m x %.3g m", name.c_str(),
                    std::string(common::polarisation_name(o.pol)).c_str(), img.range_resolution_m,
                    img.cross_range_resolution_m);
      m.title = title;
      m.x_label = "range [m]";
      m.y_label = "cross-range [m]";
      m.value_label = "image amplitude [dBsm]";
      m.x = img.range_m;
      m.y = img.cross_range_m;
      m.values = std::move(values);
      m.value_max = peak;
      m.value_range = o.dynamic_range_db;
      m.scale_bar = 0.0;  // equal scales (both axes in m) and a scale bar
      // The picture's height from the image's aspect (room for the title and the x axis).
      const double span_x = img.range_m.back() - img.range_m.front();
      const double span_y = img.cross_range_m.back() - img.cross_range_m.front();
      if (span_x > 0.0 && span_y > 0.0)
        m.height = std::clamp(static_cast<int>(760.0 * span_y / span_x) + 160, 360, 1000);
      figures.add(plot::single(std::move(m)), isar_png);
    }
  }
  figures.write();
  if (!o.quiet) {
    std::printf(
        "%zu angle(s) x %zu frequencies in %.2f s (%llu multi-bounce paths, %llu tubes cut off "
        "at the bounce cap (%d))\n",
        na, nf, elapsed_s, static_cast<unsigned long long>(stats.paths),
        static_cast<unsigned long long>(stats.tubes_cut_off), o.bounces);
    print_edge_stats(target.engine, stats);
    std::printf(
        "range resolution c/2B = %.4g m, sample spacing %.4g m, unambiguous window %.4g m\n",
        centre.resolution_m, centre.bin_m, centre.unambiguous_m);
    if (na > 1)
      std::printf("cross-range resolution lambda_c/(2 Theta) = %.4g m\n", cross_res);
    std::printf("wrote %s", o.out_csv.c_str());
    for (const std::string& p : {o.plot_png, isar_csv, isar_png}) {
      if (!p.empty())
        std::printf(", %s", p.c_str());
    }
    std::printf("\n");
  }
  warn_cut_off(stats, o.bounces);  // whatever -q says
  return 0;
}

}  // namespace radar_emu::tools
