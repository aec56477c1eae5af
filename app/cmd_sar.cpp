// `radar-emu sar`: stripmap SAR over a scene, from a TOML case (tools/sar.hpp).

#include <memory>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_checks.hpp"
#include "tools/sar.hpp"

namespace radar_emu::app {

void add_sar_command(CLI::App& app, Commands& commands) {
  CLI::App* sar = app.add_subcommand(
      "sar", "Stripmap SAR: raw echoes from the SBR tracer and terrain clutter, backprojection");
  auto o = std::make_shared<tools::SarToolOptions>();
  sar->add_option("config", o->config, "TOML case (examples/sar_seed.toml)")
      ->required()
      ->check(CLI::ExistingFile);
  CLI::Option* sar_out =
      sar->add_option("--out", o->out_dir,
                      "Output directory: raw.tif, image.tif, image.png, sar.json (default sar_out)")
          ->check(config::output_dir());
  sar->add_flag("--no-raw", o->no_raw, "Do not write raw.tif");
  sar->add_flag("-q,--quiet", o->quiet, "No progress line, estimate or summary");
  commands.push_back({sar,
                      [sar_out, o] {
                        check_default_dir(sar_out, o->out_dir);
                        OfflineRun run("sar", "pulses", o->quiet);
                        o->control = run.control();
                        return run.finish(tools::run_sar_tool(*o),
                                          "the image of the pulses done is in " + o->out_dir +
                                              ", sar.json says \"incomplete\": true");
                      },
                      true});
}

}  // namespace radar_emu::app
