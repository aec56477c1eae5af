// `radar-emu profile`: the range profile (and the ISAR image over an angle sweep) of a mesh
// (tools/rcs.hpp, PO + SBR). The options shared with `rcs` are in app/cli_common.cpp.

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

struct ProfileArgs {
  SweepText text;
  tools::ProfileToolOptions opt;
  const CLI::Option* out = nullptr;
};

int profile_command(const CLI::App& profile, ProfileArgs& a) {
  a.opt.freqs_hz = frequencies(a.text);
  a.opt.theta_deg = config::parse_sweep(a.text.theta, "--theta-deg");
  a.opt.phi_deg = config::parse_sweep(a.text.phi, "--phi-deg");
  const auto pols = tools::parse_pols(a.text.pol);
  if (pols.size() != 1)
    throw std::invalid_argument("--pol: a profile takes one polarisation");
  a.opt.pol = pols[0];
  check_rays(profile, a.opt.bounces);
  if (a.opt.theta_deg.size() == 1 && a.opt.phi_deg.size() == 1) {
    for (const char* isar : {"--isar-out", "--isar-plot"}) {
      if (profile.count(isar) > 0)
        throw std::invalid_argument(std::string(isar) +
                                    ": an ISAR image needs a sweep in theta or phi (A:B:N)");
    }
  }
  check_default_file(a.out, a.opt.out_csv);
  OfflineRun run("profile", "angles", a.opt.quiet);
  a.opt.control = run.control();
  return run.finish(tools::run_profile_tool(a.opt),
                    "the profiles done are in " + a.opt.out_csv + ", marked incomplete");
}

}  // namespace

void add_profile_command(CLI::App& app, Commands& commands) {
  CLI::App* profile = app.add_subcommand(
      "profile", "Range profile (and ISAR image over an angle sweep) of a mesh (PO + SBR)");
  auto a = std::make_shared<ProfileArgs>();
  tools::ProfileToolOptions& o = a->opt;
  a->text.pol = "VV";
  add_target_options(*profile, a->text,
                     {o.mesh, o.scale, o.materials, o.bounces, o.rays_per_wavelength, o.quiet,
                      o.edges, o.edge_turn_deg, o.edge_order});
  profile->add_option("--pol", a->text.pol, "One polarisation: HH, HV, VH or VV (default VV)");
  profile->add_option("--window", o.window,
                      "none, hann, hamming, blackman or taylor (default hann)");
  profile->add_option("--oversample", o.oversample, "Zero-padding factor (default 4)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{64}));
  profile->add_option("--dynamic-range-db", o.dynamic_range_db, "Plot range (default 50)")
      ->check(config::in_range(0.0, 400.0, "dB", true));
  a->out = profile->add_option("--out", o.out_csv, "Range-profile CSV (default profile.csv)")
               ->check(config::output_file());
  profile->add_option("--plot", o.plot_png, "Range-profile PNG")
      ->check(config::output_file({".png"}));
  profile
      ->add_option("--isar-out", o.isar_csv,
                   "ISAR CSV (default *_isar.csv; needs a theta or phi sweep)")
      ->check(config::output_file());
  profile
      ->add_option("--isar-plot", o.isar_png,
                   "ISAR PNG (default *_isar.png; needs a theta or phi sweep)")
      ->check(config::output_file({".png"}));
  commands.push_back({profile, [profile, a] { return profile_command(*profile, *a); }, true});
}

}  // namespace radar_emu::app
