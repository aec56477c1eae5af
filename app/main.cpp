// radar-emu: command-line entry point. Parses options and orchestrates; all work lives in the
// libraries (style.md item 1).

#include <sched.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <thread>

#include "config/cli_args.hpp"
#include "config/cli_checks.hpp"
#include "io/candump.hpp"
#include "loop/closed_loop.hpp"
#include "loop/outputs/live_view.hpp"
#include "loop/scenario.hpp"
#include "radar/clutter/terrain.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "scene/targets.hpp"
#include "tools/ambiguity.hpp"
#include "tools/atten.hpp"
#include "tools/image.hpp"
#include "tools/mpi_work.hpp"
#include "tools/rcs.hpp"
#include "tools/sar.hpp"
#include "tools/scene.hpp"
#include "tools/sigma0.hpp"
#include "tools/tradeoff.hpp"

namespace config = radar_emu::config;
namespace loop = radar_emu::loop;
namespace tools = radar_emu::tools;

namespace {

// SIGINT / SIGTERM during a run: the first asks the loop to stop at the next frame boundary and
// write every output; a second exits at once (status 128 + signal), outputs as they are.
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_stop_signal(int sig) {
  if (g_stop_signal.exchange(sig) != 0)
    _exit(128 + sig);
  static constexpr char kMsg[] =
      "\nradar-emu: stopping at the next frame boundary and writing the outputs (again: exit "
      "at once)\n";
  (void)!write(STDERR_FILENO, kMsg, sizeof kMsg - 1);
}

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // other threads' blocking calls carry on
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

loop::Scenario load_scenario_or_default(const std::string& scenario_file) {
  return scenario_file.empty()
             ? loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")
             : loop::load_scenario(scenario_file);
}

// Runs the loop, writes the outputs and prints the summary (run and replay). With a Modbus
// server, the final detection table stays served for `linger_s` seconds after the run. The
// outputs stream into `out` during the run; SIGINT or SIGTERM ends the run at a frame boundary
// with every output written, report.json marked "interrupted", and exit status 128 + signal.
int execute_loop(const loop::Scenario& scenario, loop::RunOptions options, const std::string& out,
                 bool quiet, double linger_s = 0.0, double view_wait_s = 0.0,
                 double view_linger_s = 0.0) {
  install_stop_handlers();
  options.stop = &g_stop_signal;
  options.out_dir = out;
  // Everything is in the files: nothing needs to stay in memory, whatever the run's length.
  options.record_frames_max = 0;
  const bool show_progress = !quiet && scenario.frames >= 100;
  if (show_progress) {
    options.progress = [](std::uint64_t done, std::uint64_t total) {
      if (done == total || done % (total / 10 == 0 ? 1 : total / 10) == 0 ||
          g_stop_signal.load(std::memory_order_relaxed) != 0) {
        std::fprintf(stderr, "\r  frame %llu/%llu", static_cast<unsigned long long>(done),
                     static_cast<unsigned long long>(total));
        if (done == total)
          std::fputc('\n', stderr);
      }
    };
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
        g_stop_signal.load(std::memory_order_relaxed) == 0) {
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
  if (!modbus.empty() && linger_s > 0.0 && !result.interrupted) {
    std::fprintf(stderr, "radar-emu: run complete; serving the final table on %s for %.1f s\n",
                 modbus.c_str(), linger_s);
    std::fflush(stderr);
    // In steps, so that a stop request ends the linger too.
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(linger_s);
    while (std::chrono::steady_clock::now() < until &&
           g_stop_signal.load(std::memory_order_relaxed) == 0) {
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
           g_stop_signal.load(std::memory_order_relaxed) == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  if (result.interrupted) {
    std::fprintf(stderr, "radar-emu: interrupted after %llu of %llu frames; outputs written%s\n",
                 static_cast<unsigned long long>(result.frames),
                 static_cast<unsigned long long>(result.frames_planned),
                 out.empty() ? " (none: no --out)" : (" to " + out).c_str());
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

struct BusArgs {
  std::string can = "sim";
  std::string nav_modbus;
  std::string modbus_server;
  double modbus_linger_s = 0.0;
  std::string trace_events;
  std::string serve;  // the live view (loop/outputs/live_view.hpp)
  double serve_wait_s = 0.0, serve_linger_s = 0.0;
};

int run_command(const std::string& scenario_file, std::uint64_t frames, const std::string& out,
                bool realtime, bool print_scenario, bool quiet, int rt_priority, bool lock_memory,
                int cpu, const BusArgs& bus) {
  if (print_scenario) {
    std::cout << loop::default_scenario_toml();
    return 0;
  }
  loop::Scenario scenario = load_scenario_or_default(scenario_file);
  if (frames > 0)
    scenario.frames = frames;
  loop::RunOptions options;
  options.realtime = realtime;
  options.rt.fifo_priority = rt_priority;
  options.rt.lock_memory = lock_memory;
  options.rt.cpu = cpu;
  options.can = bus.can;
  options.nav_modbus = bus.nav_modbus;
  options.modbus_server = bus.modbus_server;
  options.trace_events_file = bus.trace_events;
  options.serve = bus.serve;
  return execute_loop(scenario, std::move(options), out, quiet, bus.modbus_linger_s,
                      bus.serve_wait_s, bus.serve_linger_s);
}

// Replays a recorded input log (a run's bus_in.log, or any candump log of CANaerospace input)
// through the loop on the simulated clock: deterministic, whatever the machine's load.
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

// The dimensions a target kind reads (scene/targets.hpp): 1 (a), 2 (a, b) or 3 (a, b, c).
int target_dimensions(radar_emu::scene::TargetKind kind) {
  using radar_emu::scene::TargetKind;
  switch (kind) {
    case TargetKind::kTrihedralSquare:
    case TargetKind::kTrihedralTriangular:
    case TargetKind::kSphere:
      return 1;
    case TargetKind::kPlate:
    case TargetKind::kDihedral:
    case TargetKind::kCylinder:
      return 2;
    default:
      return 3;
  }
}

// Default of `scene target --max-triangles` (README): about 4 GB at the measured 210 bytes a
// triangle (scene/targets.hpp kTargetBytesPerTriangle).
constexpr double kDefaultMaxTargetTriangles = 20e6;

std::string si_bytes(double bytes) {
  char text[64];
  if (bytes >= 1e12)
    std::snprintf(text, sizeof text, "%.3g TB", bytes * 1e-12);
  else if (bytes >= 1e9)
    std::snprintf(text, sizeof text, "%.3g GB", bytes * 1e-9);
  else
    std::snprintf(text, sizeof text, "%.3g MB", bytes * 1e-6);
  return text;
}

int target_command(const std::string& kind_name, radar_emu::scene::TargetSpec spec,
                   const std::string& out, const CLI::App& cmd, double max_triangles) {
  namespace sc = radar_emu::scene;
  const auto kind = sc::target_kind_from_name(kind_name);
  if (!kind) {
    throw std::runtime_error("unknown target '" + kind_name + "' (known: " + sc::target_names() +
                             ")");
  }
  spec.kind = *kind;
  // A dimension the kind does not read is refused, not silently ignored.
  const int dims = target_dimensions(*kind);
  const char* takes = dims == 1 ? "--a-m only" : dims == 2 ? "--a-m and --b-m only" : "";
  for (int d = dims; d < 3; ++d) {
    const std::string name = d == 1 ? "--b-m" : "--c-m";
    if (cmd.count(name) > 0)
      throw std::invalid_argument(name + ": a " + kind_name + " takes " + takes);
  }
  // Refuse a mesh past the memory limit before making it, with the estimate.
  const double triangles = sc::target_triangle_estimate(spec);
  if (triangles > max_triangles) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "--facet-m %g: a %s would have about %.3g triangles (about %s of memory), over "
                  "the limit of %.3g triangles (raise it with --max-triangles, or use a coarser "
                  "--facet-m)",
                  spec.facet_m, kind_name.c_str(), triangles,
                  si_bytes(triangles * sc::kTargetBytesPerTriangle).c_str(), max_triangles);
    throw std::invalid_argument(text);
  }
  const sc::SceneDescription desc = sc::make_target(spec);
  const std::filesystem::path path(out);
  const std::string ext = path.extension().string();
  if (ext == ".glb" || ext == ".gltf") {
    sc::write_gltf(desc, path);
  } else {
    sc::write_mesh_file(desc.objects[0].mesh, desc.materials, path);
  }
  std::printf("%s: %s, %zu triangles\n", out.c_str(), kind_name.c_str(),
              desc.objects[0].mesh.triangles.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Under mpirun, rcs and profile split their sweeps over the ranks (docs/cluster.md).
  const tools::mpi_work::Scope mpi_scope;
  CLI::App app{"radar-emu: hardware-in-the-loop radar emulator (SBR physics on Embree)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "radar-emu 0.1.0");
  // Every error is one line on stderr (style.md): the option and what is wrong with it.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "radar-emu: error: " + std::string(e.what()) + " (--help lists the options)\n";
  });

  CLI::App* run = app.add_subcommand(
      "run", "Run the closed loop: aircraft state in over the bus, detections out");
  std::string scenario_file, out;
  std::uint64_t frames = 0;
  bool realtime = false, print_scenario = false, quiet = false, lock_memory = false;
  int rt_priority = 0, cpu = -1;
  run->add_option("scenario", scenario_file,
                  "Scenario TOML (keys override the embedded default; see --print-scenario)")
      ->check(CLI::ExistingFile);
  run->add_option("--frames", frames, "Number of frames (overrides the scenario)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{100'000'000}))
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  // The last --out / --frames wins, so wrappers (scripts/run.sh) can set defaults.
  run->add_option("--out", out,
                  "Directory for report.json, detections.json, truth.json, "
                  "the pictures and the bus logs")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast)
      ->check(config::output_dir());
  CLI::Option* realtime_flag =
      run->add_flag("--realtime", realtime,
                    "Pace frames on the monotonic wall clock (default: as fast as possible on "
                    "simulated time)");
  run->add_option("--rt-priority", rt_priority, "SCHED_FIFO priority with --realtime (1-99)")
      ->check(CLI::Range(1, 99))
      ->needs(realtime_flag);
  run->add_flag("--lock-memory", lock_memory, "mlockall() with --realtime")->needs(realtime_flag);
  run->add_option("--cpu", cpu, "Pin the frame loop to this CPU with --realtime")
      ->check(CLI::Range(0, CPU_SETSIZE - 1))
      ->needs(realtime_flag);
  CLI::Option* print_flag = run->add_flag("--print-scenario", print_scenario,
                                          "Print the embedded default scenario and exit");
  run->add_flag("-q,--quiet", quiet, "No progress or summary (warnings are still printed)");
  BusArgs bus_args;
  run->add_option("--can", bus_args.can,
                  "CAN backend: sim (software loopback, default), socketcan:IFACE[,fd]"
                  "[,bitrate=N][,dbitrate=N], gsusb[:SERIAL][,fd][,bitrate=N][,dbitrate=N] "
                  "(real buses need --realtime; ,fd sends the detection lists as CAN FD)");
  run->add_option("--nav-modbus", bus_args.nav_modbus,
                  "Ownship state from a Modbus navigation register map (docs/icd/modbus.md) "
                  "instead of CANaerospace: tcp:HOST:PORT, rtu:DEV:BAUD (with --realtime), or "
                  "sim (played from the scenario on the loopback register bank)");
  CLI::Option* modbus_server =
      run->add_option("--modbus-server", bus_args.modbus_server,
                      "Serve the detection table as Modbus holding registers on HOST:PORT (:PORT "
                      "binds 127.0.0.1; port 0 picks a free one, printed on stderr)");
  run->add_option("--modbus-linger-s", bus_args.modbus_linger_s,
                  "Keep serving the final detection table this long after the run [s]")
      ->check(config::in_range(0.0, 86400.0, "s"))
      ->needs(modbus_server);
  run->add_option("--trace-events", bus_args.trace_events,
                  "Write every stage of every frame as Chrome trace-event JSON to FILE (open in "
                  "https://ui.perfetto.dev or chrome://tracing)")
      ->check(config::output_file());
  CLI::Option* serve =
      run->add_option("--serve", bus_args.serve,
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
  run->add_option("--serve-wait-s", bus_args.serve_wait_s,
                  "Before the first frame, wait this long for a browser to open the live view [s]")
      ->check(config::in_range(0.0, 86400.0, "s"))
      ->needs(serve);
  run->add_option("--serve-linger-s", bus_args.serve_linger_s,
                  "Keep serving the live view's last frame this long after the run [s]")
      ->check(config::in_range(0.0, 86400.0, "s"))
      ->needs(serve);
  // --print-scenario prints and exits: every other option would be silently ignored.
  for (CLI::Option* o : run->get_options()) {
    if (o != print_flag && o->get_name() != "--help" && !o->get_name().empty())
      print_flag->excludes(o);
  }

  CLI::App* replay = app.add_subcommand(
      "replay",
      "Replay a recorded input log (candump format, e.g. a run's bus_in.log) through "
      "the closed loop, deterministically");
  std::string replay_log, replay_scenario, replay_out = "out/replay";
  std::uint64_t replay_frames = 0;
  bool replay_quiet = false;
  replay->add_option("log", replay_log, "Input log in candump -L format")
      ->required()
      ->check(CLI::ExistingFile);
  replay
      ->add_option("scenario", replay_scenario,
                   "Scenario TOML of the recording run (default: the embedded one)")
      ->check(CLI::ExistingFile);
  replay->add_option("--frames", replay_frames, "Number of frames (default: the log's span)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{100'000'000}));
  replay->add_option("--out", replay_out, "Output directory (default out/replay)")
      ->check(config::output_dir());
  replay->add_flag("-q,--quiet", replay_quiet,
                   "No progress or summary (warnings are still printed)");

  CLI::App* scene_cmd = app.add_subcommand("scene", "Scene databases and canonical targets");
  scene_cmd->require_subcommand(1);
  CLI::App* target = scene_cmd->add_subcommand(
      "target", "Write a canonical target mesh (conventions in scene/targets.hpp)");
  std::string target_kind, target_out;
  radar_emu::scene::TargetSpec spec;
  target->add_option("kind", target_kind, radar_emu::scene::target_names())->required();
  double max_triangles = kDefaultMaxTargetTriangles;
  target
      ->add_option("--a-m", spec.a_m,
                   "First dimension [m]: plate/box x, fold length, trihedral edge, radius")
      ->check(config::in_range(0.0, 1e5, "m", true));
  target
      ->add_option("--b-m", spec.b_m,
                   "Second dimension [m]: plate/box y, face width, length (not for trihedrals "
                   "and spheres)")
      ->check(config::in_range(0.0, 1e5, "m", true));
  target
      ->add_option("--c-m", spec.c_m,
                   "Third dimension [m]: box, vehicle and aircraft z (only those)")
      ->check(config::in_range(0.0, 1e5, "m", true));
  target
      ->add_option("--facet-m", spec.facet_m,
                   "Largest facet edge [m] (0: coarsest exact mesh, 32 segments for curves)")
      ->check(config::in_range(0.0, 1e5, "m"));
  target
      ->add_option("--max-triangles", max_triangles,
                   "Refuse a mesh estimated past this many triangles (about 210 bytes each "
                   "while written; default 2e7)")
      ->check(config::in_range(1.0, 1.4e9, "triangles"));
  target->add_option("--out", target_out, "Output file: .glb, .gltf, .obj or .stl")
      ->required()
      ->check(config::output_file({".glb", ".gltf", ".obj", ".stl"}));
  tools::SceneCommands scene_tools;  // scene gen | info | preview (tools/scene.hpp)
  tools::add_scene_commands(*scene_cmd, scene_tools);
  tools::ImageCommand image_tool;  // image (tools/image.hpp)
  tools::add_image_command(app, image_tool);

  // rcs / profile: options are kept as text and parsed by the tool, so errors name the option.
  struct SweepText {
    std::string freq, freq_sweep, theta = "0", phi = "0", pol;
  };
  auto add_common = [](CLI::App* cmd, SweepText& t, std::string& mesh, double& scale,
                       std::vector<std::string>& materials, int& bounces, double& rpw,
                       bool& quiet_flag) {
    cmd->add_option("--mesh", mesh, "Target mesh: .glb, .gltf, .obj or .stl")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--scale", scale,
                    "File units to metres (0.001 for mm, 0.0254 for inches; default 1)")
        ->check(config::in_range(0.0, 1e6, "", true));
    CLI::Option* freq = cmd->add_option("--freq-hz", t.freq, "One frequency [Hz]")
                            ->check(config::sweep_in_range(0.0, 1e15, "Hz", true));
    cmd->add_option("--freq-sweep-hz", t.freq_sweep, "Frequencies START:STOP:N [Hz]")
        ->check(config::sweep_in_range(0.0, 1e15, "Hz", true))
        ->excludes(freq);
    cmd->add_option("--theta-deg", t.theta,
                    "Radar direction from +z: A or A:B:N in [-180, 180] deg (default 0; "
                    "theta < 0 is the half of the cut at phi + 180, so a cut can pass through "
                    "normal incidence)")
        ->check(config::sweep_in_range(-180.0, 180.0, "deg"));
    cmd->add_option("--phi-deg", t.phi,
                    "Radar direction from +x toward +y: A or A:B:N in [-360, 360] deg")
        ->check(config::sweep_in_range(-360.0, 360.0, "deg"));
    cmd->add_option("--bounces", bounces,
                    "Bounces: 1 = facet PO only, up to " +
                        std::to_string(radar_emu::radar::kMaxRcsBounces) +
                        " (default 3; the summary counts the ray tubes still bouncing at the cap)")
        ->check(CLI::Range(1, radar_emu::radar::kMaxRcsBounces));
    cmd->add_option("--rays-per-wavelength", rpw,
                    "Ray-tube density for bounces >= 2 at the highest frequency (default 4)")
        ->check(config::in_range(0.0, 1000.0, "rays a wavelength", true));
    cmd->add_option("--material", materials,
                    "Non-metal material: NAME=EPS_REAL,EPS_LOSS (dielectric, eps = EPS_REAL - j "
                    "EPS_LOSS) or NAME=EPS_REAL,EPS_LOSS,THICKNESS_M (coating on metal); "
                    "repeatable");
    cmd->add_flag("-q,--quiet", quiet_flag, "No progress or summary (warnings are still printed)");
  };
  // --rays-per-wavelength sets the density of the ray tubes of bounces >= 2: with --bounces 1
  // it would be silently ignored.
  auto check_rays = [](const CLI::App* cmd, int bounces) {
    if (bounces == 1 && cmd->count("--rays-per-wavelength") > 0) {
      throw std::invalid_argument(
          "--rays-per-wavelength: not used with --bounces 1 (facet PO only, no ray tubes)");
    }
  };
  auto frequencies = [](const SweepText& t) {
    if (t.freq.empty() == t.freq_sweep.empty())
      throw std::invalid_argument("give exactly one of --freq-hz and --freq-sweep-hz");
    return t.freq.empty() ? config::parse_sweep(t.freq_sweep, "--freq-sweep-hz")
                          : config::parse_sweep(t.freq, "--freq-hz");
  };

  CLI::App* rcs = app.add_subcommand(
      "rcs", "Radar cross section of a mesh vs angle and frequency, polarimetric (PO + SBR)");
  SweepText rcs_text;
  rcs_text.pol = "HH,VV";
  tools::RcsToolOptions rcs_opt;
  double bistatic_theta = 0.0, bistatic_phi = 0.0;
  add_common(rcs, rcs_text, rcs_opt.mesh, rcs_opt.scale, rcs_opt.materials, rcs_opt.bounces,
             rcs_opt.rays_per_wavelength, rcs_opt.quiet);
  rcs->add_option("--edge-order", rcs_opt.edge_order,
                  "1: first-order edge currents only; 2 (default): plus the double diffraction "
                  "of the hard polarisation between parallel edges across a flat face")
      ->check(CLI::Range(1, 2));
  rcs->add_option("--edge-turn-deg", rcs_opt.edge_turn_deg,
                  "A shared mesh edge diffracts when its faces turn by more than this (default "
                  "30 deg; open-sheet boundaries always do)");
  rcs->add_flag("--no-edges{false}", rcs_opt.edges,
                "No edge diffraction (default: fringe equivalent edge currents of the mesh's "
                "wedge edges and sheet boundaries added to PO)");
  rcs->add_option("--pol", rcs_text.pol,
                  "Polarisations, receive letter first: HH,HV,VH,VV (default HH,VV)");
  rcs->add_option("--method", rcs_opt.method,
                  "po (default): physical optics + shooting and bouncing rays + edge "
                  "diffraction; mom: method of moments, exact up to the mesh on PEC targets a "
                  "few wavelengths across (triangles about lambda/10; memory 16 N^2 bytes for N "
                  "~ 1.5 x triangles unknowns)")
      ->check(CLI::IsMember({"po", "mom"}));
  rcs->add_option("--mom-equation", rcs_opt.mom_equation,
                  "With --method mom: efie (default, the accurate one), cfie (free of "
                  "interior resonances, less accurate at tips) or mfie; closed surfaces only for "
                  "mfie, and open sheets always take the EFIE")
      ->check(CLI::IsMember({"efie", "mfie", "cfie"}));
  rcs->add_option("--mom-max-unknowns", rcs_opt.mom_max_unknowns,
                  "With --method mom: refuse meshes with more unknowns (default 20000, 6.4 GB)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{200000}));
  CLI::Option* bt = rcs->add_option("--bistatic-theta-deg", bistatic_theta,
                                    "Receiver direction theta in [0, 180] deg (bistatic)")
                        ->check(config::in_range(0.0, 180.0, "deg"));
  CLI::Option* bp = rcs->add_option("--bistatic-phi-deg", bistatic_phi,
                                    "Receiver direction phi in [-360, 360] deg")
                        ->check(config::in_range(-360.0, 360.0, "deg"));
  bt->needs(bp);
  bp->needs(bt);
  CLI::Option* rcs_out = rcs->add_option("--out", rcs_opt.out_csv, "CSV output (default rcs.csv)")
                             ->check(config::output_file());
  rcs->add_option("--plot", rcs_opt.plot_png, "PNG plot of the sweep")
      ->check(config::output_file({".png"}));
  rcs->add_option("--overlay", rcs_opt.overlays,
                  "Another curve on the plot, FILE=LABEL: lines of numbers whose last two are the "
                  "swept value and dBsm (a reference table, another run); repeatable");
  CLI::Option* window_deg =
      rcs->add_option("--window-deg", rcs_opt.window_deg,
                      "Fluctuation statistics (mean, median, p10/p90, spread) over a sliding "
                      "aspect window of this width [deg] (needs a theta or phi sweep)")
          ->check(config::in_range(0.0, 360.0, "deg", true));
  rcs->add_option("--stats-out", rcs_opt.stats_csv, "CSV for --window-deg (default *_stats.csv)")
      ->check(config::output_file())
      ->needs(window_deg);

  CLI::App* profile = app.add_subcommand(
      "profile", "Range profile (and ISAR image over an angle sweep) of a mesh (PO + SBR)");
  SweepText prof_text;
  prof_text.pol = "VV";
  tools::ProfileToolOptions prof_opt;
  add_common(profile, prof_text, prof_opt.mesh, prof_opt.scale, prof_opt.materials,
             prof_opt.bounces, prof_opt.rays_per_wavelength, prof_opt.quiet);
  profile
      ->add_option("--edge-order", prof_opt.edge_order,
                   "1: first-order edge currents only; 2 (default): plus the double diffraction "
                   "of the hard polarisation between parallel edges across a flat face")
      ->check(CLI::Range(1, 2));
  profile->add_option("--edge-turn-deg", prof_opt.edge_turn_deg,
                      "A shared mesh edge diffracts when its faces turn by more than this (default "
                      "30 deg; open-sheet boundaries always do)");
  profile->add_flag("--no-edges{false}", prof_opt.edges,
                    "No edge diffraction (default: fringe equivalent edge currents added to PO)");
  profile->add_option("--pol", prof_text.pol, "One polarisation: HH, HV, VH or VV (default VV)");
  profile->add_option("--window", prof_opt.window,
                      "none, hann, hamming, blackman or taylor (default hann)");
  profile->add_option("--oversample", prof_opt.oversample, "Zero-padding factor (default 4)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{64}));
  profile->add_option("--dynamic-range-db", prof_opt.dynamic_range_db, "Plot range (default 50)")
      ->check(config::in_range(0.0, 400.0, "dB", true));
  CLI::Option* prof_out =
      profile->add_option("--out", prof_opt.out_csv, "Range-profile CSV (default profile.csv)")
          ->check(config::output_file());
  profile->add_option("--plot", prof_opt.plot_png, "Range-profile PNG")
      ->check(config::output_file({".png"}));
  profile
      ->add_option("--isar-out", prof_opt.isar_csv,
                   "ISAR CSV (default *_isar.csv; needs a theta or phi sweep)")
      ->check(config::output_file());
  profile
      ->add_option("--isar-plot", prof_opt.isar_png,
                   "ISAR PNG (default *_isar.png; needs a theta or phi sweep)")
      ->check(config::output_file({".png"}));

  CLI::App* ambiguity = app.add_subcommand(
      "ambiguity",
      "Ambiguity function of the configured waveform (heat map, cuts, measured figures)");
  tools::AmbiguityToolOptions amb_opt;
  ambiguity
      ->add_option("scenario", amb_opt.scenario,
                   "Scenario TOML whose [radar] waveform to use (default: the embedded one)")
      ->check(CLI::ExistingFile);
  // Ranges as the scenario's [radar] keys (loop/scenario.cpp).
  ambiguity->add_option("--bandwidth-hz", amb_opt.bandwidth_hz, "Override the swept bandwidth")
      ->check(config::in_range(1e3, 1e10, "Hz"));
  ambiguity->add_option("--pulse-width-s", amb_opt.pulse_width_s, "Override the pulse length")
      ->check(config::in_range(1e-10, 1.0, "s"));
  CLI::Option* train = ambiguity->add_flag(
      "--train", amb_opt.train,
      "The coherent pulse train (closed form) over +-2 PRI instead of one pulse");
  ambiguity->add_option("--prf-hz", amb_opt.prf_hz, "Override the PRF (with --train)")
      ->check(config::in_range(1.0, 1e8, "Hz"))
      ->needs(train);
  ambiguity->add_option("--pulses", amb_opt.pulses, "Override the pulses a CPI (with --train)")
      ->check(CLI::Range(1, 65536))
      ->needs(train);
  ambiguity
      ->add_option("--delay-span", amb_opt.delay_span,
                   "+- delay in pulse widths (single pulse; default 1)")
      ->check(config::in_range(0.0, 100.0, "pulse widths", true))
      ->excludes(train);
  ambiguity
      ->add_option("--doppler-span", amb_opt.doppler_span,
                   "+- Doppler in 1/T (single pulse) or PRFs (train) (default 8)")
      ->check(config::in_range(0.0, 1000.0, "", true));
  ambiguity->add_option("--points", amb_opt.points, "Grid points an axis (default 201)")
      ->check(CLI::Range(11, 2001));
  ambiguity->add_option("--oversample", amb_opt.oversample, "Samples per 1/B (default 8)")
      ->check(CLI::Range(2, 64));
  ambiguity->add_option("--dynamic-range-db", amb_opt.dynamic_range_db, "Plot range (default 40)")
      ->check(config::in_range(0.0, 400.0, "dB", true));
  ambiguity->add_option("--out", amb_opt.out_dir, "Output directory (default ./ambiguity)")
      ->check(config::output_dir());
  ambiguity->add_flag("-q,--quiet", amb_opt.quiet, "No summary");

  CLI::App* atten = app.add_subcommand(
      "atten",
      "Specific attenuation of gases, rain, fog and woodland vs frequency (ITU-R "
      "P.676/838/840/833)");
  tools::AttenToolOptions atten_opt;
  std::string atten_freq;
  // ITU-R P.676-13's domain, 1-1000 GHz, in the option's unit.
  atten->add_option("--freq-hz", atten_freq, "Frequency [Hz]: F or START:STOP:N in [1e9, 1e12]")
      ->required()
      ->check(config::sweep_in_range(1e9, 1e12, "Hz"));
  // Ranges: a standard atmosphere from the ground to 100 km (ITU-R P.835: 1013 hPa to below
  // 1e-3 hPa, -90 C to +60 C at the extremes), vapour to saturation at 60 C (130 g/m^3), the
  // scenario's fog ceiling (5 g/m^3).
  atten
      ->add_option("--pressure-hpa", atten_opt.dry_pressure_hpa,
                   "Dry-air pressure [hPa] (default 1013.25)")
      ->check(config::in_range(0.0, 1100.0, "hPa"));
  atten->add_option("--temp-c", atten_opt.temperature_c, "Temperature [C] (default 15)")
      ->check(config::in_range(-100.0, 60.0, "C"));
  atten
      ->add_option("--rho-gm3", atten_opt.water_vapour_gm3,
                   "Water-vapour density [g/m^3] (default 7.5)")
      ->check(config::in_range(0.0, 130.0, "g/m^3"));
  atten->add_option("--rain-mmh", atten_opt.rain_mm_per_h, "Rain rate [mm/h] (default 0)")
      ->check(config::in_range(0.0, 500.0, "mm/h"));  // ITU-R P.838's range here
  atten->add_option("--fog-gm3", atten_opt.fog_gm3, "Fog or cloud liquid water [g/m^3] (default 0)")
      ->check(config::in_range(0.0, 5.0, "g/m^3"));
  CLI::Option* veg =
      atten->add_option("--veg-depth-m", atten_opt.veg_depth_m,
                        "Woodland crossed [m] (ITU-R P.833 sec. 2, 1-30 GHz; default 0)");
  atten->add_flag("--out-of-leaf", atten_opt.out_of_leaf, "Woodland without leaves (P.833)")
      ->needs(veg);
  CLI::Option* atten_out =
      atten->add_option("--out", atten_opt.out_csv, "CSV output (default atten.csv)")
          ->check(config::output_file());
  atten->add_option("--plot", atten_opt.plot_png, "PNG chart (needs a sweep START:STOP:N)")
      ->check(config::output_file({".png"}));
  atten->add_flag("-q,--quiet", atten_opt.quiet, "No summary");

  CLI::App* sigma0 = app.add_subcommand(
      "sigma0", "Terrain scattering coefficient vs angle (empirical, IEM, SPM, KA, RT, total)");
  tools::Sigma0ToolOptions s0_opt;
  std::string s0_theta = "0:85:86", s0_theta_s, s0_eps;
  CLI::Option* s0_material = sigma0->add_option(
      "--material", s0_opt.material,
      "Catalogue material: " + radar_emu::radar::clutter::terrain_material_names());
  sigma0->add_option("--eps-r", s0_eps, "Custom surface permittivity RE,IM (eps = RE - j IM)")
      ->excludes(s0_material);
  sigma0->add_option("--rms-height-m", s0_opt.rms_height_m, "Custom surface rms height s [m]")
      ->excludes(s0_material);
  sigma0->add_option("--corr-length-m", s0_opt.corr_length_m, "Custom correlation length l [m]")
      ->excludes(s0_material);
  CLI::Option* s0_corr =
      sigma0
          ->add_option("--corr", s0_opt.correlation,
                       "Custom surface correlation function: gaussian, exponential (default), "
                       "xpower")
          ->check(CLI::IsMember({"gaussian", "exponential", "xpower"}))
          ->excludes(s0_material);
  sigma0
      ->add_option("--x-power", s0_opt.x_power,
                   "Exponent of the x-power function (with --corr xpower; default 1.5)")
      ->check(config::in_range(1.0, 20.0, "", true))
      ->needs(s0_corr);
  sigma0->add_option("--freq-hz", s0_opt.freq_hz, "Frequency [Hz]")
      ->required()
      ->check(config::in_range(0.0, 1e15, "Hz", true));
  sigma0->add_option("--model", s0_opt.model,
                     "empirical, iem, spm, ka, rt or total (surface + volume; default)");
  sigma0->add_option("--theta-deg", s0_theta, "Incidence angles A:B:N [deg] (default 0:85:86)");
  CLI::Option* theta_s =
      sigma0->add_option("--theta-s-deg", s0_theta_s, "Bistatic scattering angles A:B:N [deg]");
  sigma0
      ->add_option("--phi-s-deg", s0_opt.phi_s_deg,
                   "Bistatic azimuth from the plane of incidence [deg] (0: forward, 180: back; "
                   "with --theta-s-deg)")
      ->check(config::in_range(-360.0, 360.0, "deg"))
      ->needs(theta_s);
  sigma0->add_option("--pol", s0_opt.pols, "Polarisations, of HH,VV,HV,VH (default all four)");
  CLI::Option* s0_out =
      sigma0->add_option("--out", s0_opt.out_csv, "CSV output (default sigma0.csv)")
          ->check(config::output_file());
  sigma0->add_option("--plot", s0_opt.plot_png, "PNG chart")->check(config::output_file({".png"}));
  sigma0->add_flag("-q,--quiet", s0_opt.quiet, "No summary");

  CLI::App* tradeoff = app.add_subcommand(
      "tradeoff",
      "Cost (wall ms, rays) against error for each fidelity knob, and where methods fail");
  tools::TradeoffOptions to_opt;
  std::string to_cases;
  CLI::Option* to_out =
      tradeoff
          ->add_option("--out", to_opt.out_dir,
                       "Output directory: tradeoff.csv, tradeoff.png and one PNG per case "
                       "(default tradeoff)")
          ->check(config::output_dir());
  tradeoff->add_option("--cases", to_cases,
                       "Comma-separated cases of vehicle,profile,frame,sphere,grazing,iem "
                       "(default all)");
  tradeoff->add_flag("--quick", to_opt.quick,
                     "Coarse grids: the whole run in well under a minute (the CI test)");
  tradeoff->add_flag("-q,--quiet", to_opt.quiet, "No progress and no summary");

  // sar (issue 17): stripmap SAR over a scene, from a TOML case.
  CLI::App* sar = app.add_subcommand(
      "sar", "Stripmap SAR: raw echoes from the SBR tracer and terrain clutter, backprojection");
  tools::SarToolOptions sar_opt;
  sar->add_option("config", sar_opt.config, "TOML case (examples/sar_seed.toml)")
      ->required()
      ->check(CLI::ExistingFile);
  CLI::Option* sar_out =
      sar->add_option("--out", sar_opt.out_dir,
                      "Output directory: raw.tif, image.tif, image.png, sar.json (default sar_out)")
          ->check(config::output_dir());
  sar->add_flag("--no-raw", sar_opt.no_raw, "Do not write raw.tif");
  sar->add_flag("-q,--quiet", sar_opt.quiet, "No summary");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  // Output paths left at their defaults: checked before any work too (a given one was checked
  // by its validator while parsing).
  auto check_default_file = [](const CLI::Option* opt, const std::string& path) {
    if (opt->count() == 0)
      config::check_output_file(path, opt->get_name());
  };
  auto check_default_dir = [](const CLI::Option* opt, const std::string& path) {
    if (opt->count() == 0)
      config::check_output_dir(path, opt->get_name());
  };
  try {
    // Only the sweeps are split: N copies of another command would write the same files.
    if (tools::mpi_work::launched_size() > 1 && !rcs->parsed() && !profile->parsed() &&
        !sar->parsed()) {
      throw std::invalid_argument(
          "launched by mpirun as " + std::to_string(tools::mpi_work::launched_size()) +
          " ranks: only rcs, profile and sar split their work over MPI ranks; run this command "
          "without mpirun");
    }
    if (run->parsed()) {
      return run_command(scenario_file, frames, out, realtime, print_scenario, quiet, rt_priority,
                         lock_memory, cpu, bus_args);
    }
    if (replay->parsed()) {
      check_default_dir(replay->get_option("--out"), replay_out);
      return replay_command(replay_log, replay_scenario, replay_frames, replay_out, replay_quiet);
    }
    if (target->parsed())
      return target_command(target_kind, spec, target_out, *target, max_triangles);
    if (const auto scene_status = tools::run_scene_command(scene_tools))
      return *scene_status;
    if (const auto image_status = tools::run_image_command(image_tool))
      return *image_status;
    if (rcs->parsed()) {
      rcs_opt.freqs_hz = frequencies(rcs_text);
      rcs_opt.theta_deg = config::parse_sweep(rcs_text.theta, "--theta-deg");
      rcs_opt.phi_deg = config::parse_sweep(rcs_text.phi, "--phi-deg");
      rcs_opt.pols = tools::parse_pols(rcs_text.pol);
      check_rays(rcs, rcs_opt.bounces);
      if (rcs_opt.method == "mom") {
        for (const char* po_only : {"--bounces", "--rays-per-wavelength", "--edge-order",
                                    "--edge-turn-deg", "--no-edges"}) {
          if (rcs->count(po_only) > 0)
            throw std::invalid_argument(std::string(po_only) +
                                        ": a setting of --method po, not used with --method mom");
        }
      } else {
        for (const char* mom_only : {"--mom-equation", "--mom-max-unknowns"}) {
          if (rcs->count(mom_only) > 0)
            throw std::invalid_argument(std::string(mom_only) + ": used with --method mom only");
        }
      }
      if (rcs_opt.window_deg > 0.0 && rcs_opt.theta_deg.size() == 1 && rcs_opt.phi_deg.size() == 1)
        throw std::invalid_argument("--window-deg: needs a sweep in theta or phi (A:B:N)");
      check_default_file(rcs_out, rcs_opt.out_csv);
      if (bt->count() > 0) {
        rcs_opt.bistatic_theta_deg = bistatic_theta;
        rcs_opt.bistatic_phi_deg = bistatic_phi;
      }
      return tools::run_rcs_tool(rcs_opt);
    }
    if (sigma0->parsed()) {
      if (sigma0->count("--x-power") > 0 && s0_opt.correlation != "xpower")
        throw std::invalid_argument("--x-power: used with --corr xpower only (got --corr " +
                                    s0_opt.correlation + ")");
      check_default_file(s0_out, s0_opt.out_csv);
      s0_opt.theta_deg = config::parse_sweep(s0_theta, "--theta-deg");
      if (!s0_theta_s.empty())
        s0_opt.theta_s_deg = config::parse_sweep(s0_theta_s, "--theta-s-deg");
      if (!s0_eps.empty()) {
        const auto parts = config::parse_pair(s0_eps, "--eps-r");
        s0_opt.eps_real = parts.first;
        s0_opt.eps_loss = parts.second;
      }
      return tools::run_sigma0_tool(s0_opt);
    }
    if (tradeoff->parsed()) {
      check_default_dir(to_out, to_opt.out_dir);
      if (!to_cases.empty())
        to_opt.cases = tools::parse_tradeoff_cases(to_cases);
      return tools::run_tradeoff_tool(to_opt);
    }
    if (ambiguity->parsed()) {
      check_default_dir(ambiguity->get_option("--out"), amb_opt.out_dir.string());
      return tools::run_ambiguity_tool(amb_opt);
    }
    if (atten->parsed()) {
      atten_opt.freqs_hz = config::parse_sweep(atten_freq, "--freq-hz");
      if (!atten_opt.plot_png.empty() && atten_opt.freqs_hz.size() < 2)
        throw std::invalid_argument("--plot: needs a frequency sweep (--freq-hz START:STOP:N)");
      check_default_file(atten_out, atten_opt.out_csv);
      return tools::run_atten_tool(atten_opt);
    }
    if (sar->parsed()) {
      check_default_dir(sar_out, sar_opt.out_dir);
      return tools::run_sar_tool(sar_opt);
    }
    if (profile->parsed()) {
      prof_opt.freqs_hz = frequencies(prof_text);
      prof_opt.theta_deg = config::parse_sweep(prof_text.theta, "--theta-deg");
      prof_opt.phi_deg = config::parse_sweep(prof_text.phi, "--phi-deg");
      const auto pols = tools::parse_pols(prof_text.pol);
      if (pols.size() != 1)
        throw std::invalid_argument("--pol: a profile takes one polarisation");
      prof_opt.pol = pols[0];
      check_rays(profile, prof_opt.bounces);
      if (prof_opt.theta_deg.size() == 1 && prof_opt.phi_deg.size() == 1) {
        for (const char* isar : {"--isar-out", "--isar-plot"}) {
          if (profile->count(isar) > 0)
            throw std::invalid_argument(std::string(isar) +
                                        ": an ISAR image needs a sweep in theta or phi (A:B:N)");
        }
      }
      check_default_file(prof_out, prof_opt.out_csv);
      return tools::run_profile_tool(prof_opt);
    }
  } catch (const std::exception& e) {
    // Under mpirun every rank reports (a file missing on one node only must be heard); ranks
    // other than 0 say which they are.
    if (tools::mpi_work::is_root())
      std::fprintf(stderr, "radar-emu: error: %s\n", e.what());
    else
      std::fprintf(stderr, "radar-emu: error (rank %d): %s\n", tools::mpi_work::launched_rank(),
                   e.what());
    tools::mpi_work::abort_job(1);  // under mpirun, after the split started: the others may wait
    return 1;
  }
  return 0;
}
