#include "robot/safety_watchdog.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace concert::robot {

namespace {
std::string seconds(SafetyWatchdog::Clock::duration d) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f s", std::chrono::duration<double>(d).count());
  return buf;
}
}  // namespace

SafetyWatchdog::SafetyWatchdog(double timeout_s, Clock::time_point start) : start_(start) {
  if (!std::isfinite(timeout_s) || timeout_s < 0.0) {
    throw std::invalid_argument("safety timeout must be a finite number of seconds >= 0 (0: not required), got " +
                                std::to_string(timeout_s));
  }
  timeout_ = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
}

void SafetyWatchdog::heard(Clock::time_point now) {
  if (!last_ || now > *last_) last_ = now;
}

std::optional<std::string> SafetyWatchdog::silence(Clock::time_point now) const {
  if (!required()) return std::nullopt;
  if (!last_) {
    return "safety service not heard yet (" + seconds(now - start_) +
           " since the start): the robot moves only while it hears it";
  }
  if (now - *last_ > timeout_) {
    return "safety service not heard for " + seconds(now - *last_) + " (bound " + seconds(timeout_) +
           "): the robot moves only while it hears it";
  }
  return std::nullopt;
}

}  // namespace concert::robot
