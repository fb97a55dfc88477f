#include "concert/model/drive_budget.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace concert::model {

DriveBudget::DriveBudget(const RobotModel& model)
    : where_(model.where()),
      planar_(model.planar_kinematics()),
      fixed_(model.kinematics()),
      names_(model.kinematics().joint_names()) {
  limits_.reserve(names_.size());
  for (const std::string& name : names_) limits_.push_back(model.limits().at(name));
  for (const Leg& leg : model.legs()) {
    Wheel w;
    w.joint = fixed_.joint_index_or_throw(leg.wheel_joint);
    w.frame = leg.wheel_frame;
    w.radius = leg.wheel_radius;
    w.continuous = limits_[static_cast<std::size_t>(w.joint)].continuous_torque;
    wheels_.push_back(std::move(w));
  }
}

Eigen::VectorXd DriveBudget::neutral_posture() const {
  Eigen::VectorXd q(static_cast<Eigen::Index>(limits_.size()));
  for (std::size_t i = 0; i < limits_.size(); ++i) {
    q(static_cast<Eigen::Index>(i)) = std::clamp(0.0, limits_[i].lower, limits_[i].upper);
  }
  return q;
}

namespace {

// Tightens `out` with one drive: its torque is statics + scale x dynamic, kept within budget.
void tighten(BaseBudget& out, const std::string& joint, double statics, double dynamic,
             double budget, double continuous) {
  const double static_load = statics / continuous;
  const double dynamic_load = dynamic / continuous;
  if (statics > budget) {
    // The posture alone overloads this drive: no acceleration is sustainable. Report the
    // drive overloaded most.
    if (out.holds_static || static_load > out.static_load) {
      out = BaseBudget{0.0, joint, false, static_load, dynamic_load};
    }
    return;
  }
  if (!out.holds_static || dynamic <= 1e-12) return;
  const double scale = (budget - statics) / dynamic;
  if (scale < out.scale) out = BaseBudget{scale, joint, true, static_load, dynamic_load};
}

}  // namespace

BaseBudget DriveBudget::base_motion(const Eigen::VectorXd& joints, const BaseMotion& asked,
                                    double fraction) const {
  const auto n = static_cast<Eigen::Index>(names_.size());
  if (joints.size() != n) {
    throw ModelError(where_ + ": drive budget: " + std::to_string(joints.size()) +
                     " joint positions for " + std::to_string(n) + " joints");
  }
  if (!(fraction > 0.0 && fraction <= 1.0)) {
    throw ModelError(where_ + ": drive budget: torque fraction " + std::to_string(fraction) +
                     " is not in (0, 1]");
  }
  const Eigen::Vector3d a(std::abs(asked.ax), std::abs(asked.ay), std::abs(asked.aw));

  // The planar model's virtual joints (x, y, yaw) carry the base; at yaw 0 the world's axes
  // are the base's. Static: gravity and the centrifugal load of turning at wz. Dynamic: the
  // columns of M(q) for the three base accelerations, the worst sign combination.
  const Eigen::Index nv = planar_.num_virtual_joints();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(nv + n);
  q.tail(n) = joints;
  Eigen::VectorXd qd = Eigen::VectorXd::Zero(nv + n);
  qd(2) = asked.wz;
  kinematics::Data data = planar_.make_data();
  const Eigen::VectorXd statics =
      planar_.inverse_dynamics(data, q, qd, Eigen::VectorXd::Zero(nv + n));
  const Eigen::MatrixXd m = planar_.mass_matrix(data, q);
  const Eigen::MatrixXd coupling = m.leftCols(3).cwiseAbs();

  BaseBudget out;
  for (Eigen::Index i = 0; i < n; ++i) {
    const JointLimits& l = limits_[static_cast<std::size_t>(i)];
    tighten(out, names_[static_cast<std::size_t>(i)], std::abs(statics(nv + i)),
            coupling.row(nv + i).dot(a), fraction * l.continuous_torque, l.continuous_torque);
  }

  // Traction: the wheels push the whole robot. The base's force is shared evenly and its yaw
  // moment in proportion to each wheel's distance from the yaw axis (the least-squares split),
  // every wheel within its drive's budget at its radius.
  if (!wheels_.empty()) {
    kinematics::Data fixed_data = fixed_.make_data();
    std::vector<double> distance;
    double sum_d2 = 0.0;
    for (const Wheel& w : wheels_) {
      const Eigen::Vector3d p = fixed_.frame_pose(fixed_data, joints, w.frame).translation();
      distance.push_back(std::hypot(p.x(), p.y()));
      sum_d2 += distance.back() * distance.back();
    }
    const double force_static = std::hypot(statics(0), statics(1));
    const double force_dynamic = std::hypot(coupling.row(0).dot(a), coupling.row(1).dot(a));
    const double moment_static = std::abs(statics(2));
    const double moment_dynamic = coupling.row(2).dot(a);
    const double count = static_cast<double>(wheels_.size());
    for (std::size_t k = 0; k < wheels_.size(); ++k) {
      const Wheel& w = wheels_[k];
      const double share = sum_d2 > 1e-9 ? distance[k] / sum_d2 : 0.0;
      tighten(out, names_[static_cast<std::size_t>(w.joint)],
              w.radius * (force_static / count + moment_static * share),
              w.radius * (force_dynamic / count + moment_dynamic * share), fraction * w.continuous,
              w.continuous);
    }
  }
  out.scale = std::clamp(out.scale, 0.0, 1.0);
  return out;
}

}  // namespace concert::model
