// config/progress.hpp: the text of the offline commands' progress line and estimates.

#include "config/progress.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "config/memory_limit.hpp"

namespace radar_emu::config {
namespace {

TEST(Progress, LineWithPercentCountsElapsedAndTimeLeft) {
  // 1520 of 4096 in 12 s: 37.1 %, the rest at that pace 12 x 2576 / 1520 = 20.3 s.
  EXPECT_EQ(format_progress("sar", "pulses", 1520, 4096, 12.0),
            "sar: 37 % (1520/4096 pulses), 12 s elapsed, ~20 s left");
}

TEST(Progress, NoEstimateBeforeTheFirstItemOrSecondNorAtTheEnd) {
  EXPECT_EQ(format_progress("rcs", "directions", 0, 400, 5.0),
            "rcs: 0 % (0/400 directions), 5.0 s elapsed");
  EXPECT_EQ(format_progress("rcs", "directions", 3, 400, 0.4),
            "rcs: 0 % (3/400 directions), 0.4 s elapsed");
  EXPECT_EQ(format_progress("rcs", "directions", 400, 400, 61.0),
            "rcs: 100 % (400/400 directions), 61 s elapsed");
}

TEST(Progress, DurationsAndBytes) {
  EXPECT_EQ(format_duration(0.32), "0.3 s");
  EXPECT_EQ(format_duration(89.4), "89 s");
  EXPECT_EQ(format_duration(600.0), "10 min");
  EXPECT_EQ(format_duration(7200.0), "2.0 h");
  EXPECT_EQ(format_bytes(4.7e7), "47 MB");
  EXPECT_EQ(format_bytes(3.46e9), "3.5 GB");
  EXPECT_EQ(format_bytes(1200.0), "2 kB");
}

TEST(Progress, LineRemembersHowFarTheWorkGotWhenNotDrawing) {
  ProgressLine line("rcs", "directions", false);  // disabled: -q
  EXPECT_FALSE(line.drawing());
  line.update(37, 400);
  EXPECT_EQ(line.done(), 37u);
  EXPECT_EQ(line.total(), 400u);
}

// The memory limit of the large allocations (config/memory_limit.hpp): RADAR_EMU_MAX_MEMORY_MIB
// in MiB (2^20 B), the estimate and the limit in the message in decimal units.
TEST(MemoryLimit, TheVariableSetsTheLimitAndTheMessageCarriesBothFigures) {
  ASSERT_EQ(setenv("RADAR_EMU_MAX_MEMORY_MIB", "100", 1), 0);
  EXPECT_EQ(memory_limit_bytes(), 104857600.0);
  EXPECT_FALSE(over_memory_limit(104857600.0, "x").has_value());  // at the limit: allowed
  EXPECT_EQ(over_memory_limit(4.92e8, "16 beams").value_or(""),
            "needs about 492 MB of memory (16 beams), over the limit of 105 MB "
            "(RADAR_EMU_MAX_MEMORY_MIB=100; set it higher to allow more)");
  EXPECT_TRUE(over_memory_limit(std::nan(""), "x").has_value());  // a NaN estimate is refused
  for (const char* bad : {"", "abc", "0", "-5", "12MB", "inf"}) {
    ASSERT_EQ(setenv("RADAR_EMU_MAX_MEMORY_MIB", bad, 1), 0);
    EXPECT_THROW((void)memory_limit_bytes(), std::invalid_argument) << "'" << bad << "'";
  }
  ASSERT_EQ(unsetenv("RADAR_EMU_MAX_MEMORY_MIB"), 0);
  // The default: 8192 MiB, or half the physical memory when that is less.
  const double half = static_cast<double>(sysconf(_SC_PHYS_PAGES)) *
                      static_cast<double>(sysconf(_SC_PAGESIZE)) / 2.0;
  EXPECT_EQ(memory_limit_bytes(), std::min(8192.0 * 1048576.0, half));
}

}  // namespace
}  // namespace radar_emu::config
