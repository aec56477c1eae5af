#pragma once
// Command-line pieces several subcommands share: the output paths left at their defaults, sizes
// as text, and the target and sweep options of rcs and profile.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "common/work_control.hpp"
#include "config/progress.hpp"

namespace radar_emu::app {

/// An output file or directory left at its default: checked before any work too (a given one
/// was checked by its validator while parsing). Throws std::invalid_argument naming the option.
void check_default_file(const CLI::Option* opt, const std::string& path);
void check_default_dir(const CLI::Option* opt, const std::string& path);

/// A long offline command's progress and interruption (sar, rcs, profile, image, tradeoff):
/// installs the SIGINT/SIGTERM handlers (app/main.cpp), draws the progress line on a terminal
/// unless quiet, prints the tool's estimate unless quiet, and turns a stopped tool's status into
/// the one-line message.
class OfflineRun {
 public:
  /// `command` prefixes every line ("sar"), `unit` names the work items ("pulses").
  OfflineRun(std::string command, std::string unit, bool quiet);
  /// What the tool's Options take: progress, estimate and the stop flag. Valid while this lives.
  [[nodiscard]] common::WorkControl control();
  /// The tool's exit status, passed on; when it is 128 + signal (the tool stopped early and
  /// wrote `written`), ends the progress line and prints "radar-emu: CMD: interrupted by SIGINT
  /// after N of M UNIT; WRITTEN".
  int finish(int status, const std::string& written);

 private:
  std::string command_;
  bool quiet_;
  config::ProgressLine line_;
};

/// `bytes` as text: "%.3g MB", "%.3g GB" or "%.3g TB".
[[nodiscard]] std::string si_bytes(double bytes);

/// rcs / profile: the sweeps are kept as text and parsed here, so errors name the option.
struct SweepText {
  std::string freq, freq_sweep, theta = "0", phi = "0", pol;
};

/// The options rcs and profile share, bound to their storage (which must outlive parsing).
struct TargetArgs {
  std::string& mesh;
  double& scale;
  std::vector<std::string>& materials;
  int& bounces;
  double& rays_per_wavelength;
  bool& quiet;
  bool& edges;
  double& edge_turn_deg;
  int& edge_order;
};

/// Adds --mesh, --scale, --freq-hz, --freq-sweep-hz, --theta-deg, --phi-deg, --bounces,
/// --rays-per-wavelength, --material, -q, --edge-order, --edge-turn-deg and --no-edges to `cmd`.
void add_target_options(CLI::App& cmd, SweepText& t, const TargetArgs& a);

/// --rays-per-wavelength sets the density of the ray tubes of bounces >= 2: with --bounces 1 it
/// would be silently ignored, so it is refused.
void check_rays(const CLI::App& cmd, int bounces);

/// The frequencies of exactly one of --freq-hz and --freq-sweep-hz [Hz].
[[nodiscard]] std::vector<double> frequencies(const SweepText& t);

}  // namespace radar_emu::app
