#include "nav/local_controller.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "pose_text.hpp"

namespace concert::nav {

namespace {

// Longest stretch of a command checked for collisions [s at the full command].
constexpr double kMaxCheckTime = 5.0;

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

void require(bool ok, const char* name, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("local controller: ") + name + " " +
                                std::to_string(value) + ": " + what);
  }
}

}  // namespace

Eigen::Vector3d integrate_twist(const Eigen::Vector3d& pose, const BaseTwist& twist, double dt) {
  const double t0 = pose.z();
  const double t1 = t0 + twist.wz * dt;
  double ic;  // integral of cos(theta) over dt
  double is;  // integral of sin(theta) over dt
  if (std::abs(twist.wz) < 1e-9) {
    ic = std::cos(t0) * dt;
    is = std::sin(t0) * dt;
  } else {
    ic = (std::sin(t1) - std::sin(t0)) / twist.wz;
    is = (std::cos(t0) - std::cos(t1)) / twist.wz;
  }
  return {pose.x() + twist.vx * ic - twist.vy * is, pose.y() + twist.vx * is + twist.vy * ic,
          wrap(t1)};
}

const char* to_string(ControlStatus status) {
  switch (status) {
    case ControlStatus::kIdle:
      return "idle";
    case ControlStatus::kFollowing:
      return "following";
    case ControlStatus::kWaiting:
      return "waiting";
    case ControlStatus::kReached:
      return "reached";
    case ControlStatus::kBlocked:
      return "blocked";
    case ControlStatus::kFailed:
      return "failed";
  }
  return "?";
}

LocalController::LocalController(const ControllerParams& params) : params_(params) {
  const ControllerParams::Limits& l = params_.limits;
  require(l.max_vx > 0.0, "limits.max_vx", l.max_vx, "must be > 0 [m/s]");
  require(params_.drive == ControllerParams::Drive::kDifferential || l.max_vy > 0.0,
          "limits.max_vy", l.max_vy, "must be > 0 [m/s] for an omni-steering base");
  require(l.max_wz > 0.0, "limits.max_wz", l.max_wz, "must be > 0 [rad/s]");
  set_acceleration_limits(l.max_ax, l.max_ay, l.max_aw);  // checks them
  require(params_.desired_speed > 0.0, "desired_speed", params_.desired_speed, "must be > 0 [m/s]");
  require(params_.min_lookahead > 0.0 && params_.max_lookahead >= params_.min_lookahead,
          "min_lookahead", params_.min_lookahead, "need 0 < min_lookahead <= max_lookahead [m]");
  require(params_.xy_goal_tolerance > 0.0, "xy_goal_tolerance", params_.xy_goal_tolerance,
          "must be > 0 [m]");
  require(params_.yaw_goal_tolerance > 0.0, "yaw_goal_tolerance", params_.yaw_goal_tolerance,
          "must be > 0 [rad]");
  require(params_.min_approach_speed > 0.0, "min_approach_speed", params_.min_approach_speed,
          "must be > 0 [m/s]");
  require(params_.escape_speed > 0.0, "escape_speed", params_.escape_speed, "must be > 0 [m/s]");
  require(params_.approach_distance > 0.0, "approach_distance", params_.approach_distance,
          "must be > 0 [m]");
  require(params_.proximity_distance > 0.0, "proximity_distance", params_.proximity_distance,
          "must be > 0 [m]");
  require(params_.collision_check_step > 0.0, "collision_check_step", params_.collision_check_step,
          "must be > 0 [s]");
  require(params_.stop_margin >= 0.0, "stop_margin", params_.stop_margin, "must be >= 0 [m]");
  require(params_.blocked_timeout >= 0.0, "blocked_timeout", params_.blocked_timeout,
          "must be >= 0 [s]");
  require(params_.control_period > 0.0, "control_period", params_.control_period,
          "must be > 0 [s]");
  require(params_.max_path_deviation > 0.0, "max_path_deviation", params_.max_path_deviation,
          "must be > 0 [m]");
}

void LocalController::set_path(const Path& path) {
  if (path.empty()) throw std::invalid_argument("local controller: the path to follow is empty");
  path_ = path;
  progress_ = 0;
  xy_latched_ = false;
  blocked_since_.reset();
  escape_checked_ = false;
  escape_depth_.reset();
}

void LocalController::reset() {
  path_.clear();
  progress_ = 0;
  escape_checked_ = false;
  escape_depth_.reset();
  xy_latched_ = false;
  blocked_since_.reset();
  last_stamp_.reset();
  last_cmd_ = {};
}

void LocalController::set_acceleration_limits(double max_ax, double max_ay, double max_aw) {
  require(max_ax > 0.0, "limits.max_ax", max_ax, "must be > 0 [m/s^2]");
  require(params_.drive == ControllerParams::Drive::kDifferential || max_ay > 0.0, "limits.max_ay",
          max_ay, "must be > 0 [m/s^2] for an omni-steering base");
  require(max_aw > 0.0, "limits.max_aw", max_aw, "must be > 0 [rad/s^2]");
  params_.limits.max_ax = max_ax;
  params_.limits.max_ay = max_ay;
  params_.limits.max_aw = max_aw;
}

BaseTwist LocalController::limit_acceleration(const BaseTwist& want, double dt) const {
  const ControllerParams::Limits& l = params_.limits;
  auto step = [dt](double from, double to, double accel) {
    return std::clamp(to, from - accel * dt, from + accel * dt);
  };
  BaseTwist out;
  out.vx = step(last_cmd_.vx, want.vx, l.max_ax);
  out.vy =
      params_.drive == ControllerParams::Drive::kOmni ? step(last_cmd_.vy, want.vy, l.max_ay) : 0.0;
  out.wz = step(last_cmd_.wz, want.wz, l.max_aw);
  return out;
}

double LocalController::safe_scale(const Costmap& costmap, const Eigen::Vector3d& pose,
                                   const BaseTwist& cmd, double max_tau) const {
  const ControllerParams::Limits& l = params_.limits;
  // Poses along the command are parametrised by tau: at scale s the robot reaches pose(tau)
  // at time tau / s and can decelerate along it at alpha (tau units per s^2).
  double alpha = std::numeric_limits<double>::infinity();
  if (std::abs(cmd.vx) > 1e-9) alpha = std::min(alpha, l.max_ax / std::abs(cmd.vx));
  if (std::abs(cmd.vy) > 1e-9) alpha = std::min(alpha, l.max_ay / std::abs(cmd.vy));
  if (std::abs(cmd.wz) > 1e-9) alpha = std::min(alpha, l.max_aw / std::abs(cmd.wz));
  if (!std::isfinite(alpha)) return 1.0;
  const double sweep_speed =
      std::max(std::hypot(cmd.vx, cmd.vy), costmap.shape().circumscribed_radius * std::abs(cmd.wz));
  if (sweep_speed < 1e-4) return 1.0;  // no motion to speak of
  const double tau_margin = params_.stop_margin / sweep_speed + params_.control_period;
  // A slow command's margin is long in tau: the check ends after kMaxCheckTime in any case.
  const double horizon =
      std::min({1.0 / (2.0 * alpha) + tau_margin + params_.control_period, kMaxCheckTime, max_tau});
  for (double tau = params_.collision_check_step; tau <= horizon + 1e-9;
       tau += params_.collision_check_step) {
    const Eigen::Vector3d ahead = integrate_twist(pose, cmd, tau);
    if (escape_depth_ ? costmap.lethal_depth(ahead) > *escape_depth_ : costmap.in_collision(ahead)) {
      return std::min(1.0, std::sqrt(2.0 * alpha * std::max(0.0, tau - tau_margin)));
    }
  }
  return 1.0;
}

ControlOutput LocalController::stop(ControlOutput out) {
  out.cmd = {};
  last_cmd_ = {};
  blocked_since_.reset();
  return out;
}

ControlOutput LocalController::escape(const Costmap& costmap, const Eigen::Vector3d& pose, double dt,
                                      ControlOutput out) {
  // Straight to the path's first pose free at any heading, heading held (a turn would sweep the
  // footprint deeper into what it covers), slowly: the footprint is the hull of what the base may
  // occupy, not where its body is.
  std::size_t target = 0;
  while (target + 1 < path_.size() && !costmap.free_at_any_heading(path_[target].head<2>())) ++target;
  const Eigen::Vector2d d = path_[target].head<2>() - pose.head<2>();
  const double distance = d.norm();
  const double speed = std::min(params_.escape_speed, distance / params_.control_period);
  const Eigen::Vector2d v = Eigen::Rotation2Dd(-pose.z()) * (distance > 1e-9 ? Eigen::Vector2d(d / distance) : d);
  BaseTwist want;
  want.vx = speed * v.x();
  want.vy = params_.drive == ControllerParams::Drive::kOmni ? speed * v.y() : 0.0;
  out.cmd = limit_acceleration(want, dt);
  if (costmap.lethal_depth(integrate_twist(pose, out.cmd, params_.control_period)) > *escape_depth_) out.cmd = {};
  last_cmd_ = out.cmd;
  out.status = ControlStatus::kFollowing;
  return out;
}

ControlOutput LocalController::compute(const Costmap& costmap, const Eigen::Vector3d& pose,
                                       double stamp) {
  double dt = params_.control_period;
  if (last_stamp_ && stamp > *last_stamp_)
    dt = std::min(stamp - *last_stamp_, 4.0 * params_.control_period);
  last_stamp_ = stamp;

  ControlOutput out;
  if (path_.empty()) {
    out.status = ControlStatus::kIdle;
    return stop(out);
  }
  const Eigen::Vector3d& goal = path_.back();
  const Eigen::Vector2d p = pose.head<2>();
  out.distance_to_goal = (goal.head<2>() - p).norm();
  out.heading_error = wrap(goal.z() - pose.z());
  if (!pose.allFinite()) {
    out.status = ControlStatus::kFailed;
    out.reason = "the robot pose " + detail::pose_text(pose) + " is not finite";
    return stop(out);
  }
  // A path that starts where the footprint covers an obstacle (the planner's escape move): the
  // robot leaves going no deeper into it, until its footprint is free at any heading.
  if (progress_ == 0 && !escape_checked_) {
    escape_checked_ = true;
    if (costmap.in_collision(pose)) escape_depth_ = costmap.leaving_depth(pose);
  }
  if (escape_depth_ && costmap.free_at_any_heading(p)) escape_depth_.reset();
  if (escape_depth_ ? costmap.lethal_depth(pose) > *escape_depth_ : costmap.in_collision(pose)) {
    // Along the path (the pose estimate corrected, a wall marked anew): blocked, so that the
    // navigator plans again from here, leaving it; going deeper while leaving fails.
    out.status = escape_depth_ ? ControlStatus::kFailed : ControlStatus::kBlocked;
    char b[160];
    std::snprintf(b, sizeof b, "the robot's footprint at %s covers an obstacle",
                  detail::pose_text(pose).c_str());
    out.reason = b;
    if (escape_depth_) {
      std::snprintf(b, sizeof b, " %.2f m deep, more than where it started leaving it (%.2f m)",
                    costmap.lethal_depth(pose), *escape_depth_ - costmap.resolution());
      out.reason += b;
    }
    return stop(out);
  }
  if (escape_depth_) return escape(costmap, pose, dt, out);

  // Progress: the nearest path pose within a stretch ahead of the last one.
  {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_i = progress_;
    double along = 0.0;
    const double window = params_.max_path_deviation + 2.0 * params_.max_lookahead;
    for (std::size_t i = progress_; i < path_.size() && along <= window; ++i) {
      if (i > progress_) along += (path_[i].head<2>() - path_[i - 1].head<2>()).norm();
      const double d = (path_[i].head<2>() - p).norm();
      if (d < best) {
        best = d;
        best_i = i;
      }
    }
    progress_ = best_i;
    if (best > params_.max_path_deviation) {
      out.status = ControlStatus::kFailed;
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.2f m", best);
      out.reason = "the robot at " + detail::pose_text(pose) + " is " + buf +
                   " from the path (limit " + std::to_string(params_.max_path_deviation) + " m)";
      return stop(out);
    }
  }

  const bool omni = params_.drive == ControllerParams::Drive::kOmni;
  const ControllerParams::Limits& lim = params_.limits;
  if (out.distance_to_goal <= 0.5 * params_.xy_goal_tolerance) xy_latched_ = true;
  if (out.distance_to_goal > params_.xy_goal_tolerance) xy_latched_ = false;

  BaseTwist want;
  if (xy_latched_) {
    if (std::abs(out.heading_error) <= params_.yaw_goal_tolerance) {
      out.status = ControlStatus::kReached;
      return stop(out);
    }
    const double wz = params_.heading_gain * out.heading_error;
    want.wz = std::copysign(std::clamp(std::abs(wz), 0.05, lim.max_wz), wz);
  } else {
    const double speed = std::hypot(last_cmd_.vx, last_cmd_.vy);
    const double lookahead =
        std::clamp(speed * params_.lookahead_time, params_.min_lookahead, params_.max_lookahead);
    // The lookahead point: where the path leaves the circle of that radius around the robot.
    Eigen::Vector2d target = goal.head<2>();
    double target_heading = goal.z();
    bool at_end = true;
    for (std::size_t i = progress_ + 1; i < path_.size(); ++i) {
      const Eigen::Vector2d b = path_[i].head<2>();
      if ((b - p).norm() < lookahead) continue;
      const Eigen::Vector2d a = path_[i - 1].head<2>();
      const Eigen::Vector2d d = b - a;
      // |a + t d - p| = lookahead, the root in [0, 1].
      const Eigen::Vector2d f = a - p;
      const double qa = d.squaredNorm();
      const double qb = 2.0 * f.dot(d);
      const double qc = f.squaredNorm() - lookahead * lookahead;
      const double disc = std::max(0.0, qb * qb - 4.0 * qa * qc);
      const double t = qa > 0.0 ? std::clamp((-qb + std::sqrt(disc)) / (2.0 * qa), 0.0, 1.0) : 1.0;
      target = a + t * d;
      target_heading = path_[i].z();
      at_end = false;
      break;
    }
    if (at_end || out.distance_to_goal < params_.approach_distance) target_heading = goal.z();

    const Eigen::Vector2d to_target = target - p;
    const double dist_target = to_target.norm();
    const Eigen::Rotation2Dd world_to_base(-pose.z());
    const Eigen::Vector2d dir_base =
        dist_target > 1e-9 ? Eigen::Vector2d(world_to_base * (to_target / dist_target))
                           : Eigen::Vector2d::Zero();

    // Regulated speed: curvature of the pursuit arc, proximity to obstacles, goal approach.
    double v = params_.desired_speed;
    const double ref_heading = omni ? path_[progress_].z() : pose.z();
    const double alpha = wrap(std::atan2(to_target.y(), to_target.x()) - ref_heading);
    const double curvature =
        dist_target > 1e-9 ? 2.0 * std::abs(std::sin(alpha)) / dist_target : 0.0;
    if (curvature > 1e-9 && 1.0 / curvature < params_.regulated_min_radius) {
      v *= (1.0 / curvature) / params_.regulated_min_radius;
    }
    const double clearance =
        costmap.distance_from_cost(costmap.cost_at(p)) - costmap.shape().inscribed_radius;
    if (clearance < params_.proximity_distance) {
      v *= std::max(0.0, params_.proximity_gain * clearance / params_.proximity_distance);
    }
    v = std::max(v, params_.min_regulated_speed);
    if (out.distance_to_goal < params_.approach_distance) {
      v = std::min(
          v, std::max(params_.min_approach_speed,
                      params_.desired_speed * out.distance_to_goal / params_.approach_distance));
    }

    if (omni) {
      const double heading_err = wrap(target_heading - pose.z());
      const double excess = std::abs(heading_err) - params_.heading_slowdown_error;
      if (excess > 0.0) {
        const double span = std::max(1e-6, M_PI / 2.0 - params_.heading_slowdown_error);
        v *= std::max(0.2, 1.0 - 0.8 * excess / span);
      }
      // Never past the goal within one period.
      if (at_end) v = std::min(v, out.distance_to_goal / dt);
      want.vx = v * dir_base.x();
      want.vy = v * dir_base.y();
      const double over = std::max(std::abs(want.vx) / lim.max_vx, std::abs(want.vy) / lim.max_vy);
      if (over > 1.0) {
        want.vx /= over;
        want.vy /= over;
      }
      want.wz = std::clamp(params_.heading_gain * heading_err, -lim.max_wz, lim.max_wz);
    } else {
      const double bearing = std::atan2(dir_base.y(), dir_base.x());
      if (std::abs(bearing) > params_.rotate_in_place_error) {
        want.wz = std::clamp(params_.heading_gain * bearing, -lim.max_wz, lim.max_wz);
      } else {
        const double kappa = dist_target > 1e-9 ? 2.0 * dir_base.y() / dist_target : 0.0;
        if (at_end) v = std::min(v, out.distance_to_goal / dt);
        want.vx = std::min(v, lim.max_vx);
        if (std::abs(kappa * want.vx) > lim.max_wz) want.vx = lim.max_wz / std::abs(kappa);
        want.wz = kappa * want.vx;
      }
    }
  }

  // Cut the command so the robot can stop before the first colliding pose along it. When that
  // stops it, try its parts alone: the translation (omni), then the turn.
  auto moving = [&](const BaseTwist& cmd, double scale) {
    return scale * std::hypot(cmd.vx, cmd.vy) >= 0.5 * params_.min_approach_speed ||
           scale * std::abs(cmd.wz) >= 0.02;
  };
  // Up to the goal, where the command ends: the goal's footprint was checked by the planner.
  auto until_goal = [&](const BaseTwist& cmd) {
    double tau = std::numeric_limits<double>::infinity();
    const double lin = std::hypot(cmd.vx, cmd.vy);
    if (xy_latched_) {
      if (std::abs(cmd.wz) > 1e-9) tau = std::abs(out.heading_error) / std::abs(cmd.wz);
    } else if (out.distance_to_goal < params_.approach_distance && lin > 1e-9) {
      tau = out.distance_to_goal / lin;
    }
    return tau;
  };
  double scale = safe_scale(costmap, pose, want, until_goal(want));
  bool obstructed = scale < 1.0 && !moving(want, scale);
  if (obstructed) {
    std::vector<BaseTwist> parts;
    if (omni) parts.push_back({want.vx, want.vy, 0.0});
    parts.push_back({0.0, 0.0, want.wz});
    for (const BaseTwist& part : parts) {
      const double part_scale = safe_scale(costmap, pose, part, until_goal(part));
      if (moving(part, part_scale)) {
        want = part;
        scale = part_scale;
        obstructed = false;
        break;
      }
    }
  }
  if (obstructed) {
    want = {};
    if (!blocked_since_) blocked_since_ = stamp;
    if (stamp - *blocked_since_ >= params_.blocked_timeout) {
      out.status = ControlStatus::kBlocked;
      out.reason = "an obstacle in front of the robot at " + detail::pose_text(pose) +
                   " has blocked the path for " + std::to_string(stamp - *blocked_since_) + " s";
    } else {
      out.status = ControlStatus::kWaiting;
      out.reason = "an obstacle in front of the robot at " + detail::pose_text(pose);
    }
  } else {
    want.vx *= scale;
    want.vy *= scale;
    want.wz *= scale;
    blocked_since_.reset();
    out.status = ControlStatus::kFollowing;
  }
  out.cmd = limit_acceleration(want, dt);
  last_cmd_ = out.cmd;
  return out;
}

}  // namespace concert::nav
