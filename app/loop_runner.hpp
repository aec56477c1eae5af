#pragma once
// The closed loop as `run` and `replay` drive it (app/loop_runner.cpp), and run's printed summary
// (app/run_summary.cpp).

#include <string>

#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"

namespace radar_emu::app {

/// The scenario in `scenario_file`, or the embedded default when it is empty.
[[nodiscard]] loop::Scenario load_scenario_or_default(const std::string& scenario_file);

/// Runs the loop, writes the outputs and prints the summary (run and replay). With a Modbus
/// server, the final detection table stays served for `linger_s` seconds after the run. The
/// outputs stream into `out` during the run; SIGINT or SIGTERM ends the run at a frame boundary
/// with every output written, report.json marked "interrupted", and exit status 128 + signal.
int execute_loop(const loop::Scenario& scenario, loop::RunOptions options, const std::string& out,
                 bool quiet, double linger_s = 0.0, double view_wait_s = 0.0,
                 double view_linger_s = 0.0);

}  // namespace radar_emu::app
