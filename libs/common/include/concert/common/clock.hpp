#pragma once
// The one clock of message stamps.

#include <chrono>
#include <cstdint>

namespace concert {

/// Wall-clock time as every message stamp carries it (`stamp_ns` fields): nanoseconds since
/// the Unix epoch (std::chrono::system_clock). Comparable across hosts as far as their clocks
/// agree; use std::chrono::steady_clock for durations measured on one host.
inline int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace concert
