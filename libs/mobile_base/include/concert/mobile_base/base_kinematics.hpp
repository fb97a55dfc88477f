#pragma once

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

#include "concert/kinematics/model.hpp"
#include "concert/model/robot_model.hpp"

namespace concert::mobile_base {

/// One steering + wheel leg of a mobile base, found in the model.
struct Leg {
  std::string steering_joint;
  std::string wheel_joint;
  int steering_index{-1};                        ///< index in the (fixed-base) model's q
  int wheel_index{-1};                           ///< index in the (fixed-base) model's q
  Eigen::Vector2d position{Eigen::Vector2d::Zero()};  ///< steering axis (x, y) in the base frame [m]
  double wheel_radius{0.0};                      ///< [m]
  double steering_sign{1.0};                     ///< +1 if the steering axis points up, -1 if down
  double heading_offset{0.0};  ///< base-frame heading of positive wheel rolling at steering 0 [rad]
  /// The wheel centre's horizontal offset from the steering axis along the wheel's own axis [m]
  /// (the demo robot's steering modules, data/module_db: 0.1 m; the public CONCERT database's: 0). Such a wheel rolls as its leg steers or the base turns,
  /// with no motion of the steering axis: e (wz + steering_sign x steering rate) of rolling.
  double axle_offset{0.0};
  double wheel_center_height{0.0};               ///< wheel centre z in the base frame at q = 0 [m]
  double steering_lower{-1e9};                   ///< [rad]
  double steering_upper{1e9};                    ///< [rad]
};

/// Steering angle and wheel speed for one leg.
struct LegSetpoint {
  double steering_angle{0.0};  ///< [rad]
  double wheel_velocity{0.0};  ///< [rad/s]
};

/// Fastest contact speed below which the base is not driven (steering held, wheels stopped) [m/s].
inline constexpr double kSteeringDeadband = 0.005;

/// Planar base pose and twist (odometry).
struct Odometry {
  double x{0.0}, y{0.0}, yaw{0.0};     ///< pose in the odometry frame [m, m, rad]
  double vx{0.0}, vy{0.0}, wz{0.0};    ///< twist in the base frame [m/s, m/s, rad/s]
};

/// Cylinder collision radius per link of a URDF (first cylinder collision of each link) [m]
/// (wheel radii for detect_legs). Throws std::invalid_argument if the URDF cannot be parsed.
std::map<std::string, double> collision_cylinder_radii(const std::string& urdf);

/// Finds the legs of whatever mobile base the model has: a joint with a vertical axis
/// (in the base frame at q = 0) and no movable ancestor, whose only movable descendant is a
/// joint with a horizontal axis (the wheel). Wheel radii come from `wheel_radii`
/// (link name -> radius, e.g. the wheel link's collision cylinder); legs whose wheel link
/// has no entry get `default_wheel_radius` [m].
std::vector<Leg> detect_legs(const kinematics::Model& model, const std::map<std::string, double>& wheel_radii,
                             double default_wheel_radius = 0.16);

/// The leg of `steering_joint` over `wheel_joint` of `model` (fixed base), measured at q = 0:
/// where its steering axis stands, its signs, offsets and limits, with `wheel_radius` [m].
/// Throws std::invalid_argument naming both joints when the steering axis is not vertical,
/// has a movable ancestor or other movable descendants, or the wheel's axis is not horizontal;
/// kinematics::ModelError for a joint the model lacks.
Leg measure_leg(const kinematics::Model& model, const std::string& steering_joint,
                const std::string& wheel_joint, double wheel_radius);

/// The steering legs of `model`, selected by role (its chains of role leg, model::RobotModel::legs())
/// and measured (measure_leg). A leg chain without a steering joint (an unsteered wheel, a
/// differential drive's) is no steering leg and is left out. Throws std::invalid_argument naming
/// a leg chain whose joints do not make a steering leg; model::ModelError from legs().
std::vector<Leg> steering_legs(const model::RobotModel& model);

/// Height of the base frame above the floor when the base stands on its wheels [m]: the
/// largest wheel radius above its wheel centre's height (0 without legs).
double standing_height(const std::vector<Leg>& legs);

/// The same for `model`'s wheels (chains of role leg, steered or not) at q = 0: 0 for a model
/// without legs (a fixed arm).
double standing_height(const model::RobotModel& model);

/// Omni-steering kinematics of a base with N >= 2 steering+wheel legs.
class BaseKinematics {
 public:
  /// Throws std::invalid_argument if fewer than two legs are given.
  explicit BaseKinematics(std::vector<Leg> legs);

  [[nodiscard]] const std::vector<Leg>& legs() const { return legs_; }

  /// Steering angles and wheel speeds for the base twist (vx, vy [m/s], wz [rad/s]): each wheel
  /// rolls its steering axis's speed along its heading, less what the base's turn rolls it
  /// about that axis (Leg::axle_offset; the steering's own rate is the caller's to add:
  /// steering_rolling()).
  /// Each steering angle is chosen closest to `current_steering`: if the wheel would turn
  /// by more than 90 degrees, it turns by the supplement and rolls backwards (the 180
  /// degree flip); steering limits are respected by flipping too. A leg with ~zero contact
  /// speed keeps its current angle. A twist whose contacts all move slower than
  /// kSteeringDeadband is not driven: every leg keeps its angle, every wheel stops.
  [[nodiscard]] std::vector<LegSetpoint> leg_setpoints(const Eigen::Vector3d& twist,
                                                       const std::vector<double>& current_steering) const;
  /// Same into `out` (resized to the leg count: no allocation once it has that size).
  void leg_setpoints(const Eigen::Vector3d& twist, const std::vector<double>& current_steering,
                     std::vector<LegSetpoint>& out) const;

  /// Wheel speed [rad/s] leg `i` rolls with as it steers at `steering_rate` [rad/s], its
  /// steering axis standing (Leg::axle_offset; 0 for a wheel on its axis).
  [[nodiscard]] double steering_rolling(std::size_t i, double steering_rate) const;

  /// Least-squares base twist (vx, vy, wz) from measured steering angles [rad], wheel speeds
  /// [rad/s] and steering rates [rad/s] (rolling without slip; each wheel's centre, beside its
  /// steering axis by Leg::axle_offset, moves along its heading only). No steering rates
  /// (empty): the legs hold their angles.
  [[nodiscard]] Eigen::Vector3d twist_from_legs(const std::vector<double>& steering,
                                                const std::vector<double>& wheel_velocity,
                                                const std::vector<double>& steering_rate = {}) const;

  /// Integrates the odometry by `dt` [s] with the twist measured from the legs.
  void integrate(Odometry& odometry, const std::vector<double>& steering, const std::vector<double>& wheel_velocity,
                 double dt) const;
  /// Integrates the odometry by `dt` [s]: the pose with the legs' `twist` (vx, vy) and
  /// `yaw_rate` [rad/s] (a gyro's, or the twist's wz); the odometry's twist is `twist`.
  static void integrate(Odometry& odometry, const Eigen::Vector3d& twist, double yaw_rate,
                        double dt);

 private:
  std::vector<Leg> legs_;
};

}  // namespace concert::mobile_base
