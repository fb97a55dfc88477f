#include "planner/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace concert::planner {
namespace {

// Normalised profile s(u), u = t / T in [0, 1]: accelerate on [0, 1/4], cruise, brake on
// [3/4, 1]. Peak ds/dt = 4 / (3 T), peak d2s/dt2 = 16 / (3 T^2).
double profile(double u) {
  if (u <= 0.25) return 8.0 / 3.0 * u * u;
  if (u <= 0.75) return 1.0 / 6.0 + 4.0 / 3.0 * (u - 0.25);
  const double w = 1.0 - u;
  return 1.0 - 8.0 / 3.0 * w * w;
}
double profile_rate(double u) {  // ds/du
  if (u <= 0.25) return 16.0 / 3.0 * u;
  if (u <= 0.75) return 4.0 / 3.0;
  return 16.0 / 3.0 * (1.0 - u);
}

}  // namespace

MotionLimits motion_limits(const PlanningModel& model, const Params& params) {
  MotionLimits l;
  const int n = model.dof();
  l.velocity.resize(n);
  l.acceleration.resize(n);
  for (int i = 0; i < n; ++i) {
    if (i < 2) {
      l.velocity[i] = params.base_linear_velocity / std::sqrt(2.0);
      l.acceleration[i] = params.base_linear_acceleration / std::sqrt(2.0);
    } else if (i == 2) {
      l.velocity[i] = params.base_angular_velocity;
      l.acceleration[i] = params.base_angular_acceleration;
    } else {
      l.velocity[i] = params.velocity_scale * model.velocity_limits()[i];
      l.acceleration[i] = params.joint_acceleration;
    }
  }
  return l;
}

Trajectory time_parameterize(const std::vector<Eigen::VectorXd>& waypoints, const std::vector<std::string>& joint_names,
                             const MotionLimits& limits, double sample_period) {
  if (waypoints.empty()) throw PlannerError("time parameterisation: empty path");
  if (!(sample_period > 0.0)) throw PlannerError("time parameterisation: sample period must be > 0");
  if ((limits.velocity.array() <= 0.0).any() || (limits.acceleration.array() <= 0.0).any()) {
    throw PlannerError("time parameterisation: velocity and acceleration limits must be > 0");
  }
  Trajectory traj;
  traj.joint_names = joint_names;
  const Eigen::Index n = waypoints.front().size();
  double t0 = 0.0;
  traj.points.push_back({0.0, waypoints.front(), Eigen::VectorXd::Zero(n)});
  for (std::size_t w = 1; w < waypoints.size(); ++w) {
    const Eigen::VectorXd delta = waypoints[w] - waypoints[w - 1];
    double duration = 0.0;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double d = std::abs(delta[j]);
      duration = std::max({duration, 4.0 * d / (3.0 * limits.velocity[j]), std::sqrt(16.0 * d / (3.0 * limits.acceleration[j]))});
    }
    if (duration <= 0.0) continue;
    const int steps = std::max(1, static_cast<int>(std::ceil(duration / sample_period)));
    for (int s = 1; s <= steps; ++s) {
      const double u = static_cast<double>(s) / steps;
      traj.points.push_back({t0 + u * duration, waypoints[w - 1] + profile(u) * delta, profile_rate(u) / duration * delta});
    }
    traj.points.back().q = waypoints[w];
    traj.points.back().qd.setZero();
    t0 += duration;
  }
  return traj;
}

}  // namespace concert::planner
