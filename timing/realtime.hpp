#pragma once
// Real-time bring-up at start (style.md item 9, timing.md): lock memory, SCHED_FIFO, CPU
// affinity, flush denormals. Each step warns when the OS refuses; nothing here throws or exits.

#include <string>
#include <vector>

namespace radar_emu::timing {

struct RealtimeOptions {
  bool lock_memory = false;     ///< mlockall(MCL_CURRENT | MCL_FUTURE)
  int fifo_priority = 0;        ///< SCHED_FIFO priority 1..99 for the calling thread; 0 = leave
  int cpu = -1;                 ///< pin the calling thread to this CPU; -1 = leave
  bool flush_denormals = true;  ///< set FTZ/DAZ on x86 (denormals stall the FPU)
};

struct RealtimeReport {
  bool memory_locked = false;
  bool fifo = false;
  bool pinned = false;
  bool denormals_flushed = false;
  std::vector<std::string> warnings;  ///< one line per refused step, with errno text
};

/// Applies `options` to the process / calling thread. Call at setup, before worker threads that
/// should inherit the settings are started.
[[nodiscard]] RealtimeReport bring_up_realtime(const RealtimeOptions& options);

}  // namespace radar_emu::timing
