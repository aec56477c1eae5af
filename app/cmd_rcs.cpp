// `radar-emu rcs`: the radar cross section of a mesh vs angle and frequency, polarimetric
// (tools/rcs.hpp: PO + SBR + edges, or the method of moments). The options shared with
// `profile` are in app/cli_common.cpp.

#include <memory>
#include <stdexcept>
#include <string>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_args.hpp"
#include "config/cli_checks.hpp"
#include "tools/rcs.hpp"

namespace radar_emu::app {
namespace {

struct RcsArgs {
  SweepText text;
  tools::RcsToolOptions opt;
  double bistatic_theta = 0.0, bistatic_phi = 0.0;
  const CLI::Option* bistatic = nullptr;  ///< --bistatic-theta-deg
  const CLI::Option* out = nullptr;
};

int rcs_command(const CLI::App& rcs, RcsArgs& a) {
  a.opt.freqs_hz = frequencies(a.text);
  a.opt.theta_deg = config::parse_sweep(a.text.theta, "--theta-deg");
  a.opt.phi_deg = config::parse_sweep(a.text.phi, "--phi-deg");
  a.opt.pols = tools::parse_pols(a.text.pol);
  check_rays(rcs, a.opt.bounces);
  if (a.opt.method == "mom") {
    for (const char* po_only :
         {"--bounces", "--rays-per-wavelength", "--edge-order", "--edge-turn-deg", "--no-edges"}) {
      if (rcs.count(po_only) > 0)
        throw std::invalid_argument(std::string(po_only) +
                                    ": a setting of --method po, not used with --method mom");
    }
  } else {
    for (const char* mom_only : {"--mom-equation", "--mom-max-unknowns"}) {
      if (rcs.count(mom_only) > 0)
        throw std::invalid_argument(std::string(mom_only) + ": used with --method mom only");
    }
  }
  if (a.opt.window_deg > 0.0 && a.opt.theta_deg.size() == 1 && a.opt.phi_deg.size() == 1)
    throw std::invalid_argument("--window-deg: needs a sweep in theta or phi (A:B:N)");
  check_default_file(a.out, a.opt.out_csv);
  if (a.bistatic->count() > 0) {
    a.opt.bistatic_theta_deg = a.bistatic_theta;
    a.opt.bistatic_phi_deg = a.bistatic_phi;
  }
  const bool mom = a.opt.method == "mom";
  OfflineRun run("rcs", mom ? "frequencies" : "directions", a.opt.quiet);
  a.opt.control = run.control();
  return run.finish(tools::run_rcs_tool(a.opt),
                    "the rows done are in " + a.opt.out_csv + ", marked incomplete");
}

}  // namespace

void add_rcs_command(CLI::App& app, Commands& commands) {
  CLI::App* rcs = app.add_subcommand(
      "rcs", "Radar cross section of a mesh vs angle and frequency, polarimetric (PO + SBR)");
  auto a = std::make_shared<RcsArgs>();
  tools::RcsToolOptions& o = a->opt;
  a->text.pol = "HH,VV";
  add_target_options(*rcs, a->text,
                     {o.mesh, o.scale, o.materials, o.bounces, o.rays_per_wavelength, o.quiet,
                      o.edges, o.edge_turn_deg, o.edge_order});
  rcs->add_option("--pol", a->text.pol,
                  "Polarisations, receive letter first: HH,HV,VH,VV (default HH,VV)");
  rcs->add_option("--method", o.method,
                  "po (default): physical optics + shooting and bouncing rays + edge "
                  "diffraction; mom: method of moments, exact up to the mesh on PEC targets a "
                  "few wavelengths across (triangles about lambda/10; memory 16 N^2 bytes for N "
                  "~ 1.5 x triangles unknowns)")
      ->check(CLI::IsMember({"po", "mom"}));
  rcs->add_option("--mom-equation", o.mom_equation,
                  "With --method mom: efie (default, the accurate one), cfie (free of "
                  "interior resonances, less accurate at tips) or mfie; closed surfaces only for "
                  "mfie, and open sheets always take the EFIE")
      ->check(CLI::IsMember({"efie", "mfie", "cfie"}));
  rcs->add_option("--mom-max-unknowns", o.mom_max_unknowns,
                  "With --method mom: refuse meshes with more unknowns (default 20000, 6.4 GB)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{200000}));
  CLI::Option* bt = rcs->add_option("--bistatic-theta-deg", a->bistatic_theta,
                                    "Receiver direction theta in [0, 180] deg (bistatic)")
                        ->check(config::in_range(0.0, 180.0, "deg"));
  CLI::Option* bp = rcs->add_option("--bistatic-phi-deg", a->bistatic_phi,
                                    "Receiver direction phi in [-360, 360] deg")
                        ->check(config::in_range(-360.0, 360.0, "deg"));
  a->bistatic = bt;
  bt->needs(bp);
  bp->needs(bt);
  a->out = rcs->add_option("--out", o.out_csv, "CSV output (default rcs.csv)")
               ->check(config::output_file());
  rcs->add_option("--plot", o.plot_png, "PNG plot of the sweep")
      ->check(config::output_file({".png"}));
  rcs->add_option("--overlay", o.overlays,
                  "Another curve on the plot, FILE=LABEL: lines of numbers whose last two are the "
                  "swept value and dBsm (a reference table, another run); repeatable");
  CLI::Option* window_deg =
      rcs->add_option("--window-deg", o.window_deg,
                      "Fluctuation statistics (mean, median, p10/p90, spread) over a sliding "
                      "aspect window of this width [deg] (needs a theta or phi sweep)")
          ->check(config::in_range(0.0, 360.0, "deg", true));
  rcs->add_option("--stats-out", o.stats_csv, "CSV for --window-deg (default *_stats.csv)")
      ->check(config::output_file())
      ->needs(window_deg);
  commands.push_back({rcs, [rcs, a] { return rcs_command(*rcs, *a); }, true});
}

}  // namespace radar_emu::app
