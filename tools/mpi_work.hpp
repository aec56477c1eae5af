#pragma once
// Scale-out of the offline sweeps over MPI ranks (docs/cluster.md): `mpirun -np N radar-emu rcs
// ...` splits the work items (directions, angles, pulses) into N contiguous blocks, every rank
// computes its block exactly as a single process would, and rank 0 gathers the records in item
// order and alone writes files, prints and plots. The output is bit-identical to one process.
//
// A build without MPI (RADAR_EMU_MPI=OFF, or AUTO without Open MPI) compiles the same calls to
// the single-process case: rank 0 of 1, one block holding every item, gathers that do nothing.
// A process not launched by mpirun (or launched with -np 1) never initialises MPI, so a plain
// `radar-emu rcs` and the Python module are unaffected.
//
// Use, in a tool (see sweep_rcs in rcs_tool.cpp):
//   mpi_work::start();                                  // in the tool, after its checks
//   const mpi_work::Block b = mpi_work::my_block(n);    // items [b.begin, b.end)
//   for (std::size_t i = b.begin; i < b.end; ++i) compute item i into records[i * per_item...];
//   mpi_work::gather_blocks(std::span(records), per_item);  // rank 0 now has all n
//   if (mpi_work::is_root()) write the outputs;
// and in main(): `const mpi_work::Scope mpi_scope;` (MPI_Finalize at the end, if started).

#include <cstddef>
#include <span>
#include <stdexcept>
#include <type_traits>

namespace radar_emu::tools::mpi_work {

/// True when this binary was built with MPI (CMake RADAR_EMU_MPI).
[[nodiscard]] bool available() noexcept;

/// The rank count the launcher asked for, from its environment (Open MPI's
/// OMPI_COMM_WORLD_SIZE, else PMI_SIZE of Slurm / MPICH launchers); 1 when not launched by one.
/// Valid before start().
[[nodiscard]] int launched_size() noexcept;

/// Initialises MPI when launched with more than one rank (idempotent; nothing otherwise) and
/// limits this rank's TBB worker threads so that the ranks of one node share its cores (see
/// threads_per_rank). Throws std::runtime_error when launched with more than one rank by a
/// build without MPI, or when MPI's world size disagrees with the launcher's.
/// Call it late, after every check and set-up that can fail (options, files, the mesh): a rank
/// that fails before start() exits and mpirun ends the job; one that failed after it would
/// leave the others waiting in a gather (main() then ends the job with abort_job()).
void start();

/// True after start() initialised MPI (launched with more than one rank, in an MPI build).
[[nodiscard]] bool started() noexcept;

/// This process's rank in 0..size()-1 and the rank count of the split: MPI's after start()
/// initialised it, else 0 and 1 (one process computes everything, whoever launched it).
[[nodiscard]] int rank() noexcept;
[[nodiscard]] int size() noexcept;

/// The rank the launcher gave this process, from its environment (OMPI_COMM_WORLD_RANK, else
/// PMI_RANK); 0 when not launched by one. Valid before start().
[[nodiscard]] int launched_rank() noexcept;

/// Whether this process prints and writes: rank 0 of the split after start(); before it, rank
/// 0 of the launch (so that the others stay quiet from the start).
[[nodiscard]] bool is_root() noexcept;

/// TBB threads this rank uses after start(): all it may run on when the launcher bound it to
/// some cores (mpirun binds each rank to one core for -np <= 2, to a socket above), else the
/// node's cores divided among the ranks on that node (OMPI_COMM_WORLD_LOCAL_SIZE), at least 1.
/// 0 when start() left TBB's default (one rank).
[[nodiscard]] int threads_per_rank() noexcept;

/// MPI_Finalize if start() initialised MPI (idempotent). Called by Scope.
void finalize() noexcept;

/// After an error on this rank: when start() initialised MPI with more than one rank, ends every
/// rank of the job with `status` (MPI_Abort), as the others may be waiting for this one in a
/// gather; otherwise returns.
void abort_job(int status) noexcept;

/// Held by main(): finalize() when it returns.
struct Scope {
  Scope() = default;
  Scope(const Scope&) = delete;
  Scope& operator=(const Scope&) = delete;
  ~Scope() { finalize(); }
};

/// Items [begin, end) of one rank.
struct Block {
  std::size_t begin = 0, end = 0;
  [[nodiscard]] std::size_t size() const noexcept { return end - begin; }
  friend bool operator==(const Block&, const Block&) = default;
};

/// The contiguous block of `n` items of `rank` out of `ranks`: the first n % ranks ranks get
/// one item more than the others, blocks in rank order cover 0..n exactly (a rank may get none).
[[nodiscard]] Block block_of(std::size_t n, int rank, int ranks) noexcept;

/// This process's block of `n` items: block_of(n, rank(), size()).
[[nodiscard]] inline Block my_block(std::size_t n) noexcept {
  return block_of(n, rank(), size());
}

/// The byte-level gather behind gather_blocks: `records` holds n_items records of
/// `record_bytes` each; this rank's block (my_block(n_items)) is sent to rank 0, which receives
/// every block at its place. Nothing with one rank. Collective: every rank calls it with the
/// same n_items and record_bytes. Throws std::invalid_argument past MPI's int counts (more than
/// 2^31 - 1 items or bytes a record); an MPI failure aborts the job (MPI_ERRORS_ARE_FATAL).
void gather_bytes(void* records, std::size_t n_items, std::size_t record_bytes);

/// Ordered gather of fixed-size records to rank 0, in place: `all` holds n = all.size() /
/// per_item items of `per_item` T each, laid out by item, on every rank; each rank has filled
/// its block my_block(n). On return rank 0's `all` holds every item, in item order, bit for bit
/// as computed (other ranks' are unchanged). Collective; nothing with one rank.
template <class T>
void gather_blocks(std::span<T> all, std::size_t per_item = 1) {
  static_assert(std::is_trivially_copyable_v<T>, "gather_blocks sends the bytes of T");
  if (per_item == 0 || all.size() % per_item != 0)
    throw std::invalid_argument("gather_blocks: the records are not whole items");
  gather_bytes(all.data(), all.size() / per_item, per_item * sizeof(T));
}

}  // namespace radar_emu::tools::mpi_work
