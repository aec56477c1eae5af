// `radar-emu image`: the 94 GHz enhanced-vision radar image of a scenario's view, with its
// optical preview (tools/image.hpp).

#include <memory>
#include <string>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_checks.hpp"
#include "tools/image.hpp"
#include "tools/scene.hpp"

namespace radar_emu::app {

void add_image_command(CLI::App& app, Commands& commands) {
  CLI::App* image = app.add_subcommand(
      "image", "94 GHz enhanced-vision radar image of a scenario's view, with its optical preview");
  struct Args {
    tools::ImageToolOptions options;
    std::string seed_text;  ///< --seed as given (parsed when run: errors name it)
  };
  auto a = std::make_shared<Args>();
  tools::ImageToolOptions& o = a->options;
  image->add_option("scenario", o.scenario, "Scenario TOML (default: the embedded one)")
      ->check(CLI::ExistingFile);
  image->add_option("--time-s", o.time_s, "Scenario time of the ownship pose [s] (default 0)")
      ->check(config::in_range(0.0, 1e6, "s"));
  image->add_option("--looks", o.looks, "Uncorrelated looks averaged (default 10)")
      ->check(CLI::Range(1, 1000));
  image->add_option("--seed", a->seed_text, "Speckle seed, 0..2^64-1 (default 20261124)");
  image
      ->add_option("--optical-scale", o.optical_scale,
                   "Optical preview pixels per radar pixel, each way (default 4)")
      ->check(CLI::Range(1, 16));
  image->add_option("--out", o.out_dir, "Output directory (default ./image)")
      ->check(config::output_dir());
  image->add_flag("--plot", o.plot, "Also write image.png (radar and optical side by side)");
  image->add_flag("-q,--quiet", o.quiet, "No progress line, estimate or summary");
  commands.push_back({image, [a] {
                        tools::ImageToolOptions options = a->options;
                        if (!a->seed_text.empty())
                          options.seed = tools::parse_seed(a->seed_text, "--seed");
                        OfflineRun run("image", "columns", options.quiet);
                        options.control = run.control();
                        return run.finish(tools::run_image_tool(options),
                                          "the columns done are in " + options.out_dir +
                                              "/image.csv, marked incomplete (image.json too)");
                      }});
}

}  // namespace radar_emu::app
