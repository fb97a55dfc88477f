#pragma once
// DDS adapter of the collab service: the robot model in (the arm and its tool; status READY at
// the version, or "cannot transport: ..."), commands in (text with the wake phrase, or a bare
// mode/action name from the GUI/CLI), the safety state in (a stop forces the state machine to
// stop), joint states, odometry, the end-effector wrench, the lidar scan and the sonars in.
// Out: the state (latched), and the robot service's commands for each state:
//   teaching        arm gravity-compensated (a zero-gain Cartesian command), base held (0 velocity)
//   teaching/open   + the gripper's jaw joint to its upper limit (close: lower limit), if it has one
//   autonomous      arm held by Cartesian impedance where it is; lift/place: the target moved
//                   up/down by lift_height
//   follow-me       the MPC (eq. 4, 5) every cycle: base velocity + joint velocities
//   stop            base 0, arm held where it is
// DDS callbacks only queue; one control thread runs the machine and the MPC.

#include <atomic>
#include <chrono>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>

#include "collab/command_parser.hpp"
#include "collab/follow_me_mpc.hpp"
#include "collab/obstacle_map.hpp"
#include "collab/state_machine.hpp"
#include "concert/common/command_once.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "concert/model/drive_budget.hpp"
#include "concert/model/robot_model.hpp"

namespace concert::collab::dds {

struct NodeParams {
  double rate{50.0};          ///< control rate [Hz]
  double lift_height{0.15};   ///< lift/place travel [m]
  double hold_stiffness{800.0};  ///< Cartesian hold [N/m]; rotation: a tenth [N m/rad]
  /// The object's mass [kg]: from lift until open, every Cartesian command (the holds, gravity
  /// compensation) tells the robot it carries this payload at the TCP; 0: unknown, none sent.
  double object_mass{0.0};
  MpcParams mpc;
  /// The base's accelerations keep every arm joint and wheel within this share of its
  /// continuous torque (model::DriveBudget) [-], (0, 1].
  double drive_torque_fraction{1.0};
  GridParams grid;
  /// Footprint for the perimeter spheres [m]: the transport base's (lidars at +-0.62 m, sonars
  /// and wheels to +-0.42 m).
  double base_length{1.3};
  double base_width{0.9};
};

class CollabNode {
 public:
  CollabNode(concert::dds::Participant& participant, NodeParams params, std::ostream& log);
  ~CollabNode();
  CollabNode(const CollabNode&) = delete;
  CollabNode& operator=(const CollabNode&) = delete;

  /// Runs the control loop until `stop`.
  void spin(const std::atomic<bool>& stop);

 private:
  struct Rig;  // what the current model offers (arm, tool, kinematics)
  void apply_model(const msg::RobotModel& m);
  void handle(const msg::CollabCommand& c);
  void on_transition(const Transition& t, const msg::CollabCommand* c);
  void enter(const State& s);
  void follow_step();
  /// The MPC's answer at `in` sent: the base's velocity and the arm's position command, or the
  /// base stopped for this cycle when the solve failed.
  void send_follow(const MpcInput& in, const MpcResult& r);
  void hold_here(double dz);
  void gravity_compensation();
  void base_velocity(const Eigen::Vector3d& v);
  void gripper(bool open);
  void publish_state();
  bool arm_state(Eigen::VectorXd& q_full) const;
  void log_line(const std::string& line);

  concert::dds::Participant& participant_;
  NodeParams params_;
  std::ostream& log_;
  concert::dds::StatusReporter status_;
  concert::dds::Writer<msg::CollabState> state_out_;
  concert::dds::Writer<msg::CartesianImpedanceCommand> cartesian_;
  concert::dds::Writer<msg::BaseVelocityCommand> base_;
  concert::dds::Writer<msg::JointCommand> joints_out_;

  mutable std::mutex mutex_;
  std::optional<msg::RobotModel> model_in_;
  std::deque<msg::CollabCommand> commands_;
  concert::CommandOnce commands_seen_;  // (command id, stamp) of the commands taken; under mutex_
  std::optional<msg::SafetyState> safety_;
  std::optional<msg::JointState> joints_;
  std::optional<msg::Odometry> odometry_;
  std::optional<msg::EndEffectorWrench> wrench_;
  std::optional<msg::LaserScan> scan_;
  std::optional<msg::SonarRanges> sonars_;

  concert::dds::Reader<msg::RobotModel> models_;
  concert::dds::Reader<msg::CollabCommand> commands_in_;
  concert::dds::Reader<msg::SafetyState> safety_in_;
  concert::dds::Reader<msg::JointState> joints_in_;
  concert::dds::Reader<msg::Odometry> odometry_in_;
  concert::dds::Reader<msg::EndEffectorWrench> wrench_in_;
  concert::dds::Reader<msg::LaserScan> scan_in_;
  concert::dds::Reader<msg::SonarRanges> sonar_in_;

  // Control thread only.
  StateMachine machine_;
  std::unique_ptr<Rig> rig_;
  std::string rig_error_{"no robot model yet"};
  std::uint32_t model_version_{0};
  msg::CollabState state_msg_;
  std::unique_ptr<FollowMeMpc> mpc_;
  bool carrying_{false};  ///< the object hangs from the gripper (lift .. open): payload sent
  Eigen::VectorXd q_cmd_;  ///< follow-me: the MPC's joint velocities integrated (position mode)
  std::unique_ptr<ObstacleGrid> grid_;
  std::mutex log_mutex_;
};

}  // namespace concert::collab::dds
