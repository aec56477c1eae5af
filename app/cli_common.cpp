// Command-line pieces several subcommands share (app/cli_common.hpp).

#include "app/cli_common.hpp"

#include <cstdio>
#include <stdexcept>
#include <utility>

#include "app/cmd.hpp"
#include "config/cli_args.hpp"
#include "config/cli_checks.hpp"
#include "radar/em/rcs.hpp"

namespace radar_emu::app {

void check_default_file(const CLI::Option* opt, const std::string& path) {
  if (opt->count() == 0)
    config::check_output_file(path, opt->get_name());
}

void check_default_dir(const CLI::Option* opt, const std::string& path) {
  if (opt->count() == 0)
    config::check_output_dir(path, opt->get_name());
}

void add_target_options(CLI::App& cmd, SweepText& t, const TargetArgs& a) {
  cmd.add_option("--mesh", a.mesh, "Target mesh: .glb, .gltf, .obj or .stl")
      ->required()
      ->check(CLI::ExistingFile);
  cmd.add_option("--scale", a.scale,
                 "File units to metres (0.001 for mm, 0.0254 for inches; default 1)")
      ->check(config::in_range(0.0, 1e6, "", true));
  CLI::Option* freq = cmd.add_option("--freq-hz", t.freq, "One frequency [Hz]")
                          ->check(config::sweep_in_range(0.0, 1e15, "Hz", true));
  cmd.add_option("--freq-sweep-hz", t.freq_sweep, "Frequencies START:STOP:N [Hz]")
      ->check(config::sweep_in_range(0.0, 1e15, "Hz", true))
      ->excludes(freq);
  cmd.add_option("--theta-deg", t.theta,
                 "Radar direction from +z: A or A:B:N in [-180, 180] deg (default 0; "
                 "theta < 0 is the half of the cut at phi + 180, so a cut can pass through "
                 "normal incidence)")
      ->check(config::sweep_in_range(-180.0, 180.0, "deg"));
  cmd.add_option("--phi-deg", t.phi,
                 "Radar direction from +x toward +y: A or A:B:N in [-360, 360] deg")
      ->check(config::sweep_in_range(-360.0, 360.0, "deg"));
  cmd.add_option("--bounces", a.bounces,
                 "Bounces: 1 = facet PO only, up to " +
                     std::to_string(radar_emu::radar::kMaxRcsBounces) +
                     " (default 3; the summary counts the ray tubes still bouncing at the cap)")
      ->check(CLI::Range(1, radar_emu::radar::kMaxRcsBounces));
  cmd.add_option("--rays-per-wavelength", a.rays_per_wavelength,
                 "Ray-tube density for bounces >= 2 at the highest frequency (default 4)")
      ->check(config::in_range(0.0, 1000.0, "rays a wavelength", true));
  cmd.add_option("--material", a.materials,
                 "Non-metal material: NAME=EPS_REAL,EPS_LOSS (dielectric, eps = EPS_REAL - j "
                 "EPS_LOSS) or NAME=EPS_REAL,EPS_LOSS,THICKNESS_M (coating on metal); "
                 "repeatable");
  cmd.add_flag("-q,--quiet", a.quiet, "No progress or summary (warnings are still printed)");
  cmd.add_option("--edge-order", a.edge_order,
                 "1: first-order edge currents only; 2 (default): plus the double diffraction "
                 "of the hard polarisation between parallel edges across a flat face")
      ->check(CLI::Range(1, 2));
  cmd.add_option("--edge-turn-deg", a.edge_turn_deg,
                 "A shared mesh edge diffracts when its faces turn by more than this (default "
                 "30 deg; open-sheet boundaries always do)");
  cmd.add_flag("--no-edges{false}", a.edges,
               "No edge diffraction (default: fringe equivalent edge currents of the mesh's "
               "wedge edges and sheet boundaries added to PO)");
}

void check_rays(const CLI::App& cmd, int bounces) {
  if (bounces == 1 && cmd.count("--rays-per-wavelength") > 0) {
    throw std::invalid_argument(
        "--rays-per-wavelength: not used with --bounces 1 (facet PO only, no ray tubes)");
  }
}

std::string si_bytes(double bytes) {
  char text[64];
  if (bytes >= 1e12)
    std::snprintf(text, sizeof text, "%.3g TB", bytes * 1e-12);
  else if (bytes >= 1e9)
    std::snprintf(text, sizeof text, "%.3g GB", bytes * 1e-9);
  else
    std::snprintf(text, sizeof text, "%.3g MB", bytes * 1e-6);
  return text;
}

std::vector<double> frequencies(const SweepText& t) {
  if (t.freq.empty() == t.freq_sweep.empty())
    throw std::invalid_argument("give exactly one of --freq-hz and --freq-sweep-hz");
  return t.freq.empty() ? config::parse_sweep(t.freq_sweep, "--freq-sweep-hz")
                        : config::parse_sweep(t.freq, "--freq-hz");
}

OfflineRun::OfflineRun(std::string command, std::string unit, bool quiet)
    : command_(std::move(command)), quiet_(quiet), line_(command_, std::move(unit), !quiet) {
  install_stop_handlers(StopScope::kOfflineTool);
}

common::WorkControl OfflineRun::control() {
  common::WorkControl c;
  c.progress = [this](std::size_t done, std::size_t total) {
    // Once a stop is heard, the count is kept for the final message but no longer drawn: the
    // handler's acknowledgement has begun a new line, and that message must start one.
    if (stop_signal().load(std::memory_order_relaxed) != 0)
      line_.record(done, total);
    else
      line_.update(done, total);
  };
  if (!quiet_) {
    c.estimate = [this](const std::string& line) {
      std::fprintf(stderr, "%s: estimate: %s\n", command_.c_str(), line.c_str());
    };
  }
  c.note = [this](const std::string& text) {
    if (stop_signal().load(std::memory_order_relaxed) != 0)
      line_.abandon();  // the handler's acknowledgement began a new line: no redraw
    line_.print_above(text);
  };
  c.stop = &stop_signal();
  return c;
}

int OfflineRun::finish(int status, const std::string& written) {
  if (status > 128) {
    line_.abandon();  // the stop handler's acknowledgement began a new line
    return config::report_interrupted(command_, status - 128, line_, written);
  }
  line_.finish();
  return status;
}

}  // namespace radar_emu::app
