#pragma once
// The controllers of the robot's loop, behind one interface (ros2_control's shape): each
// controller owns the joints it claimed (one owner per joint, recorded in CycleData::owner),
// is built with all its memory when a model is prepared (off the loop thread), and computes
// the drive references of its joints each cycle without allocating.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "concert/kinematics/model.hpp"
#include "robot/base_kinematics.hpp"
#include "robot/hardware.hpp"
#include "robot/robot_core.hpp"

namespace concert::robot {

/// Joint-level reference of the joint controller (a JointCommand without the name).
struct JointSetpoint {
  DriveMode mode{DriveMode::kPosition};
  double position{0.0};
  double velocity{0.0};
  double effort{0.0};
  double stiffness{0.0};
  double damping{0.0};
};

/// What every controller reads and writes in one cycle, in model joint order. Sized when the
/// model is prepared; the loop only assigns into it.
struct CycleData {
  CycleData(const kinematics::Model& model, std::size_t arm_joints);

  const kinematics::Model* model{nullptr};
  double time{0.0};  ///< hardware time [s]
  double dt{0.001};  ///< control period [s]
  Eigen::VectorXd q, qd, tau;  ///< measured [rad, rad/s, Nm]
  Eigen::VectorXd gravity;     ///< g(q) [Nm]
  Eigen::VectorXd zero;        ///< zeros (RNE arguments)
  Odometry odometry;  ///< wheel odometry (odometry frame), yaw from the gyro when there is one
  /// Yaw rate of the base from an IMU on it [rad/s] (the latest sample's), NaN: none fresh.
  double base_yaw_rate{std::numeric_limits<double>::quiet_NaN()};
  // End-effector (only with an arm chain).
  Eigen::Isometry3d ee_pose{Eigen::Isometry3d::Identity()};
  Eigen::MatrixXd jacobian;    ///< 6 x dof, world-aligned
  Eigen::MatrixXd jac_arm;     ///< 6 x arm joints
  Eigen::VectorXd qd_arm;      ///< arm joint velocities
  Eigen::VectorXd id_tau;      ///< ID(q, qd, 0)
  Eigen::VectorXd residual;    ///< arm: ID - measured torque
  Vector6d wrench{Vector6d::Zero()};  ///< estimated external wrench on the end-effector
  /// Per joint: who owns it, where a holding joint stays, the rate-limited position
  /// reference, and the drive reference the owner computed this cycle.
  std::vector<JointOwner> owner;
  std::vector<double> hold_position;
  std::vector<double> position_ref;
  std::vector<DriveCommand> drive;
  /// Per joint: a wheel of the base. Rolling when its hold begins, it brakes and stays where it
  /// comes to rest rather than being driven back to where the hold began (HoldController).
  std::vector<char> wheel;

  [[nodiscard]] const kinematics::JointLimits& limits(int i) const {
    return model->joint_limits()[static_cast<std::size_t>(i)];
  }
  /// Clamps a position to joint i's limits.
  [[nodiscard]] double clamp_position(int i, double p) const;
  /// Moves joint i's rate-limited reference towards `target` (clamped to the limits) by at
  /// most `rate` times the velocity limit times dt, and returns it.
  double ramp(int i, double target, double rate = 1.0);
  /// Joint i leaves torque-level control: its references follow the measurement.
  void follow(int i);
  /// Whether a controller that drives a joint each cycle and keeps `last` (the hardware time it
  /// last did) drove it the cycle before too, not another owner; sets `last` to now.
  bool continued(double& last) const {
    const bool kept = time - last <= 1.5 * dt;
    last = time;
    return kept;
  }
  /// Joint i's drive reference, reset to a fresh one in `mode` for its owner to fill in.
  DriveCommand& new_drive(int i, DriveMode mode);
  /// Calls `f(i)` for every joint i that `who` owns, in model order. No allocation.
  template <class F>
  void for_each_owned_by(JointOwner who, F&& f) {
    for (std::size_t iu = 0; iu < owner.size(); ++iu) {
      if (owner[iu] == who) {
        f(static_cast<int>(iu));
      }
    }
  }
};

/// One controller of the loop.
class Controller {
 public:
  virtual ~Controller() = default;
  /// The owner tag of the joints this controller drives.
  [[nodiscard]] virtual JointOwner kind() const = 0;
  /// Computes data.drive[i] for every joint i with data.owner[i] == kind(). No allocation.
  virtual void update(CycleData& data) = 0;
};

/// Keeps joints where they were left (position mode, gravity feed-forward).
class HoldController final : public Controller {
 public:
  explicit HoldController(int dof)
      : held_at_(static_cast<std::size_t>(dof), -1e9), braking_(static_cast<std::size_t>(dof), 0) {}
  [[nodiscard]] JointOwner kind() const override { return JointOwner::kHold; }
  void update(CycleData& data) override;

 private:
  std::vector<double> held_at_;  // per joint: hardware time this controller last held it
  std::vector<char> braking_;    // per joint: a wheel rolling when its hold began, not yet stopped
};

/// Joint position / velocity / effort / impedance references, per joint.
class JointController final : public Controller {
 public:
  explicit JointController(int dof) : setpoints_(static_cast<std::size_t>(dof)) {}
  [[nodiscard]] JointOwner kind() const override { return JointOwner::kJoint; }
  void set(int joint, const JointSetpoint& setpoint) { setpoints_[static_cast<std::size_t>(joint)] = setpoint; }
  void update(CycleData& data) override;

 private:
  std::vector<JointSetpoint> setpoints_;
};

/// Cartesian impedance of the end-effector frame, with admittance along one axis.
class CartesianController final : public Controller {
 public:
  explicit CartesianController(const std::vector<int>& arm);
  [[nodiscard]] JointOwner kind() const override { return JointOwner::kCartesian; }
  /// New target; `keep_admittance` keeps the admittance offset (same admittance running).
  void set(const CartesianCommand& command, bool keep_admittance);
  void update(CycleData& data) override;

 private:
  std::vector<int> arm_;
  CartesianCommand command_;
  Eigen::VectorXd tau_arm_;
  double offset_{0.0};
  double rate_{0.0};
};

/// Gravity compensation (teaching mode): effort = g(q).
class GravityCompensationController final : public Controller {
 public:
  [[nodiscard]] JointOwner kind() const override { return JointOwner::kGravityCompensation; }
  void update(CycleData& data) override;
};

/// Base velocity through the steering+wheel legs; also integrates the odometry.
class BaseController final : public Controller {
 public:
  /// `trajectory_steering_rate`: fraction of the steering velocity limit used while a
  /// trajectory drives the legs; `steering_acceleration`: of the steering's reference [rad/s^2].
  BaseController(std::vector<Leg> legs, double command_timeout, double trajectory_steering_rate,
                 double steering_acceleration = 20.0);
  [[nodiscard]] JointOwner kind() const override { return JointOwner::kBase; }
  /// New twist (base frame) at hardware time `time`.
  void set(const BaseCommand& command, double time);
  /// Integrates the odometry from the measured legs (every cycle, whoever owns the legs); its
  /// yaw from the base's gyro (data.base_yaw_rate) when there is one: the wheels' yaw rate is
  /// off by their scrub in turns (3 % on the paper's base in simulation) and misses the base
  /// turning while the legs steer, which over a 1.7 m approach puts the demo's odometry 15 cm
  /// off. The gyro's bias is learnt while the whole robot stands still (a zero-velocity update:
  /// no wheel rolls, no leg steers, no arm joint moves).
  void estimate(CycleData& data);
  /// The gyro bias learnt so far [rad/s].
  [[nodiscard]] double gyro_bias() const { return gyro_bias_; }
  void update(CycleData& data) override;
  /// Drives the legs owned by `owner` towards `twist` (base frame; vx, vy [m/s], wz [rad/s]).
  void drive_legs(CycleData& data, const Eigen::Vector3d& twist, JointOwner owner);
  [[nodiscard]] const std::vector<Leg>& legs() const { return kinematics_.legs(); }

 private:
  /// Leg k's steering drive reference towards `target` at up to `rate` of its velocity limit.
  void steer(CycleData& data, std::size_t k, double target, double rate, DriveCommand& d);
  /// Leg k's wheel (joint w; its steering s), told to roll at `commanded` [rad/s] under base
  /// commands: true when it stands, held in position where it came to rest (its drive set).
  bool stands(CycleData& data, std::size_t k, int s, int w, double commanded);
  BaseKinematics kinematics_;
  double timeout_;
  double trajectory_steering_rate_;
  double steering_acceleration_;
  std::vector<double> steering_ref_rate_;  // per leg: the steering reference's rate [rad/s]
  std::vector<double> steered_at_;         // per leg: hardware time this controller last steered it
  std::vector<double> stood_at_;           // per leg: hardware time its wheel was last driven here
  std::vector<double> stand_;              // per leg: where its wheel stands [rad], NaN: rolling
  Eigen::Vector3d twist_{Eigen::Vector3d::Zero()};
  double command_time_{-1e9};
  std::vector<double> steering_, wheel_velocity_, steering_rate_;
  std::vector<LegSetpoint> setpoints_;
  double gyro_bias_{0.0};  // [rad/s], learnt while the whole robot stands still
  double bias_samples_{0.0};  // samples the bias was learnt from
  bool gyro_bias_known_{false};
};

/// A trajectory checked and mapped onto the model's joints (made off the loop thread).
struct PreparedTrajectory {
  std::uint32_t request_id{0};
  std::uint64_t sequence{0};
  std::vector<int> joints;         ///< model indices of the tracked joints
  bool base{false};                ///< base_x, base_y, base_yaw follow the joints' columns
  int columns{0};                  ///< joints.size() + 3 if base
  std::vector<double> times;       ///< [s], strictly increasing
  std::vector<double> position;    ///< times.size() x columns, row-major
  std::vector<double> velocity;    ///< same
  [[nodiscard]] double duration() const { return times.empty() ? 0.0 : times.back(); }
};

/// Tracks a PreparedTrajectory closed-loop: joints in position mode with velocity
/// feed-forward through their drives, the base by odometry feedback through the base
/// controller's legs. Owns the trajectory's joints (and the legs) while it runs; afterwards
/// they hold the final sample.
class TrajectoryController final : public Controller {
 public:
  TrajectoryController(int dof, const RobotParams& params, BaseController* base);
  [[nodiscard]] JointOwner kind() const override { return JointOwner::kTrajectory; }
  /// Starts `trajectory` (the loop keeps it alive until it is replaced): claims its joints.
  void start(const PreparedTrajectory* trajectory, CycleData& data);
  /// Stops a running trajectory with `reason`; its joints hold where they are.
  void abort(TrajectoryAbort reason, CycleData& data);
  [[nodiscard]] bool running() const { return progress_.state == TrajectoryState::kExecuting; }
  [[nodiscard]] const PreparedTrajectory* trajectory() const { return trajectory_; }
  [[nodiscard]] const TrajectoryProgress& progress() const { return progress_; }
  /// The last trajectory another one replaced while it ran (aborted, preempted).
  [[nodiscard]] const TrajectoryProgress& replaced() const { return replaced_; }
  void update(CycleData& data) override;

 private:
  void sample(double t);
  void release(CycleData& data, bool to_final);
  const RobotParams& params_;
  BaseController* base_;
  const PreparedTrajectory* trajectory_{nullptr};
  double start_time_{0.0};
  TrajectoryProgress progress_;
  TrajectoryProgress replaced_;
  std::vector<double> q_ref_, qd_ref_;  // current sample, trajectory columns
};

}  // namespace concert::robot
