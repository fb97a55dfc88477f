#pragma once
// A client's side of a command on a volatile topic (reliable, volatile: a reader that matches
// after the write never gets it). `wait_for_readers(1)` returns as soon as any reader matched,
// and that may be another tool's (the GUI's gateway, a recorder) before the service's: the
// command is then written again every `period` until the service's answer is heard. The
// service takes each command once (concert/common/command_once.hpp).

#include <algorithm>
#include <chrono>

namespace concert {

/// Calls write(), then answered(until) (which waits at most until `until` for the service's
/// answer and returns whether it came), again every `period` until answered or `deadline`.
/// Returns whether the answer came. The first write happens even with the deadline past.
template <class Write, class Answered>
bool resend_until_answered(Write&& write, Answered&& answered,
                           std::chrono::steady_clock::time_point deadline,
                           std::chrono::steady_clock::duration period = std::chrono::seconds(1)) {
  do {
    write();
    const auto next = std::min(deadline, std::chrono::steady_clock::now() + period);
    if (answered(next)) return true;
  } while (std::chrono::steady_clock::now() < deadline);
  return false;
}

}  // namespace concert
