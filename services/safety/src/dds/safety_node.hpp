#pragma once
// DDS adapter of the safety service. In: e-stop inputs, service status heartbeats, robot model,
// joint state (1 kHz), reset requests. Out: SafetyState (latched; on every change and every
// publish period) and the service's own status. Samples are handled on the DDS listener
// threads as they arrive (a limit violation is reported without waiting for a poll); the
// liveliness check runs in spin().

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "concert/common/command_once.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "safety/safety_monitor.hpp"

namespace concert::safety::dds {

class SafetyNode {
 public:
  /// `participant` must outlive the node. `log` gets one line per state change and reset.
  /// `state_file` (empty: none) keeps the latched state (LatchedState) across restarts: read
  /// here when it exists, rewritten on every change. A file that cannot be read stops the
  /// robot, naming it, until an operator reset (the state it held is unknown).
  SafetyNode(concert::dds::Participant& participant, Params params, std::ostream& log,
             std::string state_file = {});
  ~SafetyNode();
  SafetyNode(const SafetyNode&) = delete;
  SafetyNode& operator=(const SafetyNode&) = delete;

  /// One liveliness check at the current time; publishes the state if it changed or the
  /// publish period has passed.
  void tick();

  /// Calls tick() every Params::check_period until `stop` becomes true.
  void spin(const std::atomic<bool>& stop);

  SafetyStatus status() const;
  /// Names of the e-stop inputs engaged now (as the monitor has them).
  std::vector<std::string> engaged_inputs() const;
  /// Joint samples that were checked against the model's limits.
  uint64_t checked_samples() const;

 private:
  void on_estop(const msg::EStopInput& input);
  void on_status(const msg::ServiceStatus& status, const std::string& incarnation);
  void on_model(const msg::RobotModel& model);
  void on_joint_state(const msg::JointState& state);
  void on_reset(const msg::SafetyReset& reset);
  /// Publishes if the monitor changed (or `force`); caller holds mutex_. Returns the new
  /// state's summary if it changed, for note() once the lock is released.
  std::optional<std::string> publish_locked(bool force);
  /// Reads the state file at start (caller holds mutex_).
  /// The monitor restored from `state_file` (when there is one), made before any reader exists.
  static SafetyMonitor restored_monitor(Params params, const std::string& state_file, std::ostream& log);
  /// Rewrites the state file if the latched state changed (caller holds mutex_).
  void persist_locked();
  /// Puts `text` in the service status. Never called with mutex_ held: the status write is
  /// delivered in-process to our own status reader, which takes mutex_.
  void note(const std::optional<std::string>& text);

  mutable std::mutex mutex_;
  SafetyMonitor monitor_;
  std::ostream& log_;
  uint64_t published_revision_ = ~uint64_t{0};
  Clock::time_point last_publish_{};
  uint64_t checked_samples_ = 0;
  std::string model_hash_;  // content hash of the model whose limits are enforced
  std::string state_file_;
  uint64_t persisted_revision_ = ~uint64_t{0};
  concert::dds::Writer<msg::SafetyState> state_writer_;
  concert::dds::StatusReporter status_;
  // Readers last: destroyed first, so no callback runs on a half-destroyed node.
  concert::dds::Reader<msg::EStopInput> estops_;
  concert::dds::Reader<msg::ServiceStatus> statuses_;
  concert::dds::Reader<msg::RobotModel> models_;
  concert::dds::Reader<msg::JointState> joint_states_;
  concert::dds::Reader<msg::SafetyReset> resets_;
  concert::CommandOnce resets_seen_;  // (request id, stamp) of the resets taken; under mutex_
};

}  // namespace concert::safety::dds
