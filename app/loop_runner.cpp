// The closed loop as `run` and `replay` drive it: stop signals, progress, readiness lines,
// outputs, summary, lingering servers and the exit status (app/loop_runner.hpp).

#include "app/loop_runner.hpp"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <thread>
#include <utility>

#include "app/cmd.hpp"
#include "loop/outputs/report.hpp"
#include "scene/targets.hpp"

namespace radar_emu::app {

loop::Scenario load_scenario_or_default(const std::string& scenario_file) {
  return scenario_file.empty()
             ? loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")
             : loop::load_scenario(scenario_file);
}

namespace {

// --cube: what the file holds; its losses as a warning whatever -q says.
void print_cube_line(const loop::ClosedLoop& loop, bool quiet) {
  const std::optional<loop::CubeCounters> c = loop.cube_counters();
  if (!c)
    return;
  if (!quiet) {
    std::printf("cube: %llu frames (%llu..%llu) in %s, %.1f MiB\n",
                static_cast<unsigned long long>(c->frames_written),
                static_cast<unsigned long long>(c->first_frame),
                static_cast<unsigned long long>(c->last_frame), c->file.c_str(),
                static_cast<double>(c->bytes_written) / (1024.0 * 1024.0));
  }
  if (c->write_errors > 0)
    std::fprintf(stderr, "radar-emu: warning: cube: %llu HDF5 write errors (first: %s)\n",
                 static_cast<unsigned long long>(c->write_errors), c->first_error.c_str());
  if (c->frames_dropped > 0)
    std::fprintf(stderr,
                 "radar-emu: warning: cube: %llu frames dropped (the writer had no free "
                 "slot in time)\n",
                 static_cast<unsigned long long>(c->frames_dropped));
  if (c->frames_without_state > 0)
    std::fprintf(stderr,
                 "radar-emu: warning: cube: %llu frames of the range had no ownship "
                 "state (nothing sensed, not in the file)\n",
                 static_cast<unsigned long long>(c->frames_without_state));
  if (c->capture_dropped > 0)
    std::fprintf(stderr,
                 "radar-emu: warning: cube: %llu returns or false alarms found no room "
                 "in the capture (not in the raw samples)\n",
                 static_cast<unsigned long long>(c->capture_dropped));
}

}  // namespace

int execute_loop(const loop::Scenario& scenario, loop::RunOptions options, const std::string& out,
                 bool quiet, double linger_s, double view_wait_s, double view_linger_s) {
  install_stop_handlers();
  options.stop = &stop_signal();
  options.out_dir = out;
  // Everything is in the files: nothing needs to stay in memory, whatever the run's length.
  options.record_frames_max = 0;
  const bool show_progress = !quiet && scenario.frames >= 100;
  if (show_progress) {
    options.progress = [](std::uint64_t done, std::uint64_t total) {
      if (done == total || done % (total / 10 == 0 ? 1 : total / 10) == 0 ||
          stop_signal().load(std::memory_order_relaxed) != 0) {
        std::fprintf(stderr, "\r  frame %llu/%llu", static_cast<unsigned long long>(done),
                     static_cast<unsigned long long>(total));
        if (done == total)
          std::fputc('\n', stderr);
      }
    };
  }
  if (!quiet) {
    // The size of each built-in [[target]] (given or its kind's default, the table `scene
    // target` reads): a default is never a surprise.
    for (const scene::TargetPlacement& t : scenario.targets) {
      if (t.builtin)
        std::printf("target %s: %s\n", t.name.c_str(), scene::target_size_text(*t.builtin).c_str());
    }
  }
  loop::ClosedLoop loop(scenario, options);
  for (const auto& w : loop.setup_warnings())
    std::fprintf(stderr, "radar-emu: warning: %s\n", w.c_str());
  const std::string modbus = loop.modbus_server_address();
  if (!modbus.empty()) {
    // The readiness line scripts wait for (a client may connect from now on).
    std::fprintf(stderr, "radar-emu: modbus server listening on %s\n", modbus.c_str());
    std::fflush(stderr);
  }
  // The live view (--serve): the readiness line, then (--serve-wait-s) the wait for a browser.
  const std::string view = loop.live_view_address();
  if (!view.empty()) {
    std::fprintf(stderr, "radar-emu: live view on http://%s/\n", view.c_str());
    std::fflush(stderr);
    if (view_wait_s > 0.0 && !loop.wait_for_viewer(view_wait_s) &&
        stop_signal().load(std::memory_order_relaxed) == 0) {
      std::fprintf(stderr,
                   "radar-emu: warning: --serve-wait-s: no browser opened the live view within "
                   "%.1f s; running anyway\n",
                   view_wait_s);
    }
  }
  const loop::RunResult result = loop.run();
  // Warnings go to stderr whatever -q says (-q silences progress and the summary only).
  for (const auto& w : result.realtime.warnings)
    std::fprintf(stderr, "radar-emu: warning: %s\n", w.c_str());
  if (show_progress && result.interrupted)
    std::fputc('\n', stderr);
  if (!out.empty())
    loop.write_outputs(result);
  loop.write_trace_events();
  if (!quiet)
    loop::print_summary(loop.report(result), stdout);
  print_cube_line(loop, quiet);
  if (!modbus.empty() && linger_s > 0.0 && !result.interrupted) {
    std::fprintf(stderr, "radar-emu: run complete; serving the final table on %s for %.1f s\n",
                 modbus.c_str(), linger_s);
    std::fflush(stderr);
    // In steps, so that a stop request ends the linger too.
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(linger_s);
    while (std::chrono::steady_clock::now() < until &&
           stop_signal().load(std::memory_order_relaxed) == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  if (!view.empty() && view_linger_s > 0.0 && !result.interrupted) {
    std::fprintf(stderr,
                 "radar-emu: run complete; live view serving the last frame on "
                 "http://%s/ for %.1f s\n",
                 view.c_str(), view_linger_s);
    std::fflush(stderr);
    const auto until =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(view_linger_s);
    while (std::chrono::steady_clock::now() < until &&
           stop_signal().load(std::memory_order_relaxed) == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  if (result.interrupted) {
    // What was kept: the outputs under --out, and the cube file when there is one.
    std::string kept = out.empty() ? "" : " to " + out;
    if (const std::optional<loop::CubeCounters> c = loop.cube_counters())
      kept += (kept.empty() ? " (" : " and ") + c->file + (out.empty() ? ")" : "");
    if (kept.empty())
      kept = " (none: no --out)";
    std::fflush(stdout);  // the summary table first, then the one line (a shared terminal or log)
    std::fprintf(stderr, "radar-emu: interrupted after %llu of %llu frames; outputs written%s\n",
                 static_cast<unsigned long long>(result.frames),
                 static_cast<unsigned long long>(result.frames_planned), kept.c_str());
    return 128 + result.stop_signal;
  }
  // A navigation source that never answered: the run happened (outputs written) but could
  // not do its job. Exit status 3 (README, "Exit status").
  if (const std::string failure = loop.nav_source_failure(); !failure.empty()) {
    std::fprintf(stderr, "radar-emu: error: %s\n", failure.c_str());
    return 3;
  }
  return 0;
}
}  // namespace radar_emu::app
