#pragma once
// Time parameterisation of a geometric whole-body path within velocity and acceleration limits.

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

/// Rest-to-rest along each straight segment of `waypoints`, every joint following the same
/// trapezoidal profile (a quarter accelerating, half cruising, a quarter braking), the segment
/// as short as the slowest joint allows. Sampled every `sample_period` [s] plus every
/// waypoint. Throws PlannerError for an empty path or non-positive limits.
Trajectory time_parameterize(const std::vector<Eigen::VectorXd>& waypoints, const std::vector<std::string>& joint_names,
                             const MotionLimits& limits, double sample_period);

}  // namespace concert::planner
