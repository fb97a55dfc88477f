#pragma once
// DDS face of the robot service: model in, commands in, state/odometry/wrench/scan/status out.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "concert/model/description.hpp"
#include "concert/topology/types.hpp"
#include "robot/robot_core.hpp"
#include "robot/safety_watchdog.hpp"

namespace concert::robot::dds {

struct NodeParams {
  std::string service_name{"robot"};
  int odometry_decimation{10};  ///< odometry every N cycles (100 Hz at 1 kHz)
  int wrench_decimation{10};    ///< end-effector wrench every N cycles
  int trajectory_decimation{100};  ///< trajectory progress every N cycles (10 Hz), and on each change
  /// > 0: the robot holds (a safety stop) until it hears the safety service and whenever it has
  /// not heard it for this long [s] (SafetyWatchdog); 0: the safety service is not required
  /// (a robot run on its own). `concert up` sets it when it starts the safety service.
  double safety_timeout{0.0};
};

/// The end-effector a Cartesian command drives, from the model message: libs/model's tool (the
/// end-effector at the tip of an arm chain, never a wheel); "" (the core's own choice: the
/// deepest tcp link) when the message has no parsable description or no arm tool.
std::string tool_end_effector(const msg::RobotModel& model);

/// A SAFETY_STOPPED safety state holds the robot, aborts a running trajectory and refuses
/// commands until SAFETY_RUNNING. With NodeParams::safety_timeout, not hearing the safety
/// service is a stop too (checked on each publish()). Readers call the core from the DDS listener threads (the core
/// checks there and hands over to its loop without locking it); publish() is called by the
/// service's publisher thread with each new state of the loop, never by the loop itself.
/// Trajectories: JointTrajectoryCommand in, TrajectoryStatus out (refused at once with the
/// reason; executing with progress at 10 Hz; succeeded or aborted with the reason). Refused commands and models are reported on the
/// status topic with the core's message; the last good model stays.
class RobotNode {
 public:
  /// Called with each model from the model topic before the core takes it (the ethercat backend
  /// binds its joints to drive boards there); what it throws refuses the model. A model older
  /// than the running one is refused before it is called; one the core refuses after it (a
  /// model whose tool frame or legs it cannot use) leaves the hardware as the hook prepared it,
  /// and the drives hold until a model that matches arrives.
  using ModelHook = std::function<void(const model::ModelDescription&)>;

  RobotNode(concert::dds::Participant& participant, RobotCore& core, NodeParams params = {},
            ModelHook before_model = {});
  ~RobotNode();
  RobotNode(const RobotNode&) = delete;
  RobotNode& operator=(const RobotNode&) = delete;

  /// Joint state every call (KEEP_LAST 1 stream), odometry and wrench decimated, status on change.
  void publish(const RobotState& state);
  /// Latched scan of the (simulated) bus; `scan_id` increases with each scan.
  void publish_scan(const topology::EscScan& scan, const std::string& source);

  /// Reconfigures the core to a model (from the model topic, or the sim's own model in
  /// standalone mode) and reports the outcome on the status topic. Never throws.
  /// `limits` (the model's limits table) folds each listed drive's torque back as it heats.
  void apply_model(const std::string& urdf, std::uint64_t version,
                   const std::string& end_effector_frame, const std::string& content_hash = "",
                   const model::LimitsTable& limits = {});

  /// Counters for tests and diagnostics.
  [[nodiscard]] std::uint64_t refused_commands() const { return refused_.load(); }
  [[nodiscard]] std::string last_error() const;

 private:
  void on_model(const msg::RobotModel& model);
  void on_safety(const msg::SafetyState& state);
  void check_safety_silence();
  template <class F> void guarded(const std::string& what, F&& f);
  // Reconfigures through `install` (returns the model's limits table), reporting the outcome.
  template <class Install> void apply(std::uint64_t version, const std::string& content_hash, Install&& install);

  concert::dds::Participant& participant_;
  RobotCore& core_;
  NodeParams params_;
  ModelHook before_model_;
  concert::dds::StatusReporter status_;
  concert::dds::Writer<msg::JointState> joint_state_;
  concert::dds::Writer<msg::Odometry> odometry_;
  concert::dds::Writer<msg::EndEffectorWrench> wrench_;
  concert::dds::Writer<msg::EscScan> scan_;
  std::unique_ptr<concert::dds::Reader<msg::RobotModel>> model_reader_;
  std::unique_ptr<concert::dds::Reader<msg::JointCommand>> joint_reader_;
  std::unique_ptr<concert::dds::Reader<msg::CartesianImpedanceCommand>> cartesian_reader_;
  std::unique_ptr<concert::dds::Reader<msg::BaseVelocityCommand>> base_reader_;
  std::unique_ptr<concert::dds::Reader<msg::SafetyState>> safety_reader_;
  std::unique_ptr<concert::dds::Reader<msg::JointTrajectoryCommand>> trajectory_reader_;
  concert::dds::Writer<msg::TrajectoryStatus> trajectory_status_;
  std::mutex safety_mutex_;  // the watchdog and the stop it decides, from two threads
  SafetyWatchdog safety_watchdog_;
  bool safety_silent_{false};  // the stop in force is the watchdog's
  std::string holding_;        // "safety stop: holding (...)" while stopped, else empty
  struct Request {
    std::uint32_t id{0};
    std::uint64_t model_version{0};
    std::string source;
  };
  Request last_request_;                 // the last trajectory handed to the core (under mutex_)
  Request previous_request_;             // the one before it (under mutex_)
  std::uint64_t last_replaced_{0};       // sequence of the last replaced trajectory published
  void publish_trajectory(const TrajectoryProgress& progress, std::uint64_t model_version);
  std::uint64_t last_sequence_{0};       // of the last trajectory progress published
  TrajectoryState last_state_{TrajectoryState::kIdle};
  void on_trajectory(const msg::JointTrajectoryCommand& command);
  std::atomic<std::uint64_t> refused_{0};
  mutable std::mutex mutex_;
  std::string last_error_;
  bool last_ready_{false};
  std::uint64_t cycles_{0};
  model::LimitsTable limits_;       // of the model last applied (under mutex_)
  concert::dds::ModelId applied_;   // the model last applied (under mutex_)
  std::vector<bool> folded_;        // hardware order: a drive said to be folded back (publisher)
  /// Logs each drive whose torque limit folds back (to halfway between its peak and its
  /// continuous torque) and when it is back at its peak.
  void log_foldback(const RobotState& state);
  std::uint32_t scan_id_{0};
  double distance_{0.0};
  double last_x_{0.0}, last_y_{0.0};
};

}  // namespace concert::robot::dds
