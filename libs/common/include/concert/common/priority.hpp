#pragma once
// The nice value of the calling thread. On Linux a nice value belongs to a thread, not to a
// process (setpriority(PRIO_PROCESS, tid)); threads created afterwards inherit it. Lowering it
// below the current value needs CAP_SYS_NICE or an RLIMIT_NICE that allows it: callers treat
// "not permitted" as running at the priority they have, and say so.

#include <string>

namespace concert {

struct NiceResult {
  bool applied = false;  ///< the thread now runs at the value asked for
  int now = 0;           ///< the thread's nice value after the call
  std::string error;     ///< why not, when not applied ("" otherwise)
};

/// Sets the calling thread's nice value (-20..19; out of range is clamped by the kernel).
NiceResult set_thread_nice(int nice);

}  // namespace concert
