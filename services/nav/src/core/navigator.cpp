#include "nav/navigator.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "concert/bim/wall_goal.hpp"
#include "concert/mobile_base/map_frame.hpp"

namespace concert::nav {
namespace {

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

// a ∘ b for planar poses (x, y, yaw).
using mobile_base::compose;

Eigen::Vector3d vec(const Pose2& p) { return {p.x, p.y, p.yaw}; }
Pose2 pose2(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

std::string fixed(double v, int digits = 2) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

std::string where(const Pose2& p) { return "(" + fixed(p.x) + ", " + fixed(p.y) + ")"; }

bool running(GoalState s) { return s == GoalState::kPlanning || s == GoalState::kFollowing; }

// Twist covariance of the wheel odometry: wheels slip a little in every direction.
const Eigen::Matrix3d kWheelTwistCovariance = Eigen::Vector3d(4e-4, 4e-4, 1e-3).asDiagonal();
constexpr double kGyroVariance = 1e-5;   // [(rad/s)^2], the BMI055 at 200 Hz
constexpr double kHistorySpan = 1.0;     // [s] of odometry kept to place scans in time
constexpr double kFeedbackPeriod = 0.5;  // [s]
constexpr double kLostTimeout = 10.0;    // [s] lost while driving -> the goal fails

}  // namespace

const char* to_string(GoalState s) {
  switch (s) {
    case GoalState::kIdle:
      return "idle";
    case GoalState::kPlanning:
      return "planning";
    case GoalState::kFollowing:
      return "following";
    case GoalState::kReached:
      return "reached";
    case GoalState::kFailed:
      return "failed";
    case GoalState::kCancelled:
      return "cancelled";
    case GoalState::kRefused:
      return "refused";
  }
  return "?";
}

Navigator::Navigator(NavParams params, std::uint64_t seed)
    : params_(std::move(params)),
      seed_(seed),
      planner_(params_.planner),
      filter_(params_.odometry) {
  if (!(params_.control_rate > 0.0)) throw std::invalid_argument("nav: control_rate must be > 0");
  if (!(params_.cruise_speed > 0.0)) throw std::invalid_argument("nav: cruise_speed must be > 0");
  if (params_.max_replans < 0) throw std::invalid_argument("nav: max_replans must be >= 0");
  if (!(params_.drive_torque_fraction > 0.0 && params_.drive_torque_fraction <= 1.0))
    throw std::invalid_argument("nav: drive_torque_fraction must be in (0, 1]");
  params_.localiser.seed = seed_;
}

const VehicleConfig& Navigator::set_model(const model::RobotModel& model) {
  if (running(status_.state)) {
    set_state(GoalState::kCancelled,
              "the robot model changed to version " + std::to_string(model.version()));
  }
  model_version_ = model.version();
  try {
    vehicle_ = recognise_vehicle(model, params_.vehicle);
    drives_ = std::make_unique<model::DriveBudget>(model);
    posture_ = drives_->neutral_posture();
    posture_measured_ = false;
    home_ = transport_posture(model);
    arm_joint_.assign(drives_->joint_names().size(), false);
    for (const model::ChainInfo* arm : model.chains(model::ChainRole::kArm)) {
      for (const std::string& j : arm->joints) {
        const auto& names = drives_->joint_names();
        const auto it = std::find(names.begin(), names.end(), j);
        if (it != names.end()) arm_joint_[static_cast<std::size_t>(it - names.begin())] = true;
      }
    }
    vehicle_error_.clear();
  } catch (const std::exception& e) {
    vehicle_.reset();
    drives_.reset();
    vehicle_error_ = e.what();
    rebuild();
    throw;
  }
  rebuild();
  return *vehicle_;
}

void Navigator::set_map(bim::OccupancyGrid grid, std::string name,
                        std::shared_ptr<const bim::BimModel> bim) {
  auto field = std::make_shared<const LikelihoodField>(grid);  // throws on a map without walls
  if (running(status_.state)) set_state(GoalState::kCancelled, "the map changed to '" + name + "'");
  const bool was_localised =
      localiser_ && localiser_->estimate().status == LocaliserStatus::kTracking;
  const Eigen::Vector3d last =
      was_localised ? localiser_->estimate().pose : Eigen::Vector3d::Zero();
  map_ = std::make_shared<const bim::OccupancyGrid>(std::move(grid));
  field_ = std::move(field);
  map_name_ = std::move(name);
  bim_ = std::move(bim);
  localiser_ = std::make_unique<Localiser>(field_, params_.localiser);
  if (pending_initial_) {
    localiser_->set_pose(*pending_initial_, pending_sigma_, filter_.estimate().pose);
    map_to_odom_ = localiser_->estimate().map_T_odom;
    pending_initial_.reset();
  } else if (was_localised) {
    localiser_->set_pose(last,
                         {params_.initial_std_xy, params_.initial_std_xy, params_.initial_std_yaw},
                         filter_.estimate().pose);
  }
  rebuild();
}

void Navigator::rebuild() {
  costmap_.reset();
  controller_.reset();
  if (!vehicle_) return;
  ControllerParams cp = params_.controller;
  cp.drive = vehicle_->drive == DriveType::kDifferential ? ControllerParams::Drive::kDifferential
                                                         : ControllerParams::Drive::kOmni;
  const double linear = std::min(params_.cruise_speed, vehicle_->limits.linear);
  cp.limits.max_vx = linear;
  cp.limits.max_vy = vehicle_->drive == DriveType::kDifferential
                         ? 0.0
                         : std::min(linear, vehicle_->limits.lateral);
  cp.limits.max_wz = vehicle_->limits.angular;
  cp.limits.max_ax = params_.max_acceleration;
  cp.limits.max_ay = params_.max_acceleration;
  cp.limits.max_aw = params_.max_angular_acceleration;
  cp.desired_speed = linear;
  cp.control_period = 1.0 / params_.control_rate;
  controller_ = std::make_unique<LocalController>(cp);
  budget_stale_ = true;
  if (!map_) return;
  costmap_ = std::make_unique<Costmap>(
      *map_, RobotShape::from_footprint(vehicle_->footprint.polygon), params_.costmap);
}

void Navigator::set_initial_pose(const Pose2& pose, double std_xy, double std_yaw) {
  const double sxy = std_xy > 0 ? std_xy : params_.initial_std_xy;
  const Eigen::Vector3d sigma(sxy, sxy, std_yaw > 0 ? std_yaw : params_.initial_std_yaw);
  if (!localiser_) {
    pending_initial_ = vec(pose);
    pending_sigma_ = sigma;
    return;
  }
  localiser_->set_pose(vec(pose), sigma, filter_.estimate().pose);
  map_to_odom_ = localiser_->estimate().map_T_odom;
}

std::string Navigator::arm_away_from_home() const {
  if (!(params_.arm_home_tolerance > 0.0) || !drives_ || !posture_measured_ ||
      home_.size() != posture_.size()) {
    return {};
  }
  std::string worst;
  double farthest = params_.arm_home_tolerance;
  int away = 0;
  for (Eigen::Index i = 0; i < posture_.size(); ++i) {
    const double d = std::abs(posture_(i) - home_(i));
    if (!arm_joint_[static_cast<std::size_t>(i)] || d <= params_.arm_home_tolerance) continue;
    ++away;
    if (d >= farthest) {
      farthest = d;
      worst = drives_->joint_names()[static_cast<std::size_t>(i)] + " at " + fixed(posture_(i)) +
              ", home " + fixed(home_(i));
    }
  }
  if (away == 0) return {};
  return "the arm is not in its transport posture (" + std::to_string(away) + " joint" +
         (away == 1 ? "" : "s") + " away from home, farthest " + worst +
         "): move it home first (concert plan home)";
}

void Navigator::on_joint_positions(const std::vector<std::string>& names,
                                   const std::vector<double>& positions) {
  if (!drives_) return;
  const std::vector<std::string>& joints = drives_->joint_names();
  const std::size_t n = std::min(names.size(), positions.size());
  for (std::size_t k = 0; k < n; ++k) {
    const auto it = std::find(joints.begin(), joints.end(), names[k]);
    if (it == joints.end() || !std::isfinite(positions[k])) continue;
    posture_measured_ = true;
    double& q = posture_(it - joints.begin());
    // A posture change below a milliradian changes the budget by nothing worth a recompute.
    if (std::abs(q - positions[k]) > 1e-3) {
      q = positions[k];
      budget_stale_ = true;
    }
  }
}

namespace {
// Below 1 % of the platform's accelerations the base would crawl for minutes to reach speed.
constexpr double kLeastAcceleration = 0.01;
}  // namespace

void Navigator::apply_drive_budget() {
  if (budget_stale_ && drives_ && controller_ && vehicle_) update_drive_budget();
  if (drives_ && budget_.scale < kLeastAcceleration && running(status_.state)) {
    set_state(GoalState::kFailed,
              "the posture leaves the base no acceleration: " + budget_.joint + " holds " +
                  fixed(100.0 * budget_.static_load, 0) +
                  " % of its continuous torque standing still (move the arm to a posture it "
                  "holds with the base accelerating)");
  }
}

void Navigator::update_drive_budget() {
  budget_stale_ = false;
  const bool differential = vehicle_->drive == DriveType::kDifferential;
  model::BaseMotion asked;
  asked.ax = params_.max_acceleration;
  asked.ay = differential ? 0.0 : params_.max_acceleration;
  asked.aw = params_.max_angular_acceleration;
  asked.wz = vehicle_->limits.angular;
  budget_ = drives_->base_motion(posture_, asked, params_.drive_torque_fraction);
  const double scale = std::max(budget_.scale, kLeastAcceleration);
  controller_->set_acceleration_limits(asked.ax * scale, differential ? 0.0 : asked.ay * scale,
                                       asked.aw * scale);
  const bool changed = budget_.joint != noted_joint_ ||
                       std::abs(budget_.scale - noted_scale_) > 0.1 * std::max(noted_scale_, 0.01);
  if (changed) {
    noted_joint_ = budget_.joint;
    noted_scale_ = budget_.scale;
    std::ostringstream note;
    if (budget_.joint.empty()) {
      note << "base accelerations as configured (" << fixed(asked.ax) << " m/s^2, "
           << fixed(asked.aw) << " rad/s^2): every drive holds them at this posture";
    } else {
      note << "base accelerations at " << fixed(100.0 * budget_.scale, 0) << " % of the configured ("
           << fixed(asked.ax * budget_.scale) << " m/s^2, " << fixed(asked.aw * budget_.scale)
           << " rad/s^2): " << budget_.joint << " holds " << fixed(100.0 * budget_.static_load, 0)
           << " % of its continuous torque still and " << fixed(100.0 * budget_.dynamic_load, 0)
           << " % more at the full accelerations";
    }
    budget_note_ = note.str();
  }
}

std::string Navigator::take_budget_note() { return std::exchange(budget_note_, std::string()); }

void Navigator::on_wheel_odometry(double stamp, const Eigen::Vector3d& twist) {
  if (!have_odometry_) {
    filter_.reset(stamp);
    have_odometry_ = true;
  }
  filter_.update(WheelTwist{stamp, twist, kWheelTwistCovariance});
  const FilteredOdometry f = filter_.estimate();
  history_.emplace_back(f.stamp, f.pose);
  const auto old = std::find_if(history_.begin(), history_.end(),
                                [&](const auto& h) { return h.first >= f.stamp - kHistorySpan; });
  history_.erase(history_.begin(), old);
}

void Navigator::on_gyro(double stamp, double yaw_rate) {
  if (!have_odometry_) return;  // the wheels start the filter's clock
  filter_.update(GyroRate{stamp, yaw_rate, kGyroVariance});
}

void Navigator::on_imu(double stamp, const std::string& sensor, const std::string& frame,
                       const Eigen::Vector3d& angular_velocity) {
  Eigen::Matrix3d base_R_imu = Eigen::Matrix3d::Identity();
  if (vehicle_) {
    for (const auto& imu : vehicle_->perception.imus) {
      if (imu.frame == frame || imu.name == sensor) base_R_imu = imu.base_T_sensor.linear();
    }
  }
  on_gyro(stamp, (base_R_imu * angular_velocity).z());
}

void Navigator::on_scan(double stamp, PlanarScan scan) { scan_ = Scan{stamp, std::move(scan)}; }

Eigen::Vector3d Navigator::odom_at(double stamp) const {
  if (history_.empty()) return filter_.estimate().pose;
  if (stamp <= history_.front().first) return history_.front().second;
  if (stamp >= history_.back().first) return history_.back().second;
  const auto hi = std::lower_bound(history_.begin(), history_.end(), stamp,
                                   [](const auto& h, double t) { return h.first < t; });
  const auto lo = hi - 1;
  const double f = (stamp - lo->first) / std::max(1e-9, hi->first - lo->first);
  Eigen::Vector3d p = lo->second + f * (hi->second - lo->second);
  p.z() = wrap(lo->second.z() + f * wrap(hi->second.z() - lo->second.z()));
  return p;
}

Eigen::Vector3d Navigator::map_pose_of(const Eigen::Vector3d& odom) const {
  return compose(map_to_odom_, odom);
}

Pose2 Navigator::pose() const { return pose2(map_pose_of(filter_.estimate().pose)); }

LocalisationStatus Navigator::localisation() const {
  LocalisationStatus out;
  if (!localiser_) return out;
  const LocaliserEstimate& e = localiser_->estimate();
  out.state = e.status;
  const double converged = std::pow(params_.localiser.converged_sigma_xy, 2);
  out.converging = e.status == LocaliserStatus::kTracking &&
                   (e.covariance(0, 0) > converged || e.covariance(1, 1) > converged);
  out.pose = pose();
  out.covariance = e.covariance;
  out.map_to_odom = pose2(map_to_odom_);
  return out;
}

void Navigator::localise() {
  if (!scan_ || !localiser_ || !have_odometry_) return;
  const Scan scan = std::move(*scan_);
  scan_.reset();
  const Eigen::Vector3d odom = odom_at(scan.stamp);
  const LocaliserEstimate& e = localiser_->update(odom, scan.beams);
  if (e.status == LocaliserStatus::kTracking) map_to_odom_ = e.map_T_odom;
  if (!costmap_ || e.status != LocaliserStatus::kTracking) return;
  // The obstacle layer: the scan's beams in the map frame, from the pose at the scan's time.
  const Eigen::Vector3d base = map_pose_of(odom);
  const double c = std::cos(base.z()), s = std::sin(base.z());
  std::vector<Beam> beams;
  beams.reserve(scan.beams.ranges.size());
  for (std::size_t i = 0; i < scan.beams.ranges.size(); ++i) {
    const double r = scan.beams.ranges[i];
    if (std::isnan(r) || r < scan.beams.range_min) continue;
    const bool hit = std::isfinite(r) && r <= scan.beams.range_max;
    const double d = hit ? r : scan.beams.range_max;
    const double a = scan.beams.angles[i];
    const Eigen::Vector2d p(d * std::cos(a), d * std::sin(a));
    beams.push_back(
        {Eigen::Vector2d(base.x() + c * p.x() - s * p.y(), base.y() + s * p.x() + c * p.y()), hit});
  }
  costmap_->update_obstacles(base.head<2>(), beams);
}

double Navigator::wall_standoff() const {
  if (params_.wall_standoff > 0.0) return params_.wall_standoff;
  if (!vehicle_) return 0.0;
  double front = 0.0;  // the footprint's reach along +x: the base faces the wall
  for (const auto& p : vehicle_->footprint.polygon) front = std::max(front, p.x());
  return front + params_.wall_clearance;
}

void Navigator::set_state(GoalState state, std::string reason) {
  status_.state = state;
  status_.reason = std::move(reason);
  status_.pose = pose();
  if (state == GoalState::kReached || state == GoalState::kFailed ||
      state == GoalState::kCancelled) {
    const Pose2 p = status_.pose;
    status_.position_error = std::hypot(p.x - status_.goal.x, p.y - status_.goal.y);
    status_.heading_error = std::abs(wrap(p.yaw - status_.goal.yaw));
    goal_.reset();
    if (controller_) controller_->reset();
  }
  updates_.push_back(status_);
  last_feedback_ = now_;
}

std::vector<GoalStatus> Navigator::take_updates() {
  std::vector<GoalStatus> out;
  out.swap(updates_);
  return out;
}

GoalStatus Navigator::submit(const GoalRequest& goal) {
  GoalStatus refused;
  refused.id = goal.id;
  refused.model_version = goal.model_version;
  refused.state = GoalState::kRefused;
  refused.goal = goal.pose;
  refused.pose = pose();
  auto refuse = [&](std::string reason) {
    refused.reason = std::move(reason);
    updates_.push_back(refused);
    return refused;
  };
  if (goal.id == 0) return refuse("request id 0 is reserved (cancel: whatever runs)");
  if (safety_stop_)
    return refuse("the robot is in a safety stop: reset it first (concert safety reset)");
  if (model_version_ == 0) return refuse("no robot model yet");
  if (goal.model_version != model_version_) {
    return refuse("stale goal: made for model version " + std::to_string(goal.model_version) +
                  ", the robot runs version " + std::to_string(model_version_));
  }
  if (!vehicle_) {
    return refuse("model version " + std::to_string(model_version_) +
                  " cannot navigate: " + vehicle_error_);
  }
  if (!map_ || !costmap_)
    return refuse("no map (start concert_nav with --ifc FILE --storey NAME or --map FILE)");
  if (!have_odometry_) return refuse("no odometry from the robot service yet");
  if (!localiser_ || localiser_->estimate().status != LocaliserStatus::kTracking) {
    return refuse("not localised (give the robot's pose: concert nav init X Y THETA)");
  }
  if (const std::string away = arm_away_from_home(); !away.empty()) return refuse(away);
  Pose2 target = goal.pose;
  std::optional<Eigen::Isometry3d> area;
  if (goal.kind == GoalRequest::Kind::kWall) {
    if (!bim_)
      return refuse("wall goals need the building's IFC model (the map came from a map file)");
    if (!std::isfinite(goal.s) || !std::isfinite(goal.h))
      return refuse("wall goal: s and h must be numbers");
    // wall_goal places a disc of the inscribed radius; the footprint itself must fit too. The
    // face wall_goal prefers first, then the other one.
    std::string why;
    try {
      bim::WallGoal w = bim::wall_goal(*bim_, *map_, goal.wall, goal.s, goal.h, wall_standoff(),
                                       vehicle_->footprint.inscribed_radius);
      if (costmap_->in_collision(w.base_pose)) {
        why = "the footprint does not fit in front of the " +
              std::string(w.face == 0 ? "left" : "right") + " face at (" + fixed(w.base_pose.x()) +
              ", " + fixed(w.base_pose.y()) + ")";
        bim::GoalOptions other;
        other.face = w.face == 0 ? bim::FaceChoice::kRight : bim::FaceChoice::kLeft;
        try {
          w = bim::wall_goal(*bim_, *map_, goal.wall, goal.s, goal.h, wall_standoff(),
                             vehicle_->footprint.inscribed_radius, other);
        } catch (const std::exception& e) {
          return refuse(why + "; the other face: " + e.what());
        }
        if (costmap_->in_collision(w.base_pose)) {
          return refuse(why + ", nor in front of the other face at (" + fixed(w.base_pose.x()) +
                        ", " + fixed(w.base_pose.y()) + ")");
        }
      }
      target = {w.base_pose.x(), w.base_pose.y(), w.base_pose.z()};
      area = w.area_frame;
    } catch (const std::exception& e) {
      return refuse(e.what());
    }
  }
  if (!std::isfinite(target.x) || !std::isfinite(target.y) || !std::isfinite(target.yaw)) {
    return refuse("goal pose is not finite");
  }
  refused.goal = target;
  const Eigen::Vector2i cell = costmap_->cell_of({target.x, target.y});
  if (!costmap_->inside(cell.x(), cell.y())) {
    return refuse("goal " + where(target) + " is outside the map '" + map_name_ + "'");
  }
  if (costmap_->in_collision(vec(target))) {
    return refuse("goal " + where(target) +
                  " is in collision: the robot's footprint there overlaps a wall or obstacle");
  }
  if (running(status_.state))
    set_state(GoalState::kCancelled, "replaced by goal " + std::to_string(goal.id));
  goal_ = goal;
  goal_->pose = target;
  status_ = GoalStatus{};
  status_.id = goal.id;
  status_.model_version = goal.model_version;
  status_.goal = target;
  status_.area = area;
  path_.clear();
  lost_since_ = -1.0;
  set_state(GoalState::kPlanning, "");
  return status_;
}

bool Navigator::cancel(std::uint32_t id, const std::string& reason) {
  if (!running(status_.state) || (id != 0 && id != status_.id)) return false;
  set_state(GoalState::kCancelled, reason);
  return true;
}

void Navigator::set_safety_stop(bool stopped, const std::string& reason) {
  safety_stop_ = stopped;
  if (stopped && running(status_.state)) set_state(GoalState::kCancelled, reason);
}

void Navigator::plan_path(double /*stamp*/) {
  const PlanResult r = planner_.plan(*costmap_, vec(pose()), vec(goal_->pose));
  if (!r.ok()) {
    set_state(GoalState::kFailed,
              std::string("no path: ") + to_string(r.status) + ": " + r.message);
    return;
  }
  path_ = r.path;
  path_changed_ = true;
  controller_->set_path(path_);
  status_.distance_remaining = r.length;
  set_state(GoalState::kFollowing, "");
}

StepOutput Navigator::step(double stamp) {
  now_ = stamp;
  StepOutput out;
  localise();
  if (goal_ && (!costmap_ || !controller_))
    set_state(GoalState::kFailed, "the map or the vehicle went away");
  apply_drive_budget();
  if (goal_ && status_.state == GoalState::kPlanning) plan_path(stamp);
  if (goal_ && status_.state == GoalState::kFollowing) {
    out.drive = true;
    if (localiser_->estimate().status != LocaliserStatus::kTracking) {
      // Hold still while the localiser recovers; give up after a while.
      if (lost_since_ < 0) lost_since_ = stamp;
      if (stamp - lost_since_ > kLostTimeout) {
        set_state(GoalState::kFailed, "localisation lost for " + fixed(kLostTimeout, 0) + " s");
      } else if (status_.reason.empty()) {
        status_.reason = "localisation lost: waiting for it to recover";
        updates_.push_back(status_);
      }
    } else {
      lost_since_ = -1.0;
      const ControlOutput c = controller_->compute(*costmap_, vec(pose()), stamp);
      status_.distance_remaining = c.distance_to_goal;
      status_.pose = pose();
      out.command = c.cmd;
      switch (c.status) {
        case ControlStatus::kReached:
          out.command = {};
          set_state(GoalState::kReached, "");
          break;
        case ControlStatus::kBlocked:
          out.command = {};
          if (status_.replans >= static_cast<std::uint32_t>(params_.max_replans)) {
            set_state(GoalState::kFailed, "blocked: " + c.reason + " (after " +
                                              std::to_string(status_.replans) + " replans)");
          } else {
            ++status_.replans;
            set_state(GoalState::kPlanning, "blocked: " + c.reason + "; replanning");
          }
          break;
        case ControlStatus::kFailed:
          out.command = {};
          set_state(GoalState::kFailed, c.reason);
          break;
        case ControlStatus::kWaiting:
          if (status_.reason.empty()) {
            status_.reason = "waiting: " + c.reason;
            updates_.push_back(status_);
          }
          break;
        default:
          status_.reason.clear();
          break;
      }
    }
  }
  if (goal_) {
    stop_sent_ = false;
    if (stamp - last_feedback_ >= kFeedbackPeriod) {
      status_.pose = pose();
      updates_.push_back(status_);
      last_feedback_ = stamp;
    }
  } else if (!stop_sent_) {
    out.drive = true;  // one zero command after a goal ends
    out.command = {};
    stop_sent_ = true;
  }
  out.path_changed = path_changed_;
  path_changed_ = false;
  return out;
}

}  // namespace concert::nav
