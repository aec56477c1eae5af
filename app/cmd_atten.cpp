// `radar-emu atten`: the specific attenuation of gases, rain, fog and woodland vs frequency
// (tools/atten.hpp).

#include <memory>
#include <stdexcept>
#include <string>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_args.hpp"
#include "config/cli_checks.hpp"
#include "tools/atten.hpp"

namespace radar_emu::app {
namespace {

struct AttenArgs {
  tools::AttenToolOptions opt;
  std::string freq;  ///< --freq-hz as given (parsed when run: errors name it)
  const CLI::Option* out = nullptr;
};

int atten_command(AttenArgs& a) {
  a.opt.freqs_hz = config::parse_sweep(a.freq, "--freq-hz");
  if (!a.opt.plot_png.empty() && a.opt.freqs_hz.size() < 2)
    throw std::invalid_argument("--plot: needs a frequency sweep (--freq-hz START:STOP:N)");
  check_default_file(a.out, a.opt.out_csv);
  return tools::run_atten_tool(a.opt);
}

}  // namespace

void add_atten_command(CLI::App& app, Commands& commands) {
  CLI::App* atten = app.add_subcommand(
      "atten",
      "Specific attenuation of gases, rain, fog and woodland vs frequency (ITU-R "
      "P.676/838/840/833)");
  auto a = std::make_shared<AttenArgs>();
  tools::AttenToolOptions& o = a->opt;
  // ITU-R P.676-13's domain, 1-1000 GHz, in the option's unit.
  atten->add_option("--freq-hz", a->freq, "Frequency [Hz]: F or START:STOP:N in [1e9, 1e12]")
      ->required()
      ->check(config::sweep_in_range(1e9, 1e12, "Hz"));
  // Ranges: a standard atmosphere from the ground to 100 km (ITU-R P.835: 1013 hPa to below
  // 1e-3 hPa, -90 C to +60 C at the extremes), vapour to saturation at 60 C (130 g/m^3), the
  // scenario's fog ceiling (5 g/m^3).
  atten
      ->add_option("--pressure-hpa", o.dry_pressure_hpa, "Dry-air pressure [hPa] (default 1013.25)")
      ->check(config::in_range(0.0, 1100.0, "hPa"));
  atten->add_option("--temp-c", o.temperature_c, "Temperature [C] (default 15)")
      ->check(config::in_range(-100.0, 60.0, "C"));
  atten->add_option("--rho-gm3", o.water_vapour_gm3, "Water-vapour density [g/m^3] (default 7.5)")
      ->check(config::in_range(0.0, 130.0, "g/m^3"));
  atten->add_option("--rain-mmh", o.rain_mm_per_h, "Rain rate [mm/h] (default 0)")
      ->check(config::in_range(0.0, 500.0, "mm/h"));  // ITU-R P.838's range here
  atten->add_option("--fog-gm3", o.fog_gm3, "Fog or cloud liquid water [g/m^3] (default 0)")
      ->check(config::in_range(0.0, 5.0, "g/m^3"));
  CLI::Option* veg =
      atten->add_option("--veg-depth-m", o.veg_depth_m,
                        "Woodland crossed [m] (ITU-R P.833 sec. 2, 1-30 GHz; default 0)");
  atten->add_flag("--out-of-leaf", o.out_of_leaf, "Woodland without leaves (P.833)")->needs(veg);
  a->out = atten->add_option("--out", o.out_csv, "CSV output (default atten.csv)")
               ->check(config::output_file());
  atten->add_option("--plot", o.plot_png, "PNG chart (needs a sweep START:STOP:N)")
      ->check(config::output_file({".png"}));
  atten->add_flag("-q,--quiet", o.quiet, "No summary");
  commands.push_back({atten, [a] { return atten_command(*a); }});
}

}  // namespace radar_emu::app
