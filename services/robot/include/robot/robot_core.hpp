#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/kinematics/model.hpp"
#include "robot/base_kinematics.hpp"
#include "robot/hardware.hpp"

namespace concert::robot {

/// A command that cannot be executed (unknown joint, stale model version, not ready, NaN...).
class CommandError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A model that cannot be accepted (unparsable, or its joints differ from the mounted hardware).
class ModelMismatchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Reference for one joint, by name.
struct JointCommand {
  std::string joint;
  DriveMode mode{DriveMode::kPosition};
  double position{0.0};   ///< [rad] or [m]
  double velocity{0.0};   ///< [rad/s] or [m/s]
  double effort{0.0};     ///< feed-forward [Nm] or [N] (position mode adds it to the model gravity torque)
  double stiffness{0.0};  ///< impedance mode [Nm/rad]
  double damping{0.0};    ///< impedance mode [Nm s/rad]
};

/// Joint-level commands for some joints; the others keep what they were doing.
struct JointCommandSet {
  std::uint64_t model_version{0};
  std::vector<JointCommand> joints;
};

/// Admittance along one world axis on top of Cartesian impedance: the target moves along
/// `axis` until the force the end-effector exerts on the environment along `axis` equals
/// `force_setpoint` (m s'' + d s' = F_set - F_measured).
struct Admittance {
  bool enabled{false};
  Eigen::Vector3d axis{0.0, 0.0, -1.0};  ///< unit vector, world frame
  double force_setpoint{0.0};            ///< [N], >= 0 pushes along `axis`
  double mass{2.0};                      ///< virtual mass [kg]
  double damping{400.0};                 ///< virtual damping [N s/m]
  double max_offset{0.2};                ///< bound of the target shift [m]
};

/// Cartesian impedance of one frame: F = K (x_d - x) + D (v_d - v) + F_ff, tau = J^T F + g(q).
struct CartesianCommand {
  std::uint64_t model_version{0};
  std::string frame;                       ///< empty: the end-effector frame
  Eigen::Isometry3d target_pose{Eigen::Isometry3d::Identity()};  ///< world frame
  Vector6d target_twist{Vector6d::Zero()};  ///< [m/s, rad/s], world-aligned
  Vector6d stiffness{(Vector6d() << 800, 800, 800, 60, 60, 60).finished()};  ///< [N/m x3, Nm/rad x3]
  Vector6d damping{(Vector6d() << 80, 80, 80, 6, 6, 6).finished()};         ///< [N s/m x3, Nm s/rad x3]
  Vector6d feedforward_wrench{Vector6d::Zero()};  ///< wrench the frame applies [N, Nm], world-aligned
  Admittance admittance;
  double nullspace_damping{2.0};           ///< joint damping of the arm [Nm s/rad]
};

/// Base twist in the base frame.
struct BaseCommand {
  std::uint64_t model_version{0};
  double vx{0.0};  ///< [m/s]
  double vy{0.0};  ///< [m/s]
  double wz{0.0};  ///< [rad/s]
};

/// Who drives a joint this cycle.
enum class JointOwner : std::uint8_t { kHold, kJoint, kCartesian, kGravityCompensation, kBase };

/// Parameters of the robot core (loaded from YAML by the adapter).
struct RobotParams {
  double period{0.001};                  ///< control period [s] (1 kHz)
  /// Empty: the deepest frame named "tcp" or "tcp_<chain>" (modelgen's naming), else the
  /// deepest leaf link (most movable joints above it).
  std::string end_effector_frame;
  double default_wheel_radius{0.16};     ///< for wheel links without a collision cylinder [m]
  double wrench_filter_time_constant{0.02};  ///< low-pass of the wrench estimate [s]
  double base_command_timeout{0.5};      ///< base stops if no base command for this long [s]
  double velocity_guard_gain{20.0};      ///< damping added above the velocity limit [Nm s/rad]
};

/// Everything the robot publishes, sampled at the end of a cycle.
struct RobotState {
  double time{0.0};                       ///< hardware time [s]
  bool ready{false};
  std::uint64_t model_version{0};
  std::string message;                    ///< human-readable status
  std::vector<std::string> joint_names;   ///< hardware order
  std::vector<double> position, velocity, effort;
  std::vector<JointOwner> owners;         ///< hardware order
  bool has_base{false};
  Odometry odometry;
  std::string end_effector_frame;
  Eigen::Isometry3d end_effector_pose{Eigen::Isometry3d::Identity()};  ///< world (robot root) frame
  /// Estimated external wrench applied ON the end-effector by the environment, at the frame
  /// origin, world-aligned [N, Nm]; from measured joint torques (quasi-static).
  Vector6d end_effector_wrench{Vector6d::Zero()};
};

/// The robot core (XBot2's role): owns one Hardware, runs the 1 kHz joint-level loop,
/// turns joint / Cartesian / gravity-compensation / base commands into drive references
/// with the model's limits enforced, estimates the end-effector wrench, keeps odometry,
/// and reconfigures on a new model version.
///
/// Threads: commands and set_model() may come from any thread; cycle() runs on the loop
/// thread. A mutex guards the shared command/state (held only for copies).
class RobotCore {
 public:
  explicit RobotCore(Hardware& hardware, RobotParams params = {});
  ~RobotCore();

  /// Accepts a new model (URDF text) at `version`: holds every joint, rebuilds
  /// controllers/limits/legs, reports ready. Throws ModelMismatchError (old model kept) if it
  /// cannot be parsed, its joints differ from the mounted hardware, or the version is older.
  /// The mounted hardware is what the last cycle() saw (a hot swap is noticed at the next cycle).
  /// `end_effector_frame` (e.g. from the model's end-effector list) overrides
  /// RobotParams::end_effector_frame when not empty.
  void set_model(const std::string& urdf, std::uint64_t version, const std::string& end_effector_frame = "");

  void command_joints(const JointCommandSet& command);
  void command_cartesian(const CartesianCommand& command);
  void command_base(const BaseCommand& command);
  /// Gravity compensation (teaching mode) for `joints` (empty: the end-effector chain).
  void command_gravity_compensation(std::uint64_t model_version, const std::vector<std::string>& joints = {});
  /// Every joint holds its current position; the base stops.
  void hold();
  /// Safety stop (from the safety layer): while stopped every joint holds where it is and
  /// every command is refused with `reason`; release() lets commands in again (the robot
  /// keeps holding until commanded).
  void set_safety_stop(bool stopped, const std::string& reason = "");
  [[nodiscard]] bool safety_stopped() const;

  /// One control period: read the hardware, compute, write, step it by `params.period`.
  void cycle();

  [[nodiscard]] RobotState state() const;
  [[nodiscard]] bool ready() const;
  [[nodiscard]] std::uint64_t model_version() const;
  [[nodiscard]] const RobotParams& params() const { return params_; }
  /// Joints of the end-effector chain (model order), empty without a model.
  [[nodiscard]] std::vector<std::string> arm_joints() const;
  [[nodiscard]] std::vector<Leg> legs() const;
  /// Current model (null before the first set_model()).
  [[nodiscard]] std::shared_ptr<const kinematics::Model> model() const;

  struct Controllers;

 private:
  void check_command(std::uint64_t model_version) const;
  Hardware& hw_;
  RobotParams params_;
  mutable std::mutex mutex_;
  std::unique_ptr<Controllers> ctl_;
  RobotState state_;
  HardwareState hw_state_;
  std::vector<DriveCommand> drive_;
  std::vector<std::string> hw_joints_;   // as of the last cycle (the loop thread owns hw_)
  std::uint64_t hw_generation_{0};       // as of the last cycle
  std::uint64_t known_generation_{0};    // generation the current model was accepted for
  bool holding_hw_{false};
  bool safety_stopped_{false};
  std::string safety_reason_;
};

}  // namespace concert::robot
