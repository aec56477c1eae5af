#include "tools/mpi_work.hpp"

#include <sched.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#ifdef RADAR_EMU_HAVE_MPI
// The C API only: without these, mpi.h in C++ pulls in the removed C++ bindings (libmpi_cxx).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace radar_emu::tools::mpi_work {

namespace {

// A non-negative integer from the environment, or `fallback` when unset or not one.
int env_int(const char* name, int fallback) noexcept {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0')
    return fallback;
  char* end = nullptr;
  const long x = std::strtol(v, &end, 10);
  if (*end != '\0' || x < 0 || x > INT_MAX)
    return fallback;
  return static_cast<int>(x);
}

// Open MPI's mpirun sets OMPI_COMM_WORLD_*; Slurm's srun and MPICH's hydra set PMI_*.
int env_size() noexcept {
  const int s = env_int("OMPI_COMM_WORLD_SIZE", -1);
  return std::max(1, s >= 1 ? s : env_int("PMI_SIZE", 1));
}
int env_rank() noexcept {
  const int r = env_int("OMPI_COMM_WORLD_RANK", -1);
  return r >= 0 ? r : env_int("PMI_RANK", 0);
}
int env_local_size() noexcept {
  const int s = env_int("OMPI_COMM_WORLD_LOCAL_SIZE", -1);
  return std::max(1, s >= 1 ? s : env_int("MPI_LOCALNRANKS", 1));
}

struct State {
  bool started = false;
  int rank = 0, size = 1, threads = 0;
  std::unique_ptr<tbb::global_control> threads_control;
};
State& state() {
  static State s;
  return s;
}

// See threads_per_rank(): the cores this rank may run on when the launcher bound it, else its
// share of the node.
[[maybe_unused]] int pick_threads() noexcept {
  const int online = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  cpu_set_t set;
  CPU_ZERO(&set);
  const int allowed = sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : online;
  if (allowed >= 1 && allowed < online)
    return allowed;
  return std::max(1, online / env_local_size());
}

}  // namespace

bool available() noexcept {
#ifdef RADAR_EMU_HAVE_MPI
  return true;
#else
  return false;
#endif
}

int launched_size() noexcept {
  return env_size();
}

void start() {
  State& st = state();
  if (st.started)
    return;
  const int launched = launched_size();
  if (launched <= 1)
    return;
#ifndef RADAR_EMU_HAVE_MPI
  throw std::runtime_error(
      "launched by mpirun as one of " + std::to_string(launched) +
      " ranks, but this radar-emu was built without MPI (CMake RADAR_EMU_MPI; Debian "
      "libopenmpi-dev, scripts/install-deps.sh): run it without mpirun");
#else
  // Only the main thread calls MPI; TBB's workers never do.
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  st.started = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &st.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &st.size);
  if (st.size != launched) {
    throw std::runtime_error("MPI reports " + std::to_string(st.size) +
                             " ranks, the launcher's environment " + std::to_string(launched) +
                             ": is radar-emu run by the mpirun of the MPI it was built with?");
  }
  st.threads = pick_threads();
  st.threads_control = std::make_unique<tbb::global_control>(
      tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(st.threads));
#endif
}

bool started() noexcept {
  return state().started;
}

int rank() noexcept {
  const State& st = state();
  return st.started ? st.rank : 0;
}

int launched_rank() noexcept {
  return env_size() > 1 ? env_rank() : 0;
}

bool is_root() noexcept {
  const State& st = state();
  return st.started ? st.rank == 0 : launched_rank() == 0;
}

int size() noexcept {
  const State& st = state();
  return st.started ? st.size : 1;
}

int threads_per_rank() noexcept {
  return state().threads;
}

void finalize() noexcept {
  State& st = state();
  if (!st.started)
    return;
  st.threads_control.reset();
#ifdef RADAR_EMU_HAVE_MPI
  int done = 0;
  MPI_Finalized(&done);
  if (done == 0)
    MPI_Finalize();
#endif
  st.started = false;
  st.rank = 0;
  st.size = 1;
  st.threads = 0;
}

void abort_job(int status) noexcept {
  const State& st = state();
  if (!st.started || st.size == 1)
    return;
#ifdef RADAR_EMU_HAVE_MPI
  MPI_Abort(MPI_COMM_WORLD, status);
#else
  (void)status;
#endif
}

Block block_of(std::size_t n, int rank, int ranks) noexcept {
  if (ranks < 1 || rank < 0 || rank >= ranks)
    return {};
  const auto r = static_cast<std::size_t>(rank), p = static_cast<std::size_t>(ranks);
  const std::size_t base = n / p, extra = n % p;
  const std::size_t begin = r * base + std::min(r, extra);
  return {begin, begin + base + (r < extra ? 1 : 0)};
}

void gather_bytes(void* records, std::size_t n_items, std::size_t record_bytes) {
  const State& st = state();
  if (!st.started || st.size == 1 || record_bytes == 0)
    return;
  if (n_items > static_cast<std::size_t>(INT_MAX) ||
      record_bytes > static_cast<std::size_t>(INT_MAX)) {
    throw std::invalid_argument("gather_blocks: " + std::to_string(n_items) + " items of " +
                                std::to_string(record_bytes) +
                                " bytes: past MPI's int counts (2^31 - 1)");
  }
#ifdef RADAR_EMU_HAVE_MPI
  // One MPI datatype per record: counts and displacements are in items, not bytes.
  MPI_Datatype record;
  MPI_Type_contiguous(static_cast<int>(record_bytes), MPI_BYTE, &record);
  MPI_Type_commit(&record);
  std::vector<int> counts(static_cast<std::size_t>(st.size)), displs(counts.size());
  for (int r = 0; r < st.size; ++r) {
    const Block b = block_of(n_items, r, st.size);
    counts[static_cast<std::size_t>(r)] = static_cast<int>(b.size());
    displs[static_cast<std::size_t>(r)] = static_cast<int>(b.begin);
  }
  auto* base = static_cast<unsigned char*>(records);
  if (st.rank == 0) {
    MPI_Gatherv(MPI_IN_PLACE, 0, record, base, counts.data(), displs.data(), record, 0,
                MPI_COMM_WORLD);
  } else {
    const Block mine = block_of(n_items, st.rank, st.size);
    MPI_Gatherv(base + mine.begin * record_bytes, static_cast<int>(mine.size()), record, nullptr,
                nullptr, nullptr, record, 0, MPI_COMM_WORLD);
  }
  MPI_Type_free(&record);
#else
  (void)records;
#endif
}

}  // namespace radar_emu::tools::mpi_work
