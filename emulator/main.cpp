// radar-emu: command-line entry point. Parses options and orchestrates; all work lives in the
// libraries (style.md item 1).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>

#include "emulator/closed_loop.hpp"
#include "emulator/scenario.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "scene/targets.hpp"

namespace emu = radar_emu::emulator;

namespace {

void print_summary(const emu::ClosedLoop& loop, const emu::RunResult& r,
                   const std::string& out_dir) {
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
  for (const auto& w : r.realtime.warnings)
    std::printf("  warning     %s\n", w.c_str());
  if (!out_dir.empty())
    std::printf(
        "  outputs     %s/{report.json,detections.json,detections.png,bus_in.log,bus_out.log}\n",
        out_dir.c_str());
}

int run_command(const std::string& scenario_file, std::uint64_t frames, const std::string& out,
                bool realtime, bool print_scenario, bool quiet, int rt_priority, bool lock_memory,
                int cpu) {
  if (print_scenario) {
    std::cout << emu::default_scenario_toml();
    return 0;
  }
  emu::Scenario scenario = scenario_file.empty() ? emu::parse_scenario(emu::default_scenario_toml(),
                                                                       "<default scenario>")
                                                 : emu::load_scenario(scenario_file);
  if (frames > 0)
    scenario.frames = frames;
  emu::RunOptions options;
  options.realtime = realtime;
  options.rt.fifo_priority = rt_priority;
  options.rt.lock_memory = lock_memory;
  options.rt.cpu = cpu;
  const bool show_progress = !quiet && scenario.frames >= 100;
  if (show_progress) {
    options.progress = [](std::uint64_t done, std::uint64_t total) {
      if (done == total || done % (total / 10 == 0 ? 1 : total / 10) == 0) {
        std::fprintf(stderr, "\r  frame %llu/%llu", static_cast<unsigned long long>(done),
                     static_cast<unsigned long long>(total));
        if (done == total)
          std::fputc('\n', stderr);
      }
    };
  }
  emu::ClosedLoop loop(scenario, options);
  const emu::RunResult result = loop.run();
  if (!out.empty())
    loop.write_outputs(result, out);
  if (!quiet)
    print_summary(loop, result, out);
  return 0;
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
  run->add_option("--out", out, "Directory for report.json, detections.json and the bus logs")
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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (run->parsed()) {
      return run_command(scenario_file, frames, out, realtime, print_scenario, quiet, rt_priority,
                         lock_memory, cpu);
    }
    if (target->parsed())
      return target_command(target_kind, spec, target_out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "radar-emu: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
