#pragma once
// The collaborative transport of paper sections 5.5-5.6 (issue #18) in the simulator, shared by
// collab_transport_test and bench_collab_transport: the paper's transport robot
// (deploy/demo/transport_robot.yaml: mobile base, 7-DoF arm, active gripper) in MuJoCo
// (libs/sim) under the robot core (services/robot), a simulated person, and the collab core
// (services/collab: Fig. 12's state machine, the text command parser, the follow-me MPC and the
// obstacle grid) telling the robot core what to do in each state, as the collab service's DDS
// adapter does (src/dds/collab_node.cpp).
//
// In-process and in simulated time, not over DDS with the services as processes: on this
// machine (2 cores shared, loaded) a real-time run measures the load (the MPC's 10-30 ms solves
// against a 1 kHz MuJoCo loop), not the controller; here the physics runs at 1 kHz, the collab
// loop at its rate in simulated time, whatever a solve costs in wall time. The DDS path of the
// same commands is collab_dds_test's. This lives in tests/system because it joins two services'
// cores (services do not link each other).
//
// The person (issue #18, "Simulated person"): a spring-damper from the person's hand to the
// gripper's TCP (150 N/m, 30 N s/m), an external force on the TCP body in MuJoCo
// (SimHardware::set_external_force); the hand guides the TCP in teaching, lets go while the robot
// closes, lifts and places, and in follow-me walks a route at walking speed past a pillar and a
// crate. The robot measures the pull only as the robot core estimates it from its joint torques
// (RobotState::end_effector_wrench); the MPC gets the obstacles as the grid would from an ideal
// lidar (points on the obstacles' outlines, world truth, not the simulated lidar: its threads run
// beside the loop in wall time and would make the run depend on the machine's load).
// The object itself is not a simulated body (the grasp is the jaw closing on nothing; its weight
// can hang from the TCP, Params::object_mass): "placed" means the gripper was lowered by the lift
// height at the route's end and opened.

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "collab/command_parser.hpp"
#include "collab/follow_me_mpc.hpp"
#include "collab/obstacle_map.hpp"
#include "collab/state_machine.hpp"
#include "concert/kinematics/model.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/world/geometry.hpp"
#include "concert/world/world.hpp"
#include "robot/robot_core.hpp"

namespace concert::system_test::transport {

struct Params {
  double walk_speed{0.5};        ///< the person's walking speed along the route [m/s]
  double hand_stiffness{150.0};  ///< the person's arm: spring [N/m]
  double hand_damping{30.0};     ///< and damper [N s/m]
  double control_rate{50.0};     ///< the collab loop [Hz] (the service's default)
  bool see_obstacles{true};      ///< false: the MPC gets no obstacles (the counter-test)
  double lift{0.15};             ///< lift/place travel [m] (the service's default)
  /// The transport base's footprint [m]: lidars at +-0.62 m, sonars and wheels to +-0.42 m.
  double base_length{1.3};
  double base_width{0.9};
  double hold_stiffness{800.0};  ///< autonomous/stop Cartesian hold [N/m] (the service's default)
  collab::MpcParams mpc{};
  /// Tell the MPC the control period (MpcInput::period); false: the old behaviour, one MPC step
  /// per solve (the bench's before/after).
  bool mpc_knows_period{true};
  double follow_timeout{45.0};  ///< simulated seconds of follow-me at most [s]
  /// The object: its weight hangs from the TCP (an external force in MuJoCo) from lift until the
  /// gripper opens [kg]; 0: no object (the jaw closes on nothing).
  double object_mass{0.0};
  /// Collab tells the robot the object's mass (CartesianCommand::payload_mass, as the adapter's
  /// --object-mass); false: the counter-test, the robot does not know it carries anything.
  bool send_payload{true};
  /// End the run after lift and this long a hold in autonomous/lift [s]; < 0: the whole task.
  double stop_after_lift{-1.0};
  /// A cart (0.8 x 0.5 m) pushed along the route the other way on the pillar's side, 0.45 m
  /// from the route's line at 0.5 m/s, meeting the robot between the pillar and the crate
  /// (transport_world(true)).
  bool cart{false};
};

/// What happened, judged against the simulator's truth.
struct Result {
  std::vector<std::string> states;   ///< every state entered, in order ("teaching/general", ...)
  std::vector<std::string> log;      ///< each command said, and what became of it
  std::vector<std::string> ignored;  ///< the commands the machine ignored, with the reason
  // Teaching, lift, place, gripper.
  double guided{0.0};      ///< how far the hand moved the gravity-compensated TCP in teaching [m]
  double lifted{0.0};      ///< TCP height gained by lift [m]
  /// TCP height after lift against its target (the height when lift was said + the lift) [m];
  /// negative: below it (a payload the robot does not compensate sags).
  double lift_error{0.0};
  double placed{0.0};      ///< TCP height lost by place [m]
  double jaw_closed{0.0};  ///< jaw after close [rad]
  double jaw_final{0.0};   ///< jaw after open [rad]
  double jaw_open{0.0}, jaw_shut{0.0};  ///< the jaw's open and closed limits [rad]
  // Follow-me.
  double route_length{0.0};  ///< the hand's route [m]
  double follow_time{0.0};   ///< simulated time in follow-me [s]
  double base_travel{0.0};   ///< path length of the base [m]
  double end_error{0.0};     ///< TCP to the route's end, in the plane, when place was said [m]
  double mean_lag{0.0};      ///< mean hand - TCP distance in the plane while walking [m]
  double max_lag{0.0};       ///< [m]
  double peak_force{0.0};    ///< largest pull the person applied (truth, plane) [N]
  double peak_force_estimated{0.0};  ///< largest planar force the robot estimated [N]
  double mean_force{0.0};            ///< mean pull while walking (truth, plane) [N]
  double min_clearance{
      std::numeric_limits<double>::infinity()};  ///< footprint to obstacles (truth) [m]
  double min_sphere_clearance{
      std::numeric_limits<double>::infinity()};  ///< the MPC's robot spheres [m]
  double min_cart_clearance{
      std::numeric_limits<double>::infinity()};  ///< footprint to the moving cart (truth) [m]
  double peak_contact{0.0};  ///< largest force the world put on the base or arm (a collision) [N]
  std::vector<double> solve_ms;      ///< every MPC solve (wall time)
  std::vector<double> solve_cpu_ms;  ///< the same, the thread's CPU time
  std::vector<int> iterations;       ///< Ipopt iterations of each solve
  std::vector<bool> warm;            ///< each solve warm-started
  std::vector<double> force_estimated;  ///< the planar force the MPC got, each solve [N]
  std::vector<double> force_true;       ///< the person's planar pull at that solve (truth) [N]
  std::map<std::string, int> statuses;  ///< how the solves ended, counted
  int failures{0};                   ///< solves that gave no command
  double wall_seconds{0.0};          ///< the whole run's wall time
};

/// The route the person walks (the hand's positions, world frame, starting at the TCP) and the
/// obstacles near it: a pillar (r 0.15 m, 0.55 m left of the route) and a crate (0.6 x 0.4 m, its
/// edge 0.55 m right of it) that a base following the hand straight would hit (the footprint is
/// 0.45 m wide each side), then a turn left.
inline world::World transport_world(bool cart = false) {
  world::World w;
  world::WorldShape pillar;
  pillar.name = "pillar";
  pillar.type = world::WorldShape::Type::kCylinder;
  pillar.size = Eigen::Vector3d(0.15, 0.0, 2.5);
  pillar.position = Eigen::Vector3d(3.6, 0.55, 1.25);
  world::WorldShape crate;
  crate.name = "crate";
  crate.type = world::WorldShape::Type::kBox;
  crate.size = Eigen::Vector3d(0.6, 0.4, 0.8);
  crate.position = Eigen::Vector3d(6.2, -0.75, 0.4);
  w.obstacles = {pillar, crate};
  if (cart) {
    // From x 14 m at t = 0 toward x -2 m at 0.5 m/s: at the route's turn (x 7.8 m) by t = 12 s,
    // long before the person (t ~ 22 s), past the robot's base at x ~ 4.8 m, t ~ 18 s. Its edge
    // 0.45 m left of the route's line (y 0); the pillar's reaches 0.7 m, the cart's 0.9 m.
    world::WorldShape c;
    c.name = "cart";
    c.type = world::WorldShape::Type::kBox;
    c.size = Eigen::Vector3d(0.8, 0.5, 0.9);
    c.position = Eigen::Vector3d(14.0, 1.15, 0.45);
    c.path = world::ObstaclePath{{Eigen::Vector2d(-2.0, 1.15)}, 0.5, world::ObstaclePath::Mode::kOnce};
    w.obstacles.push_back(c);
  }
  return w;
}

/// The hand's route after the TCP's start (x, y offsets, world frame) [m].
inline std::vector<Eigen::Vector2d> route_offsets() {
  return {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(6.5, 0.0), Eigen::Vector2d(8.0, 1.5)};
}

namespace detail {

/// Points on the outline of an obstacle in the plane (world frame), `step` apart [m].
inline std::vector<Eigen::Vector2d> outline(const world::WorldShape& s, double t, double step) {
  const Eigen::Vector2d c = world::obstacle_position(s, t).head<2>();
  std::vector<Eigen::Vector2d> pts;
  if (s.type == world::WorldShape::Type::kCylinder) {
    const int n = std::max(8, static_cast<int>(std::ceil(2 * M_PI * s.size.x() / step)));
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      pts.push_back(c + s.size.x() * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
    return pts;
  }
  const Eigen::Rotation2Dd R(s.yaw);
  const double hx = s.size.x() / 2, hy = s.size.y() / 2;
  const std::vector<Eigen::Vector2d> corners{{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};
  for (std::size_t k = 0; k < 4; ++k) {
    const Eigen::Vector2d a = corners[k], b = corners[(k + 1) % 4];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
    for (int i = 0; i < n; ++i) pts.push_back(c + R * (a + (b - a) * (static_cast<double>(i) / n)));
  }
  return pts;
}

/// Distance from a point (world) to the obstacle's surface in the plane; < 0 inside [m].
inline double distance_to(const world::WorldShape& s, double t, const Eigen::Vector2d& p) {
  const Eigen::Vector2d c = world::obstacle_position(s, t).head<2>();
  if (s.type == world::WorldShape::Type::kCylinder) return (p - c).norm() - s.size.x();
  const Eigen::Vector2d local = Eigen::Rotation2Dd(-s.yaw) * (p - c);
  const Eigen::Vector2d d = local.cwiseAbs() - Eigen::Vector2d(s.size.x() / 2, s.size.y() / 2);
  return d.cwiseMax(0.0).norm() + std::min(0.0, d.maxCoeff());
}

/// Distance from a point (base frame) to the footprint rectangle; < 0 inside [m].
inline double to_rectangle(const Eigen::Vector2d& p, double length, double width) {
  const Eigen::Vector2d d = p.cwiseAbs() - Eigen::Vector2d(length / 2, width / 2);
  return d.cwiseMax(0.0).norm() + std::min(0.0, d.maxCoeff());
}

/// Arc-length parametrised polyline.
struct Route {
  std::vector<Eigen::Vector2d> pts;
  double length() const {
    double l = 0;
    for (std::size_t i = 1; i < pts.size(); ++i) l += (pts[i] - pts[i - 1]).norm();
    return l;
  }
  Eigen::Vector2d at(double s) const {
    for (std::size_t i = 1; i < pts.size(); ++i) {
      const double l = (pts[i] - pts[i - 1]).norm();
      if (s <= l) return pts[i - 1] + (pts[i] - pts[i - 1]) * (s / l);
      s -= l;
    }
    return pts.back();
  }
};

}  // namespace detail

/// Runs the whole task: teaching -> close -> lift -> (open: ignored) -> follow me along the route
/// (open: ignored) -> place -> teaching -> open. Throws std::runtime_error naming what is
/// missing (the robot's files, the gripper, the TCP body).
inline Result run(const std::string& source_dir, const Params& params = {}) {
  using collab::Command;
  const auto wall0 = std::chrono::steady_clock::now();
  Result res;

  const sim::AssemblyBuilder builder({source_dir + "/data/module_db"});
  const sim::SimulatedRobot robot = builder.build(source_dir + "/deploy/demo/transport_robot.yaml");
  const kinematics::Model kin = kinematics::Model::from_urdf_string(robot.urdf);
  kinematics::Data kd = kin.make_data();

  // The carrying posture (elbow down, the TCP 1.26 m ahead of the base at 1 m, gripper down) and
  // an open jaw.
  sim::SimParams sp;
  sp.initial_positions = {{"J2_E", 0.65}, {"J4_E", 1.05}, {"J6_E", 1.40}};
  world::World world = transport_world(params.cart);
  sim::SimHardware sim(robot.urdf, world, sp);
  robot::RobotCore core(sim);
  core.set_model(robot.urdf, 1);
  const std::uint64_t version = 1;

  // The arm (as the adapter's Rig: the end-effector chain's joints that move the TCP) and the jaw.
  for (int i = 0; i < 10; ++i) core.cycle();
  const std::string tcp = core.state().end_effector_frame;
  std::vector<std::string> arm;
  std::vector<int> arm_index;
  std::string jaw;
  for (const auto& j : core.arm_joints()) {
    const int k = kin.joint_index_or_throw(j);
    const auto links = kin.subtree_links(k);
    if (std::find(links.begin(), links.end(), tcp) != links.end()) {
      arm.push_back(j);
      arm_index.push_back(k);
    } else if (jaw.empty()) {
      jaw = j;
    }
  }
  if (jaw.empty()) {
    for (int d : kin.descendant_joints(arm_index.back()))
      if (std::find(arm_index.begin(), arm_index.end(), d) == arm_index.end()) {
        jaw = kin.joint_names()[static_cast<std::size_t>(d)];
        break;
      }
  }
  if (arm.empty() || jaw.empty()) throw std::runtime_error("transport: no arm or no jaw on " + tcp);
  const auto& jaw_limits =
      kin.joint_limits()[static_cast<std::size_t>(kin.joint_index_or_throw(jaw))];
  res.jaw_open = jaw_limits.upper;
  res.jaw_shut = jaw_limits.lower;
  const auto n = static_cast<Eigen::Index>(arm.size());
  collab::ArmLimits limits;
  limits.q_min.resize(n);
  limits.q_max.resize(n);
  limits.qd_max.resize(n);
  limits.q_posture = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& l =
        kin.joint_limits()[static_cast<std::size_t>(arm_index[static_cast<std::size_t>(i)])];
    limits.q_min[i] = l.lower;
    limits.q_max[i] = l.upper;
    limits.qd_max[i] = std::min(l.velocity, 1.0);
  }
  const auto spheres = collab::perimeter_spheres(params.base_length, params.base_width);
  collab::FollowMeMpc mpc(params.mpc, limits, spheres);
  collab::ObstacleGrid grid(collab::GridParams{});

  // Model-order q from the robot's state.
  const auto model_q = [&](const robot::RobotState& s) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(kin.dof());
    for (std::size_t h = 0; h < s.joint_names.size(); ++h)
      if (const auto k = kin.joint_index(s.joint_names[h])) q[*k] = s.position[h];
    return q;
  };
  const auto jaw_position = [&](const robot::RobotState& s) {
    for (std::size_t h = 0; h < s.joint_names.size(); ++h)
      if (s.joint_names[h] == jaw) return s.position[h];
    return std::nan("");
  };
  // (Named Isometry3d copies: GCC 12 warns about the temporaries' storage otherwise.)
  const auto tcp_world = [&] {
    const Eigen::Isometry3d T = sim.link_pose(tcp);
    return Eigen::Vector3d(T.translation());
  };
  const auto base_xy = [&] {
    const Eigen::Isometry3d T = sim.base_pose();
    return Eigen::Vector2d(T.translation().head<2>());
  };

  // The person's hand: grips (a spring-damper to the TCP) or not.
  bool gripping = false;
  Eigen::Vector3d hand = Eigen::Vector3d::Zero(), hand_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_tcp = tcp_world();
  Eigen::Vector3d pull = Eigen::Vector3d::Zero();

  // The collab side: the machine and what each state tells the robot core (CollabNode::enter).
  collab::StateMachine machine;
  Eigen::VectorXd q_cmd;  // follow-me: the integrated joint positions sent to the arm
  bool carrying = false;  // the object hangs from the gripper (lift .. open), as the adapter's
  const auto payload = [&] { return carrying && params.send_payload ? params.object_mass : 0.0; };
  const auto hold_here = [&](double dz) {
    // The Cartesian target is in the robot's model frame (its root: the base), as the core's
    // RobotState::end_effector_pose.
    robot::CartesianCommand c;
    c.model_version = version;
    c.frame = tcp;
    const robot::RobotState now = core.state();
    c.target_pose = now.end_effector_pose;
    c.target_pose.translation().z() += dz;
    const double k = params.hold_stiffness;
    const double d = 2.0 * std::sqrt(k * 5.0);
    c.stiffness << k, k, k, k / 10, k / 10, k / 10;
    c.damping << d, d, d, d / 10, d / 10, d / 10;
    c.payload_mass = payload();
    core.command_cartesian(c);
  };
  const auto gravity_compensation = [&] {
    robot::CartesianCommand c;
    c.model_version = version;
    c.frame = tcp;
    const robot::RobotState now = core.state();
    c.target_pose = now.end_effector_pose;
    c.stiffness.setZero();
    c.damping.setZero();
    c.payload_mass = payload();
    core.command_cartesian(c);
  };
  const auto base_zero = [&] { core.command_base({version, 0.0, 0.0, 0.0}); };
  const auto enter = [&](const collab::State& s) {
    res.states.push_back(collab::state_name(s));
    if (s.mode == collab::Mode::kAutonomous && s.sub == collab::SubState::kLift) carrying = true;
    if (s.mode == collab::Mode::kTeaching && s.sub == collab::SubState::kOpen) carrying = false;
    switch (s.mode) {
      case collab::Mode::kTeaching:
        base_zero();
        gravity_compensation();
        if (s.sub == collab::SubState::kOpen || s.sub == collab::SubState::kClose) {
          robot::JointCommandSet j;
          j.model_version = version;
          robot::JointCommand jc;
          jc.joint = jaw;
          jc.mode = robot::DriveMode::kPosition;
          jc.position = s.sub == collab::SubState::kOpen ? res.jaw_open : res.jaw_shut;
          j.joints.push_back(jc);
          core.command_joints(j);
        }
        break;
      case collab::Mode::kAutonomous:
        base_zero();
        hold_here(s.sub == collab::SubState::kLift    ? params.lift
                  : s.sub == collab::SubState::kPlace ? -params.lift
                                                      : 0.0);
        break;
      case collab::Mode::kFollowMe: {
        mpc.reset();
        const Eigen::VectorXd q = model_q(core.state());
        q_cmd.resize(n);
        for (Eigen::Index i = 0; i < n; ++i) q_cmd[i] = q[arm_index[static_cast<std::size_t>(i)]];
        mpc.set_posture(q_cmd);  // keep the carrying posture
        break;
      }
      case collab::Mode::kStop:
        base_zero();
        hold_here(0.0);
        break;
    }
  };
  const auto say = [&](Command c) {
    const std::string text = std::string("hey concert ") + collab::command_phrase(c);
    const auto parsed = collab::parse_command(text);
    if (!parsed.command)
      throw std::runtime_error("transport: \"" + text + "\" not parsed: " + parsed.reason);
    const auto t = machine.apply(*parsed.command);
    res.log.push_back("\"" + text +
                      "\": " + (t.accepted ? collab::state_name(t.to) : "ignored: " + t.reason));
    if (t.accepted) {
      enter(t.to);
    } else {
      res.ignored.push_back(std::string(collab::command_name(c)) + ": " + t.reason);
    }
  };

  // One follow-me cycle (CollabNode::follow_step on the core's state).
  const double ctrl_dt = 1.0 / params.control_rate;
  const world::World* wp = &world;
  const auto follow_step = [&] {
    const robot::RobotState s = core.state();
    const Eigen::VectorXd q = model_q(s);
    collab::MpcInput in;
    in.base = Eigen::Vector3d(s.odometry.x, s.odometry.y, s.odometry.yaw);
    in.q.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) in.q[i] = q[arm_index[static_cast<std::size_t>(i)]];
    in.ee_in_base = kin.frame_pose(kd, q, tcp).translation();
    const Eigen::MatrixXd J = kin.frame_jacobian(kd, q, tcp);
    in.arm_jacobian.resize(3, n);
    for (Eigen::Index i = 0; i < n; ++i)
      in.arm_jacobian.col(i) = J.block(0, arm_index[static_cast<std::size_t>(i)], 3, 1);
    // The estimate is in the base's axes: the MPC wants the world's (the pull is planar).
    const Eigen::Vector2d f_base = s.end_effector_wrench.head<2>();
    const Eigen::Vector2d f_world = Eigen::Rotation2Dd(s.odometry.yaw) * f_base;
    in.force = Eigen::Vector3d(f_world.x(), f_world.y(), 0.0);
    res.peak_force_estimated = std::max(res.peak_force_estimated, f_world.norm());
    grid.reset(in.base.head<2>());
    if (params.see_obstacles)
      for (const auto& o : wp->obstacles)
        for (const auto& p : detail::outline(o, sim.time(), 0.05)) grid.add_point(p);
    in.obstacles = grid.active(in.base.head<2>());
    if (in.obstacles.size() > params.mpc.max_obstacles)
      in.obstacles.resize(params.mpc.max_obstacles);
    in.period = params.mpc_knows_period ? ctrl_dt : 0.0;
    const collab::MpcResult r = mpc.solve(in);
    res.solve_ms.push_back(r.solve_ms);
    res.solve_cpu_ms.push_back(r.solve_cpu_ms);
    res.iterations.push_back(r.iterations);
    res.warm.push_back(r.warm);
    res.force_estimated.push_back(in.force.head<2>().norm());
    res.force_true.push_back(pull.head<2>().norm());
    ++res.statuses[r.status];
    if (!r.ok) {
      ++res.failures;
      base_zero();
      return;
    }
    core.command_base(
        {version, r.base_velocity_local.x(), r.base_velocity_local.y(), r.base_velocity_local.z()});
    // The arm in position mode (gravity feed-forward): the MPC's velocities integrated, kept
    // within 0.1 rad of where the joints are (a held-back arm does not wind up).
    robot::JointCommandSet j;
    j.model_version = version;
    for (Eigen::Index i = 0; i < n; ++i) {
      q_cmd[i] = std::clamp(q_cmd[i] + r.joint_velocity[i] * ctrl_dt, in.q[i] - 0.1, in.q[i] + 0.1);
      q_cmd[i] = std::clamp(q_cmd[i], limits.q_min[i], limits.q_max[i]);
      robot::JointCommand jc;
      jc.joint = arm[static_cast<std::size_t>(i)];
      jc.mode = robot::DriveMode::kPosition;
      jc.position = q_cmd[i];
      jc.velocity = r.joint_velocity[i];
      j.joints.push_back(jc);
    }
    core.command_joints(j);
  };

  // The contact check: the world's force on the base and the arm (the wheels roll on the floor).
  std::vector<std::string> body_links{"base_link"};
  for (const auto& f : kin.frame_names())
    if (f.size() > 2 && f.compare(f.size() - 2, 2, "_E") == 0 && f.rfind("L_", 0) == 0)
      body_links.push_back(f);

  // Runs the loop for `seconds` of simulated time; `during` runs each physics cycle.
  const double dt = core.params().period;
  const int per_ctrl = std::max(1, static_cast<int>(std::lround(ctrl_dt / dt)));
  long cycle = 0;
  const auto run_for = [&](double seconds, auto&& during) {
    const long cycles = std::lround(seconds / dt);
    for (long k = 0; k < cycles; ++k, ++cycle) {
      during();
      const Eigen::Vector3d p = tcp_world();
      const Eigen::Vector3d v = (p - last_tcp) / dt;
      last_tcp = p;
      if (gripping) {
        pull = params.hand_stiffness * (hand - p) + params.hand_damping * (hand_velocity - v);
      } else {
        pull.setZero();
      }
      // The object's weight while it hangs from the gripper (no inertia: a point load).
      const Eigen::Vector3d weight = carrying ? Eigen::Vector3d(0.0, 0.0, -9.81 * params.object_mass)
                                              : Eigen::Vector3d::Zero();
      if (gripping || weight.z() != 0.0) {
        sim.set_external_force(tcp, pull + weight, p);
      } else {
        sim.clear_external_force();
      }
      if (cycle % per_ctrl == 0) {
        const collab::Mode m = machine.state().mode;
        if (m == collab::Mode::kFollowMe) {
          follow_step();
        } else {
          base_zero();
          if (m == collab::Mode::kTeaching && cycle % 200 == 0) gravity_compensation();
        }
      }
      core.cycle();
      if (cycle % 10 == 0) {
        res.peak_contact = std::max(res.peak_contact, sim.contact_force_on(body_links).norm());
        const Eigen::Isometry3d B = sim.base_pose();
        const double yaw = std::atan2(B.linear()(1, 0), B.linear()(0, 0));
        const Eigen::Vector2d b = B.translation().head<2>();
        for (const auto& o : wp->obstacles) {
          for (const auto& pt : detail::outline(o, sim.time(), 0.01)) {
            const Eigen::Vector2d local = Eigen::Rotation2Dd(-yaw) * (pt - b);
            const double d = detail::to_rectangle(local, params.base_length, params.base_width);
            res.min_clearance = std::min(res.min_clearance, d);
            if (o.name == "cart") res.min_cart_clearance = std::min(res.min_cart_clearance, d);
          }
          for (const auto& sph : spheres) {
            const Eigen::Vector2d c = b + Eigen::Rotation2Dd(yaw) * sph.offset;
            res.min_sphere_clearance = std::min(res.min_sphere_clearance,
                                                detail::distance_to(o, sim.time(), c) - sph.radius);
          }
        }
      }
    }
  };
  const auto idle = [] {};

  // 0. The robot stands, holding its carrying posture (the service starts in stop).
  enter(machine.state());
  run_for(1.0, idle);

  // 1. Teaching: the person grips and guides the gravity-compensated gripper 10 cm ahead and
  //    10 cm down, onto the object.
  say(Command::kTeaching);
  const Eigen::Vector3d taught_from = tcp_world();
  hand = taught_from;
  hand_velocity.setZero();
  gripping = true;
  {
    const Eigen::Vector3d goal = taught_from + Eigen::Vector3d(0.1, 0.0, -0.1);
    double t = 0.0;
    run_for(3.0, [&] {
      t += dt;
      const double a = std::min(1.0, t / 2.0);
      hand_velocity =
          t < 2.0 ? Eigen::Vector3d((goal - taught_from) / 2.0) : Eigen::Vector3d::Zero();
      hand = taught_from + a * (goal - taught_from);
    });
  }
  res.guided = (tcp_world() - taught_from).norm();

  // 2. Close (still teaching: the person keeps the gripper where it is).
  say(Command::kClose);
  hand_velocity.setZero();
  run_for(1.5, idle);
  res.jaw_closed = jaw_position(core.state());

  // 3. Lift: the robot lifts; the person lets go. Open is ignored now (no drops).
  gripping = false;
  const double z_before_lift = tcp_world().z();
  say(Command::kLift);
  run_for(2.5, idle);
  res.lifted = tcp_world().z() - z_before_lift;
  res.lift_error = res.lifted - params.lift;
  if (params.stop_after_lift >= 0.0) {
    run_for(params.stop_after_lift, idle);
    res.lift_error = tcp_world().z() - z_before_lift - params.lift;
    sim.clear_external_force();
    res.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    return res;
  }
  say(Command::kOpen);

  // 4. Follow me: the person grips and walks the route.
  say(Command::kFollowMe);
  detail::Route route;
  const Eigen::Vector3d start = tcp_world();
  for (const auto& o : route_offsets()) route.pts.push_back(start.head<2>() + o);
  res.route_length = route.length();
  hand = start;
  hand_velocity.setZero();
  gripping = true;
  const Eigen::Vector2d base_start = base_xy();
  Eigen::Vector2d base_last = base_start;
  double walked = 0.0, t_follow = 0.0, lag_sum = 0.0, force_sum = 0.0;
  long walking_samples = 0;
  bool said_open = false;
  double arrived_for = 0.0;
  while (t_follow < params.follow_timeout) {
    run_for(0.01, [&] {
      t_follow += dt;
      const double speed =
          params.walk_speed * std::min(1.0, t_follow / 1.0);  // a second to get going
      const bool walking = walked < res.route_length;
      walked = std::min(res.route_length, walked + speed * dt);
      const Eigen::Vector2d h = route.at(walked);
      const Eigen::Vector2d hv =
          walking ? Eigen::Vector2d((h - hand.head<2>()) / dt) : Eigen::Vector2d::Zero();
      hand.head<2>() = h;
      hand_velocity = Eigen::Vector3d(hv.x(), hv.y(), 0.0);
      if (walking && cycle % 10 == 0) {
        const double lag = (h - last_tcp.head<2>()).norm();
        lag_sum += lag;
        res.max_lag = std::max(res.max_lag, lag);
        force_sum += pull.head<2>().norm();
        ++walking_samples;
      }
      res.peak_force = std::max(res.peak_force, pull.head<2>().norm());
    });
    const Eigen::Vector2d b = base_xy();
    res.base_travel += (b - base_last).norm();
    base_last = b;
    if (!said_open && walked > res.route_length / 2) {
      say(Command::kOpen);  // in follow-me: ignored (no drops)
      said_open = true;
    }
    // Arrived: the hand at the route's end and the TCP within 0.15 m of it for a second.
    const bool there =
        walked >= res.route_length && (route.pts.back() - tcp_world().head<2>()).norm() < 0.15;
    arrived_for = there ? arrived_for + 0.01 : 0.0;
    if (arrived_for >= 1.0) break;
  }
  res.follow_time = t_follow;
  res.mean_lag = walking_samples > 0 ? lag_sum / static_cast<double>(walking_samples) : 0.0;
  res.mean_force = walking_samples > 0 ? force_sum / static_cast<double>(walking_samples) : 0.0;
  res.end_error = (route.pts.back() - tcp_world().head<2>()).norm();

  // 5. Place: the person lets go, the robot lowers the object.
  gripping = false;
  const double z_before_place = tcp_world().z();
  say(Command::kPlace);
  run_for(2.5, idle);
  res.placed = z_before_place - tcp_world().z();

  // 6. Teaching, open: the object is released.
  say(Command::kTeaching);
  say(Command::kOpen);
  run_for(1.5, idle);
  res.jaw_final = jaw_position(core.state());
  sim.clear_external_force();
  res.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return res;
}

}  // namespace concert::system_test::transport
