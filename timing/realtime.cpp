#include "timing/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#if defined(__x86_64__) || defined(__i386__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

namespace radar_emu::timing {

namespace {
std::string errno_text(const char* what, int err) {
  return std::string(what) + ": " + std::strerror(err);
}
}  // namespace

RealtimeReport bring_up_realtime(const RealtimeOptions& options) {
  RealtimeReport report;
  if (options.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      report.memory_locked = true;
    } else {
      report.warnings.push_back(errno_text("mlockall refused", errno));
    }
  }
  if (options.fifo_priority > 0) {
    sched_param param{};
    param.sched_priority = options.fifo_priority;
    const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (err == 0) {
      report.fifo = true;
    } else {
      report.warnings.push_back(errno_text("SCHED_FIFO refused", err));
    }
  }
  if (options.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(options.cpu), &set);
    const int err = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (err == 0) {
      report.pinned = true;
    } else {
      report.warnings.push_back(errno_text("CPU affinity refused", err));
    }
  }
  if (options.flush_denormals) {
#if defined(__x86_64__) || defined(__i386__)
    // MXCSR bit 15 = flush to zero (FTZ), bit 6 = denormals are zero (DAZ); Intel SDM vol. 1,
    // sec. 10.2.3. Written directly: the _MM_SET_* macros trip -Wsign-conversion.
    constexpr unsigned kFtz = 1u << 15;
    constexpr unsigned kDaz = 1u << 6;
    _mm_setcsr(_mm_getcsr() | kFtz | kDaz);
    report.denormals_flushed = true;
#else
    report.warnings.push_back("denormal flushing not implemented on this architecture");
#endif
  }
  return report;
}

}  // namespace radar_emu::timing
