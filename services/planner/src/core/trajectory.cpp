#include "planner/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "concert/model/limits.hpp"

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
double profile_acceleration(double u) {  // d2s/du2; at a switch, the phase the sample ends
  if (u <= 0.25) return 16.0 / 3.0;
  if (u <= 0.75) return 0.0;
  return -16.0 / 3.0;
}

int steps_of(double duration, double sample_period) {
  return std::max(1, static_cast<int>(std::ceil(duration / sample_period)));
}

// Shortest rest-to-rest duration of each segment within the kinematic limits (0: no motion).
std::vector<double> kinematic_durations(const std::vector<Eigen::VectorXd>& waypoints, const MotionLimits& limits) {
  std::vector<double> out(waypoints.size(), 0.0);
  for (std::size_t w = 1; w < waypoints.size(); ++w) {
    const Eigen::VectorXd delta = waypoints[w] - waypoints[w - 1];
    for (Eigen::Index j = 0; j < delta.size(); ++j) {
      const double d = std::abs(delta[j]);
      out[w] = std::max({out[w], 4.0 * d / (3.0 * limits.velocity[j]),
                         std::sqrt(16.0 * d / (3.0 * limits.acceleration[j]))});
    }
  }
  return out;
}

// One arm drive as the check sees it.
struct Drive {
  int index = -1;  // in the full q
  std::string name;
  double continuous = 0.0, peak = 0.0;
};

// The drives along the path timed by `durations`; the first segment where a drive goes beyond
// a bound in `*first_over` (-1: none).
DriveReport check_drives(const std::vector<Eigen::VectorXd>& waypoints, const std::vector<double>& durations,
                         double sample_period, const DriveLimits& drives, int* first_over) {
  const PlanningModel& m = *drives.model;
  const kinematics::Model& k = m.kinematics();
  kinematics::Data data = k.make_data();
  const std::vector<int>& planned = m.planned_indices();
  std::vector<Drive> arm;
  for (std::size_t p = 3; p < planned.size(); ++p) {
    const std::string& name = m.joint_names()[p];
    const model::JointLimits& l = m.robot().limits().at(name);
    if (l.continuous_torque > 0.0 && l.peak_torque > 0.0) arm.push_back({planned[p], name, l.continuous_torque, l.peak_torque});
  }
  const Eigen::Index n = k.dof();
  Eigen::VectorXd q = drives.q_start_full, qd = Eigen::VectorXd::Zero(n), qdd = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd tau(n);
  const auto set_planned = [&](Eigen::VectorXd& full, const Eigen::VectorXd& part) {
    for (std::size_t p = 0; p < planned.size(); ++p) full[planned[p]] = part[static_cast<Eigen::Index>(p)];
  };
  set_planned(q, waypoints.front());
  // Warm: the robot has held the start posture.
  std::vector<model::ThermalLoad> heat(arm.size());
  k.inverse_dynamics_into(data, q, qd, qdd, tau);
  for (std::size_t a = 0; a < arm.size(); ++a) heat[a].hold(std::abs(tau[arm[a].index]));

  DriveReport r;
  r.checked = true;
  *first_over = -1;
  const double fraction = drives.fraction;
  const auto record = [&](int segment) {
    for (std::size_t a = 0; a < arm.size(); ++a) {
      const double rms = heat[a].rms() / arm[a].continuous;
      const double peak = std::abs(tau[arm[a].index]) / arm[a].peak;
      if (rms > r.rms_share) {
        r.rms_share = rms;
        r.rms_joint = arm[a].name;
      }
      if (peak > r.peak_share) {
        r.peak_share = peak;
        r.peak_joint = arm[a].name;
      }
      if ((rms > fraction + 1e-9 || peak > 1.0 + 1e-9) && *first_over < 0) *first_over = segment;
    }
  };
  record(0);  // the start posture held: a stretch cannot help there
  for (std::size_t w = 1; w < waypoints.size(); ++w) {
    const double T = durations[w];
    if (T <= 0.0) continue;
    const Eigen::VectorXd delta = waypoints[w] - waypoints[w - 1];
    const int steps = steps_of(T, sample_period);
    const double dt = T / steps;
    Eigen::VectorXd part(delta.size());
    for (int s = 1; s <= steps; ++s) {
      const double u = static_cast<double>(s) / steps;
      set_planned(q, waypoints[w - 1] + profile(u) * delta);
      part = profile_rate(u) / T * delta;
      set_planned(qd, part);
      part = profile_acceleration(u) / (T * T) * delta;
      set_planned(qdd, part);
      k.inverse_dynamics_into(data, q, qd, qdd, tau);
      for (std::size_t a = 0; a < arm.size(); ++a) (void)heat[a].add(std::abs(tau[arm[a].index]), dt);
      record(static_cast<int>(w));
    }
  }
  r.within = *first_over < 0;
  return r;
}

}  // namespace

std::string DriveReport::summary() const {
  if (!checked) return "drives not checked";
  char b[240];
  std::snprintf(b, sizeof b, "%s RMS %.0f %% of continuous, %s %.0f %% of peak; %d segment stretch%s, %.2f x as long%s",
                rms_joint.empty() ? "no arm drive" : rms_joint.c_str(), 100.0 * rms_share,
                peak_joint.empty() ? "no arm drive" : peak_joint.c_str(), 100.0 * peak_share, stretches,
                stretches == 1 ? "" : "es", slowed, within ? "" : " (still beyond: not sustainable)");
  return b;
}

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
                             const MotionLimits& limits, double sample_period, const DriveLimits& drives,
                             DriveReport* report) {
  if (waypoints.empty()) throw PlannerError("time parameterisation: empty path");
  if (!(sample_period > 0.0)) throw PlannerError("time parameterisation: sample period must be > 0");
  if ((limits.velocity.array() <= 0.0).any() || (limits.acceleration.array() <= 0.0).any()) {
    throw PlannerError("time parameterisation: velocity and acceleration limits must be > 0");
  }
  std::vector<double> durations = kinematic_durations(waypoints, limits);
  DriveReport checked;
  if (drives.model != nullptr) {
    if (!(drives.fraction > 0.0 && drives.fraction <= 1.0)) {
      throw PlannerError("time parameterisation: drive torque fraction " + std::to_string(drives.fraction) +
                         " is not in (0, 1]");
    }
    if (drives.q_start_full.size() != drives.model->full_dof()) {
      throw PlannerError("time parameterisation: start state has " + std::to_string(drives.q_start_full.size()) +
                         " joints, the model " + std::to_string(drives.model->full_dof()));
    }
    double kinematic = 0.0;
    for (double d : durations) kinematic += d;
    // The first segment where a drive goes beyond its bound is stretched (its torques from
    // accelerations fall with the square of the stretch), then the whole path is checked
    // again: the thermal state carries over from segment to segment.
    int over = -1;
    int stretches = 0;
    checked = check_drives(waypoints, durations, sample_period, drives, &over);
    const std::vector<double> shortest = durations;
    while (over > 0 && stretches < drives.max_stretches &&
           durations[static_cast<std::size_t>(over)] * 1.25 <= drives.max_stretch * shortest[static_cast<std::size_t>(over)]) {
      durations[static_cast<std::size_t>(over)] *= 1.25;
      ++stretches;
      checked = check_drives(waypoints, durations, sample_period, drives, &over);
    }
    checked.stretches = stretches;
    double total = 0.0;
    for (double d : durations) total += d;
    checked.slowed = kinematic > 0.0 ? total / kinematic : 1.0;
  }
  if (report != nullptr) *report = checked;

  Trajectory traj;
  traj.joint_names = joint_names;
  const Eigen::Index n = waypoints.front().size();
  double t0 = 0.0;
  traj.points.push_back({0.0, waypoints.front(), Eigen::VectorXd::Zero(n)});
  for (std::size_t w = 1; w < waypoints.size(); ++w) {
    const double duration = durations[w];
    if (duration <= 0.0) continue;
    const Eigen::VectorXd delta = waypoints[w] - waypoints[w - 1];
    const int steps = steps_of(duration, sample_period);
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
