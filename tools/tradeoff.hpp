#pragma once
// `radar-emu tradeoff`: what each fidelity knob costs (wall time, rays) against the error it
// leaves with respect to a converged reference, and where the methods themselves fail (issue 15,
// item 4). Cases:
//   vehicle  RCS of the 25k-facet armoured vehicle over an aspect cut: rays_per_wavelength,
//            max_bounces (RcsEngine); error dB RMS against the finest setting of the knob;
//   profile  range profile of the same vehicle (frequency sweep, one aspect): same knobs, error
//            dB RMS over the bins within 30 dB of the reference's peak;
//   frame    one closed-loop frame of the default scenario (SbrTracer + Sensor, thermal noise
//            off): target_ray_spacing_m, terrain_ray_spacing_rad, max_bounces, pulses; detections
//            matched to a high-fidelity frame by range/azimuth gates;
//   sphere   PO through the facet integrator against its closed form and the Mie series, ka 0.5
//            to 100 (PO invalid below ka 10);
//   grazing  double-bounce return of a dihedral with one face at 80-89 deg incidence against ray
//            density (flagged where the densest two settings disagree);
//   iem      sigma0 from IEM against ks, next to SPM and Kirchhoff, with each model's validity.
// Writes DIR/tradeoff.csv, DIR/tradeoff.png (error against cost, one series per knob) and one
// chart per case that has its own axes.

#include <string>
#include <string_view>
#include <vector>

#include "common/work_control.hpp"

namespace radar_emu::tools {

struct TradeoffOptions {
  std::string out_dir = "tradeoff";
  std::vector<std::string> cases;  ///< empty: all
  bool quick = false;              ///< coarse grids (the CI test)
  bool quiet = false;
  /// Progress in cases, and the stop flag polled between cases.
  common::WorkControl control;
};

/// Every case name, in run order: vehicle, profile, frame, sphere, grazing, iem.
[[nodiscard]] const std::vector<std::string>& tradeoff_case_names();

/// "vehicle,iem" -> {"vehicle", "iem"}; throws std::invalid_argument naming --cases and the
/// known names for anything else (or an empty list).
[[nodiscard]] std::vector<std::string> parse_tradeoff_cases(std::string_view text);

/// Runs the cases and writes the outputs. Throws on bad options (one line, naming the option)
/// and on I/O failures. Returns the process exit status: 0, or 128 + the signal when
/// control.stop ended the run between cases: the cases done keep their rows and charts, and
/// tradeoff.csv ends with "# incomplete: stopped by SIGINT after 2 of 6 cases, before frame
/// (N rows)".
int run_tradeoff_tool(const TradeoffOptions& options);

}  // namespace radar_emu::tools
