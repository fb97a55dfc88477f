#pragma once
// Automatic vehicle kinematics (paper section 5.3, Morganti et al. 2024): from the robot model of
// each version, recognise the drive (omni-steering or differential), its wheel geometry and
// velocity limits, the footprint of the whole robot in its transport posture and the perception
// modules navigation can use. Plain C++/Eigen; no DDS.
//
// Frames: everything is in the base frame, the URDF root link (x forward, y left, z up); the
// floor plane is its xy plane (poses are projected along z).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "concert/mobile_base/base_kinematics.hpp"
#include "concert/model/robot_model.hpp"

namespace concert::nav {

/// A model navigation cannot drive; what() names the model version and the reason (e.g.
/// "model version 3: 2 steered legs (chains A, B): omni-steering needs at least 3").
class VehicleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How the base is driven.
enum class DriveType {
  kOmniSteering,  ///< >= 3 legs, each a steering joint (vertical axis) above a wheel joint
  kDifferential,  ///< two coaxial driven wheels without steering (passive casters allowed)
};

/// "omni_steering", "differential".
std::string_view to_string(DriveType drive);

/// One driven wheel.
struct WheelConfig {
  std::string chain;           ///< leg chain tag
  std::string steering_joint;  ///< empty for a differential drive
  std::string wheel_joint;
  /// Omni-steering: the steering axis; differential: the wheel centre; (x, y) [m].
  Eigen::Vector2d position{Eigen::Vector2d::Zero()};
  double radius{0.0};             ///< [m]
  double max_wheel_speed{0.0};    ///< wheel joint velocity limit [rad/s]
  double max_steering_rate{0.0};  ///< steering joint velocity limit [rad/s]; 0 without steering
  /// Differential: +1 if a positive wheel speed drives the base forward (+x), -1 otherwise.
  double rolling_sign{1.0};
};

/// Velocity limits of the base (the smaller of what the wheels allow and the caps).
struct VelocityLimits {
  double linear{0.0};         ///< |(vx, vy)| [m/s]
  double lateral{0.0};        ///< |vy| [m/s]: 0 for a differential drive
  double angular{0.0};        ///< |wz| [rad/s]
  double steering_rate{0.0};  ///< slowest steering joint [rad/s]; 0 without steering
};

/// The robot's outline on the floor.
struct Footprint {
  std::vector<Eigen::Vector2d> polygon;  ///< convex, counter-clockwise, base frame [m]
  double inscribed_radius{0.0};          ///< largest origin-centred circle inside the polygon [m]
  double circumscribed_radius{0.0};      ///< smallest origin-centred circle around it [m]
  /// Which posture the arm was in: "SRDF home" (the model's `home` group state) or "q = 0".
  std::string posture;
  /// True when the legs were swept over their steering range (omni-steering): the polygon
  /// holds the wheels at every steering angle.
  bool steering_swept{false};
};

/// A sensor frame with its pose.
struct SensorPose {
  std::string name;                                                ///< model sensor name
  std::string frame;                                               ///< URDF link
  Eigen::Isometry3d base_T_sensor{Eigen::Isometry3d::Identity()};  ///< in the transport posture
};

/// The perception modules navigation can use.
struct Perception {
  /// Lidars whose module is listed in VehicleParams::planar_lidar_modules.
  std::vector<SensorPose> planar_lidars;
  /// Every other lidar: multi-beam (the database's lidars are Velodyne VLP-16s); the robot
  /// derives the planar scan navigation reads from them.
  std::vector<SensorPose> lidars_3d;
  std::vector<SensorPose> sonars;
  std::vector<SensorPose> imus;
  std::vector<SensorPose> cameras;
};

/// Everything navigation needs to know about the vehicle of one model version. Immutable.
struct VehicleConfig {
  std::uint64_t model_version{0};
  DriveType drive{DriveType::kOmniSteering};
  std::vector<WheelConfig> wheels;  ///< in model (chain) order
  /// Omni-steering: the legs as mobile_base::BaseKinematics takes them; empty otherwise.
  std::vector<mobile_base::Leg> steering_legs;
  /// Differential: distance between the two wheel centres [m]; 0 otherwise.
  double track{0.0};
  VelocityLimits limits;
  Footprint footprint;
  Perception perception;
};

/// Options of recognise_vehicle().
struct VehicleParams {
  double max_linear_speed{1.0};   ///< cap [m/s], whatever the wheels allow
  double max_angular_speed{0.5};  ///< cap [rad/s]
  /// |cos| tolerance of the axis tests (vertical steering, horizontal and coaxial wheels) [-].
  double axis_tolerance{0.02};
  int circle_segments{16};   ///< polygon sides of cylinders and spheres (circumscribed)
  int steering_samples{24};  ///< steering angles sampled over each leg's range
  /// Module keys of single-plane (2D) lidars; lidars of other modules are 3D.
  std::set<std::string> planar_lidar_modules;
};

/// Recognises the vehicle of `model`. Throws VehicleError naming the model version and the
/// reason when it cannot be driven: no leg chains ("no wheels: a fixed-base arm cannot
/// navigate"), 1 or 2 steered legs, steered and unsteered legs mixed, a number of unsteered
/// wheels other than two, two wheels that are not coaxial or do not roll along x, a leg whose
/// steering axis is not vertical, a mesh collision shape (no extents for the footprint), or
/// the origin outside the footprint.
VehicleConfig recognise_vehicle(const model::RobotModel& model, const VehicleParams& params = {});

/// The transport posture: model::RobotModel::home_posture (the SRDF's `home` group state, joints
/// it does not name at 0, within the limits); size model.kinematics().dof(). `posture` (if not
/// null) receives "SRDF home" or "q = 0" (no home state in the SRDF).
Eigen::VectorXd transport_posture(const model::RobotModel& model, std::string* posture = nullptr);

/// Convex hull (counter-clockwise, no collinear vertices) of planar points.
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points);

}  // namespace concert::nav
