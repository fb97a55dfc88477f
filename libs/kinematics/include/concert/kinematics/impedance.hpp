#pragma once
// The Cartesian impedance law and the external wrench estimate at a frame of an arm, as the
// robot service's 1 kHz loop runs them (services/robot) and the simulator's sanding runs repeat
// them (services/surface_finish): one formula, no allocation once the caller's vectors are
// sized. Vectors of 6 are linear then angular, in the base frame; `jac` is the frame's 6 x n
// Jacobian over the arm's n joints.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace concert::kinematics {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Orientation error of `current` towards `target` as a rotation vector [rad]: the axis times
/// the angle of target * current^T.
Eigen::Vector3d rotation_error(const Eigen::Matrix3d& target, const Eigen::Matrix3d& current);

/// The wrench the impedance asks at the frame: K (x_target - x) + D (twist_target - twist), the
/// orientation's error by rotation_error; `stiffness` K and `damping` D per axis.
Vector6d impedance_wrench(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& target,
                          const Vector6d& twist, const Vector6d& target_twist,
                          const Vector6d& stiffness, const Vector6d& damping);

/// Joint torques of `wrench` at the frame, with damping of the joints' own motion: J^T F -
/// nullspace_damping qd, into `tau` (sized n by the caller).
void wrench_torques(const Eigen::MatrixXd& jac, const Vector6d& wrench, const Eigen::VectorXd& qd,
                    double nullspace_damping, Eigen::VectorXd& tau);

/// The external wrench at the frame from the joints' torque residual r = ID(q, qd, 0) - tau
/// (quasi-static: J^T F = r), by damped least squares (J J^T + 1e-6 I) F = J r.
Vector6d wrench_from_residual(const Eigen::MatrixXd& jac, const Eigen::VectorXd& residual);

/// One step of a first-order low-pass filter of time constant `time_constant` [s] over `dt` [s]
/// from `filtered` towards `raw` (time_constant <= 0: raw).
Vector6d low_pass(const Vector6d& filtered, const Vector6d& raw, double dt, double time_constant);

}  // namespace concert::kinematics
