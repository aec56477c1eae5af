// radar-emu: command-line entry point. Registers the subcommands (app/cmd_<name>.cpp), parses,
// runs the parsed one and prints its error; all work lives in the libraries (style.md item 1).

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

#include "app/cmd.hpp"
#include "tools/mpi_work.hpp"

namespace tools = radar_emu::tools;

namespace radar_emu::app {
namespace {

std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");
std::atomic<bool> g_offline{false};  // which acknowledgement the handler writes

extern "C" void on_stop_signal(int sig) {
  if (g_stop_signal.exchange(sig) != 0)
    _exit(128 + sig);
  static constexpr char kRun[] =
      "\nradar-emu: stopping at the next frame boundary and writing the outputs (again: exit "
      "at once)\n";
  static constexpr char kOffline[] =
      "\nradar-emu: stopping after the current work item and writing what is done (again: exit "
      "at once)\n";
  if (g_offline.load(std::memory_order_relaxed))
    (void)!write(STDERR_FILENO, kOffline, sizeof kOffline - 1);
  else
    (void)!write(STDERR_FILENO, kRun, sizeof kRun - 1);
}

}  // namespace

void install_stop_handlers(StopScope scope) {
  g_offline.store(scope == StopScope::kOfflineTool, std::memory_order_relaxed);
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // other threads' blocking calls carry on
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

std::atomic<int>& stop_signal() {
  return g_stop_signal;
}

}  // namespace radar_emu::app

int main(int argc, char** argv) {
  namespace app = radar_emu::app;
  // Under mpirun, rcs, profile and sar split their work over the ranks (docs/cluster.md).
  const tools::mpi_work::Scope mpi_scope;
  CLI::App cli{"radar-emu: hardware-in-the-loop radar emulator (SBR physics on Embree)"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", "radar-emu 0.1.0");
  // Every error is one line on stderr (style.md): the option and what is wrong with it.
  cli.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "radar-emu: error: " + std::string(e.what()) + " (--help lists the options)\n";
  });
  app::Commands commands;
  for (auto* add : {app::add_run_command, app::add_replay_command, app::add_scene_commands,
                    app::add_image_command, app::add_rcs_command, app::add_profile_command,
                    app::add_ambiguity_command, app::add_atten_command, app::add_sigma0_command,
                    app::add_tradeoff_command, app::add_sar_command})
    add(cli, commands);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e);
  }
  try {
    const app::Command* parsed = nullptr;
    for (const app::Command& c : commands)
      if (c.cli->parsed())
        parsed = &c;
    // Only the sweeps are split: N copies of another command would write the same files.
    if (tools::mpi_work::launched_size() > 1 && (parsed == nullptr || !parsed->mpi_split)) {
      throw std::invalid_argument(
          "launched by mpirun as " + std::to_string(tools::mpi_work::launched_size()) +
          " ranks: only rcs, profile and sar split their work over MPI ranks; run this command "
          "without mpirun");
    }
    return parsed != nullptr ? parsed->run() : 0;
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
}
