// `radar-emu run`'s option table (app/cmd_run.hpp).

#include <sched.h>

#include <stdexcept>
#include <string>

#include "app/cmd_run.hpp"
#include "config/cli_checks.hpp"
#include "loop/outputs/cube_writer.hpp"
#include "loop/outputs/live_view.hpp"

namespace radar_emu::app {

void add_run_options(CLI::App& run, RunArgs& a) {
  run.add_option("scenario", a.scenario_file,
                 "Scenario TOML (keys override the embedded default; see --print-scenario)")
      ->check(CLI::ExistingFile);
  run.add_option("--frames", a.frames, "Number of frames (overrides the scenario)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{100'000'000}))
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  // The last --out / --frames wins, so wrappers (scripts/run.sh) can set defaults.
  run.add_option("--out", a.out,
                 "Directory for report.json, detections.json, truth.json, "
                 "the pictures and the bus logs")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast)
      ->check(config::output_dir());
  CLI::Option* realtime_flag =
      run.add_flag("--realtime", a.realtime,
                   "Pace frames on the monotonic wall clock (default: as fast as possible on "
                   "simulated time)");
  run.add_option("--rt-priority", a.rt_priority, "SCHED_FIFO priority with --realtime (1-99)")
      ->check(CLI::Range(1, 99))
      ->needs(realtime_flag);
  run.add_flag("--lock-memory", a.lock_memory, "mlockall() with --realtime")->needs(realtime_flag);
  run.add_option("--cpu", a.cpu, "Pin the frame loop to this CPU with --realtime")
      ->check(CLI::Range(0, CPU_SETSIZE - 1))
      ->needs(realtime_flag);
  CLI::Option* print_flag = run.add_flag("--print-scenario", a.print_scenario,
                                         "Print the embedded default scenario and exit");
  run.add_flag("-q,--quiet", a.quiet, "No progress or summary (warnings are still printed)");
  run.add_option("--can", a.bus.can,
                 "CAN backend: sim (software loopback, default), socketcan:IFACE[,fd]"
                 "[,bitrate=N][,dbitrate=N], gsusb[:SERIAL][,fd][,bitrate=N][,dbitrate=N] "
                 "(real buses need --realtime; ,fd sends the detection lists as CAN FD)");
  run.add_option("--nav-modbus", a.bus.nav_modbus,
                 "Ownship state from a Modbus navigation register map (docs/icd/modbus.md) "
                 "instead of CANaerospace: tcp:HOST:PORT, rtu:DEV:BAUD (with --realtime), or "
                 "sim (played from the scenario on the loopback register bank)");
  CLI::Option* modbus_server =
      run.add_option("--modbus-server", a.bus.modbus_server,
                     "Serve the detection table as Modbus holding registers on HOST:PORT (:PORT "
                     "binds 127.0.0.1; port 0 picks a free one, printed on stderr)");
  run.add_option("--modbus-linger-s", a.bus.modbus_linger_s,
                 "Keep serving the final detection table this long after the run [s]")
      ->check(config::in_range(0.0, 86400.0, "s"))
      ->needs(modbus_server);
  run.add_option("--trace-events", a.bus.trace_events,
                 "Write every stage of every frame as Chrome trace-event JSON to FILE (open in "
                 "https://ui.perfetto.dev or chrome://tracing)")
      ->check(config::output_file());
  CLI::Option* serve =
      run.add_option("--serve", a.bus.serve,
                     "Live view: serve a web page with the current frame's B-scope (detections "
                     "against truth), the ownship and the stage times on HOST:PORT (:PORT or "
                     "PORT: 127.0.0.1; port 0 picks a free one, printed on stderr)")
          ->check(CLI::Validator(
              [](std::string& v) {
                try {
                  (void)loop::parse_serve_address(v);
                } catch (const std::invalid_argument& e) {
                  const std::string m = e.what();
                  return m.starts_with("--serve ") ? m.substr(8) : m;
                }
                return std::string();
              },
              "HOST:PORT"));
  run.add_option("--serve-wait-s", a.bus.serve_wait_s,
                 "Before the first frame, wait this long for a browser to open the live view [s]")
      ->check(config::in_range(0.0, 86400.0, "s"))
      ->needs(serve);
  run.add_option("--serve-linger-s", a.bus.serve_linger_s,
                 "Keep serving the live view's last frame this long after the run [s]")
      ->check(config::in_range(0.0, 86400.0, "s"))
      ->needs(serve);
  run.add_option("--cube", a.cube,
                 "Data cubes out: write each frame of --cube-frames as HDF5 to FILE (.h5): "
                 "the raw samples per beam, channel and pulse before processing, the "
                 "range-Doppler-beam image the CFAR ran on, and the frame's detections "
                 "(layout, units and attributes: docs/cube.md); replaces the scenario's "
                 "[output] cube")
      ->check(config::output_file({".h5", ".hdf5"}));
  // Not ->needs(cube): the file may come from the scenario's [output] cube (loop::choose_cube
  // refuses a range without a file).
  run.add_option("--cube-frames", a.cube_frames,
                 "Frames the cube holds, FIRST:LAST (frame indices from 0, inclusive; default "
                 "the scenario's [output] cube_frames, else 0:3); refused, with the estimate, "
                 "when the file would exceed 4 GiB")
      ->check(CLI::Validator(
          [](std::string& v) {
            std::uint64_t first = 0, last = 0;
            return loop::parse_cube_frames(v, first, last);
          },
          "FIRST:LAST"));
  // --print-scenario prints and exits: every other option would be silently ignored.
  for (CLI::Option* o : run.get_options()) {
    if (o != print_flag && o->get_name() != "--help" && !o->get_name().empty())
      print_flag->excludes(o);
  }
}

}  // namespace radar_emu::app
