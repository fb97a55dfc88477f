#include "concert/mobile_base/base_kinematics.hpp"

#include <Eigen/Dense>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace concert::mobile_base {
namespace {

double wrap(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a < 0.0) {
    a += 2.0 * M_PI;
  }
  return a - M_PI;
}

}  // namespace

std::map<std::string, double> collision_cylinder_radii(const std::string& urdf) {
  const auto parsed = urdf::parseURDF(urdf);
  if (!parsed) {
    throw std::invalid_argument("collision_cylinder_radii: the URDF could not be parsed");
  }
  std::vector<urdf::LinkSharedPtr> links;
  parsed->getLinks(links);
  std::map<std::string, double> out;
  for (const auto& link : links) {
    for (const auto& c : link->collision_array) {
      if (c && c->geometry && c->geometry->type == urdf::Geometry::CYLINDER) {
        out[link->name] = dynamic_cast<const urdf::Cylinder&>(*c->geometry).radius;
        break;
      }
    }
  }
  return out;
}

double standing_height(const std::vector<Leg>& legs) {
  double height = 0.0;
  for (const auto& leg : legs) {
    height = std::max(height, leg.wheel_radius - leg.wheel_center_height);
  }
  return height;
}

namespace {

// The model at q = 0 as the legs are measured: its data, the root's pose, and which joints have
// a movable ancestor.
struct Zero {
  explicit Zero(const kinematics::Model& m)
      : model(m), data(m.make_data()), q(Eigen::VectorXd::Zero(m.dof())),
        base(m.frame_pose(data, q, m.root_link())),
        has_movable_ancestor(static_cast<std::size_t>(m.dof()), false) {
    for (int j = 0; j < m.dof(); ++j) {
      for (int d : m.descendant_joints(j)) has_movable_ancestor[static_cast<std::size_t>(d)] = true;
    }
  }
  [[nodiscard]] Eigen::Isometry3d in_base(const std::string& link) {
    return base.inverse() * model.frame_pose(data, q, link);
  }
  [[nodiscard]] Eigen::Vector3d axis_in_base(int j) {
    return in_base(model.joint_child_link(j)).linear() * model.joint_axis(j);
  }
  const kinematics::Model& model;
  kinematics::Data data;
  Eigen::VectorXd q;
  Eigen::Isometry3d base;
  std::vector<bool> has_movable_ancestor;
};

// The leg of steering joint s over wheel joint w, or none when they do not make one: s a
// vertical axis without a movable ancestor whose only movable descendant is w, a horizontal
// revolute axis.
std::optional<Leg> leg_of(Zero& zero, int s, int w, double wheel_radius) {
  const kinematics::Model& model = zero.model;
  if (model.is_virtual_joint(s) || zero.has_movable_ancestor[static_cast<std::size_t>(s)]) return std::nullopt;
  const Eigen::Vector3d steer_axis = zero.axis_in_base(s);
  const auto below = model.descendant_joints(s);
  if (std::abs(steer_axis.z()) < 0.9 || below.size() != 1 || below.front() != w) return std::nullopt;
  const Eigen::Vector3d wheel_axis = zero.axis_in_base(w);
  if (std::abs(wheel_axis.z()) > 0.1 ||
      model.joint_types()[static_cast<std::size_t>(w)] == kinematics::JointType::kPrismatic) {
    return std::nullopt;
  }
  Leg leg;
  leg.steering_joint = model.joint_names()[static_cast<std::size_t>(s)];
  leg.wheel_joint = model.joint_names()[static_cast<std::size_t>(w)];
  leg.steering_index = s;
  leg.wheel_index = w;
  leg.position = zero.in_base(model.joint_child_link(s)).translation().head<2>();
  const Eigen::Isometry3d wheel_frame = zero.in_base(model.joint_child_link(w));
  leg.wheel_center_height = wheel_frame.translation().z();
  leg.wheel_radius = wheel_radius;
  leg.steering_sign = steer_axis.z() > 0.0 ? 1.0 : -1.0;
  const Eigen::Vector3d rolling = wheel_axis.cross(Eigen::Vector3d::UnitZ());
  leg.heading_offset = std::atan2(rolling.y(), rolling.x());
  leg.axle_offset = (wheel_frame.translation().head<2>() - leg.position).dot(wheel_axis.head<2>().normalized());
  const auto& limits = model.joint_limits()[static_cast<std::size_t>(s)];
  if (limits.has_position_limits) {
    leg.steering_lower = limits.lower;
    leg.steering_upper = limits.upper;
  }
  return leg;
}

}  // namespace

std::vector<Leg> detect_legs(const kinematics::Model& model, const std::map<std::string, double>& wheel_radii,
                             double default_wheel_radius) {
  std::vector<Leg> legs;
  Zero zero(model);
  for (int s = 0; s < model.dof(); ++s) {
    const auto below = model.descendant_joints(s);
    if (below.size() != 1) continue;
    const int w = below.front();
    const auto radius = wheel_radii.find(model.joint_child_link(w));
    if (std::optional<Leg> leg =
            leg_of(zero, s, w, radius != wheel_radii.end() ? radius->second : default_wheel_radius)) {
      legs.push_back(std::move(*leg));
    }
  }
  return legs;
}

Leg measure_leg(const kinematics::Model& model, const std::string& steering_joint,
                const std::string& wheel_joint, double wheel_radius) {
  Zero zero(model);
  std::optional<Leg> leg = leg_of(zero, model.joint_index_or_throw(steering_joint),
                                  model.joint_index_or_throw(wheel_joint), wheel_radius);
  if (!leg) {
    throw std::invalid_argument("joint '" + steering_joint +
                                "' is not a vertical steering axis directly above the horizontal "
                                "axis of wheel joint '" + wheel_joint + "'");
  }
  return *leg;
}

std::vector<Leg> steering_legs(const model::RobotModel& model) {
  std::vector<Leg> out;
  for (const model::Leg& leg : model.legs()) {
    if (leg.steering_joint.empty()) continue;
    try {
      out.push_back(measure_leg(model.kinematics(), leg.steering_joint, leg.wheel_joint, leg.wheel_radius));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(model.where() + ": leg chain " + leg.chain->name + ": " + e.what());
    }
  }
  return out;
}

double standing_height(const model::RobotModel& model) {
  const kinematics::Model& k = model.kinematics();
  kinematics::Data data = k.make_data();
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(k.dof());
  double height = 0.0;
  for (const model::Leg& leg : model.legs()) {
    const double centre = k.relative_pose(data, q, k.root_link(), leg.wheel_frame).translation().z();
    height = std::max(height, leg.wheel_radius - centre);
  }
  return height;
}

BaseKinematics::BaseKinematics(std::vector<Leg> legs) : legs_(std::move(legs)) {
  if (legs_.size() < 2) {
    throw std::invalid_argument("a steerable base needs at least 2 steering+wheel legs, found " +
                                std::to_string(legs_.size()));
  }
}

double BaseKinematics::steering_rolling(std::size_t i, double steering_rate) const {
  const Leg& leg = legs_.at(i);
  return -leg.axle_offset * leg.steering_sign * steering_rate / leg.wheel_radius;
}

std::vector<LegSetpoint> BaseKinematics::leg_setpoints(const Eigen::Vector3d& twist,
                                                       const std::vector<double>& current_steering) const {
  std::vector<LegSetpoint> out(legs_.size());
  leg_setpoints(twist, current_steering, out);
  return out;
}

void BaseKinematics::leg_setpoints(const Eigen::Vector3d& twist, const std::vector<double>& current_steering,
                                   std::vector<LegSetpoint>& out) const {
  if (current_steering.size() != legs_.size()) {
    throw std::invalid_argument("leg_setpoints: " + std::to_string(current_steering.size()) +
                                " steering angles for " + std::to_string(legs_.size()) + " legs");
  }
  out.resize(legs_.size());
  const auto contact_velocity = [&](const Leg& leg) {
    return Eigen::Vector2d(twist.x() - twist.z() * leg.position.y(),
                           twist.y() + twist.z() * leg.position.x());
  };
  // A base twist whose every contact moves slower than the deadband is not driven: the direction
  // of a few mm/s (a tracking correction at the end of a path) swings with every cycle, and
  // each swing scrubs the loaded wheels (on the demo's whole-body moves a steering drive would
  // run over its continuous torque). Per leg it would not do: a leg rolling along a stale heading
  // while the others steer fights them (a wheel drive over its continuous torque).
  double fastest = 0.0;
  for (const Leg& leg : legs_) fastest = std::max(fastest, contact_velocity(leg).norm());
  if (fastest < kSteeringDeadband) {
    for (std::size_t i = 0; i < legs_.size(); ++i) out[i] = {current_steering[i], 0.0};
    return;
  }
  for (std::size_t i = 0; i < legs_.size(); ++i) {
    const Leg& leg = legs_[i];
    const double current = current_steering[i];
    const Eigen::Vector2d v = contact_velocity(leg);
    const double speed = v.norm();
    // The base's turn rolls a wheel beside its steering axis by itself (Leg::axle_offset).
    const double turning = -leg.axle_offset * twist.z() / leg.wheel_radius;
    if (speed < 1e-6) {
      out[i] = {current, turning};
      continue;
    }
    const double heading = std::atan2(v.y(), v.x());
    double angle = current + wrap(leg.steering_sign * (heading - leg.heading_offset) - current);
    double direction = 1.0;
    if (std::abs(angle - current) > M_PI / 2.0) {
      angle -= std::copysign(M_PI, angle - current);
      direction = -1.0;
    }
    // Keep inside the steering limits: shift by a full turn, or flip once more.
    for (const double shift : {2.0 * M_PI, -2.0 * M_PI}) {
      if (angle < leg.steering_lower || angle > leg.steering_upper) {
        if (angle + shift >= leg.steering_lower && angle + shift <= leg.steering_upper) {
          angle += shift;
        }
      }
    }
    if (angle < leg.steering_lower || angle > leg.steering_upper) {
      const double flipped = angle - std::copysign(M_PI, angle - 0.5 * (leg.steering_lower + leg.steering_upper));
      angle = flipped;
      direction = -direction;
    }
    out[i] = {angle, direction * speed / leg.wheel_radius + turning};
  }
}

Eigen::Vector3d BaseKinematics::twist_from_legs(const std::vector<double>& steering,
                                                const std::vector<double>& wheel_velocity,
                                                const std::vector<double>& steering_rate) const {
  if (steering.size() != legs_.size() || wheel_velocity.size() != legs_.size() ||
      (!steering_rate.empty() && steering_rate.size() != legs_.size())) {
    throw std::invalid_argument("twist_from_legs: expected " + std::to_string(legs_.size()) + " legs");
  }
  // Per leg, its wheel centre's velocity (v + wz x centre, plus the steering's own turn) along
  // its heading is what the wheel rolls, across it nothing (no side slip); the least-squares
  // twist of all legs. With the wheel beside its axis the heading row gains -axle_offset in wz:
  // the normal matrix depends on the steering angles, so it is built per call (3 x 3).
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < legs_.size(); ++i) {
    const Leg& leg = legs_[i];
    const double heading = leg.heading_offset + leg.steering_sign * steering[i];
    const Eigen::Vector2d h(std::cos(heading), std::sin(heading));
    const Eigen::Vector2d axle(-h.y(), h.x());
    const auto row = [&](const Eigen::Vector2d& d, double turn) {
      return Eigen::Vector3d(d.x(), d.y(), -d.x() * leg.position.y() + d.y() * leg.position.x() + turn);
    };
    const Eigen::Vector3d along = row(h, -leg.axle_offset);
    const Eigen::Vector3d across = row(axle, 0.0);
    const double rate = steering_rate.empty() ? 0.0 : steering_rate[i];
    const double rolled = wheel_velocity[i] * leg.wheel_radius + leg.axle_offset * leg.steering_sign * rate;
    normal += along * along.transpose() + across * across.transpose();
    rhs += along * rolled;
  }
  return normal.ldlt().solve(rhs);
}

void BaseKinematics::integrate(Odometry& odometry, const std::vector<double>& steering,
                               const std::vector<double>& wheel_velocity, double dt) const {
  const Eigen::Vector3d twist = twist_from_legs(steering, wheel_velocity);
  integrate(odometry, twist, twist.z(), dt);
}

void BaseKinematics::integrate(Odometry& odometry, const Eigen::Vector3d& twist, double yaw_rate,
                               double dt) {
  const double mid_yaw = odometry.yaw + 0.5 * yaw_rate * dt;
  odometry.x += (std::cos(mid_yaw) * twist.x() - std::sin(mid_yaw) * twist.y()) * dt;
  odometry.y += (std::sin(mid_yaw) * twist.x() + std::cos(mid_yaw) * twist.y()) * dt;
  odometry.yaw = wrap(odometry.yaw + yaw_rate * dt);
  odometry.vx = twist.x();
  odometry.vy = twist.y();
  odometry.wz = twist.z();
}

}  // namespace concert::mobile_base
