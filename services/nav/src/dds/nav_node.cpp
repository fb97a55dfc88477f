#include "dds/nav_node.hpp"

#include <cmath>
#include <sstream>
#include <utility>

#include "concert/common/clock.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/model/dds/pose.hpp"

namespace concert::nav::dds {

namespace cdds = concert::dds;

msg::Pose2D to_msg(const Pose2& p) {
  msg::Pose2D out;
  out.x(p.x);
  out.y(p.y);
  out.yaw(p.yaw);
  return out;
}

Pose2 to_core(const msg::Pose2D& p) { return {p.x(), p.y(), p.yaw()}; }

GoalRequest to_core(const msg::NavGoal& g) {
  GoalRequest out;
  out.id = g.request_id();
  out.model_version = g.model_version();
  out.kind = g.kind() == msg::NAV_GOAL_WALL ? GoalRequest::Kind::kWall : GoalRequest::Kind::kPose;
  out.pose = to_core(g.pose());
  out.wall = g.wall();
  out.s = g.s();
  out.h = g.h();
  return out;
}

namespace {

msg::NavState to_msg(GoalState s) {
  switch (s) {
    case GoalState::kIdle:
      return msg::NAV_IDLE;
    case GoalState::kPlanning:
      return msg::NAV_PLANNING;
    case GoalState::kFollowing:
      return msg::NAV_FOLLOWING;
    case GoalState::kReached:
      return msg::NAV_REACHED;
    case GoalState::kFailed:
      return msg::NAV_FAILED;
    case GoalState::kCancelled:
      return msg::NAV_CANCELLED;
    case GoalState::kRefused:
      return msg::NAV_REFUSED;
  }
  return msg::NAV_FAILED;
}

msg::LocalisationState to_msg(const LocalisationStatus& l) {
  switch (l.state) {
    case LocaliserStatus::kUninitialised:
      return msg::LOCALISATION_NONE;
    case LocaliserStatus::kTracking:
      return l.converging ? msg::LOCALISATION_CONVERGING : msg::LOCALISATION_TRACKING;
    case LocaliserStatus::kLost:
      return msg::LOCALISATION_LOST;
  }
  return msg::LOCALISATION_NONE;
}

std::int64_t to_ns(double s) { return static_cast<std::int64_t>(std::llround(s * 1e9)); }
double to_s(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }

}  // namespace

msg::NavStatus to_msg(const GoalStatus& s, std::int64_t stamp_ns) {
  msg::NavStatus out;
  out.request_id(s.id);
  out.model_version(static_cast<uint32_t>(s.model_version));
  out.stamp_ns(stamp_ns);
  out.state(to_msg(s.state));
  out.reason(s.reason);
  out.goal(to_msg(s.goal));
  if (s.area) out.goal_area(model::dds::to_pose_msg(*s.area));
  out.pose(to_msg(s.pose));
  out.distance_remaining(s.distance_remaining);
  out.replans(s.replans);
  out.position_error(s.position_error);
  out.heading_error(s.heading_error);
  return out;
}

msg::OccupancyGridMap to_msg(const bim::OccupancyGrid& g, const std::string& name,
                             const std::string& source) {
  msg::OccupancyGridMap out;
  out.stamp_ns(now_ns());
  out.name(name);
  out.source(source);
  out.resolution(g.resolution);
  out.origin_x(g.origin.x());
  out.origin_y(g.origin.y());
  out.width(static_cast<uint32_t>(g.width));
  out.height(static_cast<uint32_t>(g.height));
  out.cells().resize(g.cells.size());
  for (std::size_t i = 0; i < g.cells.size(); ++i)
    out.cells()[i] = static_cast<uint8_t>(g.cells[i]);
  return out;
}

msg::NavVehicle to_msg(const VehicleConfig& v) {
  msg::NavVehicle out;
  out.model_version(static_cast<uint32_t>(v.model_version));
  out.stamp_ns(now_ns());
  out.drive(std::string(to_string(v.drive)));
  for (const auto& p : v.footprint.polygon) {
    msg::Pose2D c;
    c.x(p.x());
    c.y(p.y());
    out.footprint().push_back(c);
  }
  out.max_speed(v.limits.linear);
  out.max_yaw_rate(v.limits.angular);
  for (const auto& l : v.perception.planar_lidars) out.lidars().push_back(l.name);
  for (const auto& l : v.perception.lidars_3d) out.lidars().push_back(l.name);
  for (const auto& s : v.perception.sonars) out.sonars().push_back(s.name);
  if (!v.perception.imus.empty()) out.imu(v.perception.imus.front().name);
  return out;
}

PlanarScan to_core(const msg::LaserScan& scan) {
  PlanarScan out;
  out.range_min = scan.range_min();
  out.range_max = scan.range_max();
  out.angles.reserve(scan.ranges().size());
  out.ranges.reserve(scan.ranges().size());
  for (std::size_t i = 0; i < scan.ranges().size(); ++i) {
    out.angles.push_back(scan.angle_min() + static_cast<double>(i) * scan.angle_increment());
    out.ranges.push_back(scan.ranges()[i]);
  }
  return out;
}

NavNode::NavNode(cdds::Participant& participant, Navigator& navigator, std::string map_source,
                 std::ostream& log)
    : navigator_(navigator),
      map_source_(std::move(map_source)),
      log_(log),
      status_(participant, "nav"),
      base_(participant, cdds::topics::base_velocity),
      statuses_(participant, cdds::topics::nav_status),
      paths_(participant, cdds::topics::nav_path),
      maps_(participant, cdds::topics::nav_map),
      odometry_out_(participant, cdds::topics::nav_odometry),
      localisation_out_(participant, cdds::topics::nav_localisation),
      vehicles_(participant, cdds::topics::nav_vehicle),
      models_(participant, cdds::topics::robot_model,
              [this](const msg::RobotModel& m, const auto&) {
                std::lock_guard lock(mutex_);
                inbox_.model = m;
              }),
      odometry_in_(participant, cdds::topics::odometry,
                   [this](const msg::Odometry& o, const auto&) {
                     std::lock_guard lock(mutex_);
                     if (inbox_.odometry.size() < 1000) inbox_.odometry.push_back(o);
                   }),
      imu_in_(participant, cdds::topics::imu,
              [this](const msg::Imu& s, const auto&) {
                std::lock_guard lock(mutex_);
                if (inbox_.imu.size() < 1000) inbox_.imu.push_back(s);
              }),
      scan_in_(participant, cdds::topics::scan,
               [this](const msg::LaserScan& s, const auto&) {
                 std::lock_guard lock(mutex_);
                 inbox_.scan = s;
               }),
      safety_in_(participant, cdds::topics::safety_state,
                 [this](const msg::SafetyState& s, const auto&) {
                   std::lock_guard lock(mutex_);
                   inbox_.safety = s;
                 }),
      joints_in_(participant, cdds::topics::joint_state,
                 [this](const msg::JointState& j, const auto&) {
                   std::lock_guard lock(mutex_);
                   inbox_.joints = j;
                 }),
      goals_in_(participant, cdds::topics::nav_goal,
                [this](const msg::NavGoal& g, const auto&) {
                  std::lock_guard lock(mutex_);
                  // A goal written again by a client that had not heard us yet is the same
                  // goal: taken once (a second submit would restart it).
                  if (goals_seen_.first_time(g.request_id(), g.stamp_ns()))
                    inbox_.goals.push_back(g);
                }),
      cancels_in_(participant, cdds::topics::nav_cancel,
                  [this](const msg::NavCancel& c, const auto&) {
                    std::lock_guard lock(mutex_);
                    inbox_.cancels.push_back(c);
                  }),
      initial_pose_in_(participant, cdds::topics::nav_initial_pose,
                       [this](const msg::NavInitialPose& p, const auto&) {
                         std::lock_guard lock(mutex_);
                         inbox_.initial_pose = p;
                       }) {
  status_.report(msg::SERVICE_STARTING, 0, "waiting for a robot model");
  publish_map();
}

NavNode::~NavNode() = default;

void NavNode::dropped_late(const std::string& what, const std::exception& e) {
  // The first and every 100th: a loaded host may deliver many late, the log must not drown.
  const std::uint64_t n = ++late_samples_;
  if (n == 1 || n % 100 == 0) {
    log_line("nav: " + what + " dropped, too late (" + std::to_string(n) + " late samples so far): " + e.what());
  }
}

void NavNode::log_line(const std::string& line) {
  std::lock_guard lock(log_mutex_);
  log_ << line << std::endl;
}

void NavNode::publish_map() {
  if (const auto* map = navigator_.map())
    maps_.write(to_msg(*map, navigator_.map_name(), map_source_));
}

void NavNode::apply_model(const msg::RobotModel& m) {
  if (m.version() == model_version_ && m.content_hash() == model_hash_) return;  // the same again
  status_.report(msg::SERVICE_RECONFIGURING, static_cast<uint32_t>(model_version_),
                 "reconfiguring to model version " + std::to_string(m.version()));
  std::shared_ptr<const model::RobotModel> robot;
  try {
    robot = model::RobotModel::build(concert::model::dds::to_description(m));
  } catch (const std::exception& e) {
    status_.refused("model version " + std::to_string(m.version()) + " refused: " + e.what());
    status_.report(
        model_version_ ? msg::SERVICE_READY : msg::SERVICE_ERROR,
        static_cast<uint32_t>(model_version_),
        std::string("model version ") + std::to_string(m.version()) + " refused: " + e.what());
    log_line("nav: " + std::string(e.what()));
    return;
  }
  model_version_ = m.version();
  model_hash_ = m.content_hash();
  const cdds::ModelId id{static_cast<uint32_t>(m.version()), m.content_hash()};
  try {
    const VehicleConfig& v = navigator_.set_model(*robot);
    vehicles_.write(to_msg(v));
    std::ostringstream note;
    note << to_string(v.drive) << " drive, " << v.wheels.size() << " wheels, footprint "
         << v.footprint.polygon.size() << " corners (r " << v.footprint.inscribed_radius << " .. "
         << v.footprint.circumscribed_radius << " m), max " << v.limits.linear << " m/s; "
         << v.perception.planar_lidars.size() + v.perception.lidars_3d.size() << " lidars, "
         << v.perception.sonars.size() << " sonars, " << v.perception.imus.size() << " IMU"
         << (navigator_.has_map() ? "; map '" + navigator_.map_name() + "'" : "; no map");
    status_.report(msg::SERVICE_READY, id, note.str());
    log_line("nav: model version " + std::to_string(m.version()) + ": " + note.str());
  } catch (const std::exception& e) {
    // A model without a drivable base is a valid robot (e.g. an arm on a fixed stand): nav is
    // configured to it and refuses goals with the reason.
    msg::NavVehicle none;
    none.model_version(static_cast<uint32_t>(m.version()));
    none.stamp_ns(now_ns());
    none.reason(e.what());
    vehicles_.write(none);
    status_.report(msg::SERVICE_READY, id, std::string("cannot navigate: ") + e.what());
    log_line(std::string("nav: cannot navigate: ") + e.what());
  }
}

void NavNode::publish_status() {
  for (const GoalStatus& s : navigator_.take_updates()) {
    statuses_.write(to_msg(s, last_stamp_ns_));
    if (s.state == GoalState::kReached || s.state == GoalState::kFailed ||
        s.state == GoalState::kCancelled || s.state == GoalState::kRefused) {
      std::ostringstream line;
      line << "nav: goal " << s.id << " " << to_string(s.state);
      if (s.state == GoalState::kReached) {
        line << " (" << s.position_error << " m, " << s.heading_error * 180.0 / M_PI
             << " deg from the goal)";
      }
      if (!s.reason.empty()) line << ": " << s.reason;
      log_line(line.str());
      if (s.state == GoalState::kRefused)
        status_.refused("goal " + std::to_string(s.id) + " refused: " + s.reason);
    }
  }
}

void NavNode::take_inputs(const Inbox& in) {
  if (in.model) apply_model(*in.model);
  if (in.safety) {
    const bool stopped = in.safety->mode() != msg::SAFETY_RUNNING;
    std::string reason = "safety stop";
    if (!in.safety->causes().empty()) reason += ": " + in.safety->causes().front();
    navigator_.set_safety_stop(stopped, reason);
  }
  if (in.initial_pose) {
    const auto& p = *in.initial_pose;
    navigator_.set_initial_pose(to_core(p.pose()), p.std_xy(), p.std_yaw());
    log_line("nav: initial pose from " + p.source());
  }
  for (const auto& o : in.odometry) {
    last_stamp_ns_ = std::max(last_stamp_ns_, static_cast<std::int64_t>(o.stamp_ns()));
    try {
      navigator_.on_wheel_odometry(to_s(o.stamp_ns()), {o.vx(), o.vy(), o.wz()});
    } catch (const LateMeasurement& e) {
      dropped_late("odometry", e);
    } catch (const std::exception& e) {
      status_.refused(std::string("odometry refused: ") + e.what());
    }
  }
  for (const auto& s : in.imu) {
    try {
      const auto& w = s.angular_velocity();
      navigator_.on_imu(to_s(s.stamp_ns()), s.sensor(), s.frame(), Eigen::Vector3d(w.x(), w.y(), w.z()));
    } catch (const LateMeasurement& e) {
      dropped_late("IMU sample", e);
    } catch (const std::exception& e) {
      status_.refused(std::string("IMU sample refused: ") + e.what());
    }
  }
  // A sample of another model version names other joints (or the same names on other modules).
  if (in.joints && in.joints->model_version() == navigator_.model_version()) {
    navigator_.on_joint_positions(in.joints->name(), in.joints->position());
  }
  if (in.scan) navigator_.on_scan(to_s(in.scan->stamp_ns()), to_core(*in.scan));
  for (const auto& c : in.cancels) navigator_.cancel(c.request_id(), "cancelled by " + c.source());
  for (const auto& g : in.goals) {
    const GoalStatus s = navigator_.submit(to_core(g));
    if (s.state != GoalState::kRefused) {
      log_line("nav: goal " + std::to_string(g.request_id()) + " from " + g.source() +
               " accepted: to (" + std::to_string(s.goal.x) + ", " + std::to_string(s.goal.y) +
               ", " + std::to_string(s.goal.yaw) + ")");
    }
  }
}

void NavNode::tick() {
  Inbox in;
  {
    std::lock_guard lock(mutex_);
    std::swap(in, inbox_);
  }
  take_inputs(in);
  if (last_stamp_ns_ == 0) {  // no robot clock yet
    publish_status();
    return;
  }
  const StepOutput out = navigator_.step(to_s(last_stamp_ns_));
  if (const std::string note = navigator_.take_budget_note(); !note.empty()) log_line("nav: " + note);
  if (out.drive && navigator_.vehicle()) {
    msg::BaseVelocityCommand c;
    c.model_version(static_cast<uint32_t>(navigator_.model_version()));
    c.stamp_ns(now_ns());
    c.source("nav");
    c.vx(out.command.vx);
    c.vy(out.command.vy);
    c.wz(out.command.wz);
    base_.write(c);
  }
  publish_status();
  if (out.path_changed) {
    msg::NavPath p;
    p.request_id(navigator_.status().id);
    p.model_version(static_cast<uint32_t>(navigator_.model_version()));
    p.stamp_ns(last_stamp_ns_);
    for (const auto& q : navigator_.path()) p.poses().push_back(to_msg(Pose2{q.x(), q.y(), q.z()}));
    paths_.write(p);
  }
  publish_odometry();
}

void NavNode::publish_odometry() {
  // Filtered odometry at the loop's rate; localisation at 10 Hz.
  const FilteredOdometry f = navigator_.odometry();
  msg::Odometry o;
  o.stamp_ns(to_ns(f.stamp));
  o.x(f.pose.x());
  o.y(f.pose.y());
  o.yaw(f.pose.z());
  o.vx(f.twist.x());
  o.vy(f.twist.y());
  o.wz(f.twist.z());
  std::array<double, 9> cov{};
  for (int i = 0; i < 9; ++i) cov[static_cast<std::size_t>(i)] = f.pose_covariance(i / 3, i % 3);
  o.covariance(cov);
  odometry_out_.write(o);
  const auto now = std::chrono::steady_clock::now();
  if (now - last_localisation_ < std::chrono::milliseconds(100)) return;
  last_localisation_ = now;
  const LocalisationStatus l = navigator_.localisation();
  msg::NavLocalisation m;
  m.stamp_ns(last_stamp_ns_);
  m.state(to_msg(l));
  m.pose(to_msg(l.pose));
  std::array<double, 9> c{};
  for (int i = 0; i < 9; ++i) c[static_cast<std::size_t>(i)] = l.covariance(i / 3, i % 3);
  m.covariance(c);
  m.map_to_odom(to_msg(l.map_to_odom));
  localisation_out_.write(m);
}

void NavNode::spin(const std::atomic<bool>& stop) {
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(1.0 / std::max(1.0, navigator_.params().control_rate)));
  auto next = std::chrono::steady_clock::now();
  while (!stop.load()) {
    try {
      tick();
    } catch (const std::exception& e) {
      // Never let one bad input take the service down: name it and carry on.
      status_.note(std::string("control step failed: ") + e.what());
      log_line(std::string("nav: control step failed: ") + e.what());
    }
    next += period;
    const auto now = std::chrono::steady_clock::now();
    if (next < now) next = now;
    std::this_thread::sleep_until(next);
  }
  if (navigator_.status().state == GoalState::kFollowing ||
      navigator_.status().state == GoalState::kPlanning) {
    navigator_.cancel(0, "nav service stopping");
    publish_status();
    msg::BaseVelocityCommand c;
    c.model_version(static_cast<uint32_t>(navigator_.model_version()));
    c.stamp_ns(now_ns());
    c.source("nav");
    base_.write(c);
  }
}

}  // namespace concert::nav::dds
