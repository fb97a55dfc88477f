#include "dds/planner_node.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "concert/common/clock.hpp"
#include "concert/common/enum_map.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/model/dds/pose.hpp"
#include "concert/sensors_dds/conversions.hpp"
#include "concert/world/world_dds.hpp"
#include "planner/request.hpp"

namespace concert::planner::dds {

World to_planner_world(const world::World& w) {
  World out;
  auto add = [&](const world::WorldShape& s) {
    if (s.type == world::WorldShape::Type::kCylinder) {
      out.cylinders.push_back({s.name, s.size.x(), s.size.z(), s.position});
    } else {
      out.boxes.push_back({s.name, s.size, s.position, s.yaw});
    }
  };
  for (const auto& s : w.walls) add(s);
  for (const auto& s : w.obstacles) add(s);
  return out;
}

Eigen::Isometry3d to_core(const msg::Pose& p) { return model::dds::to_isometry(p); }

msg::Pose to_msg(const Eigen::Isometry3d& t) { return model::dds::to_pose_msg(t); }

namespace {

// Every planning status and the failure the PlanResult reports for it, one row each.
constexpr EnumMap kFailures{std::array{
    std::pair{Status::kSucceeded, msg::PLAN_OK},
    std::pair{Status::kNoModel, msg::PLAN_NO_MODEL},
    std::pair{Status::kStaleModel, msg::PLAN_STALE_MODEL},
    std::pair{Status::kInvalidRequest, msg::PLAN_INVALID_REQUEST},
    std::pair{Status::kInvalidStart, msg::PLAN_INVALID_START},
    std::pair{Status::kUnreachable, msg::PLAN_UNREACHABLE},
    std::pair{Status::kNoPath, msg::PLAN_NO_PATH},
}};

}  // namespace

msg::PlanFailure to_failure(Status s) { return kFailures.to(s).value_or(msg::PLAN_NO_PATH); }

PlannerNode::PlannerNode(concert::dds::Participant& participant, Planner& planner,
                         NodeOptions options, std::ostream& log)
    : planner_(planner),
      options_(options),
      log_(log),
      use_world_(planner.params().environment_source != "sensors"),
      use_sensors_(planner.params().environment_source != "world"),
      world_map_(planner.environment()),
      sensor_map_(planner.params().octomap_resolution),
      results_(participant, concert::dds::topics::plan_result),
      trajectory_commands_(participant, concert::dds::topics::trajectory_command),
      status_(participant, "planner"),
      models_(participant, concert::dds::topics::robot_model,
              [this](const auto& s, const auto&) { on_model(s); }),
      joint_states_(participant, concert::dds::topics::joint_state,
                    [this](const msg::JointState& s, const auto&) {
                      if (use_sensors_) note_motion(s);
                      std::lock_guard lock(mutex_);
                      joint_state_ = s;
                    }),
      odometries_(participant, concert::dds::topics::odometry,
                  [this](const msg::Odometry& s, const auto&) {
                    map_frame_.on_odometry(s.stamp_ns(), {s.x(), s.y(), s.yaw()});
                    if (use_sensors_) note_motion(s);
                    std::lock_guard lock(mutex_);
                    odometry_ = s;
                  }),
      localisations_(participant, concert::dds::topics::nav_localisation,
                     [this](const msg::NavLocalisation& l, const auto&) {
                       if (l.state() != msg::LOCALISATION_TRACKING) return;
                       map_frame_.on_localisation(l.stamp_ns(),
                                                  {l.pose().x(), l.pose().y(), l.pose().yaw()});
                     }),
      trajectory_statuses_(participant, concert::dds::topics::trajectory_status,
                           [this](const msg::TrajectoryStatus& st, const auto&) {
                             {
                               std::lock_guard lock(mutex_);
                               trajectory_status_[st.request_id()] = st;
                             }
                             wake_.notify_all();
                           }),
      worlds_(participant, concert::dds::topics::world,
              [this](const msg::World& w, const auto&) { on_world(w); }),
      request_reader_(participant, concert::dds::topics::plan_request,
                      [this](const msg::PlanRequest& s, const auto&) { take(s); }) {
  const std::string& source = planner_.params().environment_source;
  if (use_sensors_) {
    lidars_ = std::make_unique<concert::dds::Reader<msg::LidarScan>>(
        participant, concert::dds::topics::lidar, [this](const msg::LidarScan& scan, const auto&) {
          std::lock_guard lock(map_mutex_);
          pending_scans_[scan.sensor()] = scan;
        });
    camera_info_reader_ = std::make_unique<concert::dds::Reader<msg::CameraInfo>>(
        participant, concert::dds::topics::camera_info, [this](const msg::CameraInfo& info, const auto&) {
          std::lock_guard lock(map_mutex_);
          camera_infos_[info.sensor()] = info;
        });
    depth_reader_ = std::make_unique<concert::dds::Reader<msg::Image>>(
        participant, concert::dds::topics::camera_depth, [this](const msg::Image& image, const auto&) {
          std::lock_guard lock(map_mutex_);
          auto& frames = pending_depth_[image.sensor()];
          frames.push_back(image);
          while (frames.size() > static_cast<std::size_t>(planner_.params().sensor_depth_frames)) frames.pop_front();
        });
    publish_environment();
    std::ostringstream line;
    line << "planner: map from " << source << " (lidar revolutions and depth frames every "
         << planner_.params().sensor_map_period << " s at most, of periods the base and joints stayed slower than "
         << planner_.params().sensor_max_speed << " m/s, rad/s)";
    log_line(line.str());
    sensor_mapper_ = std::thread([this] { sensor_map_loop(); });
  }
  if (planner_.model_version() == 0)
    status_.report(msg::SERVICE_STARTING, 0, "waiting for a robot model");
  executor_ = std::thread([this] { execute_loop(); });
  if (planner_.params().warm_up_time > 0.0) warmer_ = std::thread([this] { warm_up_loop(); });
}

PlannerNode::~PlannerNode() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  executor_.join();
  if (warmer_.joinable()) warmer_.join();
  if (sensor_mapper_.joinable()) sensor_mapper_.join();
  lidars_.reset();
  depth_reader_.reset();
  camera_info_reader_.reset();
}

void PlannerNode::log_line(const std::string& line) {
  // Lines come from the DDS listener, the request loop and the warm-up thread.
  std::lock_guard lock(log_mutex_);
  log_ << line << std::endl;
}

void PlannerNode::warm_up_loop() {
  // Lowest CPU priority for this thread (Linux: per-thread nice): warming up must not take
  // the core from planning, control or the other services.
  (void)setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 19);
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || warm_version_ != 0; });
    if (stopping_) return;
    const uint64_t version = warm_version_;
    warm_version_ = 0;
    lock.unlock();
    const auto model = planner_.model();
    bool drill = false;
    try {
      drill = model && !model->camera_frame(model->tool("")).empty();
    } catch (const PlannerError&) {
      drill = false;  // no tool with a camera (e.g. the sanding tool): nothing to warm up
    }
    if (drill) {
      const auto t0 = std::chrono::steady_clock::now();
      const int solved = planner_.warm_up(0.3, 2.9, 0.1, planner_.params().warm_up_time, [&] {
        std::lock_guard guard(mutex_);
        return !stopping_ && warm_version_ == 0;
      });
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::lock_guard guard(mutex_);
      {
        std::ostringstream line;
        line << "planner: model version " << version << ": posture memory warmed up at " << solved
             << " of 27 heights (0.3-2.9 m) in " << seconds << " s"
             << (stopping_            ? " (stopped: shutting down)"
                 : warm_version_ != 0 ? " (stopped: a newer model)"
                                      : "");
        log_line(line.str());
      }
    } else {
      {
        std::ostringstream line;
        line << "planner: model version " << version
             << ": no tool with a camera, no posture warm-up";
        log_line(line.str());
      }
    }
    lock.lock();
  }
}

void PlannerNode::on_model(const msg::RobotModel& model) {
  // The same model again (a restarted modelgen republishes the running one): nothing to do.
  if (const auto current = planner_.model();
      current && current->version() == model.version() &&
      current->robot().content_hash() == model.content_hash()) {
    log_line("planner: model version " + std::to_string(model.version()) +
             " again with the same content: kept as it is");
    return;
  }
  status_.report(msg::SERVICE_RECONFIGURING, static_cast<uint32_t>(planner_.model_version()),
                 "reconfiguring to model version " + std::to_string(model.version()));
  try {
    planner_.set_model(concert::model::dds::to_description(model));
    const auto m = planner_.model();
    std::string note = "planning " + std::to_string(m->dof()) + " joints (base x, y, yaw + arm)";
    if (!m->ignored_shapes().empty())
      note += "; " + std::to_string(m->ignored_shapes().size()) + " mesh collisions ignored";
    status_.report(msg::SERVICE_READY, concert::dds::ModelId{model.version(), model.content_hash()},
                   note);
    {
      std::ostringstream line;
      line << "planner: model version " << model.version() << ": " << note;
      if (const std::size_t kept = planner_.remembered(); kept > 0)
        line << "; " << kept << " goal postures remembered from an earlier version of this model";
      log_line(line.str());
    }
    {
      std::lock_guard lock(mutex_);
      warm_version_ = model.version();
    }
    wake_.notify_all();
  } catch (const std::exception& e) {
    const uint64_t kept = planner_.model_version();
    const std::string refusal =
        std::string("model version ") + std::to_string(model.version()) + " refused: " + e.what();
    status_.report(kept == 0 ? msg::SERVICE_ERROR : msg::SERVICE_READY, static_cast<uint32_t>(kept),
                   refusal);
    status_.refused(refusal);
    {
      std::ostringstream line;
      line << "planner: model version " << model.version() << " refused (keeping " << kept
           << "): " << e.what();
      log_line(line.str());
    }
  }
}

// A request is acknowledged as it arrives (PLAN_PLANNING), before it waits behind others: a
// client that hears nothing sends it again (a request written before its writer matched a
// restarted planner's reader is lost: PlanRequest is volatile). A request already taken, by
// source and id, is not taken twice. The acknowledgement is written before the request is
// queued: queued first, the request loop could answer it (a start state refused takes
// microseconds) before this thread wrote PLAN_PLANNING, and the result topic keeps only the
// last sample of a request, so the late acknowledgement would replace the final answer (the
// client would never see, e.g., "cannot be executed" and would wait in vain).
void PlannerNode::take(const msg::PlanRequest& request) {
  {
    std::lock_guard lock(mutex_);
    std::pair<std::string, std::uint32_t> key{request.source(), request.request_id()};
    if (!taken_.insert(key).second) return;
    taken_order_.push_back(std::move(key));
    if (taken_order_.size() > kTakenKept) {
      taken_.erase(taken_order_.front());
      taken_order_.pop_front();
    }
  }
  publish(planning(request));
  {
    std::lock_guard lock(mutex_);
    requests_.push_back(request);
  }
  wake_.notify_all();
}

// The result every answer to `request` starts from: PLAN_PLANNING at the current model.
msg::PlanResult PlannerNode::planning(const msg::PlanRequest& request) const {
  msg::PlanResult r;
  r.request_id(request.request_id());
  r.model_version(static_cast<uint32_t>(planner_.model_version()));
  // Home or a posture: one path.
  const bool one_path = request.arm_home() || !request.posture_names().empty();
  r.goal_count(static_cast<uint32_t>(one_path ? 1 : request.goals().size()));
  r.state(msg::PLAN_PLANNING);
  return r;
}

void PlannerNode::publish(msg::PlanResult result) {
  result.stamp_ns(now_ns());
  results_.write(result);
}

void PlannerNode::spin(const std::atomic<bool>& stop, std::chrono::milliseconds poll) {
  while (!stop) spin_once(poll);
}

bool PlannerNode::spin_once(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!wake_.wait_for(lock, timeout, [&] { return !requests_.empty() || stopping_; }) ||
      requests_.empty())
    return false;
  const msg::PlanRequest request = requests_.front();
  requests_.pop_front();
  lock.unlock();
  handle(request);
  return true;
}

namespace {

ClientRequest to_client_request(const msg::PlanRequest& request) {
  ClientRequest c;
  PlanRequest& core = c.plan;
  core.request_id = request.request_id();
  core.model_version = request.model_version();
  core.end_effector = request.end_effector();
  core.camera_distance = request.camera_distance();
  core.view_slant = request.view_slant();
  core.view_near = request.view_near();
  core.tip_distance = request.tip_distance();
  core.tip_reach = request.tip_reach();
  core.contact_force = request.contact_force();
  core.fixed_base = request.fixed_base();
  core.environment_padding = request.environment_padding();
  core.base_travel = request.base_travel();
  core.home = request.arm_home();
  // Names and positions pair up; a count that differs is refused by the planner (an unpaired
  // name is read as NaN, beyond every limit).
  const auto& names = request.posture_names();
  const auto& positions = request.posture_position();
  for (std::size_t i = 0; i < std::max(names.size(), positions.size()); ++i) {
    core.posture.emplace_back(i < names.size() ? names[i] : std::string("(unnamed)"),
                              i < positions.size() ? positions[i] : std::numeric_limits<double>::quiet_NaN());
  }
  for (const msg::Pose& g : request.goals()) core.goals.push_back({to_core(g)});
  c.start_names = request.start_names();
  c.start_position = request.start_position();
  c.execute = request.execute();
  c.odom_in_map = request.odom_in_map();
  return c;
}

MeasuredRobot to_measured(const std::optional<msg::JointState>& js, const std::optional<msg::Odometry>& odom) {
  MeasuredRobot robot;
  if (js) robot.joints = MeasuredRobot::Joints{js->model_version(), js->name(), js->position()};
  if (odom) robot.odometry = Eigen::Vector3d(odom->x(), odom->y(), odom->yaw());
  return robot;
}

// A goal's result as published: failed with its reason, or planned with its trajectory.
msg::PlanResult goal_result(msg::PlanResult r, const GoalResult& g, const Trajectory& trajectory) {
  r.goal_index(static_cast<uint32_t>(g.index));
  r.planning_time(g.nspg_seconds + g.plan_seconds);
  if (g.status != Status::kSucceeded) {
    r.state(msg::PLAN_FAILED);
    r.failure(to_failure(g.status));
    r.reason(g.reason);
    return r;
  }
  r.state(msg::PLAN_PLANNED);
  r.joint_names(trajectory.joint_names);
  for (const TrajectoryPoint& p : trajectory.points) {
    msg::TrajectorySample s;
    s.time(p.time);
    s.position(std::vector<double>(p.q.data(), p.q.data() + p.q.size()));
    s.velocity(std::vector<double>(p.qd.data(), p.qd.data() + p.qd.size()));
    r.trajectory().push_back(std::move(s));
  }
  return r;
}

}  // namespace

std::string PlannerNode::wait_for_inputs(const msg::PlanRequest& request) {
  // After a hot swap a client may name the new model version before its sample reached us:
  // wait (bounded) for it instead of answering "no model" or "stale".
  std::unique_lock lock(mutex_);
  if (request.model_version() > planner_.model_version()) {
    wake_.wait_for(lock, options_.model_wait, [&] {
      return stopping_ || planner_.model_version() >= request.model_version();
    });
  }
  // The map from the sensors alone: nothing is planned before they were first integrated.
  if (!use_sensors_ || use_world_) return {};
  if (wake_.wait_for(lock, options_.map_wait, [&] { return stopping_ || sensor_maps_ > 0; })) return {};
  std::ostringstream why;
  why << "no map from the sensors yet (environment_source: sensors): no lidar revolution or "
         "depth frame integrated within "
      << std::chrono::duration<double>(options_.map_wait).count()
      << " s (are the sensors publishing? the map takes only data of periods the robot stood still)";
  return why.str();
}

void PlannerNode::handle(const msg::PlanRequest& request) {
  const std::string map_error = wait_for_inputs(request);
  msg::PlanResult base = planning(request);
  publish(base);
  const auto model = planner_.model();
  const FrameKnowledge frame{map_frame_.map_T_odom(), map_frame_.localised(), use_sensors_};
  PreparedRequest prepared;
  if (map_error.empty()) {
    std::lock_guard lock(mutex_);
    prepared = prepare_request(to_client_request(request), model.get(), to_measured(joint_state_, odometry_), frame);
  }
  if (!map_error.empty() || prepared.refused()) {
    const std::string& why = map_error.empty() ? prepared.reason : map_error;
    base.state(msg::PLAN_FAILED);
    base.failure(map_error.empty() ? to_failure(prepared.refusal) : msg::PLAN_INVALID_REQUEST);
    base.reason(why);
    publish(base);
    log_line("planner: request " + std::to_string(request.request_id()) + " failed: " + why);
    return;
  }

  const bool execute = request.execute();
  const std::size_t count = prepared.plan.home || !prepared.plan.posture.empty() ? 1 : prepared.plan.goals.size();
  msg::PlanResult last_planned;
  const PlanResult result = planner_.plan(prepared.plan, prepared.start, [&](const GoalResult& g) {
    const Trajectory trajectory = to_odometry_frame(g.trajectory, prepared.map_T_odom, prepared.yaw_offset);
    const msg::PlanResult r = goal_result(base, g, trajectory);
    publish(r);
    if (g.status != Status::kSucceeded) return;
    last_planned = r;
    if (execute) {
      {
        std::lock_guard lock(mutex_);
        executions_.push_back({r, model, trajectory, g.index + 1 == count});
      }
      wake_.notify_all();
    }
  });
  log_line(describe(result, prepared, frame));
  if (result.goals.empty()) {  // refused before any goal (stale model, bad request...)
    base.state(msg::PLAN_FAILED);
    base.failure(to_failure(result.status));
    base.reason(result.reason);
    publish(base);
  } else if (!execute && result.status == Status::kSucceeded) {
    // The result topic keeps the last sample per request: the final one carries the last
    // goal's trajectory again, so a reader that missed PLANNED still gets it.
    last_planned.state(msg::PLAN_SUCCEEDED);
    publish(last_planned);
  }
}

void PlannerNode::execute_loop() {
  while (true) {
    std::unique_lock lock(mutex_);
    wake_.wait(lock, [&] { return stopping_ || !executions_.empty(); });
    if (stopping_) return;
    Execution e = std::move(executions_.front());
    executions_.pop_front();
    lock.unlock();
    const std::string error = execute(e);
    const bool ok = error.empty();
    msg::PlanResult r = e.result;
    r.trajectory().clear();
    r.progress(ok ? 1.0 : r.progress());
    r.state(ok ? (e.last ? msg::PLAN_SUCCEEDED : msg::PLAN_PLANNED) : msg::PLAN_FAILED);
    if (!ok) {
      r.failure(msg::PLAN_EXECUTION_ABORTED);
      r.reason("execution of goal " + std::to_string(r.goal_index()) + " aborted: " + error);
      // The failed request's later goals go with it; other requests queued behind it still
      // run, each to its own answer (dropped, they were never answered).
      std::lock_guard relock(mutex_);
      std::erase_if(executions_, [&](const Execution& later) {
        return later.result.request_id() == r.request_id();
      });
    }
    publish(r);
  }
}

std::string PlannerNode::execute(Execution& e) {
  // The robot's loop tracks the trajectory closed-loop (joints through the drives, the base
  // from odometry); the planner relays its progress and result.
  const PlanningModel& m = *e.model;
  const Trajectory& t = e.trajectory;
  msg::JointTrajectoryCommand cmd;
  const uint32_t id = next_trajectory_id_++;
  cmd.request_id(id);
  cmd.model_version(static_cast<uint32_t>(m.version()));
  cmd.stamp_ns(now_ns());
  cmd.source("planner");
  cmd.joint_names(t.joint_names);
  for (const TrajectoryPoint& p : t.points) {
    msg::JointTrajectorySample s;
    s.time(p.time);
    s.position(std::vector<double>(p.q.data(), p.q.data() + p.q.size()));
    s.velocity(std::vector<double>(p.qd.data(), p.qd.data() + p.qd.size()));
    cmd.samples().push_back(std::move(s));
  }
  e.result.state(msg::PLAN_EXECUTING);
  e.result.trajectory().clear();
  trajectory_commands_.write(cmd);
  // Bounded wait: the trajectory's duration plus the robot's settling time and a margin, and
  // while the robot reports progress, a margin after its latest report: a robot whose loop runs
  // slower than the wall clock (a loaded simulator host) is late, not gone.
  auto deadline = std::chrono::steady_clock::now() +
                  std::chrono::milliseconds(static_cast<int64_t>(1e3 * t.duration())) +
                  options_.result_margin;
  double reported = -1.0;
  double furthest = 0.0;
  std::unique_lock lock(mutex_);
  while (true) {
    if (stopping_) return "the planner is stopping";
    const auto it = trajectory_status_.find(id);
    if (it != trajectory_status_.end()) {
      const msg::TrajectoryStatus st = it->second;
      switch (st.state()) {
        case msg::TRAJECTORY_SUCCEEDED:
          trajectory_status_.erase(it);
          return "";
        case msg::TRAJECTORY_ABORTED:
        case msg::TRAJECTORY_REFUSED:
          trajectory_status_.erase(it);
          return std::string(st.state() == msg::TRAJECTORY_REFUSED ? "refused" : "aborted") +
                 " by the robot: " + st.reason();
        case msg::TRAJECTORY_EXECUTING:
          if (st.progress() > furthest) {  // moving on, not repeating where it stands
            furthest = st.progress();
            deadline = std::max(deadline, std::chrono::steady_clock::now() + options_.result_margin);
          }
          if (st.progress() >= reported + 0.05 || reported < 0.0) {
            reported = st.progress();
            e.result.progress(st.progress());
            lock.unlock();
            publish(e.result);
            lock.lock();
            // The result may have arrived while the lock was released (its notification is
            // gone): look again before waiting.
            continue;
          }
          break;
      }
    }
    if (wake_.wait_until(lock, deadline) == std::cv_status::timeout &&
        std::chrono::steady_clock::now() >= deadline) {
      return "no result from the robot service within " +
             std::to_string(static_cast<int>(
                 t.duration() + 1e-3 * static_cast<double>(options_.result_margin.count()))) +
             " s, nor progress for the last " +
             std::to_string(static_cast<int>(1e-3 * static_cast<double>(options_.result_margin.count()))) +
             " s (is it running?)";
    }
  }
}

void PlannerNode::on_world(const msg::World& w) {
  if (!use_world_) {
    log_line("planner: world version " + std::to_string(w.version()) +
             " not used: the map comes from the sensors (environment_source: sensors)");
    return;
  }
  try {
    const World world = to_planner_world(world::from_msg(w));
    Environment env(planner_.params().octomap_resolution);
    env.add_world(world);
    {
      std::lock_guard lock(map_mutex_);
      world_map_ = env;
    }
    publish_environment();
    std::ostringstream line;
    line << "planner: world version " << w.version() << " from " << w.source() << ": "
         << world.boxes.size() << " boxes, " << world.cylinders.size() << " cylinders, map "
         << env.occupied_cells() << " occupied cells";
    log_line(line.str());
  } catch (const std::exception& e) {
    log_line(std::string("planner: world version ") + std::to_string(w.version()) +
             " refused: " + e.what());
  }
}

void PlannerNode::publish_environment() {
  std::lock_guard lock(map_mutex_);
  if (!use_sensors_) {
    planner_.set_environment(world_map_);
  } else if (!use_world_) {
    planner_.set_environment(sensor_map_);
  } else {
    Environment both = world_map_;
    both.add_occupied(sensor_map_);
    planner_.set_environment(both);
  }
}

void PlannerNode::sensor_map_loop() {
  const auto period = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::duration<double>(planner_.params().sensor_map_period));
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, std::max(period, std::chrono::milliseconds(10)), [&] { return stopping_; });
    if (stopping_) return;
    lock.unlock();
    try {
      update_sensor_map();
    } catch (const std::exception& e) {
      log_line(std::string("planner: sensor map update failed: ") + e.what());
    }
    lock.lock();
  }
}

void PlannerNode::note_motion(const msg::Odometry& odometry) {
  const double limit = planner_.params().sensor_max_speed;
  if (std::hypot(odometry.vx(), odometry.vy()) <= limit && std::abs(odometry.wz()) <= limit) return;
  std::lock_guard lock(map_mutex_);
  moved_ = true;
}

void PlannerNode::note_motion(const msg::JointState& joints) {
  const double limit = planner_.params().sensor_max_speed;
  for (const double v : joints.velocity()) {
    if (std::abs(v) > limit) {
      std::lock_guard lock(map_mutex_);
      moved_ = true;
      return;
    }
  }
}

namespace {

// The pending sensor data of model `version` converted for the mapper: what is of another
// version is counted in `stale`, what cannot be converted is refused ("name: why").
SensorBatch to_batch(const std::map<std::string, msg::LidarScan>& scans,
                     const std::map<std::string, std::deque<msg::Image>>& depth,
                     const std::map<std::string, msg::CameraInfo>& infos, std::uint64_t version,
                     std::size_t& stale, std::vector<std::string>& refused) {
  SensorBatch batch;
  for (const auto& [name, m] : scans) {
    if (m.model_version() != version) {
      stale += 1;
      continue;
    }
    try {
      batch.scans.emplace_back(name, sensors_dds::from_msg(m));
    } catch (const std::exception& e) {
      refused.push_back(name + ": " + e.what());
    }
  }
  for (const auto& [name, images] : depth) {
    try {
      const auto info = infos.find(name);
      if (info == infos.end()) throw PlannerError("no camera info");
      std::vector<hardware::RgbdFrame> frames;
      for (const msg::Image& image : images) {
        if (image.model_version() != version) {
          stale += 1;
          continue;
        }
        frames.push_back(sensors_dds::to_depth_frame(image, info->second));
      }
      if (!frames.empty()) batch.depth.emplace_back(name, std::move(frames));
    } catch (const std::exception& e) {
      refused.push_back(name + ": " + e.what());
    }
  }
  return batch;
}

}  // namespace

std::optional<Eigen::VectorXd> PlannerNode::robot_in_map(const PlanningModel& model) const {
  std::lock_guard lock(mutex_);
  if (!joint_state_ || joint_state_->model_version() != model.version() || !odometry_) return std::nullopt;
  const Eigen::Vector3d base = mobile_base::compose(
      map_frame_.map_T_odom(), Eigen::Vector3d(odometry_->x(), odometry_->y(), odometry_->yaw()));
  return model.full_from_named(joint_state_->name(), joint_state_->position(), base);
}

void PlannerNode::update_sensor_map() {
  const auto model = planner_.model();
  std::map<std::string, msg::LidarScan> scans;
  std::map<std::string, std::deque<msg::Image>> depth;
  std::map<std::string, msg::CameraInfo> infos;
  bool moved = false;
  {
    std::lock_guard lock(map_mutex_);
    scans.swap(pending_scans_);
    depth.swap(pending_depth_);
    infos = camera_infos_;
    moved = std::exchange(moved_, false);
  }
  if (!model) return;  // no model: no sensor frames, no self filter
  if (!mapper_ || mapper_->model().version() != model->version()) {
    // A new model: its sensor frames and its shapes for the self filter.
    mapper_ = std::make_shared<const SensorMapper>(model, planner_.params());
    log_line("planner: sensor map: self filter on model version " + std::to_string(model->version()));
  }
  std::size_t inputs = scans.size();
  for (const auto& [name, frames] : depth) inputs += frames.size();
  if (inputs == 0) return;
  const std::optional<Eigen::VectorXd> q = robot_in_map(*model);
  if (!q || moved) {
    // No robot state of this model to place them with, or something moved during the period
    // (its revolutions and frames may be smeared).
    std::lock_guard lock(map_mutex_);
    (q ? skipped_moving_ : skipped_version_) += inputs;
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  SensorMapUpdate update;
  update.model_version = model->version();
  std::size_t stale = 0;
  std::vector<std::string> refused;
  update.rays = mapper_->batch_rays(to_batch(scans, depth, infos, model->version(), stale, refused), *q);
  update.rays.refused.insert(update.rays.refused.begin(), refused.begin(), refused.end());
  Environment map = [&] {
    std::lock_guard lock(map_mutex_);
    return sensor_map_;
  }();
  if (!update.rays.bundles.empty()) map.insert_rays(update.rays.bundles);
  {
    std::lock_guard lock(map_mutex_);
    sensor_map_ = map;
    if (update.rays.used.empty() && update.rays.refused.empty()) {
      skipped_version_ += stale;  // nothing to report yet: counted into the next line
      return;
    }
    update.skipped_moving = std::exchange(skipped_moving_, 0);
    update.skipped_version = std::exchange(skipped_version_, 0) + stale;
  }
  update.milliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  update.occupied_cells = map.occupied_cells();
  log_line(describe(update));
  // After the line, so whoever sees the new map finds the line that reports it.
  if (update.rays.used.empty()) return;
  publish_environment();
  {
    std::lock_guard lock(mutex_);
    ++sensor_maps_;
  }
  wake_.notify_all();
}

}  // namespace concert::planner::dds
