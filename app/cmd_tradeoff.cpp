// `radar-emu tradeoff`: cost against error for each fidelity knob (tools/tradeoff.hpp).

#include <memory>
#include <string>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_checks.hpp"
#include "tools/tradeoff.hpp"

namespace radar_emu::app {
namespace {

struct TradeoffArgs {
  tools::TradeoffOptions opt;
  std::string cases;  ///< --cases as given (parsed when run: errors name it)
  const CLI::Option* out = nullptr;
};

int tradeoff_command(TradeoffArgs& a) {
  check_default_dir(a.out, a.opt.out_dir);
  if (!a.cases.empty())
    a.opt.cases = tools::parse_tradeoff_cases(a.cases);
  // The progress line in cases, the per-knob lines printed above it (unless -q); the stop flag
  // is heard between cases.
  OfflineRun run("tradeoff", "cases", a.opt.quiet);
  a.opt.control = run.control();
  return run.finish(tools::run_tradeoff_tool(a.opt),
                    "the cases done are in " + a.opt.out_dir + "/tradeoff.csv, marked incomplete");
}

}  // namespace

void add_tradeoff_command(CLI::App& app, Commands& commands) {
  CLI::App* tradeoff = app.add_subcommand(
      "tradeoff",
      "Cost (wall ms, rays) against error for each fidelity knob, and where methods fail");
  auto a = std::make_shared<TradeoffArgs>();
  a->out = tradeoff
               ->add_option("--out", a->opt.out_dir,
                            "Output directory: tradeoff.csv, tradeoff.png and one PNG per case "
                            "(default tradeoff)")
               ->check(config::output_dir());
  tradeoff->add_option("--cases", a->cases,
                       "Comma-separated cases of vehicle,profile,frame,sphere,grazing,iem "
                       "(default all)");
  tradeoff->add_flag("--quick", a->opt.quick,
                     "Coarse grids: the whole run in well under a minute (the CI test)");
  tradeoff->add_flag("-q,--quiet", a->opt.quiet, "No progress and no summary");
  commands.push_back({tradeoff, [a] { return tradeoff_command(*a); }});
}

}  // namespace radar_emu::app
