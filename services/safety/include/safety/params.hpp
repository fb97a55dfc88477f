#pragma once
// Parameters of the safety service, loaded from YAML (config/safety.yaml lists every key with
// its default).

#include <chrono>
#include <string>
#include <vector>

#include "concert/config/config.hpp"

namespace concert::safety {

struct Params {
  /// A watched service silent for longer than this is a safe-stop cause [ms].
  std::chrono::milliseconds liveliness_timeout{1000};
  /// Service name of the robot service (its heartbeats are always watched).
  std::string robot_service = "robot";
  /// Task services whose silence stops the robot (watched from their first heartbeat on).
  std::vector<std::string> task_services{"nav", "planner", "drill", "collab", "surface_finish"};
  /// If true, the robot service must be heard within `liveliness_timeout` of the start.
  bool require_robot = false;
  /// Position beyond [lower - tolerance, upper + tolerance] is a violation [rad] (or [m]).
  double position_tolerance = 0.02;
  /// |velocity| beyond (1 + margin) x the model's velocity limit is a violation (fraction).
  double velocity_margin = 0.10;
  /// |effort| beyond (1 + margin) x the peak torque, or its RMS over the thermal window beyond
  /// (1 + margin) x the continuous torque, is a violation (fraction; libs/model limits rule).
  double effort_margin = 0.10;
  /// The adapter re-publishes the safety state at least this often [ms].
  std::chrono::milliseconds publish_period{200};
  /// Period of the liveliness check in the adapter [ms].
  std::chrono::milliseconds check_period{50};
  /// A liveliness check more than this many check periods after the previous one finds the
  /// safety process itself stalled: that time is not counted as anyone's silence (0: off).
  int stall_checks = 5;
  /// Nice value the safety process runs at (-20..19), set at its start before its DDS threads
  /// exist so that they inherit it: on a loaded PC the watchdog and the threads that take in the
  /// heartbeats run before the services they watch. Where the process may not lower it
  /// (no CAP_SYS_NICE), it runs at its own and says so.
  int nice = -10;
};

/// Reads a params YAML file: every key optional, unknown keys are errors. Throws
/// config::ConfigError (a std::runtime_error) naming the file, the key and the line.
Params load_params(const std::string& file);

/// Same from YAML text; `origin` names the source in error messages.
Params parse_params(const std::string& yaml, const std::string& origin);

/// Reads the parameters of `doc` (periods in seconds in the file), starting from the defaults.
Params read_params(config::Document& doc);

}  // namespace concert::safety
