#pragma once
// radar-emu's subcommands (pbrt's cmd/ over its library): each cmd_<name>.cpp registers its
// option table on the application and, for when it was parsed, the work to do (cross-checks,
// then the tool or the loop, then printing). main.cpp parses, runs the parsed command and prints
// its error as the one line "radar-emu: error: ...".

#include <CLI/CLI.hpp>
#include <atomic>
#include <functional>
#include <vector>

namespace radar_emu::app {

/// One leaf subcommand: its CLI11 node and its work.
struct Command {
  CLI::App* cli = nullptr;
  /// Runs when `cli` was parsed: returns the exit status; throws std::exception with a one-line
  /// message naming the option or file.
  std::function<int()> run;
  /// Splits its work over MPI ranks (rcs, profile, sar): the others refuse mpirun.
  bool mpi_split = false;
};
using Commands = std::vector<Command>;

/// The registrations, in the order `radar-emu --help` lists the subcommands.
void add_run_command(CLI::App& app, Commands& commands);
void add_replay_command(CLI::App& app, Commands& commands);
void add_scene_commands(CLI::App& app, Commands& commands);  // scene target|gen|info|preview
void add_scene_target_command(CLI::App& scene, Commands& commands);
void add_image_command(CLI::App& app, Commands& commands);
void add_rcs_command(CLI::App& app, Commands& commands);
void add_profile_command(CLI::App& app, Commands& commands);
void add_ambiguity_command(CLI::App& app, Commands& commands);
void add_atten_command(CLI::App& app, Commands& commands);
void add_sigma0_command(CLI::App& app, Commands& commands);
void add_tradeoff_command(CLI::App& app, Commands& commands);
void add_sar_command(CLI::App& app, Commands& commands);

/// What a stop request ends: the closed loop (at the next frame boundary) or an offline tool
/// (after its current work item); only the handler's acknowledgement on stderr differs.
enum class StopScope { kLoop, kOfflineTool };
/// SIGINT / SIGTERM (main.cpp): the first sets stop_signal(), which the loop or the tool polls
/// between frames or work items, then writes what is done; a second exits at once (status 128 +
/// signal).
void install_stop_handlers(StopScope scope = StopScope::kLoop);
/// 0, or the first stop signal received since install_stop_handlers().
std::atomic<int>& stop_signal();

}  // namespace radar_emu::app
