#pragma once
// The robot's side of the safety layer: it moves only while it hears the safety service.

#include <chrono>
#include <optional>
#include <string>

namespace concert::robot {

/// Watches the safety service's state stream (re-published at least every 0.2 s, on every
/// change at once). With a timeout the robot holds until a safety state is heard and again
/// whenever none was heard for `timeout`: a robot that cannot hear the safety layer cannot
/// hear its stops either (a restarted robot process whose DDS transport stays deaf would execute
/// a trajectory through a stop naming it; issue #21), so silence is treated as a stop. The stop
/// ends with the next safety state heard, whose own mode then decides: a safety service that
/// noticed the robot's silence latches a stop of its own until an operator reset.
/// Without a timeout (0, the default for a robot run without the safety service) nothing is
/// required. Not thread-safe: the caller serialises (RobotNode holds a mutex).
class SafetyWatchdog {
 public:
  using Clock = std::chrono::steady_clock;

  /// `timeout_s` >= 0 (0: the safety service is not required); throws std::invalid_argument
  /// otherwise. `start`: the time the robot started listening.
  SafetyWatchdog(double timeout_s, Clock::time_point start);

  [[nodiscard]] bool required() const { return timeout_.count() > 0; }

  /// A safety state arrived at `now`.
  void heard(Clock::time_point now);

  /// The reason to hold at `now` when the safety service is required and not heard (never
  /// heard since the start, or silent for longer than the timeout); nullopt otherwise.
  [[nodiscard]] std::optional<std::string> silence(Clock::time_point now) const;

 private:
  Clock::duration timeout_;
  Clock::time_point start_;
  std::optional<Clock::time_point> last_;
};

}  // namespace concert::robot
