#pragma once
// Time parameterisation of a geometric whole-body path within velocity and acceleration limits.

#include <string>
#include <vector>

#include "planner/planning_model.hpp"

namespace concert::planner {

/// Per-joint limits of the time parameterisation (planned-joint order).
struct MotionLimits {
  Eigen::VectorXd velocity;      ///< [m/s, rad/s]
  Eigen::VectorXd acceleration;  ///< [m/s^2, rad/s^2]
};

/// Limits from the model and Params: arm joints at velocity_scale of their limit and
/// joint_acceleration; base x/y at base_linear_* / sqrt(2) per axis (so the planar speed stays
/// under base_linear_*), yaw at base_angular_*.
MotionLimits motion_limits(const PlanningModel& model, const Params& params);

/// What the arm's drives sustain (libs/model's limits rule) for the time parameterisation:
/// along the trajectory, with the torques of inverse dynamics on the planar model (the base's
/// accelerations, the arm's own and gravity), every arm drive keeps its RMS torque over the
/// thermal window (model::ThermalLoad, warm from holding the start posture) within `fraction` x
/// its continuous torque and |tau| within its peak torque. Segments that do not are stretched.
struct DriveLimits {
  const PlanningModel* model = nullptr;  ///< none: the drives are not checked
  Eigen::VectorXd q_start_full;          ///< full q at the start: joints not planned stay there
  double fraction = 1.0;                 ///< of the continuous torque, for the RMS (0, 1]
  int max_stretches = 40;                ///< segment stretches (x 1.25 each) before giving up
  /// A segment is made at most this many times longer than the kinematic limits make it: its
  /// drives' load is then mostly static, which slowing down does not lower [-].
  double max_stretch = 4.0;
};

/// How the trajectory fares against DriveLimits (over its samples, finally timed).
struct DriveReport {
  bool checked = false;
  bool within = true;      ///< every drive within both bounds
  double rms_share = 0.0;  ///< largest RMS over the thermal window / continuous torque [-]
  std::string rms_joint;
  double peak_share = 0.0;  ///< largest |tau| / peak torque [-]
  std::string peak_joint;
  int stretches = 0;       ///< segment stretches applied
  double slowed = 1.0;     ///< total duration / the kinematic limits' duration [-]
  /// "J2_E RMS 93 % of continuous, J3_E 41 % of peak; 3 segments stretched, 1.42 x as long"
  [[nodiscard]] std::string summary() const;
};

/// Rest-to-rest along each straight segment of `waypoints`, every joint following the same
/// trapezoidal profile (a quarter accelerating, half cruising, a quarter braking), the segment
/// as short as the slowest joint allows and, with `drives.model`, as the drives sustain (a
/// segment where a drive's RMS or peak bound is exceeded first is stretched, and the whole
/// trajectory checked again). Sampled every `sample_period` [s] plus every waypoint. Throws
/// PlannerError for an empty path, non-positive limits, or a fraction outside (0, 1].
Trajectory time_parameterize(const std::vector<Eigen::VectorXd>& waypoints, const std::vector<std::string>& joint_names,
                             const MotionLimits& limits, double sample_period, const DriveLimits& drives = {},
                             DriveReport* report = nullptr);

}  // namespace concert::planner
