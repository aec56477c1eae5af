// The memory limit of the large setup-time allocations (config/memory_limit.hpp).

#include "config/memory_limit.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "config/progress.hpp"

namespace radar_emu::config {

double memory_limit_bytes() {
  double mib = kDefaultMemoryLimitMiB;
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0)
    mib = std::min(mib, static_cast<double>(pages) * static_cast<double>(page) / 2.0 / 1048576.0);
  if (const char* text = std::getenv(kMemoryLimitVariable); text != nullptr) {
    char* end = nullptr;
    mib = std::strtod(text, &end);
    if (end == text || *end != '\0' || !std::isfinite(mib) || !(mib > 0.0)) {
      throw std::invalid_argument(std::string(kMemoryLimitVariable) + ": '" + text +
                                  "' is not a number of MiB > 0");
    }
  }
  return mib * 1048576.0;
}

std::optional<std::string> over_memory_limit(double bytes, const std::string& what) {
  const double limit = memory_limit_bytes();
  if (bytes <= limit)  // a NaN estimate is refused too
    return std::nullopt;
  char mib[32];
  std::snprintf(mib, sizeof mib, "%.0f", limit / 1048576.0);
  return "needs about " + format_bytes(bytes) + " of memory (" + what + "), over the limit of " +
         format_bytes(limit) + " (" + kMemoryLimitVariable + "=" + mib +
         "; set it higher to allow more)";
}

}  // namespace radar_emu::config
