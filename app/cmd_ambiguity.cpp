// `radar-emu ambiguity`: the ambiguity function of the configured waveform (tools/ambiguity.hpp).

#include <memory>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_checks.hpp"
#include "tools/ambiguity.hpp"

namespace radar_emu::app {

void add_ambiguity_command(CLI::App& app, Commands& commands) {
  CLI::App* ambiguity = app.add_subcommand(
      "ambiguity",
      "Ambiguity function of the configured waveform (heat map, cuts, measured figures)");
  auto o = std::make_shared<tools::AmbiguityToolOptions>();
  ambiguity
      ->add_option("scenario", o->scenario,
                   "Scenario TOML whose [radar] waveform to use (default: the embedded one)")
      ->check(CLI::ExistingFile);
  // Ranges as the scenario's [radar] keys (loop/scenario.cpp).
  ambiguity->add_option("--bandwidth-hz", o->bandwidth_hz, "Override the swept bandwidth")
      ->check(config::in_range(1e3, 1e10, "Hz"));
  ambiguity->add_option("--pulse-width-s", o->pulse_width_s, "Override the pulse length")
      ->check(config::in_range(1e-10, 1.0, "s"));
  CLI::Option* train = ambiguity->add_flag(
      "--train", o->train,
      "The coherent pulse train (closed form) over +-2 PRI instead of one pulse");
  ambiguity->add_option("--prf-hz", o->prf_hz, "Override the PRF (with --train)")
      ->check(config::in_range(1.0, 1e8, "Hz"))
      ->needs(train);
  ambiguity->add_option("--pulses", o->pulses, "Override the pulses a CPI (with --train)")
      ->check(CLI::Range(1, 65536))
      ->needs(train);
  ambiguity
      ->add_option("--delay-span", o->delay_span,
                   "+- delay in pulse widths (single pulse; default 1)")
      ->check(config::in_range(0.0, 100.0, "pulse widths", true))
      ->excludes(train);
  ambiguity
      ->add_option("--doppler-span", o->doppler_span,
                   "+- Doppler in 1/T (single pulse) or PRFs (train) (default 8)")
      ->check(config::in_range(0.0, 1000.0, "", true));
  ambiguity->add_option("--points", o->points, "Grid points an axis (default 201)")
      ->check(CLI::Range(11, 2001));
  ambiguity->add_option("--oversample", o->oversample, "Samples per 1/B (default 8)")
      ->check(CLI::Range(2, 64));
  ambiguity->add_option("--dynamic-range-db", o->dynamic_range_db, "Plot range (default 40)")
      ->check(config::in_range(0.0, 400.0, "dB", true));
  ambiguity->add_option("--out", o->out_dir, "Output directory (default ./ambiguity)")
      ->check(config::output_dir());
  ambiguity->add_flag("-q,--quiet", o->quiet, "No summary");
  commands.push_back({ambiguity, [ambiguity, o] {
                        check_default_dir(ambiguity->get_option("--out"), o->out_dir.string());
                        return tools::run_ambiguity_tool(*o);
                      }});
}

}  // namespace radar_emu::app
