#include "robot/controllers.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>
#include <utility>

#include "concert/common/enum_map.hpp"
#include "concert/kinematics/impedance.hpp"

namespace concert::robot {
namespace {

double clamp_abs(double v, double limit) { return limit > 0.0 ? std::clamp(v, -limit, limit) : v; }

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

using namespace std::string_view_literals;

// The controller behind each owner, by the name ownership() reports.
constexpr EnumMap kControllerNames{std::array{
    std::pair{JointOwner::kHold, "hold"sv},
    std::pair{JointOwner::kJoint, "joint"sv},
    std::pair{JointOwner::kCartesian, "cartesian_impedance"sv},
    std::pair{JointOwner::kGravityCompensation, "gravity_compensation"sv},
    std::pair{JointOwner::kBase, "base_velocity"sv},
    std::pair{JointOwner::kTrajectory, "joint_trajectory"sv},
}};

}  // namespace

std::string_view controller_name(JointOwner owner) {
  return kControllerNames.to(owner).value_or("unknown");
}

CycleData::CycleData(const kinematics::Model& m, std::size_t arm_joints) : model(&m) {
  const auto n = static_cast<Eigen::Index>(m.dof());
  const auto na = static_cast<Eigen::Index>(arm_joints);
  q = qd = tau = gravity = zero = id_tau = Eigen::VectorXd::Zero(n);
  jacobian = Eigen::MatrixXd::Zero(6, n);
  jac_arm = Eigen::MatrixXd::Zero(6, na);
  qd_arm = residual = Eigen::VectorXd::Zero(na);
  const auto nu = static_cast<std::size_t>(n);
  owner.assign(nu, JointOwner::kHold);
  hold_position.assign(nu, 0.0);
  position_ref.assign(nu, 0.0);
  drive.assign(nu, DriveCommand{});
  wheel.assign(nu, 0);
}

double CycleData::clamp_position(int i, double p) const {
  const auto& lim = limits(i);
  return lim.has_position_limits ? std::clamp(p, lim.lower, lim.upper) : p;
}

double CycleData::ramp(int i, double target, double rate) {
  const double vmax = rate * limits(i).velocity;
  double& ref = position_ref[static_cast<std::size_t>(i)];
  const double step = vmax > 0.0 ? vmax * dt : 1e9;
  ref += std::clamp(clamp_position(i, target) - ref, -step, step);
  return ref;
}

void CycleData::follow(int i) {
  const auto iu = static_cast<std::size_t>(i);
  hold_position[iu] = position_ref[iu] = q(i);
}

DriveCommand& CycleData::new_drive(int i, DriveMode mode) {
  DriveCommand& d = drive[static_cast<std::size_t>(i)];
  d = DriveCommand{};
  d.mode = mode;
  return d;
}

void HoldController::update(CycleData& data) {
  data.for_each_owned_by(JointOwner::kHold, [this, &data](int i) {
    // A wheel rolling when its hold begins brakes (velocity 0) and is held where it comes to
    // rest. Held where it was when the hold began (a safety stop while the base drives), it
    // would be driven back: the stopped base rolls back 6 mm and a wheel 0.07 rad. Only then: a
    // wheel that braked whenever it rolled would let a pushed base roll away on its brakes'
    // damping (300 N moves the paper's base 14 cm in 5 s).
    constexpr double kRolling = 0.05;  // [rad/s]
    const auto iu = static_cast<std::size_t>(i);
    if (!data.continued(held_at_[iu])) {
      braking_[iu] = data.wheel[iu] != 0 && std::abs(data.qd(i)) > kRolling ? 1 : 0;
    }
    if (braking_[iu] != 0 && std::abs(data.qd(i)) <= kRolling) braking_[iu] = 0;
    if (braking_[iu] != 0) {
      data.new_drive(i, DriveMode::kVelocity).velocity = 0.0;
      data.follow(i);
      return;
    }
    DriveCommand& d = data.new_drive(i, DriveMode::kPosition);
    d.position = data.ramp(i, data.hold_position[static_cast<std::size_t>(i)]);
    d.effort = data.gravity(i);
  });
}

void JointController::update(CycleData& data) {
  data.for_each_owned_by(JointOwner::kJoint, [this, &data](int i) {
    const auto iu = static_cast<std::size_t>(i);
    const JointSetpoint& jc = setpoints_[iu];
    const auto& lim = data.limits(i);
    DriveCommand& d = data.new_drive(i, jc.mode);
    switch (jc.mode) {
      case DriveMode::kPosition:
        d.position = data.ramp(i, jc.position);
        d.effort = data.gravity(i) + jc.effort;
        break;
      case DriveMode::kVelocity:
        d.velocity = clamp_abs(jc.velocity, lim.velocity);
        if (lim.has_position_limits && ((data.q(i) >= lim.upper && d.velocity > 0.0) ||
                                        (data.q(i) <= lim.lower && d.velocity < 0.0))) {
          d.velocity = 0.0;
        }
        break;
      case DriveMode::kEffort:
        d.effort = jc.effort;
        break;
      case DriveMode::kImpedance:
        d.position = data.clamp_position(i, jc.position);
        d.velocity = clamp_abs(jc.velocity, lim.velocity);
        d.effort = jc.effort;
        d.stiffness = jc.stiffness;
        d.damping = jc.damping;
        break;
    }
    data.hold_position[iu] = data.q(i);
    if (jc.mode != DriveMode::kPosition) {
      data.position_ref[iu] = data.q(i);
    }
  });
}

CartesianController::CartesianController(const std::vector<int>& arm)
    : arm_(arm), tau_arm_(Eigen::VectorXd::Zero(static_cast<Eigen::Index>(arm.size()))) {}

void CartesianController::set(const CartesianCommand& command, bool keep_admittance) {
  command_.model_version = command.model_version;
  command_.target_pose = command.target_pose;
  command_.target_twist = command.target_twist;
  command_.stiffness = command.stiffness;
  command_.damping = command.damping;
  command_.feedforward_wrench = command.feedforward_wrench;
  command_.payload_mass = command.payload_mass;
  command_.admittance = command.admittance;
  command_.nullspace_damping = command.nullspace_damping;
  if (!keep_admittance) {
    offset_ = 0.0;
    rate_ = 0.0;
  }
}

void CartesianController::update(CycleData& data) {
  bool owns = false;
  for (int j : arm_) {
    owns = owns || data.owner[static_cast<std::size_t>(j)] == JointOwner::kCartesian;
  }
  if (!owns || arm_.empty()) {
    return;
  }
  const CartesianCommand& cc = command_;
  Eigen::Isometry3d target = cc.target_pose;
  if (cc.admittance.enabled) {
    const double pushed = -data.wrench.head<3>().dot(cc.admittance.axis);
    const double acc = (cc.admittance.force_setpoint - pushed - cc.admittance.damping * rate_) / cc.admittance.mass;
    rate_ += acc * data.dt;
    offset_ += rate_ * data.dt;
    if (std::abs(offset_) > cc.admittance.max_offset) {
      offset_ = std::copysign(cc.admittance.max_offset, offset_);
      rate_ = 0.0;
    }
    target.translation() += offset_ * cc.admittance.axis;
  }
  Vector6d twist;
  twist.noalias() = data.jac_arm.lazyProduct(data.qd_arm);
  Vector6d force = kinematics::impedance_wrench(data.ee_pose, target, twist, cc.target_twist, cc.stiffness,
                                                cc.damping) +
                   cc.feedforward_wrench;
  // The payload's weight, held at the frame's origin (J^T m (-g), beside the arm's own g(q)).
  if (cc.payload_mass > 0.0) {
    force.head<3>() -= cc.payload_mass * data.model->gravity();
  }
  kinematics::wrench_torques(data.jac_arm, force, data.qd_arm, cc.nullspace_damping, tau_arm_);
  for (std::size_t k = 0; k < arm_.size(); ++k) {
    const int i = arm_[k];
    const auto iu = static_cast<std::size_t>(i);
    if (data.owner[iu] != JointOwner::kCartesian) {
      continue;
    }
    data.new_drive(i, DriveMode::kEffort).effort =
        tau_arm_(static_cast<Eigen::Index>(k)) + data.gravity(i);
    data.follow(i);
  }
}

void GravityCompensationController::update(CycleData& data) {
  data.for_each_owned_by(JointOwner::kGravityCompensation, [&data](int i) {
    data.new_drive(i, DriveMode::kEffort).effort = data.gravity(i);
    data.follow(i);
  });
}

BaseController::BaseController(std::vector<Leg> legs, double command_timeout, double trajectory_steering_rate,
                               double steering_acceleration)
    : kinematics_(std::move(legs)),
      timeout_(command_timeout),
      trajectory_steering_rate_(trajectory_steering_rate),
      steering_acceleration_(steering_acceleration),
      steering_ref_rate_(kinematics_.legs().size(), 0.0),
      steered_at_(kinematics_.legs().size(), -1e9),
      stood_at_(kinematics_.legs().size(), -1e9),
      stand_(kinematics_.legs().size(), std::numeric_limits<double>::quiet_NaN()),
      steering_(kinematics_.legs().size(), 0.0),
      wheel_velocity_(kinematics_.legs().size(), 0.0),
      steering_rate_(kinematics_.legs().size(), 0.0),
      setpoints_(kinematics_.legs().size()) {}

void BaseController::set(const BaseCommand& command, double time) {
  twist_ = {command.vx, command.vy, command.wz};
  command_time_ = time;
}

void BaseController::estimate(CycleData& data) {
  const auto& legs = kinematics_.legs();
  for (std::size_t k = 0; k < legs.size(); ++k) {
    steering_[k] = data.q(legs[k].steering_index);
    wheel_velocity_[k] = data.qd(legs[k].wheel_index);
    steering_rate_[k] = data.qd(legs[k].steering_index);
  }
  const Eigen::Vector3d twist = kinematics_.twist_from_legs(steering_, wheel_velocity_, steering_rate_);
  double yaw_rate = twist.z();
  if (std::isfinite(data.base_yaw_rate)) {
    constexpr double kStill = 1e-3;     // wheel twist and joint speeds below this: still [m/s, rad/s]
    constexpr double kBiasTime = 10.0;  // time constant of the bias estimate [s]
    // Still: no wheel rolls, no leg steers (a leg turning in place twists the base, with no
    // wheel speed to show it) and no arm joint moves. A moving arm, or one pushing a drill into
    // a wall, can turn the standing base on its wheels' contacts (a few mrad per hole on the
    // demo wall); that turn is the gyro's to see, not a bias to learn.
    bool still = twist.head<2>().norm() < kStill && std::abs(twist.z()) < kStill &&
                 data.qd.cwiseAbs().maxCoeff() < kStill;
    if (still) {
      // A running mean at first, then a moving average over kBiasTime (one sample at 1 kHz is
      // ~5 mrad/s of noise; the mean of 10 s, 0.05 mrad/s).
      bias_samples_ += 1.0;
      const double weight = std::max(data.dt / kBiasTime, 1.0 / bias_samples_);
      gyro_bias_ += weight * (data.base_yaw_rate - gyro_bias_);
      gyro_bias_known_ = true;
      yaw_rate = 0.0;
    } else if (gyro_bias_known_) {
      yaw_rate = data.base_yaw_rate - gyro_bias_;
    }
  }
  BaseKinematics::integrate(data.odometry, twist, yaw_rate, data.dt);
}

void BaseController::steer(CycleData& data, std::size_t k, double target, double rate, DriveCommand& d) {
  // The steering's reference turns along a profile with a limited acceleration, and hands its
  // rate to the drive as a velocity feed-forward (CiA 402's velocity offset). A reference that
  // turns at full rate at once, without the feed-forward, runs ahead of the steering while the
  // drive's damping and the tyre's scrub hold it back (0.3 rad at the velocity limit), and when
  // it stops the drive catches up beyond the limit: 10.3 rad/s of 8.91 on the paper's base
  // turning its wheels 90 degrees, a safety stop.
  const int s = kinematics_.legs()[k].steering_index;
  const auto su = static_cast<std::size_t>(s);
  double& ref = data.position_ref[su];
  double& v = steering_ref_rate_[k];
  // Another owner had the leg last cycle (a hold, a stop): the profile starts from the steering's
  // own motion.
  if (!data.continued(steered_at_[k])) v = data.qd(s);
  const double vmax = rate * data.limits(s).velocity;
  const double a = steering_acceleration_;
  const double left = data.clamp_position(s, target) - ref;
  // The fastest rate from which the reference still stops at the target.
  const double stopping = std::copysign(std::sqrt(2.0 * a * std::abs(left)), left);
  const double wanted = vmax > 0.0 ? std::clamp(stopping, -vmax, vmax) : stopping;
  v += std::clamp(wanted - v, -a * data.dt, a * data.dt);
  if (std::abs(left) <= std::abs(v) * data.dt && left * v >= 0.0) {
    ref += left;  // arrives this cycle
    v = 0.0;
  } else {
    ref += v * data.dt;
  }
  // Never more than kLead ahead of the steering: a blocked or slow leg does not wind the
  // reference up (what the drive would release at once), and its rate is what the leg does.
  constexpr double kLead = 0.05;  // [rad]
  const double q = data.q(s);
  if (std::abs(ref - q) > kLead) {
    ref = std::clamp(ref, q - kLead, q + kLead);
    v = vmax > 0.0 ? std::clamp(data.qd(s), -vmax, vmax) : data.qd(s);
  }
  d.position = ref;
  d.velocity = v;
}

void BaseController::update(CycleData& data) {
  const Eigen::Vector3d twist = data.time - command_time_ > timeout_ ? Eigen::Vector3d::Zero() : twist_;
  drive_legs(data, twist, JointOwner::kBase);
}

void BaseController::drive_legs(CycleData& data, const Eigen::Vector3d& twist, JointOwner owner) {
  const auto& legs = kinematics_.legs();
  for (std::size_t k = 0; k < legs.size(); ++k) {
    steering_[k] = data.position_ref[static_cast<std::size_t>(legs[k].steering_index)];
  }
  kinematics_.leg_setpoints(twist, steering_, setpoints_);
  for (std::size_t k = 0; k < legs.size(); ++k) {
    const int s = legs[k].steering_index;
    const int w = legs[k].wheel_index;
    if (data.owner[static_cast<std::size_t>(s)] == owner) {
      DriveCommand& d = data.new_drive(s, DriveMode::kPosition);
      steer(data, k, setpoints_[k].steering_angle,
            owner == JointOwner::kTrajectory ? trajectory_steering_rate_ : 1.0, d);
      d.effort = data.gravity(s);
    }
    if (data.owner[static_cast<std::size_t>(w)] == owner) {
      double rolling = setpoints_[k].wheel_velocity;
      // Roll only as fast as the steering points the right way (swerve practice): steering a
      // rolling loaded wheel scrubs, which costs the steering more than its continuous torque
      // and moves the base where odometry does not see it (the demo robot's odometry over the
      // test's 1.2 m of moves: 33 mm off with this under base commands too, 46 mm without).
      rolling *= std::max(0.0, std::cos(setpoints_[k].steering_angle - data.q(s)));
      // A wheel beside its steering axis rolls as its leg steers (Leg::axle_offset); held, it
      // would drag the base along (35-40 mm at each start of the demo's moves, unseen by odometry).
      rolling += kinematics_.steering_rolling(k, data.qd(s));
      if (owner == JointOwner::kBase && stands(data, k, s, w, setpoints_[k].wheel_velocity)) continue;
      DriveCommand& d = data.new_drive(w, DriveMode::kVelocity);
      d.velocity = clamp_abs(rolling, data.limits(w).velocity);
      data.follow(w);
    }
  }
}

// A wheel told to stand (zero twist, or the commands timed out) is held in position where it came
// to rest, as the hold does, not driven at zero velocity: at zero velocity a sustained push rolled
// the base at F·r/(4·velocity gain), a base stopped by nav or collab pushable by hand.
bool BaseController::stands(CycleData& data, std::size_t k, int s, int w, double commanded) {
  constexpr double kRolling = 0.05;  // [rad/s]: slower, a drive has come to rest (HoldController's)
  double& at = stand_[k];
  if (!data.continued(stood_at_[k]) || commanded != 0.0) at = std::numeric_limits<double>::quiet_NaN();
  if (std::isnan(at)) {
    // Told to stand (the twist under the steering deadband gives exactly 0), the wheel and its
    // leg's steering at rest.
    if (commanded != 0.0 || std::abs(data.qd(w)) > kRolling || std::abs(data.qd(s)) > kRolling) return false;
    at = data.q(w);
    data.follow(w);
  }
  DriveCommand& d = data.new_drive(w, DriveMode::kPosition);
  d.position = data.ramp(w, at);
  d.effort = data.gravity(w);
  return true;
}

TrajectoryController::TrajectoryController(int dof, const RobotParams& params, BaseController* base)
    : params_(params),
      base_(base),
      q_ref_(static_cast<std::size_t>(dof) + 3, 0.0),
      qd_ref_(static_cast<std::size_t>(dof) + 3, 0.0) {}

void TrajectoryController::start(const PreparedTrajectory* trajectory, CycleData& data) {
  if (running()) {
    abort(TrajectoryAbort::kPreempted, data);
    replaced_ = progress_;
  }
  trajectory_ = trajectory;
  start_time_ = data.time;
  progress_ = TrajectoryProgress{};
  progress_.request_id = trajectory->request_id;
  progress_.sequence = trajectory->sequence;
  progress_.state = TrajectoryState::kExecuting;
  progress_.duration = trajectory->duration();
  for (int j : trajectory->joints) {
    data.owner[static_cast<std::size_t>(j)] = JointOwner::kTrajectory;
  }
  if (trajectory->base && base_ != nullptr) {
    for (const Leg& leg : base_->legs()) {
      data.owner[static_cast<std::size_t>(leg.steering_index)] = JointOwner::kTrajectory;
      data.owner[static_cast<std::size_t>(leg.wheel_index)] = JointOwner::kTrajectory;
    }
  }
}

void TrajectoryController::release(CycleData& data, bool to_final) {
  for (std::size_t iu = 0; iu < data.owner.size(); ++iu) {
    if (data.owner[iu] != JointOwner::kTrajectory) {
      continue;
    }
    data.owner[iu] = JointOwner::kHold;
    const int i = static_cast<int>(iu);
    data.hold_position[iu] = data.q(i);
    data.position_ref[iu] = data.q(i);
  }
  if (to_final && trajectory_ != nullptr) {
    const auto last = trajectory_->times.size() - 1;
    for (std::size_t k = 0; k < trajectory_->joints.size(); ++k) {
      const auto iu = static_cast<std::size_t>(trajectory_->joints[k]);
      data.hold_position[iu] = data.clamp_position(
          trajectory_->joints[k], trajectory_->position[last * static_cast<std::size_t>(trajectory_->columns) + k]);
    }
  }
}

void TrajectoryController::abort(TrajectoryAbort reason, CycleData& data) {
  if (!running()) {
    return;
  }
  release(data, false);
  progress_.state = TrajectoryState::kAborted;
  progress_.abort = reason;
}

void TrajectoryController::sample(double t) {
  const PreparedTrajectory& tr = *trajectory_;
  const auto cols = static_cast<std::size_t>(tr.columns);
  const auto n = tr.times.size();
  if (t <= tr.times.front() || n == 1) {
    std::copy_n(tr.position.begin(), cols, q_ref_.begin());
    std::copy_n(tr.velocity.begin(), cols, qd_ref_.begin());
    return;
  }
  if (t >= tr.times.back()) {
    std::copy_n(tr.position.begin() + static_cast<std::ptrdiff_t>((n - 1) * cols), cols, q_ref_.begin());
    std::fill_n(qd_ref_.begin(), cols, 0.0);
    return;
  }
  const auto it = std::upper_bound(tr.times.begin(), tr.times.end(), t);
  const auto b = static_cast<std::size_t>(it - tr.times.begin());
  const std::size_t a = b - 1;
  const double s = (t - tr.times[a]) / (tr.times[b] - tr.times[a]);
  for (std::size_t c = 0; c < cols; ++c) {
    const double pa = tr.position[a * cols + c], pb = tr.position[b * cols + c];
    const double va = tr.velocity[a * cols + c], vb = tr.velocity[b * cols + c];
    q_ref_[c] = pa + s * (pb - pa);
    qd_ref_[c] = va + s * (vb - va);
  }
}

void TrajectoryController::update(CycleData& data) {
  if (!running()) {
    return;
  }
  const PreparedTrajectory& tr = *trajectory_;
  const double t = data.time - start_time_;
  sample(t);
  double joint_error = 0.0;
  int worst = -1;
  for (std::size_t k = 0; k < tr.joints.size(); ++k) {
    const int i = tr.joints[k];
    const auto iu = static_cast<std::size_t>(i);
    const double error = std::abs(q_ref_[k] - data.q(i));
    if (error > joint_error) {
      joint_error = error;
      worst = i;
    }
    if (data.owner[iu] != JointOwner::kTrajectory) {
      continue;
    }
    DriveCommand& d = data.new_drive(i, DriveMode::kPosition);
    d.position = data.clamp_position(i, q_ref_[k]);
    d.velocity = clamp_abs(qd_ref_[k], data.limits(i).velocity);
    d.effort = data.gravity(i);
    data.position_ref[iu] = data.hold_position[iu] = d.position;
  }
  double base_error = 0.0;
  if (tr.base && base_ != nullptr) {
    const std::size_t c = tr.joints.size();
    const double ex = q_ref_[c] - data.odometry.x;
    const double ey = q_ref_[c + 1] - data.odometry.y;
    const double eyaw = wrap(q_ref_[c + 2] - data.odometry.yaw);
    base_error = std::hypot(ex, ey);
    const double k = params_.trajectory_base_gain;
    double vx = qd_ref_[c] + k * ex;
    double vy = qd_ref_[c + 1] + k * ey;
    double wz = qd_ref_[c + 2] + k * eyaw;
    // Below the deadband the legs keep their steering: tiny feedback corrections in changing
    // directions would otherwise swing the steering back and forth.
    const double deadband = params_.trajectory_base_deadband;
    if (std::hypot(vx, vy) < deadband && std::abs(wz) < deadband) {
      vx = vy = wz = 0.0;
    }
    const double co = std::cos(data.odometry.yaw), si = std::sin(data.odometry.yaw);
    base_->drive_legs(data, Eigen::Vector3d(co * vx + si * vy, -si * vx + co * vy, wz), JointOwner::kTrajectory);
  }
  if (joint_error > progress_.max_joint_error) {
    progress_.max_joint_error = joint_error;
    progress_.worst_joint = worst;
  }
  progress_.max_base_error = std::max(progress_.max_base_error, base_error);
  progress_.progress = tr.duration() > 0.0 ? std::clamp(t / tr.duration(), 0.0, 1.0) : 1.0;
  if (joint_error > params_.trajectory_path_tolerance) {
    progress_.worst_joint = worst;
    abort(TrajectoryAbort::kPathTolerance, data);
    return;
  }
  if (base_error > params_.trajectory_base_path_tolerance) {
    progress_.worst_joint = -1;
    abort(TrajectoryAbort::kPathTolerance, data);
    return;
  }
  if (t < tr.duration()) {
    return;
  }
  if (joint_error <= params_.trajectory_goal_tolerance && base_error <= params_.trajectory_base_goal_tolerance) {
    release(data, true);
    progress_.state = TrajectoryState::kSucceeded;
    progress_.progress = 1.0;
  } else if (t > tr.duration() + params_.trajectory_goal_time) {
    progress_.worst_joint = joint_error > params_.trajectory_goal_tolerance ? worst : -1;
    abort(TrajectoryAbort::kGoalTolerance, data);
  }
}

}  // namespace concert::robot
