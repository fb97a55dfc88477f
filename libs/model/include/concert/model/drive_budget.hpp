#pragma once
// What the drives can sustain while the mobile base accelerates: the model of the limits rule
// (limits.hpp) that producers of base motion apply before they command.
//
// Everything the base carries is accelerated with it: a base turning at alpha makes the arm's
// first joint deliver the arm's yaw inertia x alpha, a base braking loads the shoulder, and the
// wheels must push the whole robot. The safety layer stops the robot when a joint's torque
// RMS over the thermal window exceeds its continuous torque; a base controller that asks for
// accelerations the mounted arm cannot hold in its current posture is asking for that stop.
// This budget is the rigid-body answer (recursive Newton-Euler on the model's planar
// kinematics): the accelerations every joint holds within a fraction of its continuous
// torque, the posture's static load (gravity, the turn's centrifugal load) counted first.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "concert/kinematics/model.hpp"
#include "concert/model/robot_model.hpp"

namespace concert::model {

/// Base motion a controller wants to be able to use, in the base frame.
struct BaseMotion {
  double ax = 0.0;  ///< forward acceleration [m/s^2]
  double ay = 0.0;  ///< leftward acceleration [m/s^2]
  double aw = 0.0;  ///< yaw acceleration [rad/s^2]
  double wz = 0.0;  ///< yaw rate whose centrifugal load counts as static [rad/s]
};

/// The share of a BaseMotion's accelerations the drives sustain at one posture.
struct BaseBudget {
  /// Fraction in [0, 1] of the asked accelerations (all three scaled alike) that keeps every
  /// joint and every wheel within fraction x its continuous torque, whatever the signs.
  double scale = 1.0;
  /// The joint that sets `scale` when it is below 1 (the wheel joint for traction); "" else.
  std::string joint;
  /// False when the posture's static load alone exceeds that joint's budget (scale is 0).
  bool holds_static = true;
  /// That joint's static load and its load per unit of scale, as fractions of its continuous
  /// torque [-].
  double static_load = 0.0;
  double dynamic_load = 0.0;
};

/// The drives' budget for base motion of one model version. Copies what it needs from the
/// model; cheap to query (one mass matrix and one inverse dynamics pass per call).
class DriveBudget {
 public:
  /// Throws ModelError naming the version when a leg has no wheel (RobotModel::legs()).
  explicit DriveBudget(const RobotModel& model);

  /// The URDF's moving joints in the order budget() reads positions (kinematics() order).
  [[nodiscard]] const std::vector<std::string>& joint_names() const { return names_; }
  /// Each joint's position clamped into its limits at 0: the posture assumed before a sample.
  [[nodiscard]] Eigen::VectorXd neutral_posture() const;

  /// The budget at posture `joints` (size joint_names().size(); throws ModelError otherwise)
  /// for `asked`, keeping every torque within `fraction` (0, 1] x continuous.
  [[nodiscard]] BaseBudget base_motion(const Eigen::VectorXd& joints, const BaseMotion& asked,
                                       double fraction) const;

 private:
  struct Wheel {
    int joint = -1;              // index into names_
    std::string frame;           // wheel centre link
    double radius = 0.0;         // [m]
    double continuous = 0.0;     // wheel drive's continuous torque [N m]
  };

  std::string where_;
  kinematics::Model planar_;
  kinematics::Model fixed_;
  std::vector<std::string> names_;
  std::vector<JointLimits> limits_;  // one per names_ entry
  std::vector<Wheel> wheels_;
};

}  // namespace concert::model
