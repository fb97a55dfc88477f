#include "robot_conversions.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "concert/common/enum_map.hpp"
#include "concert/model/dds/pose.hpp"

namespace concert::robot::dds {
namespace {

std::string from(const std::string& source) {
  return source.empty() ? std::string("unnamed sender") : "'" + source + "'";
}

void check_length(const msg::JointCommand& c, std::size_t size, const char* field, bool required) {
  if ((required || size != 0) && size != c.name().size()) {
    throw CommandError("joint command from " + from(c.source()) + ": " +
                       std::to_string(c.name().size()) + " names but " + std::to_string(size) +
                       " values in '" + field + "'" +
                       (required ? " (required by the mode)" : " (give one per joint or none)"));
  }
}

double at(const std::vector<double>& v, std::size_t i) { return v.empty() ? 0.0 : v[i]; }

// Every drive mode and its wire twin, one row each.
constexpr EnumMap kDriveModes{std::array{
    std::pair{DriveMode::kPosition, msg::JOINT_POSITION},
    std::pair{DriveMode::kVelocity, msg::JOINT_VELOCITY},
    std::pair{DriveMode::kEffort, msg::JOINT_EFFORT},
    std::pair{DriveMode::kImpedance, msg::JOINT_IMPEDANCE},
}};

// The value fields of a joint command with how many values each carries, in the order their
// lengths are checked.
std::array<std::pair<const char*, std::size_t>, 5> value_counts(const msg::JointCommand& c) {
  return {{{"position", c.position().size()},
           {"velocity", c.velocity().size()},
           {"effort", c.effort().size()},
           {"stiffness", c.stiffness().size()},
           {"damping", c.damping().size()}}};
}

// True if a command in `mode` cannot do without `field` (one value per joint).
bool needs(DriveMode mode, std::string_view field) {
  switch (mode) {
    case DriveMode::kPosition:
      return field == "position";
    case DriveMode::kVelocity:
      return field == "velocity";
    case DriveMode::kEffort:
      return field == "effort";
    case DriveMode::kImpedance:
      return field == "position" || field == "stiffness" || field == "damping";
  }
  return false;
}

// The trajectory states a TrajectoryStatus reports; an idle trajectory is reported as executing.
constexpr EnumMap kTrajectoryStates{std::array{
    std::pair{TrajectoryState::kExecuting, msg::TRAJECTORY_EXECUTING},
    std::pair{TrajectoryState::kIdle, msg::TRAJECTORY_EXECUTING},
    std::pair{TrajectoryState::kSucceeded, msg::TRAJECTORY_SUCCEEDED},
    std::pair{TrajectoryState::kAborted, msg::TRAJECTORY_ABORTED},
}};

}  // namespace

JointCommandSet to_core(const msg::JointCommand& c) {
  JointCommandSet out;
  out.model_version = c.model_version();
  const std::optional<DriveMode> mode = kDriveModes.from(c.mode());
  if (!mode) {
    throw CommandError("joint command from " + from(c.source()) + ": unknown mode " +
                       std::to_string(static_cast<int>(c.mode())));
  }
  for (const auto& [field, size] : value_counts(c)) {
    if (needs(*mode, field)) check_length(c, size, field, true);
  }
  for (const auto& [field, size] : value_counts(c)) check_length(c, size, field, false);
  for (std::size_t i = 0; i < c.name().size(); ++i) {
    out.joints.push_back({c.name()[i], *mode, at(c.position(), i), at(c.velocity(), i),
                          at(c.effort(), i), at(c.stiffness(), i), at(c.damping(), i)});
  }
  return out;
}

CartesianCommand to_core(const msg::CartesianImpedanceCommand& c) {
  CartesianCommand out;
  out.model_version = c.model_version();
  out.frame = c.end_effector();
  const auto& p = c.target().position();
  const auto& o = c.target().orientation();
  const Eigen::Quaterniond q(o.w(), o.x(), o.y(), o.z());
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    throw CommandError("Cartesian command from " + from(c.source()) +
                       ": target.orientation is not a unit quaternion");
  }
  out.target_pose = Eigen::Isometry3d::Identity();
  out.target_pose.linear() = q.normalized().toRotationMatrix();
  out.target_pose.translation() = Eigen::Vector3d(p.x(), p.y(), p.z());
  const auto& t = c.target_twist();
  out.target_twist << t.linear().x(), t.linear().y(), t.linear().z(), t.angular().x(),
      t.angular().y(), t.angular().z();
  for (int i = 0; i < 6; ++i) {
    out.stiffness(i) = c.stiffness()[static_cast<std::size_t>(i)];
    out.damping(i) = c.damping()[static_cast<std::size_t>(i)];
  }
  const auto& f = c.feedforward();
  out.feedforward_wrench << f.force().x(), f.force().y(), f.force().z(), f.torque().x(),
      f.torque().y(), f.torque().z();
  if (!(c.payload_mass() >= 0.0) || !std::isfinite(c.payload_mass())) {
    throw CommandError("Cartesian command from " + from(c.source()) + ": payload_mass " +
                       std::to_string(c.payload_mass()) + " kg must be finite and >= 0");
  }
  out.payload_mass = c.payload_mass();
  const uint8_t axis = c.admittance_axis();
  if (axis != 255) {
    if (axis > 2) {
      throw CommandError("Cartesian command from " + from(c.source()) + ": admittance_axis " +
                         std::to_string(axis) +
                         " (rotational) is not supported; use 0..2 (x, y, z of the TCP) or 255");
    }
    if (!(c.admittance_gain() > 0.0)) {
      throw CommandError("Cartesian command from " + from(c.source()) +
                         ": admittance_gain must be > 0 [m/(N s)]");
    }
    out.admittance.enabled = true;
    // The axis is given in the TCP frame: fixed in the world at the target orientation.
    out.admittance.axis = out.target_pose.linear().col(axis);
    out.admittance.force_setpoint = c.admittance_force();
    // First-order admittance s' = gain (F_set - F): damping 1/gain, a 20 ms virtual-mass lag.
    out.admittance.damping = 1.0 / c.admittance_gain();
    out.admittance.mass = 0.02 * out.admittance.damping;
  }
  return out;
}

BaseCommand to_core(const msg::BaseVelocityCommand& c) {
  return {c.model_version(), c.vx(), c.vy(), c.wz()};
}

JointTrajectory to_core(const msg::JointTrajectoryCommand& c) {
  JointTrajectory t;
  t.request_id = c.request_id();
  t.model_version = c.model_version();
  t.source = c.source();
  t.joints = c.joint_names();
  t.samples.reserve(c.samples().size());
  for (const auto& p : c.samples()) {
    t.samples.push_back({p.time(), p.position(), p.velocity()});
  }
  return t;
}

msg::TrajectoryState to_msg(TrajectoryState state) {
  return kTrajectoryStates.to(state).value_or(msg::TRAJECTORY_EXECUTING);
}

int64_t to_stamp_ns(double time) { return static_cast<int64_t>(std::llround(time * 1e9)); }

msg::JointState to_joint_state(const RobotState& s) {
  msg::JointState out;
  out.model_version(static_cast<uint32_t>(s.model_version));
  out.stamp_ns(to_stamp_ns(s.time));
  out.name(s.joint_names);
  out.position(s.position);
  out.velocity(s.velocity);
  out.effort(s.effort);
  return out;
}

msg::Odometry to_odometry(const RobotState& s, double distance) {
  msg::Odometry out;
  out.stamp_ns(to_stamp_ns(s.time));
  out.x(s.odometry.x);
  out.y(s.odometry.y);
  out.yaw(s.odometry.yaw);
  out.vx(s.odometry.vx);
  out.vy(s.odometry.vy);
  out.wz(s.odometry.wz);
  // Wheel odometry drifts with distance: 2 % of it in x and y, 0.01 rad per metre in yaw (1 sigma).
  std::array<double, 9> cov{};
  cov[0] = cov[4] = std::pow(0.02 * distance, 2) + 1e-6;
  cov[8] = std::pow(0.01 * distance, 2) + 1e-6;
  out.covariance(cov);
  return out;
}

msg::EndEffectorWrench to_wrench(const RobotState& s) {
  msg::EndEffectorWrench out;
  out.model_version(static_cast<uint32_t>(s.model_version));
  out.stamp_ns(to_stamp_ns(s.time));
  out.end_effector(s.end_effector_frame);
  const auto& w = s.end_effector_wrench;
  msg::Wrench wrench;
  wrench.force(model::dds::to_vector_msg(w.head<3>()));
  wrench.torque(model::dds::to_vector_msg(w.tail<3>()));
  out.wrench(wrench);
  return out;
}

}  // namespace concert::robot::dds
