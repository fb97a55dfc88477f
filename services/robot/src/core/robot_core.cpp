#include "robot/robot_core.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>


namespace concert::robot {
namespace {

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) {
    out += (out.empty() ? "" : ", ") + n;
  }
  return out.empty() ? "none" : out;
}

bool finite(double v) { return std::isfinite(v); }

double clamp_abs(double v, double limit) { return limit > 0.0 ? std::clamp(v, -limit, limit) : v; }

Eigen::Vector3d rotation_error(const Eigen::Matrix3d& target, const Eigen::Matrix3d& current) {
  const Eigen::AngleAxisd aa(target * current.transpose());
  return aa.angle() * aa.axis();
}

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

}  // namespace

struct RobotCore::Controllers {
  std::shared_ptr<const kinematics::Model> model;
  kinematics::Data data;
  std::uint64_t version{0};
  std::vector<int> hw_to_model;  // hw index -> model index
  std::vector<JointOwner> owner;  // model order
  std::vector<JointCommand> joint_cmd;
  std::vector<double> hold_position;
  std::vector<double> position_ref;  // rate-limited position reference
  std::string ee_frame;
  std::vector<int> arm;
  std::vector<Leg> legs;
  std::optional<BaseKinematics> base;
  BaseCommand base_cmd;
  double base_cmd_time{-1e9};
  std::optional<CartesianCommand> cart;
  double adm_offset{0.0}, adm_rate{0.0};
  Odometry odometry;
  Vector6d wrench{Vector6d::Zero()};
  bool wrench_initialized{false};
  Eigen::Isometry3d ee_pose{Eigen::Isometry3d::Identity()};

  explicit Controllers(std::shared_ptr<const kinematics::Model> m) : model(std::move(m)), data(model->make_data()) {}
  [[nodiscard]] const kinematics::JointLimits& limits(int i) const {
    return model->joint_limits()[static_cast<std::size_t>(i)];
  }
};

RobotCore::RobotCore(Hardware& hardware, RobotParams params) : hw_(hardware), params_(std::move(params)) {
  if (params_.period <= 0.0) {
    throw std::invalid_argument("robot: period must be positive");
  }
  hw_.read(hw_state_);
  hw_joints_ = hw_.joint_names();
  hw_generation_ = hw_.generation();
  known_generation_ = hw_generation_;
  state_.message = "waiting for a robot model";
}

RobotCore::~RobotCore() = default;

void RobotCore::set_model(const std::string& urdf, std::uint64_t version, const std::string& end_effector_frame) {
  std::shared_ptr<const kinematics::Model> model;
  try {
    model = std::make_shared<const kinematics::Model>(kinematics::Model::from_urdf_string(urdf));
  } catch (const kinematics::ModelError& e) {
    throw ModelMismatchError("model version " + std::to_string(version) + " refused: " + e.what());
  }
  std::lock_guard lock(mutex_);
  if (ctl_ && version < ctl_->version) {
    throw ModelMismatchError("model version " + std::to_string(version) + " refused: older than the current version " +
                             std::to_string(ctl_->version));
  }
  // The hardware belongs to the loop thread: use what the last cycle read.
  const auto& hw_joints = hw_joints_;
  const std::set<std::string> mounted(hw_joints.begin(), hw_joints.end());
  const std::set<std::string> modelled(model->joint_names().begin(), model->joint_names().end());
  std::vector<std::string> missing, extra;
  std::set_difference(mounted.begin(), mounted.end(), modelled.begin(), modelled.end(), std::back_inserter(missing));
  std::set_difference(modelled.begin(), modelled.end(), mounted.begin(), mounted.end(), std::back_inserter(extra));
  if (!missing.empty() || !extra.empty()) {
    throw ModelMismatchError("model version " + std::to_string(version) + " '" + model->name() +
                             "' does not match the mounted hardware: mounted joints missing from the model: " +
                             join(missing) + "; model joints not mounted: " + join(extra));
  }
  auto ctl = std::make_unique<Controllers>(model);
  ctl->version = version;
  const int n = model->dof();
  for (const auto& name : hw_joints) {
    ctl->hw_to_model.push_back(model->joint_index_or_throw(name));
  }
  // Hold: every joint keeps the position it has now.
  ctl->hold_position.assign(static_cast<std::size_t>(n), 0.0);
  for (std::size_t h = 0; h < hw_joints.size(); ++h) {
    ctl->hold_position[static_cast<std::size_t>(ctl->hw_to_model[h])] = hw_state_.position[h];
  }
  ctl->position_ref = ctl->hold_position;
  ctl->owner.assign(static_cast<std::size_t>(n), JointOwner::kHold);
  ctl->joint_cmd.assign(static_cast<std::size_t>(n), JointCommand{});
  // End-effector frame and its chain.
  ctl->ee_frame = end_effector_frame.empty() ? params_.end_effector_frame : end_effector_frame;
  if (ctl->ee_frame.empty()) {
    ctl->ee_frame = default_end_effector(*model);
  } else if (!model->has_frame(ctl->ee_frame)) {
    throw ModelMismatchError("model version " + std::to_string(version) + ": end-effector frame '" + ctl->ee_frame +
                             "' is not a link of the model");
  }
  // Legs of the mobile base (never part of the arm chain).
  ctl->legs = detect_legs(*model, collision_cylinder_radii(urdf), params_.default_wheel_radius);
  std::set<int> leg_joints;
  for (const auto& leg : ctl->legs) {
    leg_joints.insert(leg.steering_index);
    leg_joints.insert(leg.wheel_index);
  }
  if (ctl->legs.size() >= 2) {
    ctl->base.emplace(ctl->legs);
  }
  if (!ctl->ee_frame.empty()) {
    for (int j = 0; j < n; ++j) {
      const auto sub = model->subtree_links(j);
      if (leg_joints.count(j) == 0 && std::find(sub.begin(), sub.end(), ctl->ee_frame) != sub.end()) {
        ctl->arm.push_back(j);
      }
    }
  }
  if (ctl_) {
    ctl->odometry = ctl_->odometry;
  }
  ctl_ = std::move(ctl);
  known_generation_ = hw_generation_;
  holding_hw_ = false;
  state_.ready = true;
  state_.model_version = version;
  state_.message = "ready at model version " + std::to_string(version);
}

void RobotCore::check_command(std::uint64_t model_version) const {
  if (safety_stopped_) {
    throw CommandError("command refused: safety stop (" + safety_reason_ + ")");
  }
  if (!ctl_ || !state_.ready) {
    throw CommandError("command refused: robot not ready (" + state_.message + ")");
  }
  if (model_version != ctl_->version) {
    throw CommandError("command for model version " + std::to_string(model_version) +
                       " refused: current model version is " + std::to_string(ctl_->version));
  }
}

void RobotCore::command_joints(const JointCommandSet& command) {
  std::lock_guard lock(mutex_);
  check_command(command.model_version);
  std::set<int> seen;
  std::vector<std::pair<int, JointCommand>> accepted;
  for (const auto& c : command.joints) {
    const auto index = ctl_->model->joint_index(c.joint);
    if (!index) {
      throw CommandError("joint command refused: unknown joint '" + c.joint + "' (model version " +
                         std::to_string(ctl_->version) + " has: " + join(ctl_->model->joint_names()) + ")");
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
    accepted.emplace_back(*index, c);
  }
  for (const auto& [i, c] : accepted) {
    ctl_->owner[static_cast<std::size_t>(i)] = JointOwner::kJoint;
    ctl_->joint_cmd[static_cast<std::size_t>(i)] = c;
  }
}

void RobotCore::command_cartesian(const CartesianCommand& command) {
  std::lock_guard lock(mutex_);
  check_command(command.model_version);
  const std::string frame = command.frame.empty() ? ctl_->ee_frame : command.frame;
  if (frame != ctl_->ee_frame) {
    throw CommandError("Cartesian command refused: frame '" + frame + "' is not the end-effector frame '" +
                       ctl_->ee_frame + "'");
  }
  if (ctl_->arm.empty()) {
    throw CommandError("Cartesian command refused: the model has no joints moving '" + frame + "'");
  }
  if ((command.stiffness.array() < 0.0).any() || (command.damping.array() < 0.0).any() ||
      !command.target_pose.matrix().allFinite() || !command.feedforward_wrench.allFinite() ||
      !command.target_twist.allFinite()) {
    throw CommandError("Cartesian command refused: negative gains or non-finite values");
  }
  if (command.admittance.enabled &&
      (std::abs(command.admittance.axis.norm() - 1.0) > 1e-6 || command.admittance.mass <= 0.0 ||
       command.admittance.damping < 0.0)) {
    throw CommandError("Cartesian command refused: admittance needs a unit axis, mass > 0, damping >= 0");
  }
  const bool keep_admittance = ctl_->cart && ctl_->cart->admittance.enabled && command.admittance.enabled;
  ctl_->cart = command;
  ctl_->cart->frame = frame;
  if (!keep_admittance) {
    ctl_->adm_offset = 0.0;
    ctl_->adm_rate = 0.0;
  }
  for (int j : ctl_->arm) {
    ctl_->owner[static_cast<std::size_t>(j)] = JointOwner::kCartesian;
  }
}

void RobotCore::command_base(const BaseCommand& command) {
  std::lock_guard lock(mutex_);
  check_command(command.model_version);
  if (!ctl_->base) {
    throw CommandError("base command refused: model version " + std::to_string(ctl_->version) + " has " +
                       std::to_string(ctl_->legs.size()) + " steering+wheel legs (needs at least 2)");
  }
  if (!finite(command.vx) || !finite(command.vy) || !finite(command.wz)) {
    throw CommandError("base command refused: non-finite twist");
  }
  ctl_->base_cmd = command;
  ctl_->base_cmd_time = hw_state_.time;
  for (const auto& leg : ctl_->legs) {
    for (int j : {leg.steering_index, leg.wheel_index}) {
      ctl_->owner[static_cast<std::size_t>(j)] = JointOwner::kBase;
    }
  }
}

void RobotCore::command_gravity_compensation(std::uint64_t model_version, const std::vector<std::string>& joints) {
  std::lock_guard lock(mutex_);
  check_command(model_version);
  std::vector<int> indices;
  if (joints.empty()) {
    indices = ctl_->arm;
  }
  for (const auto& name : joints) {
    const auto index = ctl_->model->joint_index(name);
    if (!index) {
      throw CommandError("gravity compensation refused: unknown joint '" + name + "'");
    }
    indices.push_back(*index);
  }
  for (int j : indices) {
    ctl_->owner[static_cast<std::size_t>(j)] = JointOwner::kGravityCompensation;
  }
}

void RobotCore::set_safety_stop(bool stopped, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    if (stopped == safety_stopped_ && reason == safety_reason_) {
      return;
    }
    safety_stopped_ = stopped;
    safety_reason_ = reason.empty() ? std::string("no reason given") : reason;
  }
  if (stopped) {
    hold();
  }
}

bool RobotCore::safety_stopped() const {
  std::lock_guard lock(mutex_);
  return safety_stopped_;
}

void RobotCore::hold() {
  std::lock_guard lock(mutex_);
  if (!ctl_) {
    return;
  }
  for (std::size_t h = 0; h < ctl_->hw_to_model.size() && h < hw_state_.position.size(); ++h) {
    const auto i = static_cast<std::size_t>(ctl_->hw_to_model[h]);
    ctl_->hold_position[i] = hw_state_.position[h];
    ctl_->position_ref[i] = hw_state_.position[h];
    ctl_->owner[i] = JointOwner::kHold;
  }
  ctl_->cart.reset();
  ctl_->base_cmd = BaseCommand{ctl_->version, 0.0, 0.0, 0.0};
}

void RobotCore::cycle() {
  {
    std::lock_guard lock(mutex_);
    hw_.read(hw_state_);
    if (hw_.generation() != hw_generation_) {
      hw_generation_ = hw_.generation();
      hw_joints_ = hw_.joint_names();
    }
    const std::size_t nh = hw_state_.position.size();
    const double dt = params_.period;
    if (hw_generation_ != known_generation_ || !ctl_) {
      // Mounted hardware changed (hot swap) or no model yet: hold every drive where it is
      // until a matching model arrives.
      if (ctl_ && state_.ready) {
        state_.ready = false;
        state_.message = "hardware changed: waiting for a model matching the mounted joints";
      }
      if (!holding_hw_ || drive_.size() != nh) {
        drive_.assign(nh, DriveCommand{});
        for (std::size_t h = 0; h < nh; ++h) {
          drive_[h].position = hw_state_.position[h];
        }
        holding_hw_ = true;
      }
      hw_.write(drive_);
    } else {
      Controllers& c = *ctl_;
      const auto& model = *c.model;
      const int n = model.dof();
      Eigen::VectorXd q(n), qd(n), tau_meas(n);
      for (std::size_t h = 0; h < nh; ++h) {
        const auto i = c.hw_to_model[h];
        q(i) = hw_state_.position[h];
        qd(i) = hw_state_.velocity[h];
        tau_meas(i) = hw_state_.effort[h];
      }
      const Eigen::VectorXd gravity = model.gravity_torques(c.data, q);
      // Odometry from the legs.
      if (c.base) {
        std::vector<double> steer, wheel;
        for (const auto& leg : c.legs) {
          steer.push_back(q(leg.steering_index));
          wheel.push_back(qd(leg.wheel_index));
        }
        c.base->integrate(c.odometry, steer, wheel, dt);
      }
      // End-effector pose and external wrench (quasi-static: J^T F_env = ID(q, qd, 0) - tau).
      Eigen::MatrixXd jac_arm;
      if (!c.arm.empty()) {
        c.ee_pose = model.frame_pose(c.data, q, c.ee_frame);
        const Eigen::MatrixXd jac = model.frame_jacobian(c.data, q, c.ee_frame);
        jac_arm.resize(6, static_cast<Eigen::Index>(c.arm.size()));
        Eigen::VectorXd residual(static_cast<Eigen::Index>(c.arm.size()));
        const Eigen::VectorXd id = model.inverse_dynamics(c.data, q, qd, Eigen::VectorXd::Zero(n));
        for (std::size_t k = 0; k < c.arm.size(); ++k) {
          jac_arm.col(static_cast<Eigen::Index>(k)) = jac.col(c.arm[k]);
          residual(static_cast<Eigen::Index>(k)) = id(c.arm[k]) - tau_meas(c.arm[k]);
        }
        const Eigen::Matrix<double, 6, 6> jjt = jac_arm * jac_arm.transpose() + 1e-6 * Eigen::Matrix<double, 6, 6>::Identity();
        const Vector6d raw = jjt.ldlt().solve(jac_arm * residual);
        const double alpha = params_.wrench_filter_time_constant > 0.0
                                 ? dt / (params_.wrench_filter_time_constant + dt)
                                 : 1.0;
        c.wrench = c.wrench_initialized ? Vector6d(c.wrench + alpha * (raw - c.wrench)) : raw;
        c.wrench_initialized = true;
      }
      // Cartesian impedance torques.
      Eigen::VectorXd tau_cart = Eigen::VectorXd::Zero(n);
      if (c.cart && !c.arm.empty()) {
        const CartesianCommand& cc = *c.cart;
        Eigen::Isometry3d target = cc.target_pose;
        if (cc.admittance.enabled) {
          const double pushed = -c.wrench.head<3>().dot(cc.admittance.axis);
          const double acc = (cc.admittance.force_setpoint - pushed - cc.admittance.damping * c.adm_rate) /
                             cc.admittance.mass;
          c.adm_rate += acc * dt;
          c.adm_offset += c.adm_rate * dt;
          if (std::abs(c.adm_offset) > cc.admittance.max_offset) {
            c.adm_offset = std::copysign(cc.admittance.max_offset, c.adm_offset);
            c.adm_rate = 0.0;
          }
          target.translation() += c.adm_offset * cc.admittance.axis;
        }
        Eigen::VectorXd qd_arm(static_cast<Eigen::Index>(c.arm.size()));
        for (std::size_t k = 0; k < c.arm.size(); ++k) {
          qd_arm(static_cast<Eigen::Index>(k)) = qd(c.arm[k]);
        }
        const Vector6d twist = jac_arm * qd_arm;
        Vector6d error;
        error.head<3>() = target.translation() - c.ee_pose.translation();
        error.tail<3>() = rotation_error(target.linear(), c.ee_pose.linear());
        const Vector6d force = cc.stiffness.cwiseProduct(error) + cc.damping.cwiseProduct(cc.target_twist - twist) +
                               cc.feedforward_wrench;
        const Eigen::VectorXd tau_arm = jac_arm.transpose() * force - cc.nullspace_damping * qd_arm;
        for (std::size_t k = 0; k < c.arm.size(); ++k) {
          tau_cart(c.arm[k]) = tau_arm(static_cast<Eigen::Index>(k));
        }
      }
      // Base: leg setpoints (the base stops if commands stop coming).
      std::map<int, LegSetpoint> leg_sp;
      if (c.base) {
        Eigen::Vector3d twist(c.base_cmd.vx, c.base_cmd.vy, c.base_cmd.wz);
        if (hw_state_.time - c.base_cmd_time > params_.base_command_timeout) {
          twist.setZero();
        }
        std::vector<double> steer;
        for (const auto& leg : c.legs) {
          steer.push_back(c.position_ref[static_cast<std::size_t>(leg.steering_index)]);
        }
        const auto sp = c.base->leg_setpoints(twist, steer);
        for (std::size_t k = 0; k < c.legs.size(); ++k) {
          leg_sp[c.legs[k].steering_index] = sp[k];
          leg_sp[c.legs[k].wheel_index] = sp[k];
        }
      }
      // Drive references with the model's limits.
      drive_.assign(nh, DriveCommand{});
      for (std::size_t h = 0; h < nh; ++h) {
        const int i = c.hw_to_model[h];
        const auto iu = static_cast<std::size_t>(i);
        const auto& lim = c.limits(i);
        const double vmax = lim.velocity;
        auto clamp_pos = [&](double p) { return lim.has_position_limits ? std::clamp(p, lim.lower, lim.upper) : p; };
        // Move the rate-limited reference towards `target` at most vmax * dt.
        auto ramp = [&](double target) {
          double& ref = c.position_ref[iu];
          const double step = vmax > 0.0 ? vmax * dt : 1e9;
          ref += std::clamp(clamp_pos(target) - ref, -step, step);
          return ref;
        };
        DriveCommand& d = drive_[h];
        switch (c.owner[iu]) {
          case JointOwner::kHold:
            d.mode = DriveMode::kPosition;
            d.position = ramp(c.hold_position[iu]);
            d.effort = gravity(i);
            break;
          case JointOwner::kJoint: {
            const JointCommand& jc = c.joint_cmd[iu];
            d.mode = jc.mode;
            switch (jc.mode) {
              case DriveMode::kPosition:
                d.position = ramp(jc.position);
                d.effort = gravity(i) + jc.effort;
                break;
              case DriveMode::kVelocity:
                d.velocity = clamp_abs(jc.velocity, vmax);
                if (lim.has_position_limits &&
                    ((q(i) >= lim.upper && d.velocity > 0.0) || (q(i) <= lim.lower && d.velocity < 0.0))) {
                  d.velocity = 0.0;
                }
                break;
              case DriveMode::kEffort:
                d.effort = jc.effort;
                break;
              case DriveMode::kImpedance:
                d.position = clamp_pos(jc.position);
                d.velocity = clamp_abs(jc.velocity, vmax);
                d.effort = jc.effort;
                d.stiffness = jc.stiffness;
                d.damping = jc.damping;
                break;
            }
            c.hold_position[iu] = q(i);
            if (jc.mode != DriveMode::kPosition) {
              c.position_ref[iu] = q(i);
            }
            break;
          }
          case JointOwner::kCartesian:
            d.mode = DriveMode::kEffort;
            d.effort = tau_cart(i) + gravity(i);
            c.hold_position[iu] = c.position_ref[iu] = q(i);
            break;
          case JointOwner::kGravityCompensation:
            d.mode = DriveMode::kEffort;
            d.effort = gravity(i);
            c.hold_position[iu] = c.position_ref[iu] = q(i);
            break;
          case JointOwner::kBase: {
            const LegSetpoint& sp = leg_sp.at(i);
            const bool steering = std::any_of(c.legs.begin(), c.legs.end(),
                                              [&](const Leg& l) { return l.steering_index == i; });
            if (steering) {
              d.mode = DriveMode::kPosition;
              d.position = ramp(sp.steering_angle);
              d.effort = gravity(i);
            } else {
              d.mode = DriveMode::kVelocity;
              d.velocity = clamp_abs(sp.wheel_velocity, vmax);
              c.hold_position[iu] = c.position_ref[iu] = q(i);
            }
            break;
          }
        }
        // Velocity guard for torque-level modes: damp whatever exceeds the velocity limit.
        if ((d.mode == DriveMode::kEffort || d.mode == DriveMode::kImpedance) && vmax > 0.0 &&
            std::abs(qd(i)) > vmax) {
          d.effort -= params_.velocity_guard_gain * (qd(i) - std::copysign(vmax, qd(i)));
        }
        d.effort = clamp_abs(d.effort, lim.effort);
      }
      hw_.write(drive_);
      state_.odometry = c.odometry;
      state_.end_effector_frame = c.ee_frame;
      state_.end_effector_pose = c.ee_pose;
      state_.end_effector_wrench = c.wrench;
      state_.has_base = c.base.has_value();
      state_.owners.resize(nh);
      for (std::size_t h = 0; h < nh; ++h) {
        state_.owners[h] = c.owner[static_cast<std::size_t>(c.hw_to_model[h])];
      }
    }
    state_.time = hw_state_.time;
    state_.joint_names = hw_joints_;
    state_.position = hw_state_.position;
    state_.velocity = hw_state_.velocity;
    state_.effort = hw_state_.effort;
  }
  hw_.step(params_.period);
}

RobotState RobotCore::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

bool RobotCore::ready() const {
  std::lock_guard lock(mutex_);
  return state_.ready;
}

std::uint64_t RobotCore::model_version() const {
  std::lock_guard lock(mutex_);
  return ctl_ ? ctl_->version : 0;
}

std::vector<std::string> RobotCore::arm_joints() const {
  std::lock_guard lock(mutex_);
  std::vector<std::string> out;
  if (ctl_) {
    for (int j : ctl_->arm) {
      out.push_back(ctl_->model->joint_names()[static_cast<std::size_t>(j)]);
    }
  }
  return out;
}

std::vector<Leg> RobotCore::legs() const {
  std::lock_guard lock(mutex_);
  return ctl_ ? ctl_->legs : std::vector<Leg>{};
}

std::shared_ptr<const kinematics::Model> RobotCore::model() const {
  std::lock_guard lock(mutex_);
  return ctl_ ? ctl_->model : nullptr;
}

}  // namespace concert::robot
