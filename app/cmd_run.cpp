// `radar-emu run`: the closed loop, aircraft state in over the bus, detections out. The option
// table is in app/cmd_run_options.cpp.

#include "app/cmd_run.hpp"

#include <iostream>
#include <memory>
#include <utility>

#include "app/cmd.hpp"
#include "app/loop_runner.hpp"

namespace radar_emu::app {
namespace {

int run_command(const RunArgs& a) {
  if (a.print_scenario) {
    std::cout << loop::default_scenario_toml();
    return 0;
  }
  loop::Scenario scenario = load_scenario_or_default(a.scenario_file);
  if (a.frames > 0)
    scenario.frames = a.frames;
  loop::RunOptions options;
  options.realtime = a.realtime;
  options.rt.fifo_priority = a.rt_priority;
  options.rt.lock_memory = a.lock_memory;
  options.rt.cpu = a.cpu;
  options.can = a.bus.can;
  options.nav_modbus = a.bus.nav_modbus;
  options.modbus_server = a.bus.modbus_server;
  options.trace_events_file = a.bus.trace_events;
  options.serve = a.bus.serve;
  // The scenario's [output] cube and cube_frames, each replaced by the CLI's when given.
  loop::choose_cube(scenario, a.cube, a.cube_frames, options);
  return execute_loop(scenario, std::move(options), a.out, a.quiet, a.bus.modbus_linger_s,
                      a.bus.serve_wait_s, a.bus.serve_linger_s);
}

}  // namespace

void add_run_command(CLI::App& app, Commands& commands) {
  CLI::App* run = app.add_subcommand(
      "run", "Run the closed loop: aircraft state in over the bus, detections out");
  auto a = std::make_shared<RunArgs>();
  add_run_options(*run, *a);
  commands.push_back({run, [a] { return run_command(*a); }});
}

}  // namespace radar_emu::app
