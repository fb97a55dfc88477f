#include "dds/drill_node.hpp"

#include <chrono>
#include <thread>
#include <utility>

#include "concert/common/clock.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/model/dds/pose.hpp"
#include "concert/sensors_dds/conversions.hpp"

namespace concert::drill::dds {

namespace cdds = concert::dds;
using Clock = std::chrono::steady_clock;

namespace {

constexpr const char* kSource = "drill";

}  // namespace

DrillNode::DrillNode(cdds::Participant& participant, NodeParams params, std::ostream& log)
    : params_(std::move(params)),
      log_(log),
      inputs_(params_.tuning.buffers, params_.tuning.liveness),
      status_(participant, "drill"),
      status_out_(participant, cdds::topics::drill_status),
      nav_goals_(participant, cdds::topics::nav_goal),
      nav_cancels_(participant, cdds::topics::nav_cancel),
      plan_requests_(participant, cdds::topics::plan_request),
      trajectories_(participant, cdds::topics::trajectory_command),
      cartesian_(participant, cdds::topics::cartesian_command),
      joint_commands_(participant, cdds::topics::joint_command),
      engine_(EngineParams{params_.patterns, params_.unseen_frames_dir, params_.tuning}, inputs_, map_frame_, *this),
      models_(participant, cdds::topics::robot_model,
              [this](const msg::RobotModel& m, const auto&) {
                std::lock_guard lock(mutex_);
                inbox_.model = m;
              }),
      joints_in_(participant, cdds::topics::joint_state,
                 [this](const msg::JointState& s, const auto&) {
                   inputs_.on_joints(s.stamp_ns(), {s.name(), s.position()}, Clock::now(), s.effort());
                 }),
      odometry_in_(participant, cdds::topics::odometry,
                   [this](const msg::Odometry& o, const auto&) {
                     map_frame_.on_odometry(o.stamp_ns(), odometry_of(o));
                     inputs_.on_odometry(odometry_of(o));
                   }),
      safety_in_(participant, cdds::topics::safety_state,
                 [this](const msg::SafetyState& s, const auto&) { inputs_.on_safety(to_core(s)); }),
      services_in_(participant, cdds::topics::status,
                   [this](const msg::ServiceStatus& s, const auto&) {
                     inputs_.on_service(s.service(), s.state() == msg::SERVICE_STOPPED, Clock::now());
                   }),
      plans_in_(participant, cdds::topics::plan_result,
                [this](const msg::PlanResult& r, const auto&) { inputs_.on_plan(to_core(r)); }),
      trajectories_in_(participant, cdds::topics::trajectory_status,
                       [this](const msg::TrajectoryStatus& s, const auto&) {
                         inputs_.on_trajectory(s.request_id(), to_core(s));
                       }),
      nav_in_(participant, cdds::topics::nav_status,
              [this](const msg::NavStatus& s, const auto&) { inputs_.on_nav(s.request_id(), to_core(s)); }),
      localisation_in_(
          participant, cdds::topics::nav_localisation,
          [this](const msg::NavLocalisation& l, const auto&) {
            if (l.state() != msg::LOCALISATION_TRACKING) return;
            map_frame_.on_localisation(l.stamp_ns(), {l.pose().x(), l.pose().y(), l.pose().yaw()});
          }),
      rgb_in_(participant, cdds::topics::camera_rgb,
              [this](const msg::Image& i, const auto&) { on_image(i, false); }),
      depth_in_(participant, cdds::topics::camera_depth,
                [this](const msg::Image& i, const auto&) { on_image(i, true); }),
      info_in_(participant, cdds::topics::camera_info,
               [this](const msg::CameraInfo& i, const auto&) { on_info(i); }),
      missions_in_(participant, cdds::topics::drill_mission,
                   [this](const msg::DrillMission& m, const auto&) {
                     std::lock_guard lock(mutex_);
                     inbox_.missions.push_back(m);
                   }),
      aborts_in_(participant, cdds::topics::drill_abort,
                 [this](const msg::DrillAbort& a, const auto&) {
                   std::lock_guard lock(mutex_);
                   inbox_.aborts.push_back(a);
                 }) {
  status_.report(msg::SERVICE_STARTING, 0, "waiting for a robot model");
}

DrillNode::~DrillNode() = default;

// Camera messages: the drill camera's rgb, depth and info with the same stamp make one frame,
// posed with the joint state at that stamp (the latest before it).
void DrillNode::on_image(const msg::Image& image, bool depth) {
  // Idle, the frames are not converted (1.5 MB and the camera's pose each, 15 times a second).
  if (!camera_wanted_.load(std::memory_order_relaxed)) return;
  std::lock_guard lock(mutex_);
  if (camera_.empty() || image.sensor() != camera_) return;
  (depth ? depth_ : rgb_) = image;
  assemble_frame();
}

void DrillNode::on_info(const msg::CameraInfo& info) {
  if (!camera_wanted_.load(std::memory_order_relaxed)) return;
  std::lock_guard lock(mutex_);
  if (camera_.empty() || info.sensor() != camera_) return;
  info_ = info;
  assemble_frame();
}

void DrillNode::assemble_frame() {
  if (!rgb_ || !depth_ || !info_ || rgb_->stamp_ns() != depth_->stamp_ns() ||
      info_->stamp_ns() != rgb_->stamp_ns())
    return;
  const std::int64_t stamp = rgb_->stamp_ns();
  hardware::RgbdFrame f;
  try {
    f = sensors_dds::to_rgbd_frame(*rgb_, *depth_, *info_);
  } catch (const std::exception& e) {
    log(std::string("drill: camera frame dropped: ") + e.what());
    rgb_.reset();
    return;
  }
  rgb_.reset();
  depth_.reset();
  inputs_.on_frame(stamp, std::move(f));
}

void DrillNode::spin(const std::atomic<bool>& stop) {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / params_.rate));
  auto next = Clock::now();
  const auto t0 = Clock::now();
  while (!stop) {
    tick(std::chrono::duration<double>(Clock::now() - t0).count());
    next += period;
    std::this_thread::sleep_until(next);
    if (Clock::now() > next + 10 * period) next = Clock::now();  // fell behind: do not burst
  }
  engine_.shutdown();
}

void DrillNode::tick(double now) {
  Inbox in;
  {
    std::lock_guard lock(mutex_);
    std::swap(in, inbox_);
  }
  if (in.model) apply_model(*in.model);
  for (const msg::DrillAbort& a : in.aborts) engine_.abort({a.mission_id(), a.source(), a.reason()});
  for (const msg::DrillMission& m : in.missions)
    engine_.start_mission({m.mission_id(), m.stamp_ns(), m.name(), m.yaml(), m.base_dir(), m.resume()});
  camera_wanted_.store(engine_.mission_active(), std::memory_order_relaxed);
  engine_.tick(now);
}

void DrillNode::apply_model(const msg::RobotModel& m) {
  if (m.version() <= engine_.model_version()) return;
  std::shared_ptr<const DrillRig> rig;
  std::string error;
  try {
    rig = std::make_shared<const DrillRig>(model::RobotModel::build(model::dds::to_description(m)));
  } catch (const DrillError& e) {
    error = e.what();  // "model version N cannot drill: ..." (DrillRig)
  } catch (const std::exception& e) {
    error = "model version " + std::to_string(m.version()) + " cannot drill: " + e.what();
  }
  {
    std::lock_guard lock(mutex_);
    camera_ = rig ? rig->camera() : "";
  }
  const std::string message = engine_.apply_model(m.version(), rig, error);
  status_.report(msg::SERVICE_READY, cdds::ModelId{m.version(), m.content_hash()}, message);
}

// --- DrillSink --------------------------------------------------------------------------------

void DrillNode::plan(const PlanAsk& ask) {
  msg::PlanRequest r = to_msg(ask);
  r.source(kSource);
  plan_requests_.write(r);
}

void DrillNode::trajectory(std::uint32_t id, std::uint32_t model_version, const std::vector<std::string>& names,
                           const std::vector<PathSample>& samples) {
  msg::JointTrajectoryCommand c;
  c.request_id(id);
  c.model_version(model_version);
  c.stamp_ns(now_ns());
  c.source(kSource);
  c.joint_names(names);
  for (const PathSample& s : samples) {
    msg::JointTrajectorySample out;
    out.time(s.time);
    out.position(s.position);
    out.velocity(s.velocity);
    c.samples().push_back(out);
  }
  trajectories_.write(c);
}

void DrillNode::navigate(std::uint32_t id, std::uint32_t model_version, const BasePose& goal) {
  msg::NavGoal g;
  g.request_id(id);
  g.model_version(model_version);
  g.stamp_ns(now_ns());
  g.source(kSource);
  g.kind(msg::NAV_GOAL_POSE);
  msg::Pose2D p;
  p.x(goal.x);
  p.y(goal.y);
  p.yaw(goal.theta);
  g.pose(p);
  nav_goals_.write(g);
}

void DrillNode::cancel_navigation() {
  msg::NavCancel c;
  c.request_id(0);
  c.stamp_ns(now_ns());
  c.source(kSource);
  nav_cancels_.write(c);
}

void DrillNode::hold(std::uint32_t model_version, const JointPositions& arm) {
  msg::JointCommand c;
  c.model_version(model_version);
  c.stamp_ns(now_ns());
  c.source(kSource);
  c.mode(msg::JOINT_POSITION);
  c.name(arm.names);
  c.position(arm.positions);
  joint_commands_.write(c);
}

void DrillNode::cartesian(std::uint32_t model_version, const std::string& frame, const CartesianReference& r) {
  msg::CartesianImpedanceCommand c;
  c.model_version(model_version);
  c.stamp_ns(now_ns());
  c.source(kSource);
  c.end_effector(frame);
  c.target(model::dds::to_pose_msg(r.pose));
  msg::Twist t;
  t.linear(model::dds::to_vector_msg(r.twist.head<3>()));
  t.angular(model::dds::to_vector_msg(r.twist.tail<3>()));
  c.target_twist(t);
  for (int i = 0; i < 6; ++i) {
    c.stiffness()[static_cast<std::size_t>(i)] = r.stiffness[i];
    c.damping()[static_cast<std::size_t>(i)] = r.damping[i];
  }
  c.admittance_axis(255);
  cartesian_.write(c);
}

void DrillNode::mission_status(std::uint32_t mission_id, const MissionStatus& status, const MissionReport& report) {
  status_out_.write(to_msg(mission_id, status, report));
}

void DrillNode::refused(const std::string& why) { status_.refused(why); }

void DrillNode::log(const std::string& line) {
  std::lock_guard lock(log_mutex_);
  log_ << line << std::endl;
}

}  // namespace concert::drill::dds
