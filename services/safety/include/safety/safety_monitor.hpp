#pragma once
// The safety layer's logic, free of any middleware: e-stop inputs, liveliness of the robot and
// task services, and a joint limits watchdog that applies the model's limits table with the
// limits rule of libs/model (concert/model/limits.hpp). Any cause stops the robot; the stop is
// latched until every e-stop input is released AND an explicit reset is accepted.
//
// Time is passed in by the caller (steady clock), so the logic is testable without waiting.

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "concert/model/limits.hpp"
#include "safety/latched_state.hpp"
#include "safety/params.hpp"

namespace concert::safety {

using Clock = std::chrono::steady_clock;
using TimePoint = Clock::time_point;

/// "button front left", ..., "wireless", "software".
std::string_view to_string(EStopSource source);

/// One measured joint state; vectors indexed like `name` (velocity/effort may be empty).
struct JointSample {
  uint32_t model_version = 0;
  std::vector<std::string> name;
  std::vector<double> position;  ///< [rad]
  std::vector<double> velocity;  ///< [rad/s]
  std::vector<double> effort;    ///< [N m]
  /// When the robot measured it, on the robot's clock [ns] (simulated or real time); 0: not
  /// stamped.
  int64_t stamp_ns = 0;
};

struct SafetyStatus {
  Mode mode = Mode::kRunning;
  /// True while stopped: the stop is latched and needs released inputs plus a reset.
  bool reset_required = false;
  /// Why the robot is stopped, oldest first; e.g. "estop: wireless engaged (operator)".
  std::vector<std::string> causes;
  /// The e-stop inputs engaged now, in EStopSource order.
  std::vector<EStopSource> engaged;
};

struct ResetOutcome {
  bool accepted = false;
  std::string message;  ///< why refused, or what the reset cleared
};

/// What the limits watchdog did with one joint sample.
enum class SampleOutcome { kChecked, kNoModel, kOtherModelVersion };

class SafetyMonitor {
 public:
  /// `start` is the time the monitor starts watching (for Params::require_robot).
  SafetyMonitor(Params params, TimePoint start);

  /// An e-stop input changed (or was re-sent). Engaging one stops the robot.
  void set_estop(EStopSource source, bool engaged, const std::string& reason);

  /// A status/heartbeat of the instance `service`@`host`, received at `now`. `clean_stop`:
  /// the service said it stops (SERVICE_STOPPED). Services other than the robot and the
  /// task services are ignored. A task service that stops cleanly is no longer watched; the
  /// robot service stopping is a stop cause (nothing holds the drives any more).
  /// `incarnation` names the process that sent it (opaque; "" = unknown): a watched instance
  /// heard from another process without having stopped cleanly was restarted after dying, and
  /// that stops the robot naming it, however fast the restart was (a restart within the
  /// liveliness bound is never silent long enough to be caught as silence).
  void on_heartbeat(const std::string& service, const std::string& host, bool clean_stop,
                    TimePoint now, const std::string& incarnation = {});

  /// Checks liveliness at `now`: a watched instance silent beyond the bound stops the robot,
  /// with a cause naming it. Silence counts only while the monitor checks: a check later than
  /// Params::stall_checks check periods after the previous one finds the monitor itself was
  /// stalled, and the stalled time is not counted as anyone's silence (own_stalls() counts it).
  void check_liveliness(TimePoint now);
  /// How many of its own stalls check_liveliness has found.
  uint64_t own_stalls() const { return own_stalls_; }

  /// A new robot model: the limits table the watchdog enforces from now on. The thermal load
  /// of every joint starts cold.
  void set_model(uint32_t version, model::LimitsTable limits);

  /// Checks a joint sample measured at `now` against the model's limits with the limits rule:
  /// position beyond [lower - position_tolerance, upper + position_tolerance], |velocity|
  /// beyond velocity x (1 + velocity_margin), |effort| beyond the PEAK torque x
  /// (1 + effort_margin), or the RMS effort over the thermal window (model::kThermalWindow)
  /// beyond the CONTINUOUS torque x (1 + effort_margin) stops the robot. The thermal window
  /// runs on the robot's clock: each sample's torque counts for the time since the previous
  /// sample's stamp, not since its arrival (samples queued behind a stall of this process, or
  /// of the network, arrive together; weighed by arrival, the first of them counted for the
  /// whole stall). Unstamped samples count from their arrival `now`; a stamp that goes back
  /// (a restarted robot) starts the clock again. Samples of another
  /// model version (a reconfiguration in flight) are not checked. A malformed sample (vector
  /// lengths differ from `name`) stops the robot too.
  SampleOutcome on_joint_state(const JointSample& sample, TimePoint now);

  /// Explicit reset of a latched stop. Refused while an e-stop input is engaged, or while the
  /// robot service is silent. Accepting it forgets silent task services (the operator
  /// acknowledges them gone; a new heartbeat watches them again) and clears the causes.
  ResetOutcome reset(const std::string& source, TimePoint now);

  /// What a restart of the service must not lose (LatchedState).
  LatchedState latched() const;
  /// Increases every time latched() changes.
  uint64_t latched_revision() const { return latched_revision_; }
  /// Continues from `state` after a restart of the safety service: the same stop and causes,
  /// the same inputs engaged, the same instances watched. Their silence counts from the first
  /// watched service heard after the restore (the restarted service's readers match the other
  /// processes' writers only some time after `now`), at the latest from 5 bounds after `now`;
  /// each must then be heard within the bound, from the process it was heard from before
  /// (another is a restart).
  void restore(const LatchedState& state, TimePoint now);

  const SafetyStatus& status() const { return status_; }
  /// Increases every time status() changes.
  uint64_t revision() const { return revision_; }
  /// Names of the e-stop inputs engaged now.
  std::vector<std::string> engaged_inputs() const;
  /// "service@host" of the watched instances, and whether each is silent now.
  std::vector<std::pair<std::string, bool>> watched() const;
  uint32_t model_version() const { return model_version_; }
  const Params& params() const { return params_; }

 private:
  struct Instance {
    std::string service;
    TimePoint last_seen;
    bool silent = false;
    std::string incarnation;
  };

  bool is_watched(const std::string& service) const;
  std::vector<EStopSource> engaged_sources() const;
  /// Adds a cause (once per key) and stops.
  void stop(const std::string& key, const std::string& text);
  void check_joint(std::size_t row, std::size_t i, const JointSample& sample, double dt);
  /// The time [s] the sample stamped `stamp_ns` (0: unstamped), arriving at `now`, stands for.
  double sample_period(int64_t stamp_ns, TimePoint now);

  Params params_;
  TimePoint start_;
  std::array<bool, kEStopSourceCount> engaged_{};
  std::map<std::string, Instance> instances_;  // by "service@host"
  bool robot_heard_ = false;
  bool robot_start_cause_ = false;
  uint32_t model_version_ = 0;
  model::LimitsTable limits_;
  std::map<std::string, std::size_t> joint_index_;
  std::vector<model::ThermalLoad> thermal_;  // per row of limits_
  std::optional<TimePoint> last_sample_;   // arrival of the last checked sample
  std::optional<int64_t> last_stamp_ns_;  // the robot's stamp of the last stamped sample
  std::vector<std::string> cause_keys_;
  SafetyStatus status_;
  uint64_t revision_ = 0;
  std::optional<TimePoint> last_check_;
  uint64_t own_stalls_ = 0;
  uint64_t latched_revision_ = 0;
  bool restored_unheard_ = false;  // restored instances wait for the first watched status heard
  TimePoint restored_at_{};
};

}  // namespace concert::safety
