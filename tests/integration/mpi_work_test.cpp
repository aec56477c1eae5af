// The split of tools/mpi_work.hpp (the mpirun runs themselves: check_mpi_split.py). Here,
// outside mpirun, the layer must be the single-process case whatever the build.
#include "tools/mpi_work.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <array>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <vector>

namespace mw = radar_emu::tools::mpi_work;

namespace {

TEST(MpiWork, BlocksCoverTheItemsInOrderAndDifferByAtMostOne) {
  for (std::size_t n : {0UL, 1UL, 2UL, 5UL, 7UL, 41UL, 1000UL}) {
    for (int ranks : {1, 2, 3, 4, 8, 64}) {
      std::size_t next = 0, smallest = n + 1, largest = 0;
      for (int r = 0; r < ranks; ++r) {
        const mw::Block b = mw::block_of(n, r, ranks);
        EXPECT_EQ(b.begin, next) << n << " items, rank " << r << " of " << ranks;
        EXPECT_LE(b.begin, b.end);
        next = b.end;
        smallest = std::min(smallest, b.size());
        largest = std::max(largest, b.size());
      }
      EXPECT_EQ(next, n) << n << " items over " << ranks;
      EXPECT_LE(largest - smallest, 1U) << n << " items over " << ranks;
      // n = q ranks + m: the first m ranks take q + 1.
      const std::size_t q = n / static_cast<std::size_t>(ranks);
      const std::size_t m = n % static_cast<std::size_t>(ranks);
      if (m > 0) {
        EXPECT_EQ(mw::block_of(n, static_cast<int>(m) - 1, ranks).size(), q + 1);
      }
      EXPECT_EQ(mw::block_of(n, ranks - 1, ranks).size(), q);
    }
  }
  EXPECT_EQ(mw::block_of(10, 1, 4), (mw::Block{3, 6}));  // 3 3 2 2
  EXPECT_EQ(mw::block_of(10, 3, 4), (mw::Block{8, 10}));
  EXPECT_EQ(mw::block_of(10, 4, 4), mw::Block{});   // no such rank
  EXPECT_EQ(mw::block_of(10, -1, 4), mw::Block{});  // no such rank
}

TEST(MpiWork, OutsideMpirunIsOneProcessWithEveryItem) {
  ASSERT_EQ(mw::launched_size(), 1) << "run this test without mpirun";
  mw::start();  // nothing to start: one rank
  EXPECT_FALSE(mw::started());
  EXPECT_EQ(mw::rank(), 0);
  EXPECT_EQ(mw::launched_rank(), 0);
  EXPECT_EQ(mw::size(), 1);
  EXPECT_TRUE(mw::is_root());
  EXPECT_EQ(mw::threads_per_rank(), 0);  // TBB's default left alone
  EXPECT_EQ(mw::my_block(7), (mw::Block{0, 7}));
  std::array<double, 6> records{1, 2, 3, 4, 5, 6};
  mw::gather_blocks(std::span<double>(records), 2);  // nothing to gather
  EXPECT_EQ(records, (std::array<double, 6>{1, 2, 3, 4, 5, 6}));
  EXPECT_THROW(mw::gather_blocks(std::span<double>(records), 4), std::invalid_argument);
  EXPECT_THROW(mw::gather_blocks(std::span<double>(records), 0), std::invalid_argument);
  mw::finalize();  // nothing to finalize
  EXPECT_FALSE(mw::started());
}

// A caller that never starts MPI (the Python module's sweeps) computes every item even when a
// launcher started it as rank 1 of 2; only printing follows the launch's rank.
TEST(MpiWork, LaunchedButNotStartedComputesEverything) {
  ASSERT_EQ(mw::launched_size(), 1) << "run this test without mpirun";
  ::setenv("OMPI_COMM_WORLD_SIZE", "2", 1);
  ::setenv("OMPI_COMM_WORLD_RANK", "1", 1);
  EXPECT_EQ(mw::launched_size(), 2);
  EXPECT_EQ(mw::launched_rank(), 1);
  EXPECT_FALSE(mw::is_root());  // quiet
  EXPECT_EQ(mw::rank(), 0);
  EXPECT_EQ(mw::size(), 1);
  EXPECT_EQ(mw::my_block(5), (mw::Block{0, 5}));
  ::setenv("OMPI_COMM_WORLD_SIZE", "banana", 1);  // not a launcher's: one process
  EXPECT_EQ(mw::launched_size(), 1);
  EXPECT_EQ(mw::launched_rank(), 0);
  ::unsetenv("OMPI_COMM_WORLD_SIZE");
  ::unsetenv("OMPI_COMM_WORLD_RANK");
  EXPECT_TRUE(mw::is_root());
}

}  // namespace
