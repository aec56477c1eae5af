#pragma once
// `radar-emu run`'s options (app/cmd_run_options.cpp), read by app/cmd_run.cpp.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace radar_emu::app {

/// The bus side of a run: backends, servers and the live view.
struct BusArgs {
  std::string can = "sim";
  std::string nav_modbus;
  std::string modbus_server;
  double modbus_linger_s = 0.0;
  std::string trace_events;
  std::string serve;  // the live view (loop/outputs/live_view.hpp)
  double serve_wait_s = 0.0, serve_linger_s = 0.0;
};

struct RunArgs {
  std::string scenario_file, out;
  std::uint64_t frames = 0;
  bool realtime = false, print_scenario = false, quiet = false, lock_memory = false;
  int rt_priority = 0, cpu = -1;
  BusArgs bus;
  std::string cube;         // --cube FILE.h5 (docs/cube.md)
  std::string cube_frames;  // --cube-frames FIRST:LAST; "": the scenario's (0:3)
};

/// Adds run's option table to `run`, bound to `a` (which must outlive parsing).
void add_run_options(CLI::App& run, RunArgs& a);

}  // namespace radar_emu::app
