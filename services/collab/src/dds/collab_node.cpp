#include "dds/collab_node.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/model/dds/pose.hpp"

namespace concert::collab::dds {
namespace {

namespace cdds = concert::dds;
using Clock = std::chrono::steady_clock;

msg::CollabMode to_msg(Mode m) {
  switch (m) {
    case Mode::kTeaching:
      return msg::COLLAB_TEACHING;
    case Mode::kAutonomous:
      return msg::COLLAB_AUTONOMOUS;
    case Mode::kFollowMe:
      return msg::COLLAB_FOLLOW_ME;
    case Mode::kStop:
      return msg::COLLAB_STOP;
  }
  return msg::COLLAB_STOP;
}

Eigen::Isometry3d planar(double x, double y, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

}  // namespace

struct CollabNode::Rig {
  std::shared_ptr<const model::RobotModel> model;
  std::string tool;        ///< end-effector name
  std::string tool_frame;  ///< its TCP link
  std::vector<std::string> arm_joints;
  std::vector<int> arm_index;  ///< in the fixed-base kinematics
  kinematics::Data data;
  ArmLimits limits;
  std::string jaw;          ///< the gripper's moving joint (a branch off the arm's tip), or ""
  double jaw_open{0.0}, jaw_closed{0.0};
  /// What the drives sustain of the base's accelerations (none: the model has no wheeled legs).
  std::optional<model::DriveBudget> budget;

  explicit Rig(std::shared_ptr<const model::RobotModel> m) : model(std::move(m)), data(model->kinematics().make_data()) {
    const auto grippers = model->end_effectors(model::EndEffectorKind::kGripper);
    const model::EndEffectorInfo& ee = grippers.size() == 1 ? *grippers.front() : model->tool();
    tool = ee.name;
    tool_frame = ee.frame;
    const model::ChainInfo& arm = model->chain(ee.chain);
    const auto& kin = model->kinematics();
    // The arm: the chain's joints that move the TCP (a gripper's jaw on the chain does not).
    std::vector<std::string> moving;
    for (const auto& j : arm.joints) {
      const auto links = kin.subtree_links(kin.joint_index_or_throw(j));
      if (std::find(links.begin(), links.end(), tool_frame) != links.end()) moving.push_back(j);
    }
    const auto n = static_cast<Eigen::Index>(moving.size());
    if (n == 0) throw model::ModelError("no joint of chain " + arm.name + " moves " + ee.name);
    limits.q_min.resize(n);
    limits.q_max.resize(n);
    limits.qd_max.resize(n);
    limits.q_posture.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const std::string& j = moving[static_cast<std::size_t>(i)];
      const int k = kin.joint_index_or_throw(j);
      arm_joints.push_back(j);
      arm_index.push_back(k);
      const auto& l = kin.joint_limits()[static_cast<std::size_t>(k)];
      limits.q_min[i] = l.has_position_limits ? l.lower : -M_PI;
      limits.q_max[i] = l.has_position_limits ? l.upper : M_PI;
      limits.qd_max[i] = l.velocity > 0 ? std::min(l.velocity, 1.0) : 0.5;
      limits.q_posture[i] = std::clamp(0.0, limits.q_min[i], limits.q_max[i]);
    }
    // The gripper's jaw: a moving joint below the arm's last joint that does not move the TCP.
    for (int d : kin.descendant_joints(arm_index.back())) {
      if (std::find(arm_index.begin(), arm_index.end(), d) != arm_index.end()) continue;
      const auto& l = kin.joint_limits()[static_cast<std::size_t>(d)];
      jaw = kin.joint_names()[static_cast<std::size_t>(d)];
      jaw_open = l.has_position_limits ? l.upper : 0.0;
      jaw_closed = l.has_position_limits ? l.lower : 0.0;
      break;
    }
    try {
      budget.emplace(*model);
    } catch (const model::ModelError&) {
      // A leg chain without a wheel: the base cannot drive; the MPC keeps its bounds.
    }
  }
};

CollabNode::CollabNode(cdds::Participant& participant, NodeParams params, std::ostream& log)
    : participant_(participant),
      params_(std::move(params)),
      log_(log),
      status_(participant, "collab"),
      state_out_(participant, cdds::topics::collab_state),
      cartesian_(participant, cdds::topics::cartesian_command),
      base_(participant, cdds::topics::base_velocity),
      joints_out_(participant, cdds::topics::joint_command),
      models_(participant, cdds::topics::robot_model,
              [this](const msg::RobotModel& m, const auto&) {
                std::lock_guard lock(mutex_);
                model_in_ = m;
              }),
      commands_in_(participant, cdds::topics::collab_command,
                   [this](const msg::CollabCommand& c, const auto&) {
                     std::lock_guard lock(mutex_);
                     // Written again by a client that had not heard the answer: the same
                     // command, taken once (a second "open" or "lift" would act twice).
                     if (!commands_seen_.first_time(c.command_id(), c.stamp_ns())) return;
                     if (commands_.size() < 64) commands_.push_back(c);
                   }),
      safety_in_(participant, cdds::topics::safety_state,
                 [this](const msg::SafetyState& s, const auto&) {
                   std::lock_guard lock(mutex_);
                   safety_ = s;
                 }),
      joints_in_(participant, cdds::topics::joint_state,
                 [this](const msg::JointState& s, const auto&) {
                   std::lock_guard lock(mutex_);
                   joints_ = s;
                 }),
      odometry_in_(participant, cdds::topics::odometry,
                   [this](const msg::Odometry& o, const auto&) {
                     std::lock_guard lock(mutex_);
                     odometry_ = o;
                   }),
      wrench_in_(participant, cdds::topics::ee_wrench,
                 [this](const msg::EndEffectorWrench& w, const auto&) {
                   std::lock_guard lock(mutex_);
                   wrench_ = w;
                 }),
      scan_in_(participant, cdds::topics::scan,
               [this](const msg::LaserScan& s, const auto&) {
                 std::lock_guard lock(mutex_);
                 scan_ = s;
               }),
      sonar_in_(participant, cdds::topics::sonar, [this](const msg::SonarRanges& s, const auto&) {
        std::lock_guard lock(mutex_);
        sonars_ = s;
      }) {
  grid_ = std::make_unique<ObstacleGrid>(params_.grid);
  status_.report(msg::SERVICE_STARTING, 0, "waiting for a robot model");
  state_msg_.mode(msg::COLLAB_STOP);
  state_msg_.state("stop");
}

CollabNode::~CollabNode() = default;

void CollabNode::log_line(const std::string& line) {
  std::lock_guard lock(log_mutex_);
  log_ << line << std::endl;
}

void CollabNode::apply_model(const msg::RobotModel& m) {
  if (m.version() <= model_version_) return;
  model_version_ = m.version();
  std::unique_ptr<Rig> rig;
  std::string error;
  try {
    rig = std::make_unique<Rig>(model::RobotModel::build(model::dds::to_description(m)));
    mpc_ = std::make_unique<FollowMeMpc>(params_.mpc, rig->limits,
                                         perimeter_spheres(params_.base_length, params_.base_width));
  } catch (const std::exception& e) {
    error = e.what();
    rig.reset();
    mpc_.reset();
  }
  rig_ = std::move(rig);
  rig_error_ = error;
  // A new model: whatever moved stops (the state machine goes to stop; the user restarts).
  if (machine_.state().mode != Mode::kStop && !machine_.estop_active()) {
    const auto t = machine_.apply(Command::kStop);
    on_transition(t, nullptr);
  }
  state_msg_.model_version(m.version());
  const cdds::ModelId id{m.version(), m.content_hash()};
  if (rig_) {
    status_.report(msg::SERVICE_READY, id,
                   "transport with " + rig_->tool + " on " + std::to_string(rig_->arm_joints.size()) + " joints");
    log_line("collab: model version " + std::to_string(m.version()) + ": tool " + rig_->tool + ", " +
             std::to_string(rig_->arm_joints.size()) + " arm joints");
  } else {
    status_.report(msg::SERVICE_READY, id, "cannot transport: " + error);
    log_line("collab: model version " + std::to_string(m.version()) + ": cannot transport: " + error);
  }
  publish_state();
}

void CollabNode::handle(const msg::CollabCommand& c) {
  std::optional<Command> cmd;
  std::string why;
  if (c.direct()) {
    // A GUI button or `concert collab mode`: the bare name, no wake phrase.
    const auto words = normalise_words(c.text());
    std::string joined;
    for (const auto& w : words) joined += (joined.empty() ? "" : " ") + w;
    if (joined == "follow-me" || joined == "follow_me" || joined == "followme") joined = "follow me";
    for (Command k : kAllCommands)
      if (joined == command_phrase(k)) cmd = k;
    if (!cmd) why = "unknown command \"" + c.text() + "\"";
  } else {
    const auto p = parse_command(c.text());
    cmd = p.command;
    why = p.reason;
  }
  if (!cmd) {
    Transition t{false, Command::kStop, machine_.state(), machine_.state(), why};
    state_msg_.accepted(false);
    state_msg_.reason(why);
    state_msg_.command_id(c.command_id());
    state_msg_.command(c.text());
    publish_state();
    log_line("collab: \"" + c.text() + "\" ignored: " + why);
    return;
  }
  if (!rig_ && *cmd != Command::kStop) {
    Transition t{false, *cmd, machine_.state(), machine_.state(), "cannot transport: " + rig_error_};
    on_transition(t, &c);
    return;
  }
  on_transition(machine_.apply(*cmd), &c);
}

void CollabNode::on_transition(const Transition& t, const msg::CollabCommand* c) {
  if (t.accepted) enter(t.to);
  if (c != nullptr) {
    state_msg_.command_id(c->command_id());
    state_msg_.command(c->text());
    state_msg_.command_latency(c->stamp_ns() > 0 ? static_cast<double>(now_ns() - c->stamp_ns()) * 1e-9 : 0.0);
  } else {
    state_msg_.command(command_name(t.command));
  }
  state_msg_.accepted(t.accepted);
  state_msg_.reason(t.reason);
  publish_state();
  log_line(std::string("collab: ") + command_name(t.command) + ": " + state_name(t.from) + " -> " +
           state_name(t.to) + (t.accepted ? "" : " (ignored: " + t.reason + ")"));
}

void CollabNode::enter(const State& s) {
  // The object hangs from the gripper from lift (before: it rests where it was grasped) until the
  // gripper opens.
  if (s.mode == Mode::kAutonomous && s.sub == SubState::kLift) carrying_ = true;
  if (s.mode == Mode::kTeaching && s.sub == SubState::kOpen) carrying_ = false;
  switch (s.mode) {
    case Mode::kTeaching:
      base_velocity(Eigen::Vector3d::Zero());
      gravity_compensation();
      if (s.sub == SubState::kOpen || s.sub == SubState::kClose) gripper(s.sub == SubState::kOpen);
      break;
    case Mode::kAutonomous:
      base_velocity(Eigen::Vector3d::Zero());
      hold_here(s.sub == SubState::kLift ? params_.lift_height : s.sub == SubState::kPlace ? -params_.lift_height : 0.0);
      break;
    case Mode::kFollowMe: {
      Eigen::VectorXd q;
      if (mpc_) mpc_->reset();
      if (mpc_ && arm_state(q)) {
        const auto n = static_cast<Eigen::Index>(rig_->arm_index.size());
        q_cmd_.resize(n);
        for (Eigen::Index i = 0; i < n; ++i) q_cmd_[i] = q[rig_->arm_index[static_cast<std::size_t>(i)]];
        // The postural term keeps the posture the object was lifted in, clamped into the limits.
        mpc_->set_posture(q_cmd_.cwiseMax(rig_->limits.q_min).cwiseMin(rig_->limits.q_max));
      } else {
        q_cmd_.resize(0);
      }
      break;
    }
    case Mode::kStop:
      base_velocity(Eigen::Vector3d::Zero());
      hold_here(0.0);
      break;
  }
}

bool CollabNode::arm_state(Eigen::VectorXd& q) const {
  std::lock_guard lock(mutex_);
  if (!rig_ || !joints_ || joints_->model_version() != model_version_) return false;
  const auto& kin = rig_->model->kinematics();
  q = Eigen::VectorXd::Zero(kin.dof());
  for (std::size_t i = 0; i < joints_->name().size() && i < joints_->position().size(); ++i)
    if (const auto k = kin.joint_index(joints_->name()[i])) q[*k] = joints_->position()[i];
  return true;
}

void CollabNode::gravity_compensation() {
  if (!rig_) return;
  msg::CartesianImpedanceCommand c;
  c.model_version(model_version_);
  c.stamp_ns(now_ns());
  c.source("collab");
  c.end_effector(rig_->tool_frame);
  // Unused at zero gains, but a pose all the same: the robot refuses a target that is not one.
  c.target(model::dds::to_pose_msg(Eigen::Isometry3d::Identity()));
  c.stiffness().fill(0.0);
  c.damping().fill(0.0);
  c.admittance_axis(255);
  c.payload_mass(carrying_ ? params_.object_mass : 0.0);
  cartesian_.write(c);
}

void CollabNode::hold_here(double dz) {
  Eigen::VectorXd q;
  if (!rig_ || !arm_state(q)) return;
  // The robot's Cartesian targets are in its model's frame (the root: the base), not the
  // odometry's (services/robot: RobotState::end_effector_pose; a target in the odometry frame
  // would pull the arm away once the base moves).
  Eigen::Isometry3d target = rig_->model->kinematics().frame_pose(rig_->data, q, rig_->tool_frame);
  target.translation().z() += dz;
  msg::CartesianImpedanceCommand c;
  c.model_version(model_version_);
  c.stamp_ns(now_ns());
  c.source("collab");
  c.end_effector(rig_->tool_frame);
  c.target(model::dds::to_pose_msg(target));
  const double k = params_.hold_stiffness;
  c.stiffness() = {k, k, k, k / 10, k / 10, k / 10};
  const double d = 2.0 * std::sqrt(k * 5.0);
  c.damping() = {d, d, d, d / 10, d / 10, d / 10};
  c.admittance_axis(255);
  c.payload_mass(carrying_ ? params_.object_mass : 0.0);
  cartesian_.write(c);
}

void CollabNode::base_velocity(const Eigen::Vector3d& v) {
  msg::BaseVelocityCommand b;
  b.model_version(model_version_);
  b.stamp_ns(now_ns());
  b.source("collab");
  b.vx(v.x());
  b.vy(v.y());
  b.wz(v.z());
  base_.write(b);
  msg::Twist t;
  t.linear(model::dds::to_vector_msg(Eigen::Vector3d(v.x(), v.y(), 0)));
  t.angular(model::dds::to_vector_msg(Eigen::Vector3d(0, 0, v.z())));
  state_msg_.base_velocity(t);
}

void CollabNode::gripper(bool open) {
  if (!rig_ || rig_->jaw.empty()) {
    state_msg_.reason(std::string("gripper ") + (open ? "open" : "close") + ": " + (rig_ ? rig_->tool : "no tool") +
                      " has no moving jaw in this model");
    return;
  }
  msg::JointCommand jc;
  jc.model_version(model_version_);
  jc.stamp_ns(now_ns());
  jc.source("collab");
  jc.mode(msg::JOINT_POSITION);
  jc.name({rig_->jaw});
  jc.position({open ? rig_->jaw_open : rig_->jaw_closed});
  joints_out_.write(jc);
}

void CollabNode::follow_step() {
  Eigen::VectorXd q;
  if (!rig_ || !mpc_ || !arm_state(q)) return;
  std::optional<msg::Odometry> odo;
  std::optional<msg::EndEffectorWrench> wrench;
  std::optional<msg::LaserScan> scan;
  std::optional<msg::SonarRanges> sonars;
  {
    std::lock_guard lock(mutex_);
    odo = odometry_;
    wrench = wrench_;
    scan = scan_;
    sonars = sonars_;
  }
  const auto& kin = rig_->model->kinematics();
  MpcInput in;
  if (odo) in.base = Eigen::Vector3d(odo->x(), odo->y(), odo->yaw());
  const auto n = static_cast<Eigen::Index>(rig_->arm_index.size());
  in.q.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) in.q[i] = q[rig_->arm_index[static_cast<std::size_t>(i)]];
  in.ee_in_base = kin.frame_pose(rig_->data, q, rig_->tool_frame).translation();
  const Eigen::MatrixXd J = kin.frame_jacobian(rig_->data, q, rig_->tool_frame);
  in.arm_jacobian.resize(3, n);
  for (Eigen::Index i = 0; i < n; ++i) in.arm_jacobian.col(i) = J.block(0, rig_->arm_index[static_cast<std::size_t>(i)], 3, 1);
  if (wrench && wrench->model_version() == model_version_) {
    const auto& f = wrench->wrench().force();
    in.force = planar_world_force(Eigen::Vector3d(f.x(), f.y(), f.z()), in.base.z());
  }
  const Eigen::Isometry3d world_T_base = planar(in.base.x(), in.base.y(), in.base.z());
  grid_->reset(in.base.head<2>());
  if (scan && kin.has_frame(scan->frame())) {
    PlanarScanReading reading;
    reading.world_T_sensor = world_T_base * kin.frame_pose(rig_->data, q, scan->frame());
    reading.angle_min = scan->angle_min();
    reading.angle_increment = scan->angle_increment();
    reading.range_min = scan->range_min();
    reading.range_max = scan->range_max();
    reading.ranges.assign(scan->ranges().begin(), scan->ranges().end());
    grid_->add_scan(reading);
  }
  if (sonars) {
    for (const auto& s : sonars->sonars()) {
      if (!kin.has_frame(s.frame())) continue;
      grid_->add_sonar(sonar_reading(world_T_base * kin.frame_pose(rig_->data, q, s.frame()), s.range(),
                                     s.range_max(), s.field_of_view()));
    }
  }
  in.obstacles = grid_->active(in.base.head<2>());
  if (in.obstacles.size() > params_.mpc.max_obstacles) in.obstacles.resize(params_.mpc.max_obstacles);
  in.period = 1.0 / params_.rate;
  if (rig_->budget) {
    // The base accelerates no harder than the arm's drives (and the wheels) sustain at this
    // posture, the turn's centrifugal load counted first.
    model::BaseMotion asked;
    asked.ax = asked.ay = params_.mpc.base_lin_acc_max;
    asked.aw = params_.mpc.base_ang_acc_max;
    asked.wz = odo ? odo->wz() : 0.0;
    in.base_acceleration_scale = rig_->budget->base_motion(q, asked, params_.drive_torque_fraction).scale;
  }
  send_follow(in, mpc_->solve(in));
}

void CollabNode::send_follow(const MpcInput& in, const MpcResult& r) {
  state_msg_.ee_force(model::dds::to_vector_msg(in.force));
  state_msg_.active_obstacles(static_cast<std::uint32_t>(in.obstacles.size()));
  state_msg_.mpc_solve_ms(r.solve_ms);
  if (!r.ok) {
    base_velocity(Eigen::Vector3d::Zero());  // a failed solve stops the base for this cycle
    status_.note("follow-me: " + r.status);
    return;
  }
  base_velocity(r.base_velocity_local);
  // Position mode, at most 0.1 rad ahead of the joints (integrate_position_command says why).
  integrate_position_command(q_cmd_, in.q, r.joint_velocity, 1.0 / params_.rate, 0.1, rig_->limits);
  msg::JointCommand jc;
  jc.model_version(model_version_);
  jc.stamp_ns(now_ns());
  jc.source("collab");
  jc.mode(msg::JOINT_POSITION);
  jc.name(rig_->arm_joints);
  jc.position(std::vector<double>(q_cmd_.data(), q_cmd_.data() + q_cmd_.size()));
  jc.velocity(std::vector<double>(r.joint_velocity.data(), r.joint_velocity.data() + r.joint_velocity.size()));
  joints_out_.write(jc);
}

void CollabNode::publish_state() {
  const State& s = machine_.state();
  state_msg_.stamp_ns(now_ns());
  state_msg_.mode(to_msg(s.mode));
  state_msg_.sub_state(sub_state_name(s.sub));
  state_msg_.state(state_name(s));
  state_msg_.estop(machine_.estop_active());
  state_out_.write(state_msg_);
}

void CollabNode::spin(const std::atomic<bool>& stop) {
  const auto period = std::chrono::duration<double>(1.0 / params_.rate);
  auto next = Clock::now();
  auto last_publish = Clock::now();
  publish_state();
  while (!stop.load()) {
    std::optional<msg::RobotModel> model;
    std::deque<msg::CollabCommand> commands;
    std::optional<msg::SafetyState> safety;
    {
      std::lock_guard lock(mutex_);
      model.swap(model_in_);
      commands.swap(commands_);
      safety = safety_;
    }
    if (model) apply_model(*model);
    const bool stopped = safety && safety->mode() != msg::SAFETY_RUNNING;
    if (stopped != machine_.estop_active()) {
      const auto t = machine_.set_estop(stopped);
      if (t.accepted) enter(t.to);
      state_msg_.command(stopped ? "safety stop" : "safety released");
      state_msg_.accepted(t.accepted);
      state_msg_.reason(t.reason);
      publish_state();
      log_line(std::string("collab: safety ") + (stopped ? "stop: state stop" : "released: still in stop"));
    }
    for (const auto& c : commands) handle(c);
    const Mode m = machine_.state().mode;
    if (m == Mode::kFollowMe) {
      follow_step();
    } else if (rig_ && m != Mode::kStop) {
      // Engaged (teaching, autonomous): the base holds (the robot stops it after 0.5 s anyway).
      // In stop the service commands nothing: the robot belongs to whoever else drives it (the
      // drill, the planner, nav); a zero base velocity at the control rate would preempt every
      // trajectory on the base ("preempted by another command on its joints").
      base_velocity(Eigen::Vector3d::Zero());
      if (m == Mode::kTeaching && Clock::now() - last_publish > std::chrono::milliseconds(200)) gravity_compensation();
    }
    if (Clock::now() - last_publish > std::chrono::milliseconds(m == Mode::kFollowMe ? 100 : 500)) {
      publish_state();
      last_publish = Clock::now();
    }
    next += std::chrono::duration_cast<Clock::duration>(period);
    const auto now = Clock::now();
    if (next < now) next = now;
    std::this_thread::sleep_until(next);
  }
  if (rig_) base_velocity(Eigen::Vector3d::Zero());
}

}  // namespace concert::collab::dds
