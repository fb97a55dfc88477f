#include "concert/common/priority.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace concert {

NiceResult set_thread_nice(int nice) {
  const auto tid = static_cast<id_t>(::gettid());
  NiceResult r;
  if (setpriority(PRIO_PROCESS, tid, nice) == 0) {
    r.applied = true;
  } else {
    r.error = std::strerror(errno);
  }
  errno = 0;
  const int now = getpriority(PRIO_PROCESS, tid);
  r.now = errno == 0 ? now : 0;
  if (r.applied && r.now != nice) r.applied = false;  // clamped to -20..19
  return r;
}

}  // namespace concert
