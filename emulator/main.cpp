// radar-emu: command-line entry point. Parses options and orchestrates; all work lives in the
// libraries (style.md item 1).

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

#include "emulator/ambiguity_tool.hpp"
#include "emulator/atten_tool.hpp"
#include "emulator/closed_loop.hpp"
#include "emulator/rcs_tool.hpp"
#include "emulator/scenario.hpp"
#include "emulator/scene_tool.hpp"
#include "emulator/sigma0_tool.hpp"
#include "emulator/tradeoff_tool.hpp"
#include "io/candump.hpp"
#include "radar/clutter/terrain.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "scene/targets.hpp"

namespace emu = radar_emu::emulator;

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

void print_summary(const emu::ClosedLoop& loop, const emu::RunResult& r, const std::string& out_dir,
                   const emu::OutputCounters& oc) {
  using radar_emu::timing::Stage;
  using radar_emu::timing::stage_name;
  const auto& s = loop.scenario();
  std::printf("radar-emu run: %s\n", s.name.c_str());
  std::printf("  frames      %llu at %.1f Hz (%llu with a valid ownship state), wall %.2f s\n",
              static_cast<unsigned long long>(r.frames), s.rate_hz,
              static_cast<unsigned long long>(r.frames_valid), r.wall_time_s);
  std::printf(
      "  detections  %.2f per frame (min %llu, max %llu), %llu in total\n",
      r.frames ? static_cast<double>(r.detections_total) / static_cast<double>(r.frames) : 0.0,
      static_cast<unsigned long long>(r.detections_min),
      static_cast<unsigned long long>(r.detections_max),
      static_cast<unsigned long long>(r.detections_total));
  {
    const auto& w = s.sensor.processing.waveform;
    const double cells = static_cast<double>(r.sensor.cells_touched);
    std::printf(
        "  sensor      %s %.4g GHz, %zu beams x %d range bins x %d pulses; CFAR %s Pfa %.0e: "
        "%.3g crossings a cell (%llu peaks merged across beams)\n",
        radar_emu::radar::waveform_name(w.kind), w.carrier_hz * 1e-9,
        s.sensor.antenna.beam_azimuth_rad.size(), w.range_bins, w.pulses,
        s.sensor.cfar.kind == radar_emu::radar::CfarKind::kCellAveraging ? "CA" : "OS",
        s.sensor.cfar.pfa, cells > 0.0 ? static_cast<double>(r.sensor.cfar_crossings) / cells : 0.0,
        static_cast<unsigned long long>(r.sensor.merged));
  }
  std::printf("  stage times [ms]      p50      p99      max\n");
  for (Stage st : {Stage::kInput, Stage::kSceneUpdate, Stage::kTrace, Stage::kSensor,
                   Stage::kOutput, Stage::kFrame}) {
    const auto& x = r.stages[static_cast<std::size_t>(st)];
    std::printf("    %-14s %8.3f %8.3f %8.3f\n", std::string(stage_name(st)).c_str(), x.p50_s * 1e3,
                x.p99_s * 1e3, x.max_s * 1e3);
  }
  std::printf(
      "  budget      %.1f ms: %llu frames over budget, %llu overruns, %llu missed periods\n",
      1e3 / s.rate_hz, static_cast<unsigned long long>(r.frames_over_budget),
      static_cast<unsigned long long>(r.overruns),
      static_cast<unsigned long long>(r.missed_periods));
  std::printf(
      "  bus         %llu frames in (%llu rejected), %llu frames out, %llu lists at the "
      "avionics\n",
      static_cast<unsigned long long>(r.bus_frames_in),
      static_cast<unsigned long long>(r.decoder.rejected()),
      static_cast<unsigned long long>(r.bus_frames_out),
      static_cast<unsigned long long>(r.sink_lists));
  if (r.frames_valid < r.frames) {
    std::printf("  validity    %llu frames with a stale ownship state (older than %.3g s): %s\n",
                static_cast<unsigned long long>(r.frames - r.frames_valid), s.state_timeout_s,
                s.stale_output_silent ? "no list sent" : "empty lists flagged OWNSHIP_INVALID");
  }
  if (r.replay_frames_fed > 0 || r.replay_frames_left > 0) {
    std::printf("  replay      %llu log frames fed, %llu after the last frame\n",
                static_cast<unsigned long long>(r.replay_frames_fed),
                static_cast<unsigned long long>(r.replay_frames_left));
  }
  for (const auto& w : r.realtime.warnings)
    std::printf("  warning     %s\n", w.c_str());
  if (r.interrupted) {
    std::printf("  interrupted by %s after %llu of %llu frames\n",
                r.stop_signal == SIGINT    ? "SIGINT"
                : r.stop_signal == SIGTERM ? "SIGTERM"
                                           : "a stop",
                static_cast<unsigned long long>(r.frames),
                static_cast<unsigned long long>(r.frames_planned));
  }
  if (!out_dir.empty()) {
    std::printf(
        "  outputs     %s/{report.json,detections.json,truth.json,frames.csv,detections.png,"
        "timing.png,bus_in.log,bus_out.log}\n",
        out_dir.c_str());
    std::uint64_t write_errors = 0;
    for (const auto& f : oc.files)
      write_errors += f.write_errors;
    std::printf(
        "              %s: %llu frames and %llu bus frames written, %llu and %llu dropped, %llu "
        "write errors\n",
        oc.complete() ? "complete" : "INCOMPLETE",
        static_cast<unsigned long long>(oc.frames_written),
        static_cast<unsigned long long>(oc.bus_frames_written),
        static_cast<unsigned long long>(oc.frames_dropped),
        static_cast<unsigned long long>(oc.bus_frames_dropped),
        static_cast<unsigned long long>(write_errors));
  }
}

emu::Scenario load_scenario_or_default(const std::string& scenario_file) {
  return scenario_file.empty()
             ? emu::parse_scenario(emu::default_scenario_toml(), "<default scenario>")
             : emu::load_scenario(scenario_file);
}

// Runs the loop, writes the outputs and prints the summary (run and replay). With a Modbus
// server, the final detection table stays served for `linger_s` seconds after the run. The
// outputs stream into `out` during the run; SIGINT or SIGTERM ends the run at a frame boundary
// with every output written, report.json marked "interrupted", and exit status 128 + signal.
int execute_loop(const emu::Scenario& scenario, emu::RunOptions options, const std::string& out,
                 bool quiet, double linger_s = 0.0) {
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
  emu::ClosedLoop loop(scenario, options);
  for (const auto& w : loop.setup_warnings())
    std::fprintf(stderr, "radar-emu: warning: %s\n", w.c_str());
  const std::string modbus = loop.modbus_server_address();
  if (!modbus.empty()) {
    // The readiness line scripts wait for (a client may connect from now on).
    std::fprintf(stderr, "radar-emu: modbus server listening on %s\n", modbus.c_str());
    std::fflush(stderr);
  }
  const emu::RunResult result = loop.run();
  if (show_progress && result.interrupted)
    std::fputc('\n', stderr);
  if (!out.empty())
    loop.write_outputs(result);
  loop.write_trace_events();
  const emu::OutputCounters oc = loop.output_counters();
  if (!quiet)
    print_summary(loop, result, out, oc);
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
};

int run_command(const std::string& scenario_file, std::uint64_t frames, const std::string& out,
                bool realtime, bool print_scenario, bool quiet, int rt_priority, bool lock_memory,
                int cpu, const BusArgs& bus) {
  if (print_scenario) {
    std::cout << emu::default_scenario_toml();
    return 0;
  }
  emu::Scenario scenario = load_scenario_or_default(scenario_file);
  if (frames > 0)
    scenario.frames = frames;
  emu::RunOptions options;
  options.realtime = realtime;
  options.rt.fifo_priority = rt_priority;
  options.rt.lock_memory = lock_memory;
  options.rt.cpu = cpu;
  options.can = bus.can;
  options.nav_modbus = bus.nav_modbus;
  options.modbus_server = bus.modbus_server;
  options.trace_events_file = bus.trace_events;
  return execute_loop(scenario, std::move(options), out, quiet, bus.modbus_linger_s);
}

// Replays a recorded input log (a run's bus_in.log, or any candump log of CANaerospace input)
// through the loop on the simulated clock: deterministic, whatever the machine's load.
int replay_command(const std::string& log_file, const std::string& scenario_file,
                   std::uint64_t frames, const std::string& out, bool quiet) {
  emu::Scenario scenario = load_scenario_or_default(scenario_file);
  emu::RunOptions options;
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
    if (!quiet) {
      std::fprintf(stderr,
                   "radar-emu replay: log starts at %.6f s, not within a day of the "
                   "scenario's epoch: epoch set to %lld s\n",
                   static_cast<double>(first_ns) * 1e-9,
                   static_cast<long long>(scenario.epoch_unix_ns / 1'000'000'000LL));
    }
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

int target_command(const std::string& kind_name, radar_emu::scene::TargetSpec spec,
                   const std::string& out) {
  namespace sc = radar_emu::scene;
  const auto kind = sc::target_kind_from_name(kind_name);
  if (!kind) {
    throw std::runtime_error("unknown target '" + kind_name + "' (known: " + sc::target_names() +
                             ")");
  }
  spec.kind = *kind;
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
  CLI::App app{"radar-emu: hardware-in-the-loop radar emulator (SBR physics on Embree)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "radar-emu 0.1.0");

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
                  "Directory for report.json, detections.json, truth.json, the pictures and the "
                  "bus logs")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  run->add_flag("--realtime", realtime,
                "Pace frames on the monotonic wall clock (default: as fast as possible on "
                "simulated time)");
  run->add_option("--rt-priority", rt_priority, "SCHED_FIFO priority with --realtime (1-99)")
      ->check(CLI::Range(0, 99));
  run->add_flag("--lock-memory", lock_memory, "mlockall() with --realtime");
  run->add_option("--cpu", cpu, "Pin the frame loop to this CPU with --realtime");
  run->add_flag("--print-scenario", print_scenario, "Print the embedded default scenario and exit");
  run->add_flag("-q,--quiet", quiet, "No progress or summary");
  BusArgs bus_args;
  run->add_option("--can", bus_args.can,
                  "CAN backend: sim (software loopback, default), socketcan:IFACE[,fd]"
                  "[,bitrate=N][,dbitrate=N], gsusb[:SERIAL][,fd][,bitrate=N][,dbitrate=N] "
                  "(real buses need --realtime; ,fd sends the detection lists as CAN FD)");
  run->add_option("--nav-modbus", bus_args.nav_modbus,
                  "Ownship state from a Modbus navigation register map (docs/icd/modbus.md) "
                  "instead of CANaerospace: tcp:HOST:PORT, rtu:DEV:BAUD (with --realtime), or "
                  "sim (played from the scenario on the loopback register bank)");
  run->add_option("--modbus-server", bus_args.modbus_server,
                  "Serve the detection table as Modbus holding registers on HOST:PORT (:PORT "
                  "binds 127.0.0.1; port 0 picks a free one, printed on stderr)");
  run->add_option("--modbus-linger-s", bus_args.modbus_linger_s,
                  "Keep serving the final detection table this long after the run [s]")
      ->check(CLI::Range(0.0, 86400.0));
  run->add_option("--trace-events", bus_args.trace_events,
                  "Write every stage of every frame as Chrome trace-event JSON to FILE (open in "
                  "https://ui.perfetto.dev or chrome://tracing)");

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
  replay->add_option("--out", replay_out, "Output directory (default out/replay)");
  replay->add_flag("-q,--quiet", replay_quiet, "No progress or summary");

  CLI::App* scene_cmd = app.add_subcommand("scene", "Scene databases and canonical targets");
  scene_cmd->require_subcommand(1);
  CLI::App* target = scene_cmd->add_subcommand(
      "target", "Write a canonical target mesh (conventions in scene/targets.hpp)");
  std::string target_kind, target_out;
  radar_emu::scene::TargetSpec spec;
  target->add_option("kind", target_kind, radar_emu::scene::target_names())->required();
  target->add_option("--a-m", spec.a_m,
                     "First dimension [m]: plate/box x, fold length, trihedral edge, radius");
  target->add_option("--b-m", spec.b_m, "Second dimension [m]: plate/box y, face width, length");
  target->add_option("--c-m", spec.c_m, "Third dimension [m]: box z");
  target->add_option("--facet-m", spec.facet_m,
                     "Largest facet edge [m] (0: coarsest exact mesh, 32 segments for curves)");
  target->add_option("--out", target_out, "Output file: .glb, .gltf, .obj or .stl")->required();
  emu::SceneCommands scene_tools;  // scene gen | info | preview (emulator/scene_tool.hpp)
  emu::add_scene_commands(*scene_cmd, scene_tools);

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
                    "File units to metres (0.001 for mm, 0.0254 for inches; default 1)");
    cmd->add_option("--freq-hz", t.freq, "One frequency [Hz]");
    cmd->add_option("--freq-sweep-hz", t.freq_sweep, "Frequencies START:STOP:N [Hz]");
    cmd->add_option("--theta-deg", t.theta,
                    "Radar direction from +z: A or A:B:N [deg] (default 0)");
    cmd->add_option("--phi-deg", t.phi, "Radar direction from +x toward +y: A or A:B:N [deg]");
    cmd->add_option("--bounces", bounces,
                    "Bounces: 1 = facet PO only, up to " +
                        std::to_string(radar_emu::radar::kMaxRcsBounces) +
                        " (default 3; the summary counts the ray tubes still bouncing at the cap)")
        ->check(CLI::Range(1, radar_emu::radar::kMaxRcsBounces));
    cmd->add_option("--rays-per-wavelength", rpw,
                    "Ray-tube density for bounces >= 2 at the highest frequency (default 4)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--material", materials,
                    "Non-metal material: NAME=EPS_REAL,EPS_LOSS (dielectric, eps = EPS_REAL - j "
                    "EPS_LOSS) or NAME=EPS_REAL,EPS_LOSS,THICKNESS_M (coating on metal); "
                    "repeatable");
    cmd->add_flag("-q,--quiet", quiet_flag, "No progress or summary");
  };
  auto frequencies = [](const SweepText& t) {
    if (t.freq.empty() == t.freq_sweep.empty())
      throw std::invalid_argument("give exactly one of --freq-hz and --freq-sweep-hz");
    return t.freq.empty() ? emu::parse_sweep(t.freq_sweep, "--freq-sweep-hz")
                          : emu::parse_sweep(t.freq, "--freq-hz");
  };

  CLI::App* rcs = app.add_subcommand(
      "rcs", "Radar cross section of a mesh vs angle and frequency, polarimetric (PO + SBR)");
  SweepText rcs_text;
  rcs_text.pol = "HH,VV";
  emu::RcsToolOptions rcs_opt;
  double bistatic_theta = 0.0, bistatic_phi = 0.0;
  add_common(rcs, rcs_text, rcs_opt.mesh, rcs_opt.scale, rcs_opt.materials, rcs_opt.bounces,
             rcs_opt.rays_per_wavelength, rcs_opt.quiet);
  rcs->add_option("--edge-turn-deg", rcs_opt.edge_turn_deg,
                  "A shared mesh edge diffracts when its faces turn by more than this (default "
                  "30 deg; open-sheet boundaries always do)");
  rcs->add_flag("--no-edges{false}", rcs_opt.edges,
                "No edge diffraction (default: fringe equivalent edge currents of the mesh's "
                "wedge edges and sheet boundaries added to PO)");
  rcs->add_option("--pol", rcs_text.pol,
                  "Polarisations, receive letter first: HH,HV,VH,VV (default HH,VV)");
  CLI::Option* bt = rcs->add_option("--bistatic-theta-deg", bistatic_theta,
                                    "Receiver direction theta [deg] (bistatic)");
  CLI::Option* bp =
      rcs->add_option("--bistatic-phi-deg", bistatic_phi, "Receiver direction phi [deg]");
  bt->needs(bp);
  bp->needs(bt);
  rcs->add_option("--out", rcs_opt.out_csv, "CSV output (default rcs.csv)");
  rcs->add_option("--plot", rcs_opt.plot_png, "PNG plot of the sweep");
  rcs->add_option("--overlay", rcs_opt.overlays,
                  "Another curve on the plot, FILE=LABEL: lines of numbers whose last two are the "
                  "swept value and dBsm (a reference table, another run); repeatable");
  rcs->add_option("--window-deg", rcs_opt.window_deg,
                  "Fluctuation statistics (mean, median, p10/p90, spread) over a sliding aspect "
                  "window of this width [deg]")
      ->check(CLI::PositiveNumber);
  rcs->add_option("--stats-out", rcs_opt.stats_csv, "CSV for --window-deg (default *_stats.csv)");

  CLI::App* profile = app.add_subcommand(
      "profile", "Range profile (and ISAR image over an angle sweep) of a mesh (PO + SBR)");
  SweepText prof_text;
  prof_text.pol = "VV";
  emu::ProfileToolOptions prof_opt;
  add_common(profile, prof_text, prof_opt.mesh, prof_opt.scale, prof_opt.materials,
             prof_opt.bounces, prof_opt.rays_per_wavelength, prof_opt.quiet);
  profile->add_option("--edge-turn-deg", prof_opt.edge_turn_deg,
                      "A shared mesh edge diffracts when its faces turn by more than this (default "
                      "30 deg; open-sheet boundaries always do)");
  profile->add_flag("--no-edges{false}", prof_opt.edges,
                    "No edge diffraction (default: fringe equivalent edge currents added to PO)");
  profile->add_option("--pol", prof_text.pol, "One polarisation: HH, HV, VH or VV (default VV)");
  profile->add_option("--window", prof_opt.window,
                      "none, hann, hamming, blackman or taylor (default hann)");
  profile->add_option("--oversample", prof_opt.oversample, "Zero-padding factor (default 4)");
  profile->add_option("--dynamic-range-db", prof_opt.dynamic_range_db, "Plot range (default 50)")
      ->check(CLI::PositiveNumber);
  profile->add_option("--out", prof_opt.out_csv, "Range-profile CSV (default profile.csv)");
  profile->add_option("--plot", prof_opt.plot_png, "Range-profile PNG");
  profile->add_option("--isar-out", prof_opt.isar_csv, "ISAR CSV (default *_isar.csv)");
  profile->add_option("--isar-plot", prof_opt.isar_png, "ISAR PNG (default *_isar.png)");

  CLI::App* ambiguity = app.add_subcommand(
      "ambiguity",
      "Ambiguity function of the configured waveform (heat map, cuts, measured figures)");
  emu::AmbiguityToolOptions amb_opt;
  ambiguity->add_option("scenario", amb_opt.scenario,
                        "Scenario TOML whose [radar] waveform to use (default: the embedded one)");
  ambiguity->add_option("--bandwidth-hz", amb_opt.bandwidth_hz, "Override the swept bandwidth");
  ambiguity->add_option("--pulse-width-s", amb_opt.pulse_width_s, "Override the pulse length");
  ambiguity->add_option("--prf-hz", amb_opt.prf_hz, "Override the PRF (with --train)");
  ambiguity->add_option("--pulses", amb_opt.pulses, "Override the pulses a CPI (with --train)");
  ambiguity->add_flag("--train", amb_opt.train,
                      "The coherent pulse train (closed form) over +-2 PRI instead of one pulse");
  ambiguity->add_option("--delay-span", amb_opt.delay_span, "+- delay in pulse widths (default 1)");
  ambiguity->add_option("--doppler-span", amb_opt.doppler_span,
                        "+- Doppler in 1/T (single pulse) or PRFs (train) (default 8)");
  ambiguity->add_option("--points", amb_opt.points, "Grid points an axis (default 201)");
  ambiguity->add_option("--oversample", amb_opt.oversample, "Samples per 1/B (default 8)");
  ambiguity->add_option("--dynamic-range-db", amb_opt.dynamic_range_db, "Plot range (default 40)");
  ambiguity->add_option("--out", amb_opt.out_dir, "Output directory (default ./ambiguity)");
  ambiguity->add_flag("-q,--quiet", amb_opt.quiet, "No summary");

  CLI::App* atten = app.add_subcommand(
      "atten",
      "Specific attenuation of gases, rain, fog and woodland vs frequency (ITU-R "
      "P.676/838/840/833)");
  emu::AttenToolOptions atten_opt;
  std::string atten_freq;
  atten->add_option("--freq-hz", atten_freq, "Frequency [Hz]: F or START:STOP:N")->required();
  atten->add_option("--pressure-hpa", atten_opt.dry_pressure_hpa,
                    "Dry-air pressure [hPa] (default 1013.25)");
  atten->add_option("--temp-c", atten_opt.temperature_c, "Temperature [C] (default 15)");
  atten->add_option("--rho-gm3", atten_opt.water_vapour_gm3,
                    "Water-vapour density [g/m^3] (default 7.5)");
  atten->add_option("--rain-mmh", atten_opt.rain_mm_per_h, "Rain rate [mm/h] (default 0)");
  atten->add_option("--fog-gm3", atten_opt.fog_gm3,
                    "Fog or cloud liquid water [g/m^3] (default 0)");
  atten->add_option("--veg-depth-m", atten_opt.veg_depth_m,
                    "Woodland crossed [m] (ITU-R P.833 sec. 2, 1-30 GHz; default 0)");
  atten->add_flag("--out-of-leaf", atten_opt.out_of_leaf, "Woodland without leaves (P.833)");
  atten->add_option("--out", atten_opt.out_csv, "CSV output (default atten.csv)");
  atten->add_option("--plot", atten_opt.plot_png, "PNG chart");
  atten->add_flag("-q,--quiet", atten_opt.quiet, "No summary");

  CLI::App* sigma0 = app.add_subcommand(
      "sigma0", "Terrain scattering coefficient vs angle (empirical, IEM, SPM, KA, RT, total)");
  emu::Sigma0ToolOptions s0_opt;
  std::string s0_theta = "0:85:86", s0_theta_s, s0_eps;
  sigma0->add_option("--material", s0_opt.material,
                     "Catalogue material: " + radar_emu::radar::clutter::terrain_material_names());
  sigma0->add_option("--eps-r", s0_eps, "Custom surface permittivity RE,IM (eps = RE - j IM)");
  sigma0->add_option("--rms-height-m", s0_opt.rms_height_m, "Custom surface rms height s [m]");
  sigma0->add_option("--corr-length-m", s0_opt.corr_length_m, "Custom correlation length l [m]");
  sigma0->add_option("--corr", s0_opt.correlation,
                     "Correlation function: gaussian, exponential (default), xpower");
  sigma0->add_option("--x-power", s0_opt.x_power, "Exponent of the x-power function (default 1.5)");
  sigma0->add_option("--freq-hz", s0_opt.freq_hz, "Frequency [Hz]")->required();
  sigma0->add_option("--model", s0_opt.model,
                     "empirical, iem, spm, ka, rt or total (surface + volume; default)");
  sigma0->add_option("--theta-deg", s0_theta, "Incidence angles A:B:N [deg] (default 0:85:86)");
  sigma0->add_option("--theta-s-deg", s0_theta_s, "Bistatic scattering angles A:B:N [deg]");
  sigma0->add_option("--phi-s-deg", s0_opt.phi_s_deg,
                     "Bistatic azimuth from the plane of incidence [deg] (0: forward, 180: back)");
  sigma0->add_option("--pol", s0_opt.pols, "Polarisations, of HH,VV,HV,VH (default all four)");
  sigma0->add_option("--out", s0_opt.out_csv, "CSV output (default sigma0.csv)");
  sigma0->add_option("--plot", s0_opt.plot_png, "PNG chart");
  sigma0->add_flag("-q,--quiet", s0_opt.quiet, "No summary");

  CLI::App* tradeoff = app.add_subcommand(
      "tradeoff",
      "Cost (wall ms, rays) against error for each fidelity knob, and where methods fail");
  emu::TradeoffOptions to_opt;
  std::string to_cases;
  tradeoff->add_option("--out", to_opt.out_dir,
                       "Output directory: tradeoff.csv, tradeoff.png and one PNG per case "
                       "(default tradeoff)");
  tradeoff->add_option("--cases", to_cases,
                       "Comma-separated cases of vehicle,profile,frame,sphere,grazing,iem "
                       "(default all)");
  tradeoff->add_flag("--quick", to_opt.quick,
                     "Coarse grids: the whole run in well under a minute (the CI test)");
  tradeoff->add_flag("-q,--quiet", to_opt.quiet, "No progress and no summary");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (run->parsed()) {
      return run_command(scenario_file, frames, out, realtime, print_scenario, quiet, rt_priority,
                         lock_memory, cpu, bus_args);
    }
    if (replay->parsed())
      return replay_command(replay_log, replay_scenario, replay_frames, replay_out, replay_quiet);
    if (target->parsed())
      return target_command(target_kind, spec, target_out);
    if (const auto scene_status = emu::run_scene_command(scene_tools))
      return *scene_status;
    if (rcs->parsed()) {
      rcs_opt.freqs_hz = frequencies(rcs_text);
      rcs_opt.theta_deg = emu::parse_sweep(rcs_text.theta, "--theta-deg");
      rcs_opt.phi_deg = emu::parse_sweep(rcs_text.phi, "--phi-deg");
      rcs_opt.pols = emu::parse_pols(rcs_text.pol);
      if (bt->count() > 0) {
        rcs_opt.bistatic_theta_deg = bistatic_theta;
        rcs_opt.bistatic_phi_deg = bistatic_phi;
      }
      return emu::run_rcs_tool(rcs_opt);
    }
    if (sigma0->parsed()) {
      s0_opt.theta_deg = emu::parse_sweep(s0_theta, "--theta-deg");
      if (!s0_theta_s.empty())
        s0_opt.theta_s_deg = emu::parse_sweep(s0_theta_s, "--theta-s-deg");
      if (!s0_eps.empty()) {
        const auto parts = emu::parse_pair(s0_eps, "--eps-r");
        s0_opt.eps_real = parts.first;
        s0_opt.eps_loss = parts.second;
      }
      return emu::run_sigma0_tool(s0_opt);
    }
    if (tradeoff->parsed()) {
      if (!to_cases.empty())
        to_opt.cases = emu::parse_tradeoff_cases(to_cases);
      return emu::run_tradeoff_tool(to_opt);
    }
    if (ambiguity->parsed())
      return emu::run_ambiguity_tool(amb_opt);
    if (atten->parsed()) {
      atten_opt.freqs_hz = emu::parse_sweep(atten_freq, "--freq-hz");
      return emu::run_atten_tool(atten_opt);
    }
    if (profile->parsed()) {
      prof_opt.freqs_hz = frequencies(prof_text);
      prof_opt.theta_deg = emu::parse_sweep(prof_text.theta, "--theta-deg");
      prof_opt.phi_deg = emu::parse_sweep(prof_text.phi, "--phi-deg");
      const auto pols = emu::parse_pols(prof_text.pol);
      if (pols.size() != 1)
        throw std::invalid_argument("--pol: a profile takes one polarisation");
      prof_opt.pol = pols[0];
      return emu::run_profile_tool(prof_opt);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "radar-emu: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
