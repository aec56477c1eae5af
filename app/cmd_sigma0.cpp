// `radar-emu sigma0`: the terrain scattering coefficient vs angle (tools/sigma0.hpp).

#include <memory>
#include <stdexcept>
#include <string>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_args.hpp"
#include "config/cli_checks.hpp"
#include "radar/clutter/terrain.hpp"
#include "tools/sigma0.hpp"

namespace radar_emu::app {
namespace {

// The angles and the permittivity are kept as text and parsed when run, so errors name the option.
struct Sigma0Args {
  tools::Sigma0ToolOptions opt;
  std::string theta = "0:85:86", theta_s, eps;
  const CLI::Option* out = nullptr;
};

int sigma0_command(const CLI::App& sigma0, Sigma0Args& a) {
  if (!a.opt.catalogue_chart_png.empty())
    return tools::run_catalogue_chart(a.opt);
  if (sigma0.count("--freq-hz") == 0)
    throw std::invalid_argument("--freq-hz is required");
  if (sigma0.count("--x-power") > 0 && a.opt.correlation != "xpower")
    throw std::invalid_argument("--x-power: used with --corr xpower only (got --corr " +
                                a.opt.correlation + ")");
  check_default_file(a.out, a.opt.out_csv);
  a.opt.theta_deg = config::parse_sweep(a.theta, "--theta-deg");
  if (!a.theta_s.empty())
    a.opt.theta_s_deg = config::parse_sweep(a.theta_s, "--theta-s-deg");
  if (!a.eps.empty()) {
    const auto parts = config::parse_pair(a.eps, "--eps-r");
    a.opt.eps_real = parts.first;
    a.opt.eps_loss = parts.second;
  }
  return tools::run_sigma0_tool(a.opt);
}

}  // namespace

void add_sigma0_command(CLI::App& app, Commands& commands) {
  CLI::App* sigma0 = app.add_subcommand(
      "sigma0", "Terrain scattering coefficient vs angle (empirical, IEM, SPM, KA, RT, total)");
  auto a = std::make_shared<Sigma0Args>();
  tools::Sigma0ToolOptions& o = a->opt;
  CLI::Option* s0_material = sigma0->add_option(
      "--material", o.material,
      "Catalogue material: " + radar_emu::radar::clutter::terrain_material_names());
  sigma0->add_option("--eps-r", a->eps, "Custom surface permittivity RE,IM (eps = RE - j IM)")
      ->excludes(s0_material);
  sigma0->add_option("--rms-height-m", o.rms_height_m, "Custom surface rms height s [m]")
      ->excludes(s0_material);
  sigma0->add_option("--corr-length-m", o.corr_length_m, "Custom correlation length l [m]")
      ->excludes(s0_material);
  CLI::Option* s0_corr =
      sigma0
          ->add_option("--corr", o.correlation,
                       "Custom surface correlation function: gaussian, exponential (default), "
                       "xpower")
          ->check(CLI::IsMember({"gaussian", "exponential", "xpower"}))
          ->excludes(s0_material);
  sigma0
      ->add_option("--x-power", o.x_power,
                   "Exponent of the x-power function (with --corr xpower; default 1.5)")
      ->check(config::in_range(1.0, 20.0, "", true))
      ->needs(s0_corr);
  sigma0
      ->add_option("--freq-hz", o.freq_hz,
                   "Frequency [Hz] (required, except with --catalogue-chart)")
      ->check(config::in_range(0.0, 1e15, "Hz", true));
  sigma0->add_option("--model", o.model,
                     "total (default: the measured-data catalogue, what the images use), "
                     "physical (IEM surface + RT volume), empirical (Ulaby-Dobson L/S/C rows), "
                     "iem, spm, ka or rt");
  sigma0
      ->add_option("--catalogue-chart", o.catalogue_chart_png,
                   "PNG: the catalogue's sigma0 vs incidence at 10, 35 and 94 GHz for "
                   "--chart-materials, with the published points of --points")
      ->check(config::output_file({".png"}));
  sigma0->add_option("--chart-materials", o.chart_materials,
                     "Materials of --catalogue-chart (default grass,asphalt,forest,water)");
  sigma0->add_option("--points", o.points_csv,
                     "Published points for --catalogue-chart (default "
                     "tests/data/sigma0_catalogue_points.csv)");
  sigma0->add_option("--theta-deg", a->theta, "Incidence angles A:B:N [deg] (default 0:85:86)");
  CLI::Option* theta_s =
      sigma0->add_option("--theta-s-deg", a->theta_s, "Bistatic scattering angles A:B:N [deg]");
  sigma0
      ->add_option("--phi-s-deg", o.phi_s_deg,
                   "Bistatic azimuth from the plane of incidence [deg] (0: forward, 180: back; "
                   "with --theta-s-deg)")
      ->check(config::in_range(-360.0, 360.0, "deg"))
      ->needs(theta_s);
  sigma0->add_option("--pol", o.pols, "Polarisations, of HH,VV,HV,VH (default all four)");
  a->out = sigma0->add_option("--out", o.out_csv, "CSV output (default sigma0.csv)")
               ->check(config::output_file());
  sigma0->add_option("--plot", o.plot_png, "PNG chart")->check(config::output_file({".png"}));
  sigma0->add_flag("-q,--quiet", o.quiet, "No summary");
  commands.push_back({sigma0, [sigma0, a] { return sigma0_command(*sigma0, *a); }});
}

}  // namespace radar_emu::app
