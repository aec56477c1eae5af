#pragma once
// `radar-emu rcs` and `radar-emu profile`: the offline RCS tools on the PO + SBR engine
// (radar/em/rcs.hpp). Loading, option checking, sweeps with progress, CSV and PNG outputs.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/polarisation.hpp"
#include "common/work_control.hpp"
#include "radar/em/mom.hpp"
#include "radar/em/rcs.hpp"
#include "scene/scene.hpp"

namespace radar_emu::tools {

/// A target mesh with radar surfaces for every material it names.
struct LoadedTarget {
  scene::SceneDescription description;
  std::vector<radar::SurfaceModel> surfaces;  ///< per material
  std::vector<std::string> warnings;          ///< from the loader, for the user
};

/// Loads a glTF, OBJ or STL mesh (by extension; `scale` converts file units to metres) and maps
/// its materials through radar::resolve_surfaces() (no carrier; the definitions are its
/// overrides): catalogue conductors (metal, steel, aluminium) are PEC; others need a
/// definition "NAME=EPS_REAL,EPS_LOSS" (dielectric half-space, eps = EPS_REAL - j EPS_LOSS) or
/// "NAME=EPS_REAL,EPS_LOSS,THICKNESS_M" (that layer on a PEC). Throws std::runtime_error or
/// std::invalid_argument with the file, material and what is expected.
[[nodiscard]] LoadedTarget load_target(const std::string& mesh_path, double scale,
                                       const std::vector<std::string>& material_definitions);

/// "HH,VV" -> {kHH, kVV}; receive letter first, either case (common/polarisation.hpp), repeats
/// dropped. Throws std::invalid_argument "--pol: 'X' is not one of HH, HV, VH, VV".
[[nodiscard]] std::vector<common::Polarisation> parse_pols(std::string_view text);
[[nodiscard]] std::complex<double> component(const radar::ScatteringMatrix& s,
                                             common::Polarisation p) noexcept;

/// How an error message names an option: the command line's "--edge-turn-deg" or Python's
/// "edge_turn_deg" (the radar_emu module, docs/python.md).
enum class OptionSpelling { kCli, kPython };

/// The engine settings of `rcs` and `profile` (--bounces, --rays-per-wavelength, --no-edges,
/// --edge-turn-deg), checked: bounces in 1..radar::kMaxRcsBounces, rays_per_wavelength > 0,
/// edge_turn_deg in [0, 180). Throws std::invalid_argument naming the option as `spelling` says.
[[nodiscard]] radar::RcsConfig rcs_config(int bounces, double rays_per_wavelength, bool edges,
                                          double edge_turn_deg,
                                          OptionSpelling spelling = OptionSpelling::kCli);

/// The counters of one direction of an `rcs` sweep, as its CSV prints them.
struct RcsDirectionStats {
  std::uint64_t facets_lit = 0, facets_partial = 0, tubes_cut_off = 0, edges_used = 0;
};

/// The sweep of `radar-emu rcs`: every (theta, phi) direction [deg], theta outer, at all
/// `freqs_hz`; the receiver at `bistatic_deg` (theta, phi) when given, else monostatic.
/// Writes s[(it * np + ip) * nf + k] and per_direction[it * np + ip] (sizes nt * np * nf and
/// nt * np), adds every counter to `total`, and calls `progress` (may be empty) with the number
/// of directions done after each one. In one process, a non-zero `*stop` (may be null) ends the
/// sweep after the current direction; returns the directions done (nt * np when not stopped;
/// under mpirun the sweep always runs whole). Under mpirun, after mpi_work::start(): each rank
/// computes its block of directions (mpi_work::my_block(nt * np)), `progress` counts within it, and
/// rank 0 gathers every direction bit for bit (other ranks' outputs and `total` hold their block
/// only). Collective then: every rank calls it.
std::size_t sweep_rcs(const radar::RcsEngine& engine, std::span<const double> theta_deg,
                      std::span<const double> phi_deg, std::span<const double> freqs_hz,
                      std::optional<std::pair<double, double>> bistatic_deg,
                      std::span<radar::ScatteringMatrix> s,
                      std::span<RcsDirectionStats> per_direction, radar::RcsStats& total,
                      const std::function<void(std::size_t)>& progress = {},
                      const std::atomic<int>* stop = nullptr);

/// The angle sweep of `radar-emu profile`: theta or phi swept (the other one value, degrees),
/// monostatic, at all `freqs_hz`. Writes s[a * nf + k] and edges_used[a] (the edge terms of
/// angle a; sizes na * nf and na, na = nt * np), adds every counter to `total`, and calls
/// `progress` (may be empty) with the number of angles done after each one. Split over MPI
/// ranks by angle as sweep_rcs is by direction, and stopped by `*stop` as it is; returns the
/// angles done.
std::size_t sweep_profile(const radar::RcsEngine& engine, std::span<const double> theta_deg,
                          std::span<const double> phi_deg, std::span<const double> freqs_hz,
                          std::span<radar::ScatteringMatrix> s, std::span<std::uint64_t> edges_used,
                          radar::RcsStats& total,
                          const std::function<void(std::size_t)>& progress = {},
                          const std::atomic<int>* stop = nullptr);

struct RcsToolOptions {
  std::string mesh;
  double scale = 1.0;
  std::vector<std::string> materials;
  std::vector<double> freqs_hz;
  std::vector<double> theta_deg{0.0}, phi_deg{0.0};
  std::vector<common::Polarisation> pols{common::Polarisation::kHH, common::Polarisation::kVV};
  int bounces = 3;
  double rays_per_wavelength = 4.0;
  bool edges = true;            ///< edge diffraction (radar/em/edges.hpp); --no-edges turns it off
  double edge_turn_deg = 30.0;  ///< a shared edge diffracts when it turns more [deg]
  int edge_order = 2;  ///< 1: first-order edge currents; 2: plus double diffraction (edges.hpp)
  /// "po": physical optics + SBR + edges (RcsEngine); "mom": the method of moments
  /// (radar/em/mom.hpp), exact up to discretisation on PEC targets a few wavelengths across.
  std::string method = "po";
  std::string mom_equation = "efie";  ///< efie, mfie or cfie (radar::MomEquation)
  std::size_t mom_max_unknowns = radar::MomConfig{}.max_unknowns;
  std::optional<double> bistatic_theta_deg, bistatic_phi_deg;
  std::string out_csv = "rcs.csv";
  std::string plot_png;  ///< empty: no plot
  /// Curves drawn on the plot beside the computed ones, "FILE=LABEL": text lines of numbers
  /// (whitespace or commas) whose last two are x (the swept angle or frequency) and dBsm, e.g.
  /// a reference table or another run; a first line that is not numbers is a header.
  std::vector<std::string> overlays;
  double window_deg = 0.0;  ///< > 0: fluctuation statistics over +-window/2 of the swept angle
  std::string stats_csv;    ///< where they go (default: next to out_csv, *_stats.csv)
  bool quiet = false;
  /// Progress (directions; with --method mom, frequencies), the estimate before a MoM sweep, and
  /// the stop flag polled between them.
  common::WorkControl control;
};
/// Runs the sweep and writes the outputs; prints a summary unless quiet. Returns the process
/// exit status: 0, or 128 + the signal when control.stop ended the sweep early: then the CSV
/// holds the rows of the directions (frequencies) done and ends with a line
/// "# incomplete: ..." (no plot, no statistics). Throws on bad input (with context).
int run_rcs_tool(const RcsToolOptions& options);

struct ProfileToolOptions {
  std::string mesh;
  double scale = 1.0;
  std::vector<std::string> materials;
  std::vector<double> freqs_hz;                      ///< uniformly spaced, >= 2
  std::vector<double> theta_deg{0.0}, phi_deg{0.0};  ///< several in one of them: ISAR
  common::Polarisation pol = common::Polarisation::kVV;
  int bounces = 3;
  double rays_per_wavelength = 4.0;
  bool edges = true;            ///< edge diffraction (radar/em/edges.hpp); --no-edges turns it off
  double edge_turn_deg = 30.0;  ///< a shared edge diffracts when it turns more [deg]
  int edge_order = 2;  ///< 1: first-order edge currents; 2: plus double diffraction (edges.hpp)
  std::string window = "hann";
  std::size_t oversample = 4;
  double dynamic_range_db = 50.0;  ///< plots
  std::string out_csv = "profile.csv";
  std::string plot_png;  ///< range profile(s)
  std::string isar_csv;  ///< with an angle sweep (default: next to out_csv, *_isar.csv)
  std::string isar_png;
  bool quiet = false;
  common::WorkControl control;  ///< progress in angles; the stop flag polled between them
};
/// As run_rcs_tool: 128 + signal when stopped early, the CSV then holding the profiles of the
/// angles done and a last line "# incomplete: ..." (no plots, no ISAR image).
int run_profile_tool(const ProfileToolOptions& options);

}  // namespace radar_emu::tools
