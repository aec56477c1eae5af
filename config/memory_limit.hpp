#pragma once
// The memory limit of radar-emu's large setup-time allocations (issue 32, "no silent
// surprises"): the sensor's range-Doppler cube of a scenario, a SAR run's raw data and image, the
// method of moments' matrix, the EV image's looks. Each is estimated before it is allocated and
// refused past the limit with its estimate, instead of swapping the machine to a halt.
//
// The limit is 8192 MiB (kDefaultMemoryLimitMiB), or half the machine's physical memory when
// that is less, unless the environment variable RADAR_EMU_MAX_MEMORY_MIB gives another, a
// positive number of MiB (`scene import` has its own --max-memory-mib, default 8192). Setup
// only: reads the environment, allocates.

#include <cstdint>
#include <optional>
#include <string>

namespace radar_emu::config {

inline constexpr double kDefaultMemoryLimitMiB = 8192.0;
inline constexpr const char* kMemoryLimitVariable = "RADAR_EMU_MAX_MEMORY_MIB";

/// The limit [bytes]: RADAR_EMU_MAX_MEMORY_MIB when set, else the smaller of
/// kDefaultMemoryLimitMiB and half the physical memory (sysconf). Throws
/// std::invalid_argument "RADAR_EMU_MAX_MEMORY_MIB: 'TEXT' is not a number of MiB > 0" for a
/// value that is not one.
[[nodiscard]] double memory_limit_bytes();

/// None when `bytes` fits the limit; else the reason, one clause for the caller's message:
/// "needs about 7.1 GB of memory (WHAT), over the limit of 8.6 GB (RADAR_EMU_MAX_MEMORY_MIB=8192;
/// set it higher to allow more)".
[[nodiscard]] std::optional<std::string> over_memory_limit(double bytes, const std::string& what);

}  // namespace radar_emu::config
