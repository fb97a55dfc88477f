#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "concert/kinematics/model.hpp"
#include "concert/model/limits.hpp"
#include "concert/model/robot_model.hpp"
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
  /// Mass held at the frame's origin (an object in the gripper) [kg], >= 0: its weight is added
  /// to the gravity compensation, the frame pushes up by m |g| (the model's gravity).
  double payload_mass{0.0};
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

/// Who drives a joint this cycle: the controller that owns it (one owner per joint).
enum class JointOwner : std::uint8_t { kHold, kJoint, kCartesian, kGravityCompensation, kBase, kTrajectory };

/// Name of the controller behind an owner ("hold", "joint", "cartesian_impedance", ...).
std::string_view controller_name(JointOwner owner);

/// Name of the virtual planar-base joints a joint trajectory may carry (odometry frame).
inline constexpr const char* kBaseX = "base_x";
inline constexpr const char* kBaseY = "base_y";
inline constexpr const char* kBaseYaw = "base_yaw";

/// One timed sample of a joint trajectory; vectors are indexed like JointTrajectory::joints.
struct TrajectorySample {
  double time{0.0};              ///< [s] from the start of the trajectory
  std::vector<double> position;  ///< [rad] or [m]
  std::vector<double> velocity;  ///< [rad/s] or [m/s]
};

/// A joint trajectory for the robot's loop to track closed-loop: the joints through their
/// drives (position with velocity feed-forward), the planar base (base_x, base_y, base_yaw,
/// all three or none, in the odometry frame) through the base controller with odometry
/// feedback. Samples are linearly interpolated; times strictly increase from >= 0.
struct JointTrajectory {
  std::uint32_t request_id{0};
  std::uint64_t model_version{0};
  std::string source;
  std::vector<std::string> joints;
  std::vector<TrajectorySample> samples;
};

/// Where the tracked trajectory stands.
enum class TrajectoryState : std::uint8_t { kIdle, kExecuting, kSucceeded, kAborted };

/// Why a trajectory was aborted.
enum class TrajectoryAbort : std::uint8_t {
  kNone,
  kSafetyStop,      ///< the safety layer stopped the robot
  kPreempted,       ///< another command took some of its joints (or hold())
  kModelChanged,    ///< a new model version was switched in
  kHardwareChanged, ///< the mounted hardware changed (hot swap)
  kPathTolerance,   ///< tracking error beyond RobotParams::trajectory_path_tolerance
  kGoalTolerance,   ///< final sample not reached within RobotParams::trajectory_goal_time
};

/// Progress of the last trajectory the loop took (sampled each cycle).
struct TrajectoryProgress {
  std::uint32_t request_id{0};
  std::uint64_t sequence{0};          ///< increases with each trajectory taken (0: none yet)
  TrajectoryState state{TrajectoryState::kIdle};
  TrajectoryAbort abort{TrajectoryAbort::kNone};
  double progress{0.0};               ///< time along the trajectory / its duration [0, 1]
  double duration{0.0};               ///< [s]
  double max_joint_error{0.0};        ///< largest joint tracking error so far [rad] or [m]
  double max_base_error{0.0};         ///< largest base position error so far [m]
  int worst_joint{-1};                ///< model index of the joint with max_joint_error (-1: base)
};

/// Parameters of the robot core (loaded from YAML by the adapter).
struct RobotParams {
  double period{0.001};                  ///< control period [s] (1 kHz)
  /// Empty: the deepest frame named "tcp" or "tcp_<chain>" (modelgen's naming), else the
  /// deepest leaf link (most movable joints above it).
  std::string end_effector_frame;
  double default_wheel_radius{0.16};     ///< a bare URDF's wheel links without a collision cylinder [m]
  double wrench_filter_time_constant{0.02};  ///< low-pass of the wrench estimate [s]
  double base_command_timeout{0.5};      ///< base stops if no base command for this long [s]
  double velocity_guard_gain{20.0};      ///< damping added above the velocity limit [Nm s/rad]
  /// Position guard of the torque-level modes (effort, impedance: Cartesian impedance, gravity
  /// compensation): within this of a position limit [rad or m] (at most a tenth of the joint's
  /// range) a spring pushes the joint back inside, reaching position_guard_torque x its peak
  /// torque at the limit itself, and motion outward is damped; 0: off. A Cartesian target a
  /// joint cannot reach stops the arm short of its limit instead of tripping the safety
  /// service's position rule (its tolerance is 0.02 rad past the limit).
  double position_guard_margin{0.03};
  double position_guard_torque{0.5};     ///< the guard's torque at the limit [-] of the peak torque
  double position_guard_damping{10.0};   ///< against motion outward within the margin [Nm s/rad]
  double trajectory_path_tolerance{0.3};  ///< joint tracking error that aborts a trajectory [rad] or [m]
  double trajectory_base_path_tolerance{0.5};  ///< base position error that aborts it [m]
  double trajectory_goal_tolerance{0.03};  ///< final joint error to succeed [rad] or [m]
  double trajectory_base_goal_tolerance{0.08};  ///< final base position error to succeed [m]
  double trajectory_goal_time{3.0};      ///< time after the last sample to get within the goal tolerance [s]
  double trajectory_base_gain{1.5};      ///< odometry feedback of the base [1/s]
  double trajectory_base_deadband{0.01};  ///< base twists below this keep the steering [m/s, rad/s]
  /// Fraction of the steering velocity limit while tracking a trajectory (base commands use the
  /// whole limit): a conservative margin, sized for a steering without velocity feed-forward,
  /// whose drive's damping at the limit costs more than its continuous torque.
  double trajectory_steering_rate{0.35};
  /// Acceleration of the steering's reference [rad/s^2]: a leg turning 90 degrees peaks at
  /// 5.6 rad/s (of the paper's 8.91) instead of being whipped past its velocity limit.
  double steering_acceleration{20.0};
};

/// Everything the robot publishes, sampled at the end of a cycle.
struct RobotState {
  double time{0.0};                       ///< hardware time [s]
  std::uint64_t cycle{0};                 ///< loop cycles since start
  bool ready{false};
  std::uint64_t model_version{0};
  std::string message;                    ///< human-readable status
  std::vector<std::string> joint_names;   ///< hardware order
  std::vector<double> position, velocity, effort;
  std::vector<JointOwner> owners;         ///< hardware order: the ownership record
  /// Hardware order: each drive's torque limit this cycle [Nm]: its rated peak, less while it
  /// is folded back (0: no limit known).
  std::vector<double> torque_limit;
  bool has_base{false};
  Odometry odometry;
  std::string end_effector_frame;
  Eigen::Isometry3d end_effector_pose{Eigen::Isometry3d::Identity()};  ///< world (robot root) frame
  /// Estimated external wrench applied ON the end-effector by the environment, at the frame
  /// origin, world-aligned [N, Nm]; from measured joint torques (quasi-static).
  Vector6d end_effector_wrench{Vector6d::Zero()};
  TrajectoryProgress trajectory;           ///< the trajectory taken last
  TrajectoryProgress replaced_trajectory;  ///< the last one a newer one replaced while it ran
};

/// The robot core (XBot2's role): owns one Hardware, runs the 1 kHz joint-level loop with
/// controllers behind one interface (ros2_control's shape: each controller owns the joints
/// it claimed; see controllers.hpp), enforces the model's limits, estimates the end-effector
/// wrench, keeps odometry, tracks joint trajectories, and reconfigures on a new model version.
///
/// Threads: cycle() runs on the loop thread and never waits for another thread nor
/// allocates. Commands, set_model() and state() may come from any other thread: commands are
/// checked there and handed to the loop through a lock-free triple buffer; a new model is
/// prepared there in full (controllers, KDL scratch, vectors) and switched in by the loop at
/// the next cycle boundary; the loop hands its state out through another triple buffer.
class RobotCore {
 public:
  explicit RobotCore(Hardware& hardware, RobotParams params = {});
  ~RobotCore();
  RobotCore(const RobotCore&) = delete;
  RobotCore& operator=(const RobotCore&) = delete;

  /// Accepts a new model (URDF text) at `version`: prepares its controllers off the loop,
  /// which switches to it at the next cycle boundary holding every joint, and reports ready.
  /// Throws ModelMismatchError (old model kept) if it cannot be parsed, its joints differ
  /// from the mounted hardware (Hardware::mounted(): what the loop runs after its pending
  /// switch), or the version is older. `end_effector_frame` (e.g. the tool end-effector of
  /// the model message) overrides RobotParams::end_effector_frame when not empty.
  ///
  /// `limits` (the model's limits table, by joint name) gives each joint's continuous torque:
  /// a leg joint (steering, wheel) listed there has its drive's torque limit folded back as its
  /// RMS torque over the thermal window nears the continuous torque
  /// (model::folded_back_torque); arm joints and joints not listed keep their rated peak.
  void set_model(const std::string& urdf, std::uint64_t version, const std::string& end_effector_frame = "",
                 const model::LimitsTable& limits = {});
  /// The model as every service holds it (libs/model), read by role, never guessed: the
  /// end-effector is the model's tool (the one end-effector at the tip of an arm), else
  /// RobotParams::end_effector_frame when set, else the arm chain's tip link, else none (a base
  /// alone); the legs are its steered leg chains, measured (mobile_base::measure_leg;
  /// unsteered wheels are not driven); the limits its table. A description without chains (a
  /// bare URDF with its limits) is run as set_model(urdf, version) runs one. Throws
  /// ModelMismatchError as that does, and naming a leg whose joints are not a steering axis
  /// over a wheel.
  void set_model(const std::shared_ptr<const model::RobotModel>& model);

  void command_joints(const JointCommandSet& command);
  void command_cartesian(const CartesianCommand& command);
  void command_base(const BaseCommand& command);
  /// Gravity compensation (teaching mode) for `joints` (empty: the end-effector chain).
  void command_gravity_compensation(std::uint64_t model_version, const std::vector<std::string>& joints = {});
  /// Checks a joint trajectory (model version, known and distinct joints, base joints all
  /// three or none, sample sizes, finite values, strictly increasing times) and hands it to
  /// the loop, which starts tracking it at the next cycle (aborting the one it replaces).
  /// Throws CommandError naming the problem.
  void command_trajectory(const JointTrajectory& trajectory);
  /// Every joint holds its current position; the base stops; a running trajectory aborts.
  void hold();
  /// Safety stop (from the safety layer): while stopped every joint holds where it is, a
  /// running trajectory aborts, and every command is refused with `reason`; release() lets
  /// commands in again (the robot keeps holding until commanded).
  void set_safety_stop(bool stopped, const std::string& reason = "");
  [[nodiscard]] bool safety_stopped() const;

  /// An IMU sample (any thread but the loop's; from the backend's sensor sink). One on the
  /// base (its root link or a link fixed to it) gives the odometry its yaw rate.
  void on_imu(const hardware::ImuSample& sample);

  /// One control period: switch what was prepared, read the hardware, run the controllers,
  /// write, step it by `params.period`. Loop thread only.
  void cycle();

  /// The latest state the loop handed out.
  [[nodiscard]] RobotState state() const;
  [[nodiscard]] bool ready() const;
  [[nodiscard]] std::uint64_t model_version() const;
  [[nodiscard]] const RobotParams& params() const { return params_; }
  /// Joints of the end-effector chain (model order), empty without a model.
  [[nodiscard]] std::vector<std::string> arm_joints() const;
  [[nodiscard]] std::vector<Leg> legs() const;
  /// Current model (null before the first set_model()).
  [[nodiscard]] std::shared_ptr<const kinematics::Model> model() const;
  /// The ownership record as the loop last published it: joint -> controller name.
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> ownership() const;
  /// Human-readable reason of an aborted trajectory (names the joint for tracking errors).
  [[nodiscard]] std::string describe(const TrajectoryProgress& progress) const;

  /// Throws ModelMismatchError (`what` first) when `version` is older than the accepted one
  /// (what set_model() refuses first; checked before anything is prepared for the model).
  void check_newer(std::uint64_t version, const std::string& what) const;

  struct Slot;
  struct Loop;

 private:
  struct Shared;
  // The model installed with its end-effector frame (checked a link of it), legs and limits.
  void install(std::shared_ptr<const kinematics::Model> model, std::uint64_t version, const std::string& ee,
               std::vector<Leg> legs, const model::LimitsTable& limits);
  void check_command(std::uint64_t model_version) const;
  Hardware& hw_;
  RobotParams params_;
  std::unique_ptr<Shared> shared_;  // non-real-time side (guarded by its own mutex)
  std::unique_ptr<Loop> loop_;      // loop-thread side
};

}  // namespace concert::robot
