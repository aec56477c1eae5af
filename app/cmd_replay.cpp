// `radar-emu replay`: a recorded input log (a run's bus_in.log, or any candump log of
// CANaerospace input) through the loop on the simulated clock: deterministic, whatever the
// machine's load.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "app/loop_runner.hpp"
#include "config/cli_checks.hpp"
#include "io/candump.hpp"

namespace radar_emu::app {
namespace {

int replay_command(const std::string& log_file, const std::string& scenario_file,
                   std::uint64_t frames, const std::string& out, bool quiet) {
  loop::Scenario scenario = load_scenario_or_default(scenario_file);
  loop::RunOptions options;
  options.replay = true;
  {
    // The parsed lines are freed before the run: a long log is held once, as frames.
    const std::vector<radar_emu::io::CandumpLine> lines =
        radar_emu::io::read_candump_file(log_file);
    options.replay_input.reserve(lines.size());
    for (const auto& line : lines)
      options.replay_input.push_back(line.frame);
  }
  if (options.replay_input.empty())
    throw std::runtime_error(log_file + ": no frames to replay");
  // The log's time stamps are bus times: scenario time 0 is the scenario's epoch. A log recorded
  // elsewhere (a real bus: CLOCK_REALTIME of another day) is aligned on its first whole second.
  const std::int64_t first_ns = options.replay_input.front().timestamp_ns;
  const std::int64_t last_ns = options.replay_input.back().timestamp_ns;
  constexpr std::int64_t kDay_ns = 86'400'000'000'000LL;
  if (first_ns < scenario.epoch_unix_ns || first_ns - scenario.epoch_unix_ns > kDay_ns) {
    scenario.epoch_unix_ns = first_ns - first_ns % 1'000'000'000LL;
    // A warning: printed whatever -q says.
    std::fprintf(stderr,
                 "radar-emu replay: warning: log starts at %.6f s, not within a day of the "
                 "scenario's epoch: epoch set to %lld s\n",
                 static_cast<double>(first_ns) * 1e-9,
                 static_cast<long long>(scenario.epoch_unix_ns / 1'000'000'000LL));
  }
  if (frames > 0) {
    scenario.frames = frames;
  } else {
    // Enough frames to consume the whole log: frame k runs at epoch + k / rate.
    const double span_s = static_cast<double>(last_ns - scenario.epoch_unix_ns) * 1e-9;
    scenario.frames = static_cast<std::uint64_t>(std::ceil(span_s * scenario.rate_hz - 1e-9)) + 1;
  }
  return execute_loop(scenario, std::move(options), out, quiet);
}

}  // namespace

void add_replay_command(CLI::App& app, Commands& commands) {
  CLI::App* replay = app.add_subcommand(
      "replay",
      "Replay a recorded input log (candump format, e.g. a run's bus_in.log) through "
      "the closed loop, deterministically");
  struct Args {
    std::string log, scenario, out = "out/replay";
    std::uint64_t frames = 0;
    bool quiet = false;
  };
  auto a = std::make_shared<Args>();
  replay->add_option("log", a->log, "Input log in candump -L format")
      ->required()
      ->check(CLI::ExistingFile);
  replay
      ->add_option("scenario", a->scenario,
                   "Scenario TOML of the recording run (default: the embedded one)")
      ->check(CLI::ExistingFile);
  replay->add_option("--frames", a->frames, "Number of frames (default: the log's span)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{100'000'000}));
  replay->add_option("--out", a->out, "Output directory (default out/replay)")
      ->check(config::output_dir());
  replay->add_flag("-q,--quiet", a->quiet, "No progress or summary (warnings are still printed)");
  commands.push_back({replay, [replay, a] {
                        check_default_dir(replay->get_option("--out"), a->out);
                        return replay_command(a->log, a->scenario, a->frames, a->out, a->quiet);
                      }});
}

}  // namespace radar_emu::app
