#pragma once
// The follow-me MPC (paper section 5.5.1, eq. 4) with obstacle avoidance (section 5.6, eq. 5),
// solved with Ipopt (Debian's coinor-libipopt-dev, interior point, sequential MUMPS) and warm-
// started from the previous solution. Plain C++ + Eigen; no DDS.
//
// Eq. 4: a virtual mass-damper M x'' + D x' = F_ee driven by the end-effector force; its state
// integrated over the horizon is the end-effector reference. The MPC's state is the planar base
// pose (x, y, theta: the non-flight constraint holds by construction, the base only moves in the
// horizontal plane) and the n arm joints; its inputs are the base velocity (world frame) and the
// joint velocities, integrated with s_{k+1} = s_k + dt u_k. The cost: end-effector tracking of the
// reference, joint velocity and acceleration regularisation, a postural term toward a desired
// joint configuration; bounds on joint positions, velocities and accelerations.
//
// The end-effector position is linearised at the current state each solve (the arm Jacobian and
// the base rotation's derivative), a real-time iteration: the problem is re-solved every cycle at
// the new state, so the linearisation is refreshed at the control rate. The arm's kinematics come
// from the caller (the adapter: libs/kinematics on the current RobotModel; tests: an analytic arm).
//
// Eq. 5, soft: for each active obstacle sphere o (one per radial sector, see obstacle_map.hpp)
// and the robot sphere paired with it, |c_robot(s_k) - o|^2 + sigma >= (r_robot + r_obs + margin)^2
// at every step, sigma >= 0 penalised (linear + quadratic), so the problem stays feasible when a
// person pulls the robot into an obstacle: the robot then stops short instead of failing.

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace concert::collab {

/// A sphere (a circle in the plane for the obstacle constraints): centre [m], radius [m].
struct Sphere {
  Eigen::Vector3d centre{Eigen::Vector3d::Zero()};
  double radius{0.0};
};

/// The robot's collision spheres, in the base frame (only x, y of the centre count).
struct RobotSphere {
  Eigen::Vector2d offset{Eigen::Vector2d::Zero()};  ///< centre in the base frame [m]
  double radius{0.3};                              ///< [m]
};

struct MpcParams {
  std::size_t horizon{10};  ///< steps N
  double dt{0.1};           ///< step [s]
  /// Eq. 4: virtual mass [kg] and damping [N s/m] per axis (x, y, z, world frame).
  Eigen::Vector3d mass{Eigen::Vector3d(8.0, 8.0, 8.0)};
  Eigen::Vector3d damping{Eigen::Vector3d(40.0, 40.0, 60.0)};
  double w_ee{200.0};        ///< end-effector tracking weight [1/m^2]
  double w_posture{2.0};     ///< postural weight [1/rad^2]
  double w_base_vel{0.05};   ///< base velocity regularisation
  double w_joint_vel{0.5};   ///< joint velocity regularisation
  double w_acc{0.5};         ///< acceleration regularisation (input differences)
  double w_slack_lin{500.0}; ///< obstacle slack, linear [1/m^2]
  double w_slack_quad{5e4};  ///< obstacle slack, quadratic
  double base_lin_vel_max{1.0};  ///< |vx|, |vy| [m/s]
  double base_ang_vel_max{1.0};  ///< |omega| [rad/s]
  double base_lin_acc_max{2.0};  ///< [m/s^2]
  double base_ang_acc_max{3.0};  ///< [rad/s^2]
  double joint_acc_max{4.0};     ///< [rad/s^2]
  /// The base's acceleration bounds are never scaled below this share
  /// (MpcInput::base_acceleration_scale), so that the base can always brake [-], in (0, 1].
  double min_base_acceleration_scale{0.1};
  double margin{0.05};           ///< extra clearance added to r_robot + r_obs [m]
  std::size_t max_obstacles{8};  ///< constraint slots (one per sector); unused slots are inert
  int max_iter{50};
  /// Low-pass time constant of the end-effector force before eq. 4 [s]; 0: none. The robot's
  /// estimate is quasi-static: the arm's and the base's accelerations read as force, and the
  /// MPC, chasing those spikes, accelerates the arm into more of them (on the MuJoCo robot, 0.15 s
  /// against none: 2 Ipopt iterations median instead of 5, a peak pull of 33 N instead of 75).
  double force_filter{0.15};
  /// An obstacle within this distance of the one a constraint slot had at the last solve keeps
  /// that slot (and its warm start) [m]; 0: slots follow the order of MpcInput::obstacles and
  /// keep the warm start of whatever obstacle had them at the last solve.
  double slot_match{0.3};
};

/// The arm, as the MPC needs it: joint limits, the desired posture.
struct ArmLimits {
  Eigen::VectorXd q_min, q_max;  ///< [rad]
  Eigen::VectorXd qd_max;        ///< [rad/s], > 0
  Eigen::VectorXd q_posture;     ///< the postural term's target [rad]
};

/// The current state and what the controller measured at it.
struct MpcInput {
  Eigen::Vector3d base{Eigen::Vector3d::Zero()};  ///< x, y [m], theta [rad] (world)
  Eigen::VectorXd q;                               ///< joint positions [rad]
  Eigen::Vector3d ee_in_base{Eigen::Vector3d::Zero()};  ///< end-effector position in the base frame [m]
  Eigen::MatrixXd arm_jacobian;  ///< d ee_in_base / d q, 3 x n (base frame)
  Eigen::Vector3d force{Eigen::Vector3d::Zero()};  ///< end-effector force, world frame [N]
  std::vector<Sphere> obstacles;  ///< active obstacles, world frame (at most max_obstacles)
  /// Time since the previous solve, the control period [s]; 0: one MPC step (params.dt). The
  /// virtual mass-damper advances by it, and the warm start moves one step along the horizon
  /// once a step's time has passed (a 50 Hz loop over 0.1 s steps: every fifth solve).
  double period{0.0};
  /// Share of base_lin_acc_max and base_ang_acc_max usable now, in [0, 1]: what the arm's drives
  /// sustain at this posture (model::DriveBudget). Raised to min_base_acceleration_scale.
  double base_acceleration_scale{1.0};
};

struct MpcResult {
  bool ok{false};
  std::string status;        ///< Ipopt's status, or the reason it was not solved
  Eigen::Vector3d base_velocity{Eigen::Vector3d::Zero()};  ///< vx, vy (world) [m/s], omega [rad/s]
  Eigen::Vector3d base_velocity_local{Eigen::Vector3d::Zero()};  ///< the same in the base frame
  Eigen::VectorXd joint_velocity;  ///< [rad/s]
  Eigen::Vector3d virtual_velocity{Eigen::Vector3d::Zero()};  ///< eq. 4's x' after one control period [m/s]
  Eigen::Vector3d force{Eigen::Vector3d::Zero()};  ///< the force eq. 4 used (after params.force_filter) [N]
  int iterations{0};
  double solve_ms{0.0};      ///< wall time of the solve [ms]
  double solve_cpu_ms{0.0};  ///< the solving thread's CPU time [ms] (a loaded machine's waits left out)
  double max_slack{0.0};  ///< largest obstacle slack (squared-distance units): 0 when clear
  bool warm{false};       ///< warm-started
};

/// The force the MPC takes (world axes, planar: the arm carries the height) from the wrench
/// estimate's force in the base's axes, with the base turned by `base_yaw` [rad].
Eigen::Vector3d planar_world_force(const Eigen::Vector3d& force_in_base, double base_yaw);

/// The arm's command in position mode (the robot adds gravity feed-forward in position mode, not
/// in velocity mode, where a 2 m arm sags): the MPC's joint velocities `qd` integrated over `dt`
/// into `q_cmd` (restarted at `q` when its size differs), kept within `wind_up` [rad] of the
/// measured joints `q`, so a held-back arm does not wind up, and within the joint limits.
void integrate_position_command(Eigen::VectorXd& q_cmd, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                double dt, double wind_up, const ArmLimits& limits);

/// One follow-me controller for one arm. Not thread-safe; one per control loop.
class FollowMeMpc {
 public:
  /// Throws std::invalid_argument naming the bad parameter (sizes, signs, limits).
  FollowMeMpc(MpcParams params, ArmLimits arm, std::vector<RobotSphere> robot_spheres);
  ~FollowMeMpc();
  FollowMeMpc(const FollowMeMpc&) = delete;
  FollowMeMpc& operator=(const FollowMeMpc&) = delete;

  /// Solves once at `in` and advances the virtual mass-damper by one control period
  /// (in.period). Bad input (a size mismatch, NaN, a negative period) gives ok=false with the
  /// reason, never a throw.
  MpcResult solve(const MpcInput& in);

  /// Forgets the warm start and the virtual velocity (on entering follow-me).
  void reset();
  /// The postural term's target from now on (e.g. the carrying posture the arm has when
  /// follow-me starts). Throws std::invalid_argument on a wrong size or a value outside the
  /// joint limits, naming the joint.
  void set_posture(const Eigen::VectorXd& q);

  const MpcParams& params() const { return params_; }
  std::size_t joints() const { return static_cast<std::size_t>(arm_.q_min.size()); }

 private:
  struct Impl;
  MpcParams params_;
  ArmLimits arm_;
  std::vector<RobotSphere> spheres_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::collab
