#include "robot/robot_core.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <set>

#include "concert/hardware/realtime_buffer.hpp"
#include "concert/kinematics/impedance.hpp"
#include "robot/controllers.hpp"

namespace concert::robot {

using hardware::Handover;
using hardware::RealtimeBuffer;

namespace {
// An IMU sample older than this (hardware time) is not used for the odometry's yaw [s].
constexpr double kGyroFresh = 0.05;
}  // namespace

namespace {

/// Joint count the loop's hardware-order vectors are reserved for (more is served, with an
/// allocation at the hardware switch that needs it).
constexpr std::size_t kReservedJoints = 64;

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) {
    out += (out.empty() ? "" : ", ") + n;
  }
  return out.empty() ? "none" : out;
}

bool finite(double v) { return std::isfinite(v); }

// The deepest "tcp"/"tcp_<tag>" frame, else the last deepest link ("" for a model without
// movable joints). Depth = number of movable joints above the frame.
std::string default_end_effector(const kinematics::Model& model) {
  std::map<std::string, int> depth;
  for (int j = 0; j < model.dof(); ++j) {
    for (const auto& link : model.subtree_links(j)) {
      ++depth[link];
    }
  }
  std::string best_tcp, best_leaf;
  int tcp_depth = 0, leaf_depth = 0;
  // frame_names() is depth-first: with >=, the last frame of the deepest chain wins.
  for (const auto& frame : model.frame_names()) {
    const auto it = depth.find(frame);
    const int d = it == depth.end() ? 0 : it->second;
    const bool is_tcp = frame == "tcp" || frame.rfind("tcp_", 0) == 0;
    if (is_tcp && d > tcp_depth) {
      best_tcp = frame;
      tcp_depth = d;
    }
    if (d > 0 && d >= leaf_depth) {
      best_leaf = frame;
      leaf_depth = d;
    }
  }
  return best_tcp.empty() ? best_leaf : best_tcp;
}

void reserve_state(RobotState& s) {
  s.message.reserve(256);
  s.end_effector_frame.reserve(64);
  s.joint_names.reserve(kReservedJoints);
  s.position.reserve(kReservedJoints);
  s.velocity.reserve(kReservedJoints);
  s.effort.reserve(kReservedJoints);
  s.owners.reserve(kReservedJoints);
  s.torque_limit.reserve(kReservedJoints);
}

RobotState reserved_state() {
  RobotState s;
  reserve_state(s);
  s.message = "waiting for a robot model";
  return s;
}

/// The claim of one joint by a controller; `seq` orders claims and trajectories.
struct Claim {
  std::uint64_t seq{0};
  JointOwner owner{JointOwner::kHold};
};

}  // namespace

/// Commands as the other threads leave them for the loop: the latest claim of each joint,
/// the latest reference of each controller, and sequence numbers saying what is new.
struct CommandFrame {
  std::vector<Claim> claims;          // model order
  std::vector<JointSetpoint> joints;  // model order (joint controller)
  std::uint64_t hold_seq{0};
  std::uint64_t cartesian_seq{0};
  CartesianCommand cartesian;
  bool keep_admittance{false};
  std::uint64_t base_seq{0};
  BaseCommand base;
  std::uint64_t trajectory_seq{0};
};

/// Everything the loop needs for one model version, prepared off the loop thread.
struct RobotCore::Slot {
  Slot(std::shared_ptr<const kinematics::Model> m, const RobotParams& params, std::vector<int> arm_joints,
       std::vector<Leg> leg_list)
      : model(std::move(m)),
        data(model->make_data()),
        arm(std::move(arm_joints)),
        legs(leg_list),
        cycle(*model, arm.size()),
        joint(model->dof()),
        cartesian(arm),
        base(leg_list.size() >= 2 ? std::make_unique<BaseController>(leg_list, params.base_command_timeout,
                                                                   params.trajectory_steering_rate,
                                                                   params.steering_acceleration)
                                  : nullptr),
        trajectory(model->dof(), params, base.get()),
        commands(make_frame(model->dof())),
        applied_claim(static_cast<std::size_t>(model->dof()), 0) {
    controllers = {&hold, &joint, &cartesian, &gravity, base.get(), &trajectory};
    if (base) {
      for (const Leg& leg : legs) cycle.wheel[static_cast<std::size_t>(leg.wheel_index)] = 1;
    }
  }
  ~Slot() { delete running; }

  static CommandFrame make_frame(int dof) {
    CommandFrame f;
    f.claims.assign(static_cast<std::size_t>(dof), Claim{});
    f.joints.assign(static_cast<std::size_t>(dof), JointSetpoint{});
    return f;
  }

  std::shared_ptr<const kinematics::Model> model;
  kinematics::Data data;  // KDL scratch of the loop
  std::uint64_t version{0};
  std::uint64_t generation{0};  // hardware generation the model matches
  std::string ready_message;
  std::string ee_frame;
  std::vector<int> arm;
  std::vector<Leg> legs;
  std::vector<int> hw_to_model;
  /// Model order: each joint's limits from the model's table; continuous torque 0 when the
  /// table does not list it (no foldback).
  std::vector<model::JointLimits> limits;
  CycleData cycle;
  HoldController hold{model->dof()};
  JointController joint;
  CartesianController cartesian;
  GravityCompensationController gravity;
  std::unique_ptr<BaseController> base;
  TrajectoryController trajectory;
  std::array<Controller*, 6> controllers{};
  // Hand-over from the other threads.
  RealtimeBuffer<CommandFrame> commands;
  Handover<PreparedTrajectory> trajectories;
  // Loop side.
  bool fresh{true};
  bool wrench_initialized{false};
  std::vector<std::uint64_t> applied_claim;
  std::uint64_t applied_hold{0}, applied_cartesian{0}, applied_base{0}, applied_trajectory{0};
  PreparedTrajectory* running{nullptr};  // taken from `trajectories`, tracked by `trajectory`
};

/// The non-real-time side: writers serialise on `mutex`; the loop never takes it.
struct RobotCore::Shared {
  std::mutex mutex;
  Handover<Slot> slots;
  Slot* accepted{nullptr};  // newest model handed to the loop (owned by `slots` or the loop)
  CommandFrame staged;      // accumulated commands of `accepted`
  std::uint64_t seq{0};
  bool safety_stopped{false};
  std::string safety_reason;
  bool cartesian_admittance{false};
  mutable std::mutex state_mutex;  // readers of the loop's state buffer
  // on_imu: the model and IMU frame last seen, and whether that frame rides on the base.
  std::mutex imu_mutex;
  std::shared_ptr<const kinematics::Model> imu_model;  // held: a new model never reuses its address
  std::string imu_frame;
  bool imu_on_base{false};
  Eigen::Matrix3d base_R_imu{Eigen::Matrix3d::Identity()};
};

/// The loop-thread side.
struct RobotCore::Loop {
  Loop() : state([] { return reserved_state(); }) {
    hw_state.position.reserve(kReservedJoints);
    hw_state.velocity.reserve(kReservedJoints);
    hw_state.effort.reserve(kReservedJoints);
    drive.reserve(kReservedJoints);
    thermal.reserve(kReservedJoints);
  }
  ~Loop() { delete active; }
  Slot* active{nullptr};
  HardwareState hw_state;
  std::vector<DriveCommand> drive;  // hardware order
  // Hardware order: each drive's RMS torque over the thermal window (measured), kept across
  // model versions of the same hardware, restarted cold with new hardware.
  std::vector<model::ThermalLoad> thermal;
  std::uint64_t thermal_generation{0};
  bool holding_hw{false};
  std::uint64_t holding_generation{0};
  bool stop_seen{false};
  std::uint64_t cycles{0};
  TrajectoryProgress last_progress;  // of a trajectory that ended with its model
  std::atomic<bool> safety_stopped{false};
  RealtimeBuffer<RobotState> state;
  // The latest yaw rate of the base from an IMU on it (written by on_imu from sensor threads).
  std::atomic<double> gyro_yaw_rate{0.0};
  std::atomic<double> gyro_stamp{-1e9};
};

RobotCore::RobotCore(Hardware& hardware, RobotParams params)
    : hw_(hardware), params_(std::move(params)), shared_(std::make_unique<Shared>()), loop_(std::make_unique<Loop>()) {
  if (params_.period <= 0.0) {
    throw std::invalid_argument("robot: period must be positive");
  }
}

RobotCore::~RobotCore() = default;

namespace {

// Throws ModelMismatchError (`what` first) unless the model's joints are the mounted ones.
void check_mounted(const kinematics::Model& model, const MountedHardware& mounted, const std::string& what) {
  const std::set<std::string> have(mounted.joint_names.begin(), mounted.joint_names.end());
  const std::set<std::string> modelled(model.joint_names().begin(), model.joint_names().end());
  std::vector<std::string> missing, extra;
  std::set_difference(have.begin(), have.end(), modelled.begin(), modelled.end(), std::back_inserter(missing));
  std::set_difference(modelled.begin(), modelled.end(), have.begin(), have.end(), std::back_inserter(extra));
  if (!missing.empty() || !extra.empty()) {
    throw ModelMismatchError(what + " '" + model.name() +
                             "' does not match the mounted hardware: mounted joints missing from the model: " +
                             join(missing) + "; model joints not mounted: " + join(extra));
  }
}

// The joints that move the end-effector frame `ee`, legs excepted (model order); none without one.
std::vector<int> arm_chain(const kinematics::Model& model, const std::string& ee, const std::set<int>& leg_joints) {
  std::vector<int> arm;
  if (ee.empty()) return arm;
  for (int j = 0; j < model.dof(); ++j) {
    const auto sub = model.subtree_links(j);
    if (leg_joints.count(j) == 0 && std::find(sub.begin(), sub.end(), ee) != sub.end()) arm.push_back(j);
  }
  return arm;
}

}  // namespace

void RobotCore::set_model(const std::string& urdf, std::uint64_t version, const std::string& end_effector_frame,
                          const model::LimitsTable& limits) {
  const std::string what = "model version " + std::to_string(version);
  std::shared_ptr<const kinematics::Model> model;
  try {
    model = std::make_shared<const kinematics::Model>(kinematics::Model::from_urdf_string(urdf));
  } catch (const kinematics::ModelError& e) {
    throw ModelMismatchError(what + " refused: " + e.what());
  }
  std::string ee = end_effector_frame.empty() ? params_.end_effector_frame : end_effector_frame;
  if (ee.empty()) ee = default_end_effector(*model);
  // A bare URDF carries no roles: the legs by their axes, the only place the robot guesses them.
  std::vector<Leg> legs = detect_legs(*model, collision_cylinder_radii(urdf), params_.default_wheel_radius);
  install(model, version, ee, std::move(legs), limits);
}

void RobotCore::set_model(const std::shared_ptr<const model::RobotModel>& m) {
  if (m->chains().empty()) {
    set_model(m->description().urdf, m->version(), "", m->limits());
    return;
  }
  const std::string what = "model version " + std::to_string(m->version());
  // The tool, else the configured frame, else the arm's tip; none without one arm.
  std::string ee;
  try {
    ee = m->tool().frame;
  } catch (const model::ModelError&) {
    ee = params_.end_effector_frame;
    if (ee.empty()) {
      try {
        ee = m->arm().tip_link;
      } catch (const model::ModelError&) {
        ee.clear();
      }
    }
  }
  check_newer(m->version(), what);
  // The steered leg chains, by role, measured. Unsteered wheels (a differential drive) are not
  // this base controller's: the robot runs without driving them. A leg the model cannot give
  // (no wheel, no wheel radius) refuses the model, as nav refuses it.
  std::vector<Leg> legs;
  try {
    legs = mobile_base::steering_legs(*m);
  } catch (const std::exception& e) {  // model::ModelError, std::invalid_argument
    throw ModelMismatchError(what + " refused: " + e.what());
  }
  // The fixed-base kinematics of the model, kept alive with it.
  install(std::shared_ptr<const kinematics::Model>(m, &m->kinematics()), m->version(), ee, std::move(legs),
          m->limits());
}

void RobotCore::check_newer(std::uint64_t version, const std::string& what) const {
  std::lock_guard lock(shared_->mutex);
  if (shared_->accepted != nullptr && version < shared_->accepted->version) {
    throw ModelMismatchError(what + " refused: older than the current version " +
                             std::to_string(shared_->accepted->version));
  }
}

void RobotCore::install(std::shared_ptr<const kinematics::Model> model, std::uint64_t version, const std::string& ee,
                        std::vector<Leg> legs, const model::LimitsTable& limits) {
  const std::string what = "model version " + std::to_string(version);
  check_newer(version, what);
  // The hardware the loop runs once its pending switch (if any) is done.
  const MountedHardware mounted = hw_.mounted();
  check_mounted(*model, mounted, what);
  if (!ee.empty() && !model->has_frame(ee)) {
    throw ModelMismatchError(what + ": end-effector frame '" + ee + "' is not a link of the model");
  }
  // The legs of the mobile base are never part of the arm chain.
  std::set<int> leg_joints;
  for (const auto& leg : legs) {
    leg_joints.insert(leg.steering_index);
    leg_joints.insert(leg.wheel_index);
  }
  std::vector<int> arm = arm_chain(*model, ee, leg_joints);
  auto slot = std::make_unique<Slot>(model, params_, std::move(arm), std::move(legs));
  slot->version = version;
  slot->generation = mounted.generation;
  slot->ee_frame = ee;
  slot->ready_message = "ready at model version " + std::to_string(version);
  for (const auto& name : mounted.joint_names) {
    slot->hw_to_model.push_back(model->joint_index_or_throw(name));
  }
  // The legs' drives fold their torque back as they heat; the arm's keep their peak torque. A
  // wheel or a steering that yields slips or lags (the base slows); an arm joint that yields
  // moves the tool: with J2_E folded back to its continuous torque while the demo arm moves
  // off a drilled hole, J5_E runs into its limit and J6_E past its velocity limit (a safety stop
  // anyway). For the arm, safety's sustained-torque stop is the better end.
  slot->limits.resize(static_cast<std::size_t>(model->dof()));
  for (int j = 0; j < model->dof(); ++j) {
    const std::string& name = model->joint_names()[static_cast<std::size_t>(j)];
    const model::JointLimits* row = limits.find(name);
    if (row != nullptr && leg_joints.count(j) != 0) {
      slot->limits[static_cast<std::size_t>(j)] = *row;
    } else {
      slot->limits[static_cast<std::size_t>(j)].name = name;
    }
  }
  std::lock_guard lock(shared_->mutex);
  if (shared_->accepted != nullptr && version < shared_->accepted->version) {
    throw ModelMismatchError(what + " refused: older than the current version " +
                             std::to_string(shared_->accepted->version));
  }
  shared_->accepted = slot.get();
  shared_->staged = Slot::make_frame(model->dof());
  shared_->cartesian_admittance = false;
  shared_->slots.submit(std::move(slot));
}

void RobotCore::check_command(std::uint64_t model_version) const {
  if (shared_->safety_stopped) {
    throw CommandError("command refused: safety stop (" + shared_->safety_reason + ")");
  }
  const Slot* s = shared_->accepted;
  if (s == nullptr) {
    throw CommandError("command refused: robot not ready (waiting for a robot model)");
  }
  if (s->generation != hw_.mounted_generation()) {
    throw CommandError(
        "command refused: robot not ready (hardware changed: waiting for a model matching the mounted joints)");
  }
  if (model_version != s->version) {
    throw CommandError("command for model version " + std::to_string(model_version) +
                       " refused: current model version is " + std::to_string(s->version));
  }
}

namespace {
/// Hands the staged frame of `slot` to the loop.
void publish_frame(RealtimeBuffer<CommandFrame>& buffer, const CommandFrame& staged) {
  buffer.back() = staged;
  buffer.publish();
}
}  // namespace

void RobotCore::command_joints(const JointCommandSet& command) {
  std::lock_guard lock(shared_->mutex);
  check_command(command.model_version);
  Slot& s = *shared_->accepted;
  std::set<int> seen;
  std::vector<std::pair<int, JointSetpoint>> accepted;
  for (const auto& c : command.joints) {
    const auto index = s.model->joint_index(c.joint);
    if (!index) {
      throw CommandError("joint command refused: unknown joint '" + c.joint + "' (model version " +
                         std::to_string(s.version) + " has: " + join(s.model->joint_names()) + ")");
    }
    if (!seen.insert(*index).second) {
      throw CommandError("joint command refused: joint '" + c.joint + "' given twice");
    }
    if (!finite(c.position) || !finite(c.velocity) || !finite(c.effort) || !finite(c.stiffness) ||
        !finite(c.damping)) {
      throw CommandError("joint command refused: non-finite value for joint '" + c.joint + "'");
    }
    if (c.stiffness < 0.0 || c.damping < 0.0) {
      throw CommandError("joint command refused: negative stiffness or damping for joint '" + c.joint + "'");
    }
    accepted.emplace_back(*index, JointSetpoint{c.mode, c.position, c.velocity, c.effort, c.stiffness, c.damping});
  }
  const std::uint64_t seq = ++shared_->seq;
  for (const auto& [i, sp] : accepted) {
    shared_->staged.claims[static_cast<std::size_t>(i)] = {seq, JointOwner::kJoint};
    shared_->staged.joints[static_cast<std::size_t>(i)] = sp;
  }
  publish_frame(s.commands, shared_->staged);
}

void RobotCore::command_cartesian(const CartesianCommand& command) {
  std::lock_guard lock(shared_->mutex);
  check_command(command.model_version);
  Slot& s = *shared_->accepted;
  const std::string frame = command.frame.empty() ? s.ee_frame : command.frame;
  if (frame != s.ee_frame) {
    throw CommandError("Cartesian command refused: frame '" + frame + "' is not the end-effector frame '" +
                       s.ee_frame + "'");
  }
  if (s.arm.empty()) {
    throw CommandError("Cartesian command refused: the model has no joints moving '" + frame + "'");
  }
  if ((command.stiffness.array() < 0.0).any() || (command.damping.array() < 0.0).any() ||
      !command.target_pose.matrix().allFinite() || !command.feedforward_wrench.allFinite() ||
      !command.target_twist.allFinite()) {
    throw CommandError("Cartesian command refused: negative gains or non-finite values");
  }
  if (!(command.payload_mass >= 0.0) || !std::isfinite(command.payload_mass)) {
    throw CommandError("Cartesian command refused: payload_mass " + std::to_string(command.payload_mass) +
                       " kg must be finite and >= 0");
  }
  if (command.admittance.enabled &&
      (std::abs(command.admittance.axis.norm() - 1.0) > 1e-6 || command.admittance.mass <= 0.0 ||
       command.admittance.damping < 0.0)) {
    throw CommandError("Cartesian command refused: admittance needs a unit axis, mass > 0, damping >= 0");
  }
  const std::uint64_t seq = ++shared_->seq;
  CommandFrame& f = shared_->staged;
  f.keep_admittance = shared_->cartesian_admittance && command.admittance.enabled;
  shared_->cartesian_admittance = command.admittance.enabled;
  f.cartesian = command;
  f.cartesian.frame.clear();
  f.cartesian_seq = seq;
  for (int j : s.arm) {
    f.claims[static_cast<std::size_t>(j)] = {seq, JointOwner::kCartesian};
  }
  publish_frame(s.commands, f);
}

void RobotCore::command_base(const BaseCommand& command) {
  std::lock_guard lock(shared_->mutex);
  check_command(command.model_version);
  Slot& s = *shared_->accepted;
  if (!s.base) {
    throw CommandError("base command refused: model version " + std::to_string(s.version) + " has " +
                       std::to_string(s.legs.size()) + " steering+wheel legs (needs at least 2)");
  }
  if (!finite(command.vx) || !finite(command.vy) || !finite(command.wz)) {
    throw CommandError("base command refused: non-finite twist");
  }
  const std::uint64_t seq = ++shared_->seq;
  CommandFrame& f = shared_->staged;
  f.base = command;
  f.base_seq = seq;
  for (const auto& leg : s.legs) {
    for (int j : {leg.steering_index, leg.wheel_index}) {
      f.claims[static_cast<std::size_t>(j)] = {seq, JointOwner::kBase};
    }
  }
  publish_frame(s.commands, f);
}

void RobotCore::command_gravity_compensation(std::uint64_t model_version, const std::vector<std::string>& joints) {
  std::lock_guard lock(shared_->mutex);
  check_command(model_version);
  Slot& s = *shared_->accepted;
  std::vector<int> indices;
  if (joints.empty()) {
    indices = s.arm;
  }
  for (const auto& name : joints) {
    const auto index = s.model->joint_index(name);
    if (!index) {
      throw CommandError("gravity compensation refused: unknown joint '" + name + "'");
    }
    indices.push_back(*index);
  }
  const std::uint64_t seq = ++shared_->seq;
  for (int j : indices) {
    shared_->staged.claims[static_cast<std::size_t>(j)] = {seq, JointOwner::kGravityCompensation};
  }
  publish_frame(s.commands, shared_->staged);
}

namespace {

// Which of a trajectory's columns are which model joints, and which are the base's (all three
// or none). Throws CommandError (`what` first) naming a joint given twice or unknown, a base
// given in part, a base the model lacks, or a leg joint given with the base.
void resolve_columns(const JointTrajectory& t, const RobotCore::Slot& s, const std::string& what,
                     PreparedTrajectory& prepared, std::vector<int>& column_of_joint, std::array<int, 3>& base_columns) {
  std::set<std::string> seen;
  base_columns = {-1, -1, -1};
  for (std::size_t k = 0; k < t.joints.size(); ++k) {
    const std::string& name = t.joints[k];
    if (!seen.insert(name).second) {
      throw CommandError(what + "joint '" + name + "' given twice");
    }
    const int base_axis = name == kBaseX ? 0 : name == kBaseY ? 1 : name == kBaseYaw ? 2 : -1;
    if (base_axis >= 0) {
      base_columns[static_cast<std::size_t>(base_axis)] = static_cast<int>(k);
      continue;
    }
    const auto index = s.model->joint_index(name);
    if (!index) {
      throw CommandError(what + "unknown joint '" + name + "' (model version " + std::to_string(s.version) +
                         " has: " + join(s.model->joint_names()) + ")");
    }
    prepared.joints.push_back(*index);
    column_of_joint.push_back(static_cast<int>(k));
  }
  const int base_count = (base_columns[0] >= 0) + (base_columns[1] >= 0) + (base_columns[2] >= 0);
  if (base_count != 0 && base_count != 3) {
    throw CommandError(what + "the base needs all of base_x, base_y, base_yaw or none of them");
  }
  prepared.base = base_count == 3;
  if (prepared.base && !s.base) {
    throw CommandError(what + "it moves the base, and model version " + std::to_string(s.version) +
                       " has no mobile base");
  }
  if (!prepared.base) return;
  for (const auto& leg : s.legs) {
    for (int j : {leg.steering_index, leg.wheel_index}) {
      if (std::find(prepared.joints.begin(), prepared.joints.end(), j) != prepared.joints.end()) {
        throw CommandError(what + "leg joint '" + s.model->joint_names()[static_cast<std::size_t>(j)] +
                           "' is driven by the base; give base_x, base_y, base_yaw or the leg joints, not both");
      }
    }
  }
}

// The samples in the prepared trajectory's column order (joints, then the base). Throws
// CommandError naming a sample of the wrong size, a time that does not increase, a non-finite value.
void add_samples(const JointTrajectory& t, const std::string& what, const std::vector<int>& column_of_joint,
                 const std::array<int, 3>& base_columns, PreparedTrajectory& prepared) {
  prepared.columns = static_cast<int>(prepared.joints.size()) + (prepared.base ? 3 : 0);
  const auto cols = static_cast<std::size_t>(prepared.columns);
  prepared.times.reserve(t.samples.size());
  prepared.position.reserve(t.samples.size() * cols);
  prepared.velocity.reserve(t.samples.size() * cols);
  for (std::size_t n = 0; n < t.samples.size(); ++n) {
    const TrajectorySample& p = t.samples[n];
    const std::string at = "sample " + std::to_string(n);
    if (p.position.size() != t.joints.size() || (!p.velocity.empty() && p.velocity.size() != t.joints.size())) {
      throw CommandError(what + at + " has " + std::to_string(p.position.size()) + " positions and " +
                         std::to_string(p.velocity.size()) + " velocities for " + std::to_string(t.joints.size()) +
                         " joints");
    }
    if (!finite(p.time) || p.time < 0.0 || (n > 0 && p.time <= prepared.times.back())) {
      throw CommandError(what + at + " time " + std::to_string(p.time) +
                         " s: times must be finite, >= 0 and strictly increasing");
    }
    for (std::size_t k = 0; k < t.joints.size(); ++k) {
      if (!finite(p.position[k]) || (!p.velocity.empty() && !finite(p.velocity[k]))) {
        throw CommandError(what + at + ": non-finite value for '" + t.joints[k] + "'");
      }
    }
    prepared.times.push_back(p.time);
    auto add = [&](int column) {
      const auto c = static_cast<std::size_t>(column);
      prepared.position.push_back(p.position[c]);
      prepared.velocity.push_back(p.velocity.empty() ? 0.0 : p.velocity[c]);
    };
    for (int c : column_of_joint) add(c);
    if (prepared.base) {
      for (int c : base_columns) add(c);
    }
  }
}

}  // namespace

void RobotCore::command_trajectory(const JointTrajectory& t) {
  std::lock_guard lock(shared_->mutex);
  check_command(t.model_version);
  Slot& s = *shared_->accepted;
  const std::string what = "trajectory " + std::to_string(t.request_id) + " refused: ";
  if (t.joints.empty()) {
    throw CommandError(what + "no joints");
  }
  if (t.samples.empty()) {
    throw CommandError(what + "no samples");
  }
  auto prepared = std::make_unique<PreparedTrajectory>();
  prepared->request_id = t.request_id;
  std::vector<int> column_of_joint;
  std::array<int, 3> base_columns{};
  resolve_columns(t, s, what, *prepared, column_of_joint, base_columns);
  add_samples(t, what, column_of_joint, base_columns, *prepared);
  const std::uint64_t seq = ++shared_->seq;
  prepared->sequence = seq;
  s.trajectories.submit(std::move(prepared));
  shared_->staged.trajectory_seq = seq;
  publish_frame(s.commands, shared_->staged);
}

void RobotCore::set_safety_stop(bool stopped, const std::string& reason) {
  {
    std::lock_guard lock(shared_->mutex);
    const std::string why = reason.empty() ? std::string("no reason given") : reason;
    if (stopped == shared_->safety_stopped && why == shared_->safety_reason) {
      return;
    }
    shared_->safety_stopped = stopped;
    shared_->safety_reason = why;
    loop_->safety_stopped.store(stopped, std::memory_order_release);
  }
  if (stopped) {
    hold();
  }
}

bool RobotCore::safety_stopped() const {
  std::lock_guard lock(shared_->mutex);
  return shared_->safety_stopped;
}

void RobotCore::hold() {
  std::lock_guard lock(shared_->mutex);
  Slot* s = shared_->accepted;
  if (s == nullptr) {
    return;
  }
  const std::uint64_t seq = ++shared_->seq;
  CommandFrame& f = shared_->staged;
  f.hold_seq = seq;
  for (auto& claim : f.claims) {
    claim = {seq, JointOwner::kHold};
  }
  f.base = BaseCommand{s->version, 0.0, 0.0, 0.0};
  f.base_seq = seq;
  shared_->cartesian_admittance = false;
  publish_frame(s->commands, f);
}

namespace {

/// The loop's half of command hand-over: applies what is new in the slot's frame.
void apply_commands(RobotCore::Slot& s) {
  if (!s.commands.update()) {
    return;
  }
  CycleData& c = s.cycle;
  const CommandFrame& f = s.commands.front();
  if (f.trajectory_seq > s.applied_trajectory) {
    s.applied_trajectory = f.trajectory_seq;
    if (PreparedTrajectory* next = s.trajectories.take()) {
      s.trajectory.start(next, c);
      if (s.running != nullptr && !s.trajectories.retire(s.running)) {
        delete s.running;  // unreachable in practice: the submitter collects before each hand-over
      }
      s.running = next;
    }
  }
  const std::uint64_t tracked = s.trajectory.running() ? s.trajectory.trajectory()->sequence : 0;
  if (f.hold_seq > s.applied_hold) {
    s.applied_hold = f.hold_seq;
    if (f.hold_seq > tracked) {
      s.trajectory.abort(TrajectoryAbort::kPreempted, c);
    }
    for (std::size_t i = 0; i < c.owner.size(); ++i) {
      if (c.owner[i] != JointOwner::kTrajectory) {
        c.owner[i] = JointOwner::kHold;
        c.follow(static_cast<int>(i));
      }
    }
  }
  for (std::size_t i = 0; i < f.claims.size(); ++i) {
    const Claim& claim = f.claims[i];
    if (claim.seq <= s.applied_claim[i]) {
      continue;
    }
    s.applied_claim[i] = claim.seq;
    if (c.owner[i] == JointOwner::kTrajectory && s.trajectory.running()) {
      if (claim.seq < tracked) {
        continue;  // older than the trajectory that took the joint
      }
      s.trajectory.abort(TrajectoryAbort::kPreempted, c);
    }
    c.owner[i] = claim.owner;
    if (claim.owner == JointOwner::kJoint) {
      s.joint.set(static_cast<int>(i), f.joints[i]);
    }
  }
  if (f.cartesian_seq > s.applied_cartesian) {
    s.applied_cartesian = f.cartesian_seq;
    s.cartesian.set(f.cartesian, f.keep_admittance);
  }
  if (f.base_seq > s.applied_base && s.base) {
    s.applied_base = f.base_seq;
    s.base->set(f.base, c.time);
  }
}

}  // namespace

namespace {

// Every drive's thermal load, from its measured torque (new hardware starts cold).
void add_thermal_load(RobotCore::Loop& L, std::uint64_t generation, double dt) {
  const std::size_t nh = L.hw_state.position.size();
  if (L.thermal.size() != nh || L.thermal_generation != generation) {
    L.thermal.assign(nh, model::ThermalLoad{});
    L.thermal_generation = generation;
  }
  for (std::size_t h = 0; h < nh && h < L.hw_state.effort.size(); ++h) {
    L.thermal[h].add(L.hw_state.effort[h], dt);
  }
}

// No model yet, or the mounted hardware changed (hot swap): every drive holds where it is until
// a matching model arrives.
void hold_drives(RobotCore::Loop& L, RobotCore::Slot* s, Hardware& hw) {
  const std::size_t nh = L.hw_state.position.size();
  if (s != nullptr && s->trajectory.running()) {
    s->trajectory.abort(TrajectoryAbort::kHardwareChanged, s->cycle);
  }
  if (!L.holding_hw || L.holding_generation != hw.generation() || L.drive.size() != nh) {
    L.drive.resize(nh);
    for (std::size_t h = 0; h < nh; ++h) {
      L.drive[h] = DriveCommand{};
      L.drive[h].position = L.hw_state.position[h];
    }
    L.holding_hw = true;
    L.holding_generation = hw.generation();
  }
  hw.write(L.drive);
}

// The hardware's reading in model order; every joint held where it is on a model's first cycle
// and when a safety stop begins.
void take_reading(RobotCore::Loop& L, RobotCore::Slot& s, double dt, bool stopped) {
  CycleData& c = s.cycle;
  c.time = L.hw_state.time;
  c.dt = dt;
  c.base_yaw_rate = std::abs(c.time - L.gyro_stamp.load(std::memory_order_acquire)) <= kGyroFresh
                        ? L.gyro_yaw_rate.load(std::memory_order_relaxed)
                        : std::numeric_limits<double>::quiet_NaN();
  for (std::size_t h = 0; h < s.hw_to_model.size(); ++h) {
    const int i = s.hw_to_model[h];
    c.q(i) = L.hw_state.position[h];
    c.qd(i) = L.hw_state.velocity[h];
    c.tau(i) = L.hw_state.effort[h];
  }
  const bool stop_begins = stopped && !L.stop_seen;
  if (stop_begins) s.trajectory.abort(TrajectoryAbort::kSafetyStop, c);
  if (s.fresh || stop_begins) {
    s.fresh = false;
    for (std::size_t i = 0; i < c.owner.size(); ++i) {
      c.owner[i] = JointOwner::kHold;
      c.follow(static_cast<int>(i));
    }
  }
  L.stop_seen = stopped;
}

// Estimation shared by the controllers: gravity, odometry, the end-effector's pose and wrench
// (quasi-static: J^T F_env = ID(q, qd, 0) - tau, low-pass filtered).
void estimate(RobotCore::Slot& s, const RobotParams& params, double dt) {
  CycleData& c = s.cycle;
  const kinematics::Model& model = *s.model;
  model.inverse_dynamics_into(s.data, c.q, c.zero, c.zero, c.gravity);
  if (s.base) s.base->estimate(c);
  if (s.arm.empty()) return;
  model.frame_pose_into(s.data, c.q, s.ee_frame, c.ee_pose);
  model.frame_jacobian_into(s.data, c.q, s.ee_frame, c.jacobian);
  model.inverse_dynamics_into(s.data, c.q, c.qd, c.zero, c.id_tau);
  for (std::size_t k = 0; k < s.arm.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    c.jac_arm.col(kk) = c.jacobian.col(s.arm[k]);
    c.residual(kk) = c.id_tau(s.arm[k]) - c.tau(s.arm[k]);
    c.qd_arm(kk) = c.qd(s.arm[k]);
  }
  const Vector6d raw = kinematics::wrench_from_residual(c.jac_arm, c.residual);
  c.wrench = s.wrench_initialized ? kinematics::low_pass(c.wrench, raw, dt, params.wrench_filter_time_constant) : raw;
  s.wrench_initialized = true;
}

// The position guard's torque on joint i (RobotParams::position_guard_margin): a spring back
// inside the margin, reaching position_guard_torque x the peak torque at the limit, and damping
// of motion outward; 0 outside the margin, for joints without position limits or peak torque.
double position_guard(const CycleData& c, int i, const RobotParams& params) {
  const auto& lim = c.limits(i);
  if (!lim.has_position_limits || lim.effort <= 0.0 || params.position_guard_margin <= 0.0 ||
      lim.upper <= lim.lower)
    return 0.0;
  const double margin = std::min(params.position_guard_margin, 0.1 * (lim.upper - lim.lower));
  const double stiffness = params.position_guard_torque * lim.effort / margin;
  const double q = c.q(i);
  const double qd = c.qd(i);
  if (q < lim.lower + margin)
    return stiffness * (lim.lower + margin - q) - (qd < 0.0 ? params.position_guard_damping * qd : 0.0);
  if (q > lim.upper - margin)
    return stiffness * (lim.upper - margin - q) - (qd > 0.0 ? params.position_guard_damping * qd : 0.0);
  return 0.0;
}

// The controllers' drive references in hardware order, within the model's limits.
void limit_drives(RobotCore::Loop& L, const RobotCore::Slot& s, const RobotParams& params) {
  const CycleData& c = s.cycle;
  const std::size_t nh = s.hw_to_model.size();
  L.drive.resize(nh);
  for (std::size_t h = 0; h < nh; ++h) {
    const int i = s.hw_to_model[h];
    const auto& lim = c.limits(i);
    DriveCommand d = c.drive[static_cast<std::size_t>(i)];
    // Velocity guard for torque-level modes: damp whatever exceeds the velocity limit.
    const double vmax = lim.velocity;
    if ((d.mode == DriveMode::kEffort || d.mode == DriveMode::kImpedance) && vmax > 0.0 &&
        std::abs(c.qd(i)) > vmax) {
      d.effort -= params.velocity_guard_gain * (c.qd(i) - std::copysign(vmax, c.qd(i)));
    }
    if (d.mode == DriveMode::kEffort || d.mode == DriveMode::kImpedance) d.effort += position_guard(c, i, params);
    if (lim.effort > 0.0) {
      d.effort = std::clamp(d.effort, -lim.effort, lim.effort);
    }
    // A leg drive's I^2 t protection: its torque limit folds back to the continuous torque as
    // its RMS torque nears it, so a load nobody planned (wheels scrubbing while the legs
    // steer, a base pushing an obstacle) makes it slip or lag, not the safety layer stop the
    // robot on the sustained-torque rule. Arm joints: continuous torque 0 here (set_model).
    const model::JointLimits& rated = s.limits[static_cast<std::size_t>(i)];
    if (rated.continuous_torque > 0.0) {
      d.max_effort = model::folded_back_torque(rated, L.thermal[h].rms());
      d.effort = std::clamp(d.effort, -d.max_effort, d.max_effort);
    } else {
      d.max_effort = lim.effort;  // no continuous torque known: the rated peak
    }
    L.drive[h] = d;
  }
}

// The cycle's state for the other threads (RobotCore::state()).
void hand_out_state(RobotCore::Loop& L, const RobotCore::Slot* s, Hardware& hw, bool matching) {
  const std::size_t nh = L.hw_state.position.size();
  RobotState& out = L.state.back();
  out.time = L.hw_state.time;
  out.cycle = ++L.cycles;
  out.ready = matching;
  out.joint_names = hw.joint_names();
  out.position = L.hw_state.position;
  out.velocity = L.hw_state.velocity;
  out.effort = L.hw_state.effort;
  out.owners.resize(nh);
  out.torque_limit.resize(nh);
  for (std::size_t h = 0; h < nh; ++h) {
    out.torque_limit[h] = h < L.drive.size() ? L.drive[h].max_effort : 0.0;
  }
  if (matching) {
    const CycleData& c = s->cycle;
    out.model_version = s->version;
    out.message = s->ready_message;
    out.has_base = s->base != nullptr;
    out.odometry = c.odometry;
    out.end_effector_frame = s->ee_frame;
    out.end_effector_pose = c.ee_pose;
    out.end_effector_wrench = c.wrench;
    for (std::size_t h = 0; h < nh; ++h) {
      out.owners[h] = c.owner[static_cast<std::size_t>(s->hw_to_model[h])];
    }
  } else {
    out.model_version = s != nullptr ? s->version : 0;
    out.message = s != nullptr ? "hardware changed: waiting for a model matching the mounted joints"
                               : "waiting for a robot model";
    std::fill(out.owners.begin(), out.owners.end(), JointOwner::kHold);
  }
  const bool own_progress = s != nullptr && s->trajectory.progress().sequence >= L.last_progress.sequence;
  out.trajectory = own_progress ? s->trajectory.progress() : L.last_progress;
  out.replaced_trajectory = s != nullptr ? s->trajectory.replaced() : TrajectoryProgress{};
  L.state.publish();
}

}  // namespace

void RobotCore::cycle() {
  Loop& L = *loop_;
  const double dt = params_.period;
  // Cycle boundary: switch to a prepared model, then to prepared hardware.
  if (Slot* next = shared_->slots.take()) {
    if (Slot* old = L.active) {
      next->cycle.odometry = old->cycle.odometry;
      if (old->trajectory.running()) {
        old->trajectory.abort(TrajectoryAbort::kModelChanged, old->cycle);
        L.last_progress = old->trajectory.progress();
      }
      if (!shared_->slots.retire(old)) {
        delete old;  // unreachable in practice: set_model() collects before each hand-over
      }
    }
    L.active = next;
  }
  hw_.switch_prepared();
  hw_.read(L.hw_state);
  add_thermal_load(L, hw_.generation(), dt);
  Slot* s = L.active;
  const bool matching = s != nullptr && s->generation == hw_.generation() &&
                        s->hw_to_model.size() == L.hw_state.position.size();
  if (!matching) {
    hold_drives(L, s, hw_);
  } else {
    L.holding_hw = false;
    take_reading(L, *s, dt, L.safety_stopped.load(std::memory_order_acquire));
    apply_commands(*s);
    estimate(*s, params_, dt);
    for (Controller* controller : s->controllers) {
      if (controller != nullptr) controller->update(s->cycle);
    }
    limit_drives(L, *s, params_);
    hw_.write(L.drive);
  }
  hand_out_state(L, s, hw_, matching);
  hw_.step(dt);
}

RobotState RobotCore::state() const {
  std::lock_guard lock(shared_->state_mutex);
  loop_->state.update();
  return loop_->state.front();
}

bool RobotCore::ready() const {
  std::lock_guard lock(shared_->mutex);
  return shared_->accepted != nullptr && shared_->accepted->generation == hw_.mounted_generation();
}

std::uint64_t RobotCore::model_version() const {
  std::lock_guard lock(shared_->mutex);
  return shared_->accepted != nullptr ? shared_->accepted->version : 0;
}

std::vector<std::string> RobotCore::arm_joints() const {
  std::lock_guard lock(shared_->mutex);
  std::vector<std::string> out;
  if (const Slot* s = shared_->accepted) {
    for (int j : s->arm) {
      out.push_back(s->model->joint_names()[static_cast<std::size_t>(j)]);
    }
  }
  return out;
}

std::vector<Leg> RobotCore::legs() const {
  std::lock_guard lock(shared_->mutex);
  return shared_->accepted != nullptr ? shared_->accepted->legs : std::vector<Leg>{};
}

void RobotCore::on_imu(const hardware::ImuSample& sample) {
  const std::shared_ptr<const kinematics::Model> m = model();
  if (!m || !sample.angular_velocity.allFinite()) return;
  std::lock_guard lock(shared_->imu_mutex);
  if (shared_->imu_model != m || shared_->imu_frame != sample.frame) {
    shared_->imu_model = m;
    shared_->imu_frame = sample.frame;
    // On the base: the root link or a link no joint moves relative to it.
    bool on_base = m->has_frame(sample.frame);
    for (int j = 0; on_base && j < m->dof(); ++j) {
      if (m->is_virtual_joint(j)) continue;
      const auto links = m->subtree_links(j);
      on_base = std::find(links.begin(), links.end(), sample.frame) == links.end();
    }
    shared_->imu_on_base = on_base;
    if (on_base) {
      kinematics::Data data = m->make_data();
      shared_->base_R_imu =
          m->relative_pose(data, Eigen::VectorXd::Zero(m->dof()), m->root_link(), sample.frame)
              .linear();
    }
  }
  if (!shared_->imu_on_base) return;
  // The base stands level on the floor: its yaw rate is the angular velocity's z in its frame.
  loop_->gyro_yaw_rate.store((shared_->base_R_imu * sample.angular_velocity).z(),
                             std::memory_order_relaxed);
  loop_->gyro_stamp.store(sample.stamp, std::memory_order_release);
}

std::shared_ptr<const kinematics::Model> RobotCore::model() const {
  std::lock_guard lock(shared_->mutex);
  return shared_->accepted != nullptr ? shared_->accepted->model : nullptr;
}

std::vector<std::pair<std::string, std::string>> RobotCore::ownership() const {
  const RobotState s = state();
  std::vector<std::pair<std::string, std::string>> out;
  for (std::size_t h = 0; h < s.joint_names.size() && h < s.owners.size(); ++h) {
    out.emplace_back(s.joint_names[h], controller_name(s.owners[h]));
  }
  return out;
}

std::string RobotCore::describe(const TrajectoryProgress& p) const {
  const auto m = model();
  auto joint = [&](int i) -> std::string {
    if (i < 0) {
      return "the base";
    }
    if (m && i < m->dof()) {
      return "joint '" + m->joint_names()[static_cast<std::size_t>(i)] + "'";
    }
    return "joint " + std::to_string(i);
  };
  switch (p.abort) {
    case TrajectoryAbort::kNone:
      return "";
    case TrajectoryAbort::kSafetyStop: {
      std::lock_guard lock(shared_->mutex);
      return "safety stop (" + shared_->safety_reason + ")";
    }
    case TrajectoryAbort::kPreempted:
      return "preempted by another command on its joints";
    case TrajectoryAbort::kModelChanged:
      return "the robot model changed";
    case TrajectoryAbort::kHardwareChanged:
      return "the mounted hardware changed";
    case TrajectoryAbort::kPathTolerance:
      return "tracking error of " + joint(p.worst_joint) + " beyond the path tolerance (" +
             std::to_string(p.worst_joint < 0 ? params_.trajectory_base_path_tolerance
                                              : params_.trajectory_path_tolerance) +
             ")";
    case TrajectoryAbort::kGoalTolerance:
      return joint(p.worst_joint) + " did not reach the final sample within " +
             std::to_string(params_.trajectory_goal_time) + " s";
  }
  return "";
}

}  // namespace concert::robot
