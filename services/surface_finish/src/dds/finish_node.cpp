#include "dds/finish_node.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/model/dds/pose.hpp"

namespace concert::surface_finish::dds {

namespace cdds = concert::dds;
namespace topics = concert::dds::topics;

namespace {

constexpr const char* kSource = "surface_finish";
constexpr std::size_t kMaxMeasured = 5000;

}  // namespace

FinishNode::FinishNode(cdds::Participant& participant, NodeParams params, std::ostream& log)
    : params_(std::move(params)),
      log_(log),
      status_(participant, "surface_finish"),
      areas_writer_(participant, topics::finish_areas),
      status_writer_(participant, topics::finish_status),
      trajectories_(participant, topics::trajectory_command),
      cartesian_(participant, topics::cartesian_command),
      model_reader_(participant, topics::robot_model,
                    [this](const msg::RobotModel& m, const auto&) {
                      std::lock_guard lock(mutex_);
                      if (!new_model_ || m.version() > new_model_->version()) new_model_ = m;
                    }),
      joint_reader_(participant, topics::joint_state,
                    [this](const msg::JointState& s, const auto&) {
                      Measured m{s.stamp_ns(), s.name(), s.position()};
                      std::lock_guard lock(mutex_);
                      if (run_active_.load()) {
                        measured_.push_back(m);
                        if (measured_.size() > kMaxMeasured) measured_.pop_front();
                      }
                      latest_ = std::move(m);
                    }),
      scan_reader_(participant, topics::scan,
                   [this](const msg::LaserScan& s, const auto&) {
                     std::lock_guard lock(mutex_);
                     scan_ = s;
                     scan_seen_ = std::chrono::steady_clock::now();
                   }),
      command_reader_(participant, topics::finish_command,
                      [this](const msg::FinishCommand& c, const auto&) {
                        std::lock_guard lock(mutex_);
                        commands_.push_back(c);
                      }),
      trajectory_reader_(participant, topics::trajectory_status,
                         [this](const msg::TrajectoryStatus& s, const auto&) {
                           if (s.source() != kSource) return;
                           std::lock_guard lock(mutex_);
                           trajectory_statuses_[s.request_id()] = s;
                         }),
      wrench_reader_(
          participant, topics::ee_wrench,
          [this](const msg::EndEffectorWrench& w, const auto&) {
            if (!run_active_.load()) return;
            const auto& f = w.wrench().force();
            std::lock_guard lock(mutex_);
            wrenches_.push_back(Wrench{w.stamp_ns(), Eigen::Vector3d(f.x(), f.y(), f.z())});
            if (wrenches_.size() > kMaxMeasured) wrenches_.pop_front();
          }),
      safety_reader_(participant, topics::safety_state,
                     [this](const msg::SafetyState& st, const auto&) {
                       std::lock_guard lock(mutex_);
                       safety_ = st;
                     }) {
  status_.report(msg::SERVICE_STARTING, 0u, "waiting for the robot model");
}

FinishNode::~FinishNode() = default;

void FinishNode::log_line(const std::string& line) { log_ << line << std::endl; }

void FinishNode::spin(const std::atomic<bool>& stop) {
  const auto period = std::chrono::duration<double>(1.0 / params_.rate);
  while (!stop.load()) {
    const auto next = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    tick();
    std::this_thread::sleep_until(next);
  }
  if (run_) abort_run("the service stops");
}

void FinishNode::tick() {
  std::optional<msg::RobotModel> model;
  std::deque<msg::FinishCommand> commands;
  {
    std::lock_guard lock(mutex_);
    if (new_model_ && new_model_->version() > version_seen_) model = new_model_;
    new_model_.reset();
    commands.swap(commands_);
  }
  if (model) on_model(*model);
  if (preparing_.valid() && preparing_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) finish_preparation();
  for (const msg::FinishCommand& c : commands) handle(c);
  if (run_) follow_run();
}

void FinishNode::on_model(const msg::RobotModel& m) {
  version_seen_ = m.version();
  if (run_ && run_->sand && run_->reach) {
    NewModel n;
    n.version = m.version();
    n.before = &run_->reach->model();
    n.tcp_frame = run_->reach->tcp_frame();
    std::shared_ptr<const model::RobotModel> after;
    try {
      after = model::RobotModel::build(model::dds::to_description(m));
      n.after = after.get();
    } catch (const std::exception& e) {
      n.error = e.what();
    }
    {
      std::lock_guard lock(mutex_);
      if (latest_) {
        n.names = latest_->names;
        n.positions = latest_->positions;
      }
    }
    if (leave_for_new_model(*run_->sand, n)) {
      command_version_ = m.version();
      log_line("surface_finish: request " + std::to_string(run_->request_id) + ": " + run_->sand->reason() +
               ": the tool leaves the wall first");
    } else {
      end_run(msg::FINISH_ABORTED, run_->sand->reason());
    }
  } else if (run_) {
    abort_run("the robot model changed to version " + std::to_string(m.version()), false);
  }
  status_.report(msg::SERVICE_RECONFIGURING, cdds::ModelId{m.version(), m.content_hash()},
                 "computing the areas of model version " + std::to_string(m.version()));
  preparing_version_ = m.version();
  const NodeParams params = params_;
  // The areas take seconds (inverse kinematics over the wall grid at several distances): a
  // worker thread; a newer model replaces the result when it comes.
  preparing_ = std::async(std::launch::async, [m, params]() {
    Prepared p;
    try {
      p.model = model::RobotModel::build(model::dds::to_description(m));
      const bool sprays = !p.model->end_effectors(model::EndEffectorKind::kSpraying).empty();
      const bool sands = !p.model->end_effectors(model::EndEffectorKind::kSanding).empty();
      if (!sprays && !sands) {
        (void)p.model->tool(model::EndEffectorKind::kSpraying);  // throws, listing what the arm carries
      }
      p.task = sprays ? Task::kSpray : Task::kSand;
      ReachParams rp;
      rp.contact_force = sprays ? 0.0 : params.sand_force;
      p.reach = std::make_shared<Reach>(p.model, sprays ? model::EndEffectorKind::kSpraying : model::EndEffectorKind::kSanding, rp);
      const ToolSpec& tool = sprays ? params.spray : params.sand;
      p.areas = working_areas(*p.reach, p.task, tool.standoff, params.areas);
    } catch (const std::exception& e) {
      p.error = e.what();
    }
    return p;
  });
}

void FinishNode::finish_preparation() {
  Prepared p = preparing_.get();
  if (preparing_version_ < version_seen_) return;  // a newer model is being prepared
  current_ = std::move(p);
  current_version_ = preparing_version_;
  command_version_ = current_version_;
  msg::FinishAreas a;
  a.model_version(static_cast<std::uint32_t>(current_version_));
  a.stamp_ns(now_ns());
  const std::string hash = current_.model ? current_.model->content_hash() : std::string();
  if (current_.areas) {
    const AreaMap& m = *current_.areas;
    a.tool(to_string(current_.task));
    a.wall_distance(m.wall_distance);
    a.standoff(m.standoff);
    a.roll(m.roll);
    for (const Area& area : m.areas) {
      msg::FinishArea fa;
      fa.id(area.id);
      fa.x0(area.rect.x0);
      fa.x1(area.rect.x1);
      fa.y0(area.rect.y0);
      fa.y1(area.rect.y1);
      a.areas().push_back(fa);
    }
    status_.report(msg::SERVICE_READY, cdds::ModelId{static_cast<std::uint32_t>(current_version_), hash},
                   std::string(to_string(current_.task)) + " with " + current_.reach->tool_name() + ": band " +
                       m.band.str() + " at " + std::to_string(m.wall_distance).substr(0, 4) + " m from the wall");
    log_line("surface_finish: model version " + std::to_string(current_version_) + ": " + to_string(current_.task) +
             ", band " + m.band.str() + ", working distance " + std::to_string(m.wall_distance).substr(0, 4) + " m");
  } else {
    a.reason("cannot finish: " + current_.error);
    status_.report(msg::SERVICE_READY, cdds::ModelId{static_cast<std::uint32_t>(current_version_), hash},
                   "cannot finish: " + current_.error);
    log_line("surface_finish: model version " + std::to_string(current_version_) + ": cannot finish: " + current_.error);
  }
  areas_writer_.write(a);
}

void FinishNode::publish(std::uint32_t request_id, msg::FinishState state, const std::string& reason, const Run* run,
                         const std::string& report) {
  msg::FinishStatus s;
  s.request_id(request_id);
  s.stamp_ns(now_ns());
  s.model_version(static_cast<std::uint32_t>(current_version_));
  s.state(state);
  s.reason(reason);
  if (run != nullptr) {
    s.progress(run->progress);
    s.strokes(static_cast<std::uint32_t>(run->plan.strokes.size()));
    s.duration(run->plan.duration());
    s.wall_distance(run->wall_distance);
  }
  s.report_json(report);
  status_writer_.write(s);
}

void FinishNode::refuse(const msg::FinishCommand& c, const std::string& why) {
  status_.refused("request " + std::to_string(c.request_id()) + ": " + why);
  log_line("surface_finish: request " + std::to_string(c.request_id()) + " refused: " + why);
  publish(c.request_id(), msg::FINISH_FAILED, why, nullptr);
}

void FinishNode::handle(const msg::FinishCommand& c) {
  // A sender writes its command again until a status names it (the topic is volatile): each
  // (request id, stamp) is taken once.
  if (!taken_.first_time(c.request_id(), c.stamp_ns())) return;
  if (c.verb() == msg::FINISH_ABORT) {
    if (run_) abort_run("aborted by " + (c.source().empty() ? std::string("a client") : c.source()), true);
    return;
  }
  if (c.model_version() != current_version_ || current_version_ == 0) {
    refuse(c, "command for model version " + std::to_string(c.model_version()) + " refused: " +
                  (current_version_ == 0 ? std::string("no model ready yet")
                                         : "current model version is " + std::to_string(current_version_)));
    return;
  }
  if (!current_.areas) return refuse(c, "cannot finish: " + current_.error);
  if (run_) return refuse(c, "a run is in progress (request " + std::to_string(run_->request_id) + ")");
  if (c.verb() == msg::FINISH_SAND) {
    if (current_.task != Task::kSand) return refuse(c, "the arm carries no sanding tool (it sprays)");
    try {
      start_sand(c);
    } catch (const std::exception& e) {
      run_.reset();
      run_active_.store(false);
      refuse(c, e.what());
    }
    return;
  }
  if (current_.task != Task::kSpray) return refuse(c, "the arm carries no spraying tool (it sands)");
  try {
    start_spray(c);
  } catch (const std::exception& e) {
    run_.reset();
    run_active_.store(false);
    refuse(c, e.what());
  }
}

Eigen::VectorXd FinishNode::q_of(const Measured& m) const { return q_in(*current_.model, m); }

Eigen::VectorXd FinishNode::q_in(const model::RobotModel& model, const Measured& m) {
  const kinematics::Model& k = model.kinematics();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(k.dof());
  for (std::size_t i = 0; i < m.names.size() && i < m.positions.size(); ++i) {
    if (auto j = k.joint_index(m.names[i])) q[*j] = m.positions[i];
  }
  return q;
}

WallFit FinishNode::measure_wall() {
  std::optional<msg::LaserScan> scan;
  std::optional<Measured> latest;
  std::chrono::steady_clock::time_point seen;
  {
    std::lock_guard lock(mutex_);
    scan = scan_;
    latest = latest_;
    seen = scan_seen_;
  }
  if (!scan) throw FinishError("no laser scan received (concert/sensors/scan): the wall is unknown");
  if (std::chrono::duration<double>(std::chrono::steady_clock::now() - seen).count() > params_.scan_max_age) {
    throw FinishError("the laser scan is older than " + std::to_string(params_.scan_max_age).substr(0, 3) + " s");
  }
  if (!latest) throw FinishError("no joint state received: the robot's posture is unknown");
  const kinematics::Model& k = current_.model->kinematics();
  if (!k.has_frame(scan->frame())) throw FinishError("the laser scan's frame '" + scan->frame() + "' is not in model version " + std::to_string(current_version_));
  kinematics::Data data = k.make_data();
  const Eigen::Isometry3d base_T_scan = k.frame_pose(data, q_of(*latest), scan->frame());
  std::vector<Eigen::Vector2d> pts;
  for (std::size_t i = 0; i < scan->ranges().size(); ++i) {
    const double r = scan->ranges()[i];
    if (!std::isfinite(r) || r < scan->range_min() || r > scan->range_max()) continue;
    const double a = scan->angle_min() + static_cast<double>(i) * scan->angle_increment();
    const Eigen::Vector3d p = base_T_scan * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0.0);
    pts.emplace_back(p.x(), p.y());
  }
  return fit_wall(pts, current_.reach->standing_height());
}

WallFit FinishNode::measure_wall_for(const AreaMap& areas) {
  const WallFit fit = measure_wall();
  const double d = fit.wall.distance();
  if (std::abs(d - areas.wall_distance) > params_.distance_tolerance) {
    char b[200];
    std::snprintf(b, sizeof b,
                  "the wall is %.2f m from the base (scan), the areas need the base %.2f m +- %.2f "
                  "m from it: move the base first",
                  d, areas.wall_distance, params_.distance_tolerance);
    throw FinishError(b);
  }
  return fit;
}

Eigen::VectorXd FinishNode::q_now_measured() {
  std::optional<Measured> latest;
  {
    std::lock_guard lock(mutex_);
    latest = latest_;
  }
  return q_of(*latest);
}

FinishNode::Run FinishNode::plan_run(const msg::FinishCommand& c, const ToolSpec& tool,
                                     PathParams path, std::string& target, int& inliers) {
  const AreaMap& areas = *current_.areas;
  const Area& area = areas.area(c.area());
  const Rect rect = c.has_rect() ? reshape(area, Rect{c.x0(), c.x1(), c.y0(), c.y1()}) : area.rect;
  const WallFit fit = measure_wall_for(areas);
  const Eigen::VectorXd q_now = q_now_measured();
  if (c.speed() > 0.0) path.speed = c.speed();
  const auto strokes = serpentine_strokes(rect, tool, path.visible);
  Run run;
  run.request_id = c.request_id();
  run.wall = fit.wall;
  run.wall_distance = fit.wall.distance();
  run.reach = current_.reach;
  run.plan = plan_serpentine(*current_.reach, fit.wall, rect, tool, areas.roll, path, q_now,
                             &areas.posture_near(strokes.front().x, strokes.front().y_start));
  target = rect.str() + " of area '" + area.id + "'";
  inliers = fit.inliers;
  return run;
}

void FinishNode::start_spray(const msg::FinishCommand& c) {
  std::string target;
  int inliers = 0;
  Run run = plan_run(c, params_.spray, params_.path, target, inliers);
  run.deposition = std::make_unique<SprayDeposition>(run.wall, run.plan.rect, params_.spray,
                                                     c.speed() > 0.0 ? c.speed() : params_.path.speed,
                                                     static_cast<int>(run.plan.strokes.size()));
  {
    std::lock_guard lock(mutex_);
    measured_.clear();
  }
  run_active_.store(true);
  send_trajectory(run, run.plan.samples.size() - 1);
  char b[200];
  std::snprintf(
      b, sizeof b,
      "request %u: spraying %s: %zu strokes, %.1f s, wall %.3f m (scan, %d points)",
      c.request_id(), target.c_str(), run.plan.strokes.size(), run.plan.duration(),
      run.wall_distance, inliers);
  log_line(std::string("surface_finish: ") + b);
  run_ = std::move(run);
  publish(run_->request_id, msg::FINISH_RUNNING, "", &*run_);
}

void FinishNode::send_trajectory(Run& run, std::size_t last_sample) {
  // One joint trajectory of the arm's joints: the plan's samples [0, last_sample], at rest at
  // its end.
  const kinematics::Model& k = current_.model->kinematics();
  msg::JointTrajectoryCommand t;
  run.trajectory_id = next_trajectory_++;
  t.request_id(run.trajectory_id);
  t.model_version(static_cast<std::uint32_t>(current_version_));
  t.stamp_ns(now_ns());
  t.source(kSource);
  const std::vector<int>& arm = current_.reach->arm_joints();
  for (int j : arm) t.joint_names().push_back(k.joint_names()[static_cast<std::size_t>(j)]);
  for (std::size_t i = 0; i <= last_sample && i < run.plan.samples.size(); ++i) {
    const PathSample& s = run.plan.samples[i];
    msg::JointTrajectorySample out;
    out.time(s.t);
    for (int j : arm) {
      out.position().push_back(s.q[j]);
      out.velocity().push_back(i == last_sample ? 0.0 : s.qd[j]);
    }
    t.samples().push_back(out);
  }
  run.sent = std::chrono::steady_clock::now();
  trajectories_.write(t);
}

void FinishNode::start_sand(const msg::FinishCommand& c) {
  const double force = c.force();
  if (!(force > 0.0) || !std::isfinite(force)) {
    char b[120];
    std::snprintf(b, sizeof b, "the force setpoint must be positive (got %g N)", force);
    throw FinishError(b);
  }
  if (force > params_.sand_force + 1e-9) {
    char b[200];
    std::snprintf(b, sizeof b,
                  "force %.1f N refused: the areas keep the joint torques within their continuous "
                  "torques for up to "
                  "%.1f N",
                  force, params_.sand_force);
    throw FinishError(b);
  }
  {
    std::lock_guard lock(mutex_);
    if (safety_ && safety_->mode() != msg::SAFETY_RUNNING) {
      std::string causes;
      for (const auto& cause : safety_->causes()) causes += (causes.empty() ? "" : ", ") + cause;
      throw FinishError("the robot is safety-stopped (" + causes + ")");
    }
  }
  std::string target;
  int inliers = 0;
  Run run = plan_run(c, params_.sand, params_.sand_path, target, inliers);
  SandParams sp = params_.sanding;
  sp.force = force;
  run.sand = std::make_unique<SandSequence>(run.plan, sp);
  {
    std::lock_guard lock(mutex_);
    measured_.clear();
    wrenches_.clear();
  }
  run_active_.store(true);
  send_trajectory(run, run.sand->approach_index());
  run.last_status = std::chrono::steady_clock::now();
  char b[220];
  std::snprintf(b, sizeof b,
                "request %u: sanding %s at %.1f N: %zu strokes, %.1f s, wall %.3f m "
                "(scan, %d points)",
                c.request_id(), target.c_str(), force, run.plan.strokes.size(),
                run.plan.duration(), run.wall_distance, inliers);
  log_line(std::string("surface_finish: ") + b);
  run_ = std::move(run);
  publish(run_->request_id, msg::FINISH_RUNNING, "", &*run_);
}

void FinishNode::follow_sand() {
  Run& run = *run_;
  SandSequence& seq = *run.sand;
  std::deque<Wrench> wrenches;
  std::optional<msg::TrajectoryStatus> ts;
  std::optional<msg::SafetyState> safety;
  {
    std::lock_guard lock(mutex_);
    wrenches.swap(wrenches_);
    measured_.clear();
    safety = safety_;
    if (auto it = trajectory_statuses_.find(run.trajectory_id); it != trajectory_statuses_.end())
      ts = it->second;
  }
  const auto now = std::chrono::steady_clock::now();
  const double tick =
      run.last_tick == std::chrono::steady_clock::time_point{}
          ? 0.0
          : std::min(0.1, std::chrono::duration<double>(now - run.last_tick).count());
  run.last_tick = now;
  run.silence = wrenches.empty() ? run.silence + tick : 0.0;
  SandCycle cycle;
  if (safety && safety->mode() != msg::SAFETY_RUNNING) {
    std::string causes;
    for (const auto& cause : safety->causes()) causes += (causes.empty() ? "" : ", ") + cause;
    cycle.safety_stop = causes;
  }
  if (ts) {
    const bool stopped = ts->state() == msg::TRAJECTORY_ABORTED || ts->state() == msg::TRAJECTORY_REFUSED;
    cycle.move = ts->state() == msg::TRAJECTORY_SUCCEEDED ? MoveReport::kSucceeded
                 : stopped                                 ? MoveReport::kStopped
                                                           : MoveReport::kRunning;
    cycle.move_progress = ts->progress();
    cycle.move_reason = ts->reason();
  }
  cycle.since_sent = std::chrono::duration<double>(now - run.sent).count();
  {
    std::optional<Measured> latest;
    {
      std::lock_guard lock(mutex_);
      latest = latest_;
    }
    if (latest && run.reach) cycle.tcp = run.reach->tcp_pose(q_in(run.reach->model(), *latest));
  }
  cycle.silence = run.silence;
  for (const Wrench& w : wrenches) cycle.forces.push_back({static_cast<double>(w.stamp_ns) * 1e-9, w.force});
  const SandStep step = supervise(seq, cycle, SandWatch{params_.wrench_timeout, 10.0});
  if (step.command) send_sand(*step.command);
  run.progress = seq.progress();
  if (step.end == SandEnd::kSucceeded) {
    end_run(msg::FINISH_SUCCEEDED, "");
  } else if (step.end == SandEnd::kFailed) {
    end_run(msg::FINISH_FAILED, step.reason);
  } else if (step.end == SandEnd::kAborted) {
    end_run(msg::FINISH_ABORTED, step.reason);
  } else if (now - run.last_status > std::chrono::seconds(1)) {
    run.last_status = now;
    publish(run.request_id, msg::FINISH_RUNNING, std::string("sanding: ") + to_string(seq.phase()),
            &run);
  }
}

void FinishNode::send_sand(const SandCommand& sc) {
  msg::CartesianImpedanceCommand m;
  m.model_version(static_cast<std::uint32_t>(command_version_));
  m.stamp_ns(now_ns());
  m.source(kSource);
  m.end_effector(run_->reach->tcp_frame());
  m.target(model::dds::to_pose_msg(sc.target));
  m.target_twist().linear().x(sc.velocity.x());
  m.target_twist().linear().y(sc.velocity.y());
  m.target_twist().linear().z(sc.velocity.z());
  for (std::size_t i = 0; i < 6; ++i) {
    m.stiffness()[i] = sc.stiffness[i];
    m.damping()[i] = sc.damping[i];
  }
  m.admittance_axis(sc.admittance ? 2 : 255);  // the TCP's z
  m.admittance_force(sc.force_setpoint);
  m.admittance_gain(sc.admittance ? sc.admittance_gain : 0.0);
  m.payload_mass(0.0);
  cartesian_.write(m);
}

void FinishNode::follow_run() {
  Run& run = *run_;
  if (run.sand) {
    follow_sand();
    return;
  }
  std::deque<Measured> measured;
  std::optional<msg::TrajectoryStatus> ts;
  {
    std::lock_guard lock(mutex_);
    measured.swap(measured_);
    if (auto it = trajectory_statuses_.find(run.trajectory_id); it != trajectory_statuses_.end()) ts = it->second;
  }
  // The deposition model, fed the TCP of every measured posture; the plan sample it is at is
  // tracked forwards in joint space (the nearest of the next samples).
  const auto& samples = run.plan.samples;
  for (const Measured& m : measured) {
    const Eigen::VectorXd q = q_of(m);
    const std::size_t best = track_sample(run.plan, run.reach->arm_joints(), run.index, q);
    run.index = best;
    const double dt = run.last_stamp > 0 ? static_cast<double>(m.stamp_ns - run.last_stamp) * 1e-9 : 0.0;
    run.last_stamp = m.stamp_ns;
    const std::size_t next = std::min(best + 1, samples.size() - 1);
    const PathSample& s = samples[next];
    ++run.postures;
    if (!s.tool_on || dt <= 0.0 || dt > 0.1) continue;
    ++run.tool_on;
    const Eigen::Isometry3d tcp = current_.reach->tcp_pose(q);
    if (valve_open(run.plan.strokes[static_cast<std::size_t>(s.stroke)], run.wall.coordinates(tcp.translation()))) {
      run.deposition->add(tcp, dt, s.stroke);
      ++run.painted;
    }
  }
  if (ts) run.progress = ts->progress();
  if (ts && ts->state() == msg::TRAJECTORY_SUCCEEDED) {
    end_run(msg::FINISH_SUCCEEDED, "");
  } else if (ts && (ts->state() == msg::TRAJECTORY_ABORTED || ts->state() == msg::TRAJECTORY_REFUSED)) {
    end_run(msg::FINISH_FAILED, "the robot stopped the path: " + ts->reason());
  } else if (!ts && std::chrono::steady_clock::now() - run.sent > std::chrono::seconds(10)) {
    end_run(msg::FINISH_FAILED, "the robot service did not answer the path's trajectory within 10 s");
  }
}

void FinishNode::end_run(msg::FinishState state, const std::string& reason) {
  Run& run = *run_;
  run_active_.store(false);
  if (run.sand) {
    const SandSequence& seq = *run.sand;
    // The arm from the Cartesian hold to a joint hold where it is (off the wall when done).
    hold_here();
    const std::string json = seq.report_json();
    const bool strokes = std::any_of(seq.trace().begin(), seq.trace().end(),
                                     [](const ForceSample& f) { return f.stroke; });
    if (!params_.out_dir.empty()) {
      try {
        std::filesystem::create_directories(params_.out_dir);
        const std::string stem = params_.out_dir + "/sand_" + std::to_string(run.request_id);
        std::ofstream(stem + ".json") << json << "\n";
        if (strokes)
          write_force_png(seq.trace(), seq.params().force, seq.params().tolerance, stem + ".png");
      } catch (const std::exception& e) {
        log_line(std::string("surface_finish: cannot write the report: ") + e.what());
      }
    }
    char b[260];
    if (strokes) {
      const ForceStats st = seq.stats();
      std::snprintf(b, sizeof b,
                    "request %u: %s: force (robot's estimate) mean %.2f N, min %.2f N, max %.2f N, "
                    "within +-%.1f N for "
                    "%.1f %% of %.1f s of strokes (%.2f s outside)",
                    run.request_id, state == msg::FINISH_SUCCEEDED ? "done" : "stopped", st.mean,
                    st.min, st.max, seq.params().tolerance, st.within_fraction * 100.0, st.duration,
                    st.time_outside);
    } else {
      std::snprintf(b, sizeof b, "request %u: stopped before the strokes", run.request_id);
    }
    log_line(std::string("surface_finish: ") + b + (reason.empty() ? "" : " (" + reason + ")"));
    if (state == msg::FINISH_SUCCEEDED) run.progress = 1.0;
    publish(run.request_id, state, reason, &run, json);
    run_.reset();
    return;
  }
  std::vector<double> xs;
  std::vector<bool> ups;
  for (const Stroke& s : run.plan.strokes) {
    xs.push_back(s.x);
    ups.push_back(s.up());
  }
  const SprayReport rep = run.deposition->measure(xs, ups);
  const std::string json = SprayDeposition::to_json(rep);
  if (!params_.out_dir.empty()) {
    try {
      std::filesystem::create_directories(params_.out_dir);
      const std::string stem = params_.out_dir + "/spray_" + std::to_string(run.request_id);
      std::ofstream(stem + ".json") << json << "\n";
      run.deposition->write_png(stem + ".png");
    } catch (const std::exception& e) {
      log_line(std::string("surface_finish: cannot write the report: ") + e.what());
    }
  }
  char b[300];
  std::snprintf(b, sizeof b,
                "request %u: %s: coverage %.2f %%, max |dh| %.1f mm, max coat width error %.1f mm (%zu measured "
                "postures, %zu at a stroke, %zu painted)",
                run.request_id, state == msg::FINISH_SUCCEEDED ? "done" : "stopped", rep.coverage * 100.0,
                rep.max_abs_delta_h * 1e3, rep.max_width_error * 1e3, run.postures, run.tool_on, run.painted);
  log_line(std::string("surface_finish: ") + b + (reason.empty() ? "" : " (" + reason + ")"));
  if (state == msg::FINISH_SUCCEEDED) run.progress = 1.0;
  publish(run.request_id, state, reason, &run, json);
  run_.reset();
}

void FinishNode::hold_here() {
  std::optional<Measured> latest;
  {
    std::lock_guard lock(mutex_);
    latest = latest_;
  }
  if (!latest || !current_.model || !current_.reach) return;
  const kinematics::Model& k = current_.model->kinematics();
  const Eigen::VectorXd q = q_of(*latest);
  msg::JointTrajectoryCommand t;
  t.request_id(next_trajectory_++);
  t.model_version(static_cast<std::uint32_t>(command_version_));
  t.stamp_ns(now_ns());
  t.source(kSource);
  msg::JointTrajectorySample a, b;
  a.time(0.0);
  b.time(0.1);
  for (int j : current_.reach->arm_joints()) {
    t.joint_names().push_back(k.joint_names()[static_cast<std::size_t>(j)]);
    a.position().push_back(q[j]);
    b.position().push_back(q[j]);
  }
  t.samples().push_back(a);
  t.samples().push_back(b);
  trajectories_.write(t);
}

void FinishNode::abort_run(const std::string& why, bool leave_wall) {
  if (run_ && run_->sand) {
    if (leave_wall && run_->sand->abort(why)) {
      log_line("surface_finish: request " + std::to_string(run_->request_id) + ": " + why +
               ": the tool leaves the wall first");
      return;  // follow_sand ends the run when it has
    }
    run_->sand->stop(why);  // end_run holds the arm
  } else {
    hold_here();
  }
  end_run(msg::FINISH_ABORTED, why);
}

}  // namespace concert::surface_finish::dds
