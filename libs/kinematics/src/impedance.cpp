#include "concert/kinematics/impedance.hpp"

#include <Eigen/Cholesky>

namespace concert::kinematics {

Eigen::Vector3d rotation_error(const Eigen::Matrix3d& target, const Eigen::Matrix3d& current) {
  const Eigen::AngleAxisd aa(target * current.transpose());
  return aa.angle() * aa.axis();
}

Vector6d impedance_wrench(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& target,
                          const Vector6d& twist, const Vector6d& target_twist,
                          const Vector6d& stiffness, const Vector6d& damping) {
  Vector6d error;
  error.head<3>() = target.translation() - pose.translation();
  error.tail<3>() = rotation_error(target.linear(), pose.linear());
  return stiffness.cwiseProduct(error) + damping.cwiseProduct(target_twist - twist);
}

void wrench_torques(const Eigen::MatrixXd& jac, const Vector6d& wrench, const Eigen::VectorXd& qd,
                    double nullspace_damping, Eigen::VectorXd& tau) {
  tau.noalias() = jac.transpose().lazyProduct(wrench);
  tau -= nullspace_damping * qd;
}

Vector6d wrench_from_residual(const Eigen::MatrixXd& jac, const Eigen::VectorXd& residual) {
  Eigen::Matrix<double, 6, 6> jjt;
  jjt.noalias() = jac.lazyProduct(jac.transpose());
  jjt.diagonal().array() += 1e-6;
  Vector6d jr;
  jr.noalias() = jac.lazyProduct(residual);
  return jjt.ldlt().solve(jr);
}

Vector6d low_pass(const Vector6d& filtered, const Vector6d& raw, double dt, double time_constant) {
  if (time_constant <= 0.0) return raw;
  return filtered + dt / (time_constant + dt) * (raw - filtered);
}

}  // namespace concert::kinematics
