#include "drill/engine.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <iterator>
#include <sstream>
#include <utility>

#include "concert/bim/storey_map.hpp"
#include "concert/bim/wall_goal.hpp"
#include "concert/model/same_arm.hpp"

namespace concert::drill {

using Clock = std::chrono::steady_clock;

namespace {


// The planner's drilling force for a hole drilled with `p`: the thrust bound with a margin
// (Params::approach.thrust_checked).
double checked_thrust(const Params& tuning, const DrillParams& p) {
  return tuning.approach.thrust_checked * thrust_bound(p);
}

// The lead a hole's posture request holds the thrust of (the attempt whose checked thrust it asks).
double lead_checked(const Params& tuning, const PlanAsk& r) {
  for (const HoleAttempt& a : tuning.hole.attempts) {
    if (std::abs(checked_thrust(tuning, light_drilling(tuning.motion, a.lead)) - r.contact_force) < 1e-6) return a.lead;
  }
  return 1.0;
}

std::string thrust_text(double lead, const DrillParams& p) {
  if (lead >= 1.0) return "";
  return ", at " + std::to_string(std::lround(100.0 * thrust_bound(light_drilling(p, lead)) / thrust_bound(p))) +
         " % of the thrust";
}

// How the drill's own paths are timed (drill/paths.hpp).
PathTiming path_timing(const Params& t) {
  return {t.paths.settle_min, t.paths.base_kept, t.paths.joint_speed, t.paths.base_speed, t.paths.speed_share};
}

// An attempt at another lead.
HoleAttempt at_lead(HoleAttempt a, double lead) {
  a.lead = lead;
  return a;
}

// The first attempt with the bit's reach checked and the base fixed at `lead` (the loader
// checks one exists for the placement's light lead).
std::size_t first_fixed_at(const Params& tuning, double lead) {
  const auto& attempts = tuning.hole.attempts;
  for (std::size_t i = 0; i < attempts.size(); ++i) {
    if (attempts[i].reach && attempts[i].fixed_base && attempts[i].lead == lead) return i;
  }
  return 0;
}

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// A hole's posture request for attempt `a`: the bit's tip `further` beyond the hole's distance
// in front of it, the planner also checking the arm's torques with the bit at the hole's depth;
// or the camera on the hole's axis as far out.
// (`hole_distance`: the bit's tip from the wall the posture asks for before `further`.)
void set_hole_task(PlanAsk& r, const HoleAttempt& a, double hole_distance,
                   double depth, const Params& tuning) {
  const double tip = hole_distance + a.further;
  r.contact_force = checked_thrust(tuning, light_drilling(tuning.motion, a.lead));
  r.tip_distance = tip;
  r.tip_reach = a.reach ? tip + depth : 0.0;
  r.camera_distance = 0.0;
  r.fixed_base = a.fixed_base;
  r.base_travel = a.base_travel;
}

}  // namespace

// --- The control loop ------------------------------------------------------------------------

// A mission was accepted and has not ended (idle until its first tick).
bool DrillEngine::mission_active() const {
  return tree_ && (tree_->status().state == MissionState::kIdle ||
                   tree_->status().state == MissionState::kRunning);
}

DrillEngine::DrillEngine(EngineParams params, Inputs& inputs, mobile_base::MapFrame& map_frame, DrillSink& sink)
    : params_(std::move(params)), inputs_(inputs), map_frame_(map_frame), sink_(sink) {
  if (!params_.patterns.empty()) {
    try {
      patterns_ = load_patterns(params_.patterns);
    } catch (const DrillError& e) {
      log_line(std::string("drill: ") + e.what() + " (ArUco areas will fail until a mission names a table)");
    }
  }
}

DrillEngine::~DrillEngine() = default;

void DrillEngine::log_line(const std::string& line) { sink_.log(line); }

void DrillEngine::abort(const AbortOrder& a) {
  if (!mission_active()) return;
  if (a.mission_id != 0 && a.mission_id != mission_id_) return;
  tree_->abort("aborted by " + (a.source.empty() ? std::string("an operator") : a.source) +
               (a.reason.empty() ? "" : ": " + a.reason));
  log_line("drill: mission " + std::to_string(mission_id_) + " aborted");
}

void DrillEngine::tick(double now) {
  now_ = now;
  resend_unacknowledged();
  rest_step();
  if (leaving_wall()) {
    control_motion();
  } else if (mission_active()) {
    control_motion();
    const MissionState state = tree_->tick(now_);
    if (state != MissionState::kRunning) {
      last_reports_[tree_->report().mission] = tree_->report();
      const MissionReport& r = tree_->report();
      log_line("drill: mission '" + r.mission + "' " + to_string(state) + ": " + std::to_string(r.holes_drilled()) +
               " of " + std::to_string(r.holes_marked()) + " holes drilled" +
               (r.reason.empty() ? "" : " (" + r.reason + ")"));
    }
  }
  publish_status(false);
}

void DrillEngine::step_motion(double now) {
  now_ = now;
  resend_unacknowledged();
  rest_step();
  control_motion();
}

void DrillEngine::shutdown() {
  shutting_down_ = true;
  if (!mission_active()) return;
  tree_->abort("the drill service is stopping");
  publish_status(true);
}

// A plan request to the planner, sent again (same id) while the planner acknowledges nothing
// (resend_unacknowledged).
void DrillEngine::send_plan(const PlanAsk& request, bool may_rest) {
  const std::string why = held_requests_.empty() && may_rest ? rest_reason(request) : std::string();
  if (held_requests_.empty() && why.empty()) {
    forward_plan(request);
    return;
  }
  if (held_requests_.empty()) {
    log_line("drill: the arm rests at home before the planner's next answer (" + why +
             "): holding the posture while the planner searches would pass the drive's thermal limit");
    rest_since_ = -1.0;
    // From a hole's posture, first back along the area's holes' paths to its approach posture:
    // the planner's way home does not keep the bit (no collision shape) off the wall.
    if (const std::optional<std::uint32_t> back = send_way_back()) {
      rest_return_ = *back;
    } else {
      rest_home();
    }
  }
  held_requests_.push_back(request);
}

// The arm back along the area's holes' paths, reversed, to its approach posture: the id of the
// trajectory sent, or none when there is nothing to go back along (or no joint state yet).
std::optional<std::uint32_t> DrillEngine::send_way_back() {
  if (hole_chain_.empty()) return std::nullopt;
  const std::optional<Sample> s = inputs_.latest_sample();
  if (!s) return std::nullopt;
  return send_trajectory(hole_chain_.front().names, return_path(hole_chain_, *s, path_timing(tuning_)));
}

void DrillEngine::rest_home() {
  const PlanAsk home = home_ask();
  rest_request_ = home.request_id;
  forward_plan(home);
}

std::vector<DrillEngine::ArmHeat> DrillEngine::arm_heat() const {
  std::vector<ArmHeat> out;
  if (!rig_) return out;
  const std::map<std::string, Inputs::Heat> heat = inputs_.heat();
  const model::ModelDescription& d = rig_->model().description();
  for (const model::JointLimits& j : rig_->model().limits().rows()) {
    const auto chain = std::find_if(d.chains.begin(), d.chains.end(),
                                    [&](const model::ChainInfo& c) { return c.name == j.chain; });
    if (chain == d.chains.end() || chain->role != model::ChainRole::kArm || j.continuous_torque <= 0.0) continue;
    if (const auto h = heat.find(j.name); h != heat.end()) out.push_back({j.name, h->second, j.continuous_torque});
  }
  return out;
}

std::string DrillEngine::rest_reason(const PlanAsk& r) const {
  // Only a request planned from where the robot stands: the arm is held there, still, while the
  // planner searches. One from another start is planned while the robot does something else.
  if (!r.start_names.empty()) return {};
  std::ostringstream why;
  why.setf(std::ios::fixed);
  for (const ArmHeat& a : arm_heat()) {
    const double rms = a.heat.rms / a.continuous, held = a.heat.present / a.continuous;
    if (rms > tuning_.rest.above) {
      why.precision(0);
      why << a.joint << ": RMS " << a.heat.rms << " N m over the thermal window, ";
      why.precision(2);
      why << rms << " of its continuous torque";
      return why.str();
    }
    if (held > tuning_.rest.hold) {
      why.precision(0);
      why << a.joint << ": holds " << a.heat.present << " N m, ";
      why.precision(2);
      why << held << " of its continuous torque";
      return why.str();
    }
  }
  return {};
}

double DrillEngine::arm_rms_share() const {
  double share = 0.0;
  for (const ArmHeat& a : arm_heat()) share = std::max(share, a.heat.rms / a.continuous);
  return share;
}

// The thrust's share while drilling (Params::Thermal): full below fold_start, falling to the
// floor at fold_end, where the feed stops until the drive cooled below fold_start again. Said in
// the log when it starts folding and when the feed stops.
void DrillEngine::fold_thrust() {
  const double h = arm_rms_share();
  const Params::Thermal& t = tuning_.thermal;
  const double was = drill_motion_.thrust_share();
  double share = std::clamp((t.fold_end - h) / (t.fold_end - t.fold_start), 0.0, 1.0);
  if (was <= 0.0 && h >= t.fold_start) share = 0.0;  // stopped: until cooled below fold_start
  if (share > 0.0 && share < 1.0 && was >= 1.0) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(2);
    line << "drill: " << point_.label << ": the arm's drives at " << h
         << " of their continuous torque (RMS): the thrust folds back";
    log_line(line.str());
  } else if (share <= 0.0 && was > 0.0) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(2);
    line << "drill: " << point_.label << ": the arm's drives at " << h
         << " of their continuous torque (RMS): the feed stops until they cool below " << t.fold_start;
    log_line(line.str());
  }
  drill_motion_.set_thrust_share(share);
}

// While requests are held: the homing's answer, then the arm at home until its drives cooled
// (Params::Rest::until) or the rest's timeout (robot time), then the requests to the planner.
void DrillEngine::rest_step() {
  if (held_requests_.empty()) return;
  if (rest_return_ != 0) {
    const std::optional<MotionReply> back = inputs_.trajectory(rest_return_);
    if (!back || back->progress == Progress::kRunning) return;
    rest_return_ = 0;
    if (back->progress != Progress::kSucceeded) {
      release_held("the arm could not go back from the holes to rest (" + back->failure + ": " + back->reason +
                   "); asked from where it stands");
      return;
    }
    hole_chain_.clear();  // at the area's approach posture: nothing left to go back along
    rest_home();
    return;
  }
  if (rest_request_ != 0) {
    const std::optional<PlanReply> home = inputs_.plan(rest_request_);
    if (!home || (home->state != PlanState::kSucceeded && home->state != PlanState::kFailed)) return;
    rest_request_ = 0;
    if (home->state == PlanState::kFailed) {
      release_held("the arm could not go home to rest (" + home->reason + "); asked from where it stands");
      return;
    }
    // The way back to the area's approach posture (execute()) now starts with the homing's
    // path, reversed: the arm leaves home the way it came, collision free.
    if (home->path.samples.size() >= 2) hole_chain_.push_back(home->path);
  }
  const std::optional<Sample> s = inputs_.latest_sample();
  if (!s) return;
  if (rest_since_ < 0.0) rest_since_ = robot_time(*s);
  const double share = arm_rms_share();
  const double rested = robot_time(*s) - rest_since_;
  std::ostringstream why;
  why.setf(std::ios::fixed);
  why.precision(2);
  if (share < tuning_.rest.until) {
    why << "the arm rested " << std::setprecision(1) << rested << " s at home, its drives at " << std::setprecision(2)
        << share << " of continuous";
    release_held(why.str());
  } else if (rested >= tuning_.rest.timeout) {
    why << "the arm rested " << std::setprecision(1) << rested << " s at home, its drives still at "
        << std::setprecision(2) << share << " of continuous";
    release_held(why.str());
  }
}

void DrillEngine::release_held(const std::string& why) {
  log_line("drill: " + why + "; " + std::to_string(held_requests_.size()) + " plan request" +
           (held_requests_.size() == 1 ? "" : "s") + " sent");
  std::vector<PlanAsk> held;
  held.swap(held_requests_);
  rest_since_ = -1.0;
  for (const PlanAsk& r : held) forward_plan(r);
}

void DrillEngine::forward_plan(const PlanAsk& request) {
  PlanAsk r = request;
  // The odometry frame where the marks seen again put it, while nav localises nothing: the
  // planner's map (the world) then has the wall where the camera sees it, not where odometry
  // puts it (OdometryDrift).
  if (!map_frame_.localised() && drift_.corrected()) {
    const Eigen::Vector3d d = drift_.odom_in_map();
    r.odom_in_map = d;
  }
  sink_.plan(r);
  unacknowledged_[r.request_id] = {r, now_, 0};
}

std::string DrillEngine::landmark(std::size_t area, const std::string& label) const {
  return std::to_string(area) + ":" + label;
}

void DrillEngine::hole_seen_again(const Eigen::Vector3d& in_odom) {
  const std::optional<double> moved = drift_.seen_again(landmark(detection_.area, point_.label), in_odom);
  if (!moved) return;
  const Eigen::Vector3d d = drift_.odom_in_map();
  std::ostringstream line;
  line.setf(std::ios::fixed);
  line.precision(1);
  line << "drill: " << point_.label << ": the odometry frame at (" << d.x() * 1e3 << ", " << d.y() * 1e3
       << ") mm in the map as the hole tells (moved " << *moved * 1e3 << " mm)"
       << (map_frame_.localised() ? "; nav's localisation used instead" : "");
  log_line(line.str());
}

// Plan requests travel volatile: one written before the drill's writer matched the reader of a
// planner that just (re)started is lost, and the drill would wait for its answer for good. The
// planner acknowledges each request as it arrives (PlanState::kPlanning) and takes a resend once.
void DrillEngine::resend_unacknowledged() {
  for (auto it = unacknowledged_.begin(); it != unacknowledged_.end();) {
    if (plan_result(it->first)) {
      it = unacknowledged_.erase(it);
      continue;
    }
    Unacknowledged& u = it->second;
    if (now_ - u.sent >= tuning_.plan_requests.ack_bound) {
      if (u.resends >= tuning_.plan_requests.resends) {
        log_line("drill: plan request " + std::to_string(it->first) + " not acknowledged by the planner after " +
                 std::to_string(tuning_.plan_requests.resends + 1) + " sends; waiting for its answer");
        it = unacknowledged_.erase(it);
        continue;
      }
      ++u.resends;
      u.sent = now_;
      log_line("drill: plan request " + std::to_string(it->first) + " not acknowledged by the planner within " +
               std::to_string(static_cast<int>(tuning_.plan_requests.ack_bound)) + " s; sent again (" +
               std::to_string(u.resends) + " of " + std::to_string(tuning_.plan_requests.resends) + ")");
      sink_.plan(u.request);
    }
    ++it;
  }
}

std::string DrillEngine::apply_model(std::uint32_t version, std::shared_ptr<const DrillRig> rig,
                                     const std::string& why) {
  const std::uint64_t old = model_version_;
  // A bit in the wall leaves it under the new model only when the new model puts the tool where
  // the old one did (the same arm); with another arm the joints no longer say where the bit is.
  const std::optional<Sample> sample = inputs_.latest_sample();
  leave_allowed_ = sample && rig_ && rig && rig_->tcp_frame() == rig->tcp_frame() &&
                   model::same_frame_pose(rig_->model(), rig->model(), rig_->tcp_frame(), sample->joints.names,
                                          sample->joints.positions);
  model_version_ = version;
  rig_ = rig;
  inputs_.set_rig(rig);
  rig_error_ = rig ? "" : why;
  if (leaving_wall() && !leave_allowed_) {
    log_line("drill: the robot model changed while the bit left the wall, and the new model's arm is another: "
             "the arm holds where it is");
    motion_ = Motion::kNone;
    send_hold();
  }
  if (mission_active()) {
    tree_->abort("the robot model changed (version " + std::to_string(old) + " -> " + std::to_string(version) + ")");
  }
  leave_allowed_ = true;
  if (!rig) {
    log_line("drill: " + why);
    return why;
  }
  log_line("drill: model version " + std::to_string(version) + ": drill " + rig->tool() + " at " + rig->tcp_frame() +
           ", camera " + rig->camera());
  return "drill " + rig->tool() + ", camera " + rig->camera();
}

void DrillEngine::start_mission(const MissionOrder& m) {
  // Written again by a sender that had not heard us yet: the same mission, taken once.
  if (!missions_seen_.first_time(m.mission_id, m.stamp_ns)) return;
  const auto refuse = [&](const std::string& why) {
    sink_.refused("mission " + std::to_string(m.mission_id) + ": " + why);
    MissionReport report;
    report.mission = m.name;
    report.state = MissionState::kFailed;
    report.reason = why;
    MissionStatus st;
    st.state = MissionState::kFailed;
    st.reason = why;
    sink_.mission_status(m.mission_id, st, report);
    log_line("drill: mission " + std::to_string(m.mission_id) + " refused: " + why);
  };
  if (mission_active()) {
    return refuse("mission " + std::to_string(mission_id_) + " ('" + tree_->report().mission +
                  "') is running; abort it first");
  }
  if (leaving_wall()) {
    return refuse("the bit is leaving the wall after the last mission; send the mission again when it is out");
  }
  if (!rig_)
    return refuse(rig_error_.empty() ? "no robot model yet" : rig_error_);
  Mission mission;
  try {
    mission = parse_mission(
        m.yaml, m.name.empty() ? "mission " + std::to_string(m.mission_id) : m.name,
        m.base_dir);
    if (!mission.patterns.empty()) patterns_ = load_patterns(mission.patterns);
  } catch (const DrillError& e) {
    return refuse(e.what());
  }
  mission_ = std::make_unique<Mission>(std::move(mission));
  mission_id_ = m.mission_id;
  resolving_.clear();
  bim_frames_.clear();
  surfaces_.clear();
  start_blobs_.clear();
  drift_.forget_marks();
  plans_.clear();
  hole_chain_.clear();
  returning_ = false;
  motion_ = Motion::kNone;
  mission_started_ = Clock::now();
  tree_ = std::make_unique<MissionTree>(*mission_, *this);
  if (m.resume) {
    const auto previous = last_reports_.find(mission_->name);
    if (previous != last_reports_.end()) tree_->resume(previous->second);
  }
  log_line("drill: mission " + std::to_string(mission_id_) + " '" + mission_->name + "': " +
           std::to_string(mission_->areas.size()) + " areas" + (m.resume ? " (resuming)" : ""));
  last_active_ = "-";  // the status after the first tick goes out at once
}

void DrillEngine::publish_status(bool force) {
  if (!tree_) return;
  const MissionStatus st = tree_->status();
  if (!force && st.active == last_active_ && seconds_since(last_status_) < 0.5) return;
  last_active_ = st.active;
  last_status_ = Clock::now();
  sink_.mission_status(mission_id_, st, tree_->report());
}

// --- Ports: health, areas, navigation, planning, execution -----------------------------------

Outcome DrillEngine::health() {
  if (!rig_) return Outcome::failed(rig_error_.empty() ? "the robot model cannot drill" : rig_error_);
  return inputs_.health(mission_started_, nav_request_ != 0, Clock::now());
}

void DrillEngine::resolve(std::size_t area, const AreaSpec& spec) {
  resolve_specs_[area] = spec;
  resolve_since_[area] = inputs_.newest_stamp();
  if (spec.wall.empty()) return;  // located from the camera in resolution()
  // A BIM wall: the area frame and the base pose from the building's model (load_ifc runs the
  // IFC import step, a second or two, off the control thread).
  const Mission mission = *mission_;
  const double standoff = tuning_.bim.wall_standoff, radius = tuning_.bim.robot_radius;
  resolving_[area] = std::async(std::launch::async, [mission, spec, standoff, radius] {
    const bim::BimModel model = bim::load_ifc(mission.ifc.string());
    const bim::Element& wall = model.element(spec.wall);
    const bim::Storey& storey = model.storey(mission.storey.empty() ? wall.storey : mission.storey);
    const bim::OccupancyGrid grid = bim::storey_map(model, storey);
    bim::GoalOptions options;
    options.face = bim::face_choice(spec.face);
    const bim::WallGoal goal = bim::wall_goal(model, grid, spec.wall, spec.at.x(), spec.at.y(),
                                              standoff, radius, options);
    ResolvedArea out;
    out.frame = goal.area_frame;
    out.base = BasePose{goal.base_pose.x(), goal.base_pose.y(), goal.base_pose.z()};
    return out;
  });
}

Outcome DrillEngine::resolution(std::size_t area, ResolvedArea& out) {
  const AreaSpec& spec = resolve_specs_.at(area);
  if (!spec.wall.empty()) {
    auto it = resolving_.find(area);
    if (it == resolving_.end())
      return Outcome::failed("area '" + spec.name + "' was not being located");
    if (it->second.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
      return Outcome::running();
    try {
      out = it->second.get();
    } catch (const std::exception& e) {
      resolving_.erase(it);
      return Outcome::failed("area '" + spec.name + "': wall " + spec.wall + ": " + e.what());
    }
    resolving_.erase(it);
    // The base pose stays in the map (nav's goal); the area frame goes to the odometry frame,
    // where the camera and the planner's requests are (again when it is planned: nav corrects
    // the odometry's drift on the way).
    bim_frames_[area] = out.frame;
    out.frame = map_frame_.to_odom(out.frame);
    if (map_frame_.localised()) {
      const Eigen::Vector3d m = map_frame_.map_T_odom();
      std::ostringstream line;
      line << std::fixed << std::setprecision(3) << "drill: area '" << spec.name
           << "': BIM frame at (" << bim_frames_[area].translation().transpose()
           << ") in the map, (" << out.frame.translation().transpose()
           << ") in the odometry frame (map -> odom " << m.x() << ", " << m.y() << ", " << m.z()
           << ")";
      log_line(line.str());
    }
    return Outcome::succeeded();
  }
  const std::optional<CameraFrame> view =
      inputs_.averaged_view(resolve_since_[area], tuning_.camera.averaged_frames);
  if (!view) return Outcome::running();
  const CameraView camera{&view->frame, view->world_T_optical};
  if (spec.point && !in_view(camera, *spec.point)) {
    // Where the arm is parked the drill camera may not see the point: plan the approach to a
    // frame facing the robot, and measure the surface with the drill camera once there.
    const std::optional<Sample> s = inputs_.latest_sample();
    out = provisional_area(
        *spec.point, rig_->base_in_world(s ? s->odometry : Eigen::Vector3d::Zero()).translation());
    log_line("drill: area '" + spec.name +
             "': the drill camera does not see the point from here; approach planned "
             "facing the robot, the surface measured there");
    return Outcome::succeeded();
  }
  try {
    out = locate_area(spec, camera);
  } catch (const DrillError& e) {
    return Outcome::failed(e.what());
  }
  // The surface as measured from here: where the odometry frame is now in the map (no drift
  // from where the mission started, or the drift the marks told since).
  surfaces_[area] = {drift_.to_map(out.frame.translation()), out.frame.linear().col(2)};
  if (spec.marks == MarkKind::kBlobs) {
    // The blobs this view shows around the area, for follow_start_blobs after the approach.
    std::vector<DrillPoint>& blobs = start_blobs_[area];
    blobs.clear();
    try {
      for (const Blob& b : detect_blobs(view->frame)) {
        DrillPoint p;
        p.frame.translation() = view->world_T_optical * b.position;
        const Eigen::Vector3d local = out.frame.inverse() * p.frame.translation();
        if (local.head<2>().norm() > area_radius(tuning_.camera.working_distance, tuning_.camera.fov) ||
            std::abs(local.z()) > tuning_.blobs.match)
          continue;
        p.label = "start view blob " + std::to_string(blobs.size() + 1);
        blobs.push_back(p);
      }
    } catch (const DrillError&) {
      blobs.clear();  // none taken: the area is then found from the view after the approach alone
    }
  }
  return Outcome::succeeded();
}

// Nav drives with the arm in its transport posture (its footprint and drive budget hold it
// there, and it refuses a goal otherwise): the arm first goes home, planned and executed by the
// planner from wherever the last area left it, then the goal goes to nav. The holes' paths no
// longer lead back to this area's approach.
void DrillEngine::navigate(const BasePose& goal) {
  nav_goal_ = goal;
  send_home();
}

// The planner's home request, executed: the arm to its homing posture, the base standing.
PlanAsk DrillEngine::home_ask() {
  PlanAsk r;
  r.request_id = next_request_++;
  r.model_version = static_cast<std::uint32_t>(model_version_);
  r.end_effector = rig_ ? rig_->tool() : "";
  r.home = true;
  r.execute = true;
  return r;
}

void DrillEngine::send_home() {
  hole_chain_.clear();
  const PlanAsk r = home_ask();
  home_request_ = r.request_id;
  send_plan(r);
}

Outcome DrillEngine::homing() {
  if (home_request_ == 0) return Outcome::failed("no homing was asked for");
  const std::optional<PlanReply> home = inputs_.plan(home_request_);
  if (!home || (home->state != PlanState::kSucceeded && home->state != PlanState::kFailed))
    return Outcome::running();
  home_request_ = 0;
  if (home->state == PlanState::kFailed) return Outcome::failed(home->reason);
  return Outcome::succeeded();
}

// The arm home at the mission's end: first back along the last area's holes' paths to its
// approach posture, as before the next area, then the planner's homing from there. The planner
// checks its path with the drill module's shapes and not the bit's (it has none): planned from a
// hole's posture, in front of the wall, its way home can sweep the bit through the wall.
void DrillEngine::stow() {
  stow_returning_ = false;
  if (const std::optional<std::uint32_t> back = send_way_back()) {
    trajectory_request_ = *back;
    stow_returning_ = true;
    return;
  }
  send_home();
}

Outcome DrillEngine::stowing() {
  if (!stow_returning_) return homing();
  const std::optional<MotionReply> status = inputs_.trajectory(trajectory_request_);
  if (!status || status->progress == Progress::kRunning) return Outcome::running();
  stow_returning_ = false;
  if (status->progress != Progress::kSucceeded)
    return Outcome::failed("robot: the way back from the holes " + status->failure + ": " + status->reason);
  send_home();
  return Outcome::running();
}

Outcome DrillEngine::navigation() {
  if (home_request_ != 0) {
    const Outcome home = homing();
    if (home.progress == Progress::kRunning) return home;
    if (home.progress == Progress::kFailed) return Outcome::failed("the arm home before driving: " + home.reason);
    nav_request_ = next_request_++;
    sink_.navigate(nav_request_, static_cast<std::uint32_t>(model_version_), nav_goal_);
    return Outcome::running();
  }
  const std::optional<MotionReply> reply = inputs_.nav(nav_request_);
  if (!reply || reply->progress == Progress::kRunning) return Outcome::running();
  nav_request_ = 0;
  if (reply->progress == Progress::kSucceeded) return Outcome::succeeded();
  return Outcome::failed("navigation: " + reply->reason);
}

void DrillEngine::plan(std::size_t area, const Eigen::Isometry3d& located,
                     std::optional<std::size_t> after) {
  const auto bim = bim_frames_.find(area);
  const Eigen::Isometry3d frame =
      bim == bim_frames_.end() ? located : map_frame_.to_odom(bim->second);
  Plan p;
  p.request_id = next_request_++;
  PlanAsk r;
  r.request_id = p.request_id;
  r.model_version = static_cast<std::uint32_t>(model_version_);
  r.end_effector = rig_ ? rig_->tool() : "";
  r.goals.push_back(frame);
  r.execute = false;
  r.environment_padding = tuning_.approach.padding;
  r.contact_force = checked_thrust(tuning_, tuning_.motion);
  if (after) {
    const auto prev = plans_.find(*after);
    if (prev != plans_.end() && prev->second.end.size() > 0) {
      r.start_names = prev->second.names;
      r.start_position.assign(prev->second.end.data(), prev->second.end.data() + prev->second.end.size());
    }
  }
  p.request = r;
  plans_[area] = p;
  send_plan(r);
}

Outcome DrillEngine::planning(std::size_t area) {
  auto it = plans_.find(area);
  if (it == plans_.end()) return Outcome::failed("no plan was asked for this area");
  Plan& p = it->second;
  if (p.result) return Outcome::succeeded();
  const std::optional<PlanReply> r = inputs_.plan(p.request_id);
  if (!r) return Outcome::running();
  if (r->state == PlanState::kFailed && p.attempts < tuning_.approach.attempts &&
      (r->failure == PlanFailure::kNoPath || r->failure == PlanFailure::kUnreachable)) {
    // The search is randomised (seeded by the request id): another request searches anew.
    ++p.attempts;
    p.request_id = next_request_++;
    p.request.request_id = p.request_id;
    log_line("drill: area " + std::to_string(area) + ": " + r->reason +
             "; planning again (attempt " + std::to_string(p.attempts) + " of " +
             std::to_string(tuning_.approach.attempts) + ")");
    send_plan(p.request);
    return Outcome::running();
  }
  if (r->state == PlanState::kFailed) return Outcome::failed("planner: " + r->reason);
  if ((r->state == PlanState::kPlanned || r->state == PlanState::kSucceeded) &&
      !r->path.samples.empty()) {
    p.result = r;
    p.names = r->path.names;
    const auto& last = r->path.samples.back().position;
    p.end = Eigen::Map<const Eigen::VectorXd>(last.data(), static_cast<Eigen::Index>(last.size()));
    return Outcome::succeeded();
  }
  return Outcome::running();
}

std::uint32_t DrillEngine::send_trajectory(const std::vector<std::string>& names,
                                           const std::vector<PathSample>& samples) {
  const std::uint32_t id = next_request_++;
  sink_.trajectory(id, static_cast<std::uint32_t>(model_version_), names, samples);
  return id;
}

// An area's approach starts where the previous area's approach ended (it was planned from
// there while that area was drilled): the arm first goes back along the holes' planned paths,
// reversed, from the last hole to the first.
void DrillEngine::execute(std::size_t area) {
  executing_area_ = area;
  if (const std::optional<std::uint32_t> back = send_way_back()) {
    trajectory_request_ = *back;
    returning_ = true;
    return;
  }
  returning_ = false;
  const Plan& p = plans_.at(area);
  trajectory_request_ = send_trajectory(p.names, p.result->path.samples);
}

Outcome DrillEngine::execution() {
  const std::optional<MotionReply> status = inputs_.trajectory(trajectory_request_);
  if (!status) return Outcome::running();
  const MotionReply& reply = *status;
  if (returning_ && reply.progress == Progress::kSucceeded) {
    returning_ = false;
    hole_chain_.clear();
    const Plan& p = plans_.at(*executing_area_);
    trajectory_request_ = send_trajectory(p.names, p.result->path.samples);
    return Outcome::running();
  }
  if (reply.progress == Progress::kRunning) return Outcome::running();
  if (reply.progress == Progress::kSucceeded) {
    hole_chain_.clear();
    return Outcome::succeeded();
  }
  return Outcome::failed(std::string(returning_ ? "robot: the way back from the holes " : "robot: approach trajectory ") +
                         reply.failure + ": " + reply.reason);
}

// --- Ports: detection and the drilling motion ------------------------------------------------

void DrillEngine::detect(std::size_t area, const AreaSpec& spec, const ResolvedArea& located) {
  detection_ = Detection{};
  detection_.area = area;
  detection_.spec = spec;
  detection_.located = located;
  detection_.since_ns = inputs_.newest_stamp();  // frames taken after the arm stopped
}

// The approach drifts odometry along the wall too (by up to several centimetres), where the
// surface tells nothing: the pick, kept in odometry coordinates, can then lie between two blobs
// 0.1 m apart, and the neighbour be drilled. The start view's blobs, seen again as a set (the
// shift that lays two or more of them onto blobs seen now), measure that drift: the pick moves
// with it, along the wall only (the surface was measured again already).
void DrillEngine::follow_start_blobs(const CameraView& camera, ResolvedArea& located) {
  const auto it = start_blobs_.find(detection_.area);
  if (it == start_blobs_.end() || it->second.size() < 2) return;
  std::optional<AreaShift> shift;
  try {
    shift = blob_shift(camera, it->second, tuning_.blobs.match, tuning_.blobs.set_shift, tuning_.blobs.set_shift);
  } catch (const DrillError&) {
    return;
  }
  if (!shift || shift->blobs < 2) return;
  const Eigen::Vector3d n = located.frame.linear().col(2);
  const Eigen::Vector3d along = shift->by - n * n.dot(shift->by);
  located.frame.translation() += along;
  // Not handed to drift_ (the planner's odometry frame in the map): the start view's blobs, up
  // to 2.5 m away, are placed to 1 cm along the normal (perception_test), worse than the surface
  // measured again from 0.6 m, and drift_ takes a mark's whole shift. The drift from here on
  // comes from the holes, landmarks as odometry puts them now.
  std::ostringstream line;
  line.setf(std::ios::fixed);
  line.precision(1);
  line << "drill: area '" << detection_.spec.name << "': " << shift->blobs << " of the start view's "
       << it->second.size() << " blobs seen again " << along.norm() * 1e3
       << " mm along the wall from where they were: the pick moved with them";
  log_line(line.str());
}

Outcome DrillEngine::detection(std::vector<DrillPoint>& points) {
  const std::optional<CameraFrame> view =
      inputs_.averaged_view(detection_.since_ns, tuning_.camera.averaged_frames);
  if (!view) return Outcome::running();
  if (!patterns_ && detection_.spec.marks == MarkKind::kAruco) {
    return Outcome::failed(
        "area '" + detection_.spec.name +
        "': no hole-pattern table (give the service --patterns or the mission patterns:)");
  }
  try {
    static const PatternTable kNone;
    const CameraView camera{&view->frame, view->world_T_optical};
    // The area's surface as the drill camera sees it now, 0.6 m in front of it (a BIM wall or
    // a point located from afar may be a few centimetres off).
    ResolvedArea located = detection_.located;
    if (!detection_.spec.pixel && in_view(camera, located.frame.translation())) {
      AreaSpec here = detection_.spec;
      here.point = located.frame.translation();
      located = locate_area(here, camera);
      // The surface measured again after the approach: the odometry's drift along its normal.
      if (const auto first = surfaces_.find(detection_.area); first != surfaces_.end()) {
        if (const std::optional<double> moved =
                drift_.surface_seen(first->second.point, first->second.normal, located.frame.translation())) {
          const Eigen::Vector3d d = drift_.odom_in_map();
          std::ostringstream line;
          line.setf(std::ios::fixed);
          line.precision(1);
          line << "drill: area '" << detection_.spec.name << "': its surface measured again "
               << *moved * 1e3 << " mm along its normal from where it was first; the odometry frame at ("
               << d.x() * 1e3 << ", " << d.y() * 1e3 << ") mm in the map";
          log_line(line.str());
        }
      }
    }
    if (detection_.spec.marks == MarkKind::kBlobs) follow_start_blobs(camera, located);
    points = find_holes(detection_.spec, located, camera, patterns_ ? *patterns_ : kNone,
                        area_radius(tuning_.camera.working_distance, tuning_.camera.fov));
    area_points_ = points;
    for (const DrillPoint& p : points)
      drift_.first_seen(landmark(detection_.area, p.label), p.frame.translation());
    markers_seen_.clear();
    markers_seen_at_.clear();
    for (const DrillPoint& p : points)
      if (p.marker >= 0) markers_seen_at_[p.marker] = now_;
    if (detection_.spec.marks == MarkKind::kBlobs && !points.empty()) {
      // Which blob is drilled first, and by what margin (odometry drifts over the approach: a
      // pick between two blobs can land nearer the other one).
      std::ostringstream line;
      line.setf(std::ios::fixed);
      line.precision(1);
      line << "drill: area '" << detection_.spec.name << "': " << points.size()
           << " blobs, nearest first, from (" << std::setprecision(3)
           << located.frame.translation().transpose() << ")" << std::setprecision(1);
      for (const DrillPoint& p : points)
        line << "; " << p.label << " at "
             << (p.frame.translation() - located.frame.translation()).norm() * 1e3 << " mm";
      log_line(line.str());
    }
    if (detection_.spec.marks == MarkKind::kBlobs && detection_.spec.expected > 0 &&
        points.size() < static_cast<std::size_t>(detection_.spec.expected)) {
      // What the camera saw, for the report's "expected holes not found".
      std::ostringstream line;
      line.setf(std::ios::fixed);
      line.precision(3);
      line << "drill: area '" << detection_.spec.name << "': " << points.size() << " of "
           << detection_.spec.expected << " blobs found around ("
           << located.frame.translation().transpose() << "); blobs in the image:";
      for (const Blob& b : detect_blobs(view->frame))
        line << " [px " << b.pixel.transpose() << ", at "
             << (view->world_T_optical * b.position).transpose() << "]";
      log_line(line.str());
    }
  } catch (const DrillError& e) {
    return Outcome::failed(e.what());
  }
  return Outcome::succeeded();
}

// --- Ports: which of an area's holes the robot can reach (ReachSurvey) -------------------------

// "a whole-body posture at full thrust", "... at 35 % of the thrust", "..., the bit's reach to
// the hole's depth unchecked": what a survey attempt asks, for the report.
static std::string survey_text(const HoleAttempt& a, const DrillParams& motion) {
  std::string t = "a whole-body posture";
  t += a.lead >= 1.0 ? " at full thrust" : thrust_text(a.lead, motion).substr(1);
  if (!a.reach) t += ", the bit's reach to the hole's depth unchecked";
  return t;
}

// Every hole's first survey attempt goes out at once (planned only, from where the robot stands);
// classification() reads the answers.
void DrillEngine::classify(std::size_t area, const std::vector<DrillPoint>& holes) {
  survey_ = Survey{};
  survey_.holes = holes;
  survey_.survey.emplace(holes.size(), tuning_.survey.attempts.size(), tuning_.survey.tries);
  survey_.ids.assign(holes.size(), 0);
  survey_.started = now_;
  if (!rig_) {  // no model to ask about: nothing judged, the holes attempted as they are
    for (std::size_t i = 0; i < holes.size(); ++i) survey_.survey->unknown(i, "no drill model");
    return;
  }
  log_line("drill: area " + std::to_string(area) + ": can the robot reach its " + std::to_string(holes.size()) +
           (holes.size() == 1 ? " hole?" : " holes?"));
  for (std::size_t i = 0; i < holes.size(); ++i) survey_ask(i);
}

void DrillEngine::survey_ask(std::size_t i) {
  const std::optional<std::size_t> a = survey_.survey->next(i);
  if (!a) return;
  PlanAsk r = placement_request(survey_.holes[i].frame);
  set_hole_task(r, tuning_.survey.attempts[*a], tuning_.motion.standoff + tuning_.hole.align_margin, hole_depth(),
                tuning_);
  survey_.ids[i] = r.request_id;
  send_plan(r);
}

// Each answer moves its hole's verdict on (ReachSurvey): a posture found, none found (the
// attempt again or the next one), or a request the planner could not judge (refused, another
// model: unknown). Succeeded once every hole has its verdict.
Outcome DrillEngine::classification(std::vector<HoleReach>& reach) {
  if (!survey_.survey) return Outcome::failed("no survey started");
  ReachSurvey& s = *survey_.survey;
  for (std::size_t i = 0; i < survey_.holes.size() && !s.done(); ++i) {
    const std::optional<std::size_t> a = s.next(i);
    if (!a || survey_.ids[i] == 0) continue;
    const std::optional<PlanReply> r = answered(survey_.ids[i]);
    if (!r) continue;
    survey_.ids[i] = 0;
    const HoleAttempt& attempt = tuning_.survey.attempts[*a];
    if (r->state == PlanState::kSucceeded) {
      s.found(i, survey_text(attempt, tuning_.motion));
    } else if (r->failure == PlanFailure::kUnreachable || r->failure == PlanFailure::kNoPath) {
      s.not_found(i, "no posture found, even " + survey_text(attempt, tuning_.motion) + ": " + r->reason);
      survey_ask(i);
    } else {
      s.unknown(i, "the planner could not judge: " + r->reason);
    }
  }
  if (!s.done()) return Outcome::running();
  if (!survey_.logged) {
    survey_.logged = true;
    std::ostringstream t;
    t.setf(std::ios::fixed);
    t.precision(1);
    t << now_ - survey_.started;
    log_line("drill: " + s.summary() + " (asked in " + t.str() + " s)");
  }
  reach = s.verdicts();
  return Outcome::succeeded();
}

// --- Ports: the base's placement for an area's holes (drill/placement.hpp) --------------------

// A planned-only request for a posture at `goal` from the robot's current state; the task is the
// caller's.
PlanAsk DrillEngine::placement_request(const Eigen::Isometry3d& goal) {
  PlanAsk r;
  r.request_id = next_request_++;
  r.model_version = static_cast<std::uint32_t>(model_version_);
  r.end_effector = rig_->tool();
  r.goals.push_back(goal);
  r.execute = false;
  return r;
}

// An ArUco area of several holes: from where the base stands, then from whole-body postures
// drawn (placement.draws: the bit a little further out than a hole's, in front of the holes'
// centre or of a point nearer the marker), the arm alone is asked for each hole's drilling posture (as a hole's
// first request: the bit's reach and the full thrust checked) and, from a drawn posture, the
// camera for a look at the marker. The base then moves once, to the first posture reaching every
// hole with a look, or stays (PlacementChoice). Blob areas are left as they are: their holes are
// drilled with visual servoing, which takes out the odometry's drift.
void DrillEngine::place(std::size_t area, const std::vector<DrillPoint>& holes) {
  motion_outcome_.reset();
  placement_ = Placement{};
  hole_placing_ = false;
  area_placement_ = Placement{};
  placed_for_.clear();
  placed_lead_.reset();
  const std::optional<Sample> s = inputs_.latest_sample();
  const bool pattern = !holes.empty() && std::all_of(holes.begin(), holes.end(), [&](const DrillPoint& h) {
    return h.marker >= 0 && h.marker == holes.front().marker;
  });
  if (holes.size() < 2 || !pattern || !patterns_ || !rig_ || !s) {
    motion_outcome_ = Outcome::succeeded();
    return;
  }
  placement_.holes = holes;
  placement_.started = now_;
  placement_.choice.emplace(holes.size(), tuning_.placement.draws.size());
  point_ = holes.front();
  const Eigen::VectorXd q = rig_->q(s->joints);
  const Eigen::Isometry3d camera = rig_->camera_in_base(q);
  camera_to_tip_ = (rig_->tip_in_base(q).translation() - camera.translation()).dot(camera.linear().col(2));
  hole_distance_ = tuning_.motion.standoff + tuning_.hole.align_margin;
  log_line("drill: area " + std::to_string(area) + ": placing the base for its " +
           std::to_string(holes.size()) + " holes");
  place_check(false);
}

Outcome DrillEngine::placement(std::vector<std::size_t>& order) {
  if (!motion_outcome_) return Outcome::running();
  if (motion_outcome_->progress == Progress::kSucceeded) order = placement_.order;
  return *motion_outcome_;
}

// "; holes 1, 4 last" when some but not all of the holes are `reached`, for the log.
static std::string last_holes(const std::vector<bool>& reached) {
  const auto n = static_cast<std::size_t>(std::count(reached.begin(), reached.end(), true));
  if (n == 0 || n == reached.size()) return "";
  std::string last;
  for (std::size_t i = 0; i < reached.size(); ++i) {
    if (!reached[i]) last += (last.empty() ? "" : ", ") + std::to_string(i + 1);
  }
  return "; holes " + last + " last";
}

// The arm alone onto every hole, from where the base stands or (`drawn`) from the end of the
// posture drawn last, with a look at the marker from there too.
void DrillEngine::place_check(bool drawn) {
  placement_.hole_checks.clear();
  placement_.look_check = {};
  const auto from = [&](PlanAsk& r) {
    if (!drawn) return;
    r.start_names = placement_.names.back();
    r.start_position = placement_.bodies.back().back().position;
  };
  for (const DrillPoint& h : placement_.holes) {
    PlanAsk r = placement_request(h.frame);
    set_hole_task(r, at_lead(tuning_.hole.attempts[0], placement_.lead), hole_distance_, hole_depth(), tuning_);
    from(r);
    placement_.hole_checks.push_back({r.request_id, 0, r});
    send_plan(r);
  }
  if (drawn) {
    // The whole marker in view whichever way the camera rolls (marker_look_radius), the base
    // where the drawn posture put it. No drilling force at a look: 1 N, the planner's least.
    const std::optional<Eigen::Isometry3d> mark = marker_of(placement_.holes.front(), *patterns_);
    if (mark) {
      PlanAsk r = placement_request(*mark);
      r.camera_distance =
          any_roll_distance(marker_look_radius(patterns_->marker_size(), tuning_.looks.marker_drift), camera_fov()) +
          tuning_.placement.look_further[0];
      r.fixed_base = true;
      r.contact_force = 1.0;
      from(r);
      placement_.look_check = {r.request_id, 0, r};
      send_plan(r);
    }
  }
  motion_ = Motion::kPlaceCheck;
}

// "planned in 23.4 s", for the log.
std::string DrillEngine::placement_time() const {
  std::ostringstream t;
  t.setf(std::ios::fixed);
  t.precision(1);
  t << "planned in " << now_ - placement_.started << " s";
  return t.str();
}

// After a check or a draw: the next draw, the move to the posture chosen, or no move.
void DrillEngine::place_next() {
  const PlacementChoice& c = *placement_.choice;
  switch (c.next()) {
    case PlacementChoice::Next::kCheckStanding:  // not after a check: standing was checked first
    case PlacementChoice::Next::kDraw: {
      const PlacementDraw& d = tuning_.placement.draws[c.draws()];
      std::optional<Eigen::Vector3d> mark;
      if (const std::optional<Eigen::Isometry3d> m = marker_of(placement_.holes.front(), *patterns_))
        mark = m->translation();
      PlanAsk r = placement_request(placement_goal(placement_.holes, mark, d.toward));
      set_hole_task(r, {true, false, 0.0, d.out, placement_.lead}, hole_distance_, hole_depth(), tuning_);
      placement_.draw = r.request_id;
      send_plan(r);
      motion_ = Motion::kPlaceDraw;
      return;
    }
    case PlacementChoice::Next::kStand: {
      if (c.short_of_every_hole() && placement_.lead > tuning_.placement.light_lead) {
        log_line("drill: " + c.summary() + thrust_text(placement_.lead, tuning_.motion) +
                 "; the placement checked again" + thrust_text(tuning_.placement.light_lead, tuning_.motion));
        Placement again;
        again.holes = placement_.holes;
        again.started = placement_.started;
        again.lead = tuning_.placement.light_lead;
        again.choice.emplace(again.holes.size(), tuning_.placement.draws.size());
        placement_ = std::move(again);
        place_check(false);
        return;
      }
      placement_.order = reached_first(placement_.standing_reached);
      placement_.placed = placement_.standing_reached;
      log_line("drill: " + c.summary() + thrust_text(placement_.lead, tuning_.motion) +
               "; the base stays where it stands (" + placement_time() + ")" +
               last_holes(placement_.standing_reached));
      placement_done(true);
      return;
    }
    case PlacementChoice::Next::kMove: {
      const std::size_t k = c.chosen();
      placement_.order = reached_first(placement_.reached[k]);
      placement_.placed = placement_.reached[k];
      log_line("drill: " + c.summary() + thrust_text(placement_.lead, tuning_.motion) +
               "; the whole body to posture " + std::to_string(k + 1) +
               " drawn (" + placement_time() + ")" + last_holes(placement_.reached[k]));
      trajectory_request_ = send_trajectory(placement_.names[k], placement_.bodies[k]);
      motion_ = Motion::kPlaceMove;
      return;
    }
  }
}

// A placement check asked again (its request changed): a new id, stamped now.
void DrillEngine::resend(Placement::Check& c) {
  c.id = next_request_++;
  c.request.request_id = c.id;
  send_plan(c.request);
}

// The placement's state machine (place()): one step a tick of the state it is in.
void DrillEngine::control_placement() {
  if (motion_ == Motion::kPlaceCheck) {
    place_check_step();
    return;
  }
  if (motion_ == Motion::kPlaceDraw) {
    place_draw_step();
    return;
  }
  if (motion_ == Motion::kPlaceMove) {
    place_move_step();
    return;
  }
  if (motion_ == Motion::kPlaceLook) {
    place_look_step();
    return;
  }
  if (motion_ == Motion::kPlaceLookAgain) {
    place_look_again_step();
    return;
  }
  if (motion_ == Motion::kPlaceSee) {
    place_see_step();
    return;
  }
}

// A plan request's final answer (succeeded or failed), or none yet.
std::optional<PlanReply> DrillEngine::answered(std::uint32_t id) const {
  std::optional<PlanReply> r = plan_result(id);
  if (r && (r->state == PlanState::kSucceeded || r->state == PlanState::kFailed)) return r;
  return std::nullopt;
}

// The posture drawn the placement moves to (the first while none is chosen).
std::size_t DrillEngine::chosen_draw() const { return placement_.choice ? placement_.choice->chosen() : 0; }

void DrillEngine::place_check_step() {
  const bool drawn = !placement_.bodies.empty();
  std::size_t reached = 0;
  bool waiting = false;
  std::vector<bool> flags;
  for (Placement::Check& c : placement_.hole_checks) {
    const std::optional<PlanReply> r = answered(c.id);
    if (!r) {
      waiting = true;
      continue;
    }
    if (r->state == PlanState::kFailed && c.attempt < (drawn ? tuning_.placement.last_hole_attempt : 0) &&
        (r->failure == PlanFailure::kUnreachable || r->failure == PlanFailure::kNoPath)) {
      // The hole's next posture further out, as the hole itself will ask (Params::hole.attempts).
      set_hole_task(c.request, at_lead(tuning_.hole.attempts[++c.attempt], placement_.lead), hole_distance_,
                    hole_depth(), tuning_);
      resend(c);
      waiting = true;
      continue;
    }
    reached += r->state == PlanState::kSucceeded;
    flags.push_back(r->state == PlanState::kSucceeded);
  }
  if (waiting) return;
  std::optional<PlanReply> look;
  Placement::Check& l = placement_.look_check;
  if (l.id != 0 && !(look = answered(l.id))) return;
  if (look && look->state == PlanState::kFailed && l.attempt + 1 < tuning_.placement.look_further.size() &&
      (look->failure == PlanFailure::kUnreachable || look->failure == PlanFailure::kNoPath)) {
    l.request.camera_distance +=
        tuning_.placement.look_further[l.attempt + 1] - tuning_.placement.look_further[l.attempt];
    ++l.attempt;
    resend(l);
    return;
  }
  if (!drawn) {
    placement_.choice->standing(reached);
    placement_.standing_reached = flags;
  } else {
    placement_.reached.back() = flags;
    const bool seen = look && look->state == PlanState::kSucceeded && !look->path.samples.empty();
    if (seen) {
      placement_.looks.back() = look->path.samples;
      placement_.look_distances.back() = l.request.camera_distance;
    }
    placement_.choice->drawn(reached, seen);
  }
  place_next();
}

void DrillEngine::place_draw_step() {
  const std::optional<PlanReply> r = answered(placement_.draw);
  if (!r) return;
  placement_.names.push_back(r->path.names);
  placement_.reached.emplace_back(placement_.holes.size(), false);
  placement_.looks.emplace_back();
  placement_.look_distances.push_back(0.0);
  if (r->state == PlanState::kSucceeded && !r->path.samples.empty()) {
    placement_.bodies.push_back(r->path.samples);
    place_check(true);
    return;
  }
  placement_.bodies.emplace_back();
  log_line("drill: no whole-body posture drawn for the placement (" + r->reason + ")");
  placement_.choice->drawn(0, false);
  place_next();
}

void DrillEngine::place_move_step() {
  const std::size_t k = chosen_draw();
  if (!trajectory_ran("the base's placement")) return;
  hole_chain_.push_back({placement_.names[k], placement_.bodies[k]});
  // The base moved: the marker's last sighting no longer places the holes.
  markers_seen_at_.erase(point_.marker);
  if (const std::optional<Sample> s = inputs_.latest_sample()) {
    const PathSample here = sample_here(placement_.names[k], *s, placement_.bodies[k].back());
    double off = 0.0, turn = 0.0;
    for (std::size_t i = 0; i < placement_.names[k].size() && i < here.position.size(); ++i) {
      const double d = here.position[i] - placement_.bodies[k].back().position[i];
      if (placement_.names[k][i] == "base_yaw") turn = std::abs(d);
      else if (placement_.names[k][i] == "base_x" || placement_.names[k][i] == "base_y") off += d * d;
    }
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(1);
    line << "drill: the base placed " << std::sqrt(off) * 1e3 << " mm and " << turn * 1e3
         << " mrad from the posture planned (odometry)";
    log_line(line.str());
  }
  if (placement_.looks[k].empty()) {  // no look was checked (cannot be: kMove needs one)
    placement_done(false);
    return;
  }
  place_look(0);
}

void DrillEngine::place_look_step() {
  const std::size_t k = chosen_draw();
  if (!trajectory_ran("the camera onto the marker from the placement")) return;
  hole_chain_.push_back({placement_.names[k], placement_.looks[k]});
  start_reanchor(Motion::kPlaceSee);
}

void DrillEngine::place_look_again_step() {
  const std::size_t k = chosen_draw();
  const std::optional<PlanReply> r = plan_result(placement_.look_again);
  if (!r) return;
  if (!r->path.samples.empty()) placement_.again_path = r->path;
  if (r->state == PlanState::kSucceeded) {
    if (!placement_.again_path.samples.empty()) hole_chain_.push_back(placement_.again_path);
    start_reanchor(Motion::kPlaceSee);
  } else if (r->state == PlanState::kFailed && r->failure == PlanFailure::kExecutionAborted) {
    motion_ = Motion::kNone;
    motion_outcome_ = Outcome::failed("robot: the camera onto the marker from the placement: " + r->reason);
  } else if (const std::optional<Sample> s = inputs_.latest_sample();
             r->state == PlanState::kFailed && placement_.looks_again == 0 && s) {
    // None from where the base stands: the look checked from the posture planned, its arm
    // path taken with the base where it stands (aimed off by the base's tracking error).
    log_line("drill: no look at marker " + std::to_string(point_.marker) + " from where the base stands (" +
             r->reason + "); the look checked from the posture planned");
    std::vector<PathSample> look = placement_.looks[k];
    const PathSample here = sample_here(placement_.names[k], *s, look.front());
    look.front() = here;
    keep_base(placement_.names[k], here, look);
    placement_.looks[k] = look;
    trajectory_request_ = send_trajectory(placement_.names[k], look);
    motion_ = Motion::kPlaceLook;
  } else if (r->state == PlanState::kFailed) {
    log_line("drill: the camera cannot be turned onto marker " + std::to_string(point_.marker) +
             " further out from the placement (" + r->reason + "); each hole looks for it");
    placement_done(false);
  }
}

void DrillEngine::place_see_step() {
  const std::optional<CameraFrame> view = inputs_.averaged_view(reanchor_since_ns_, tuning_.camera.reanchor_frames);
  if (!view) return;
  // The pattern measured again as a hole's look measures it (its drift to OdometryDrift, the
  // marker's sighting kept for the area's holes).
  if (!remeasure_looked_marker(CameraView{&view->frame, view->world_T_optical})) {
    const std::optional<Eigen::Isometry3d> predicted = marker_of(point_, *patterns_);
    if (predicted && placement_.looks_again + 1 < tuning_.placement.look_further.size()) {
      // Further out, the arm alone from where it stands: more room for the drift.
      place_look(placement_.looks_again + 1);
      std::ostringstream line;
      line.setf(std::ios::fixed);
      line.precision(2);
      line << "drill: marker " << point_.marker << " not seen from the placement's look; the camera "
           << placement_.look_distance << " m out";
      log_line(line.str());
      return;
    }
    log_line("drill: marker " + std::to_string(point_.marker) +
             " not seen from the placement's looks; each hole looks for it");
  }
  placement_done(false);
}

// The camera onto the area's marker placement.look_further[attempt] [m] further out than the look checked
// from the posture drawn, the arm alone from where the robot stands, planned and executed
// (kPlaceLookAgain). The look checked from the posture drawn, replayed with the base where it
// stands, is aimed off by the base's tracking error: a placement's posture can end 40 mm nearer
// the wall than planned, and its checked look then shows the bare wall.
void DrillEngine::place_look(std::size_t attempt) {
  const std::optional<Eigen::Isometry3d> mark = marker_of(point_, *patterns_);
  if (!mark) {
    placement_done(false);
    return;
  }
  placement_.looks_again = attempt;
  placement_.look_distance = placement_.look_distances[placement_.choice->chosen()] + tuning_.placement.look_further[attempt];
  PlanAsk r = placement_request(*mark);
  r.camera_distance = placement_.look_distance;
  r.fixed_base = true;
  r.contact_force = 1.0;
  r.execute = true;
  placement_.look_again = r.request_id;
  placement_.again_path = {};
  send_plan(r);
  motion_ = Motion::kPlaceLookAgain;
}

void DrillEngine::placement_done(bool stood) {
  if (!hole_placing_) {
    motion_ = Motion::kNone;
    motion_outcome_ = Outcome::succeeded();
    return;
  }
  hole_placing_ = false;
  placed_for_ = point_.label;
  placed_lead_.reset();
  if (!stood && !placement_.placed.empty() && placement_.placed.front()) placed_lead_ = placement_.lead;
  placement_ = std::move(area_placement_);
  area_placement_ = Placement{};
  if (stood) {
    // No posture drawn reaches the hole with a look either: the base has not moved, and the
    // hole's last whole-body posture drawn is taken, as without a placement.
    log_line("drill: " + point_.label + ": no placement reaches it with a look at marker " +
             std::to_string(point_.marker) + " either; the last whole-body posture drawn taken");
    checked_look_ = 0;
    move_to_candidate();
    return;
  }
  // The base placed and the marker measured again from there: the hole aligned afresh, the arm
  // alone first, at the thrust the placement reached it with.
  const DrillPoint hole = point_;
  align(hole);
}

// No whole-body posture drawn for a marker hole lets the camera see the marker from its end, so
// after that move the hole would be drilled where odometry puts it: on the generated sites of
// seed 1, 4 holes of 54 were 6.6-8.9 mm off that way (bench_drill_mission). Instead the base is
// placed for the hole alone as an area's placement places it: postures drawn with the bit further
// out, from which the arm alone reaches the hole and the camera the marker; the base moves
// there, the camera measures the marker again (the move's drift), and the hole is aligned from
// there. Planned only until the move: the robot still stands where the hole's attempts left it.
void DrillEngine::place_for_hole() {
  hole_placing_ = true;
  area_placement_ = std::move(placement_);
  placement_ = Placement{};
  placement_.holes = {point_};
  placement_.started = now_;
  placement_.lead = tuning_.hole.attempts[hole_attempt_].lead;
  placement_.choice.emplace(1, tuning_.placement.draws.size());
  // The arm alone does not reach it from where the base stands: the hole's first attempts said so.
  placement_.standing_reached = {false};
  placement_.choice->standing(0);
  place_next();
}

// Aligning a hole: the approach put the drill camera at the working distance (0.6 m), the bit
// about 0.4 m further from the wall than it drills. Stretching the arm that far in Cartesian
// impedance is not checked against anything (with the demo arm it holds the shoulder J2_E at
// its continuous torque, and the safety layer stops the robot), so the planner plans each
// hole's drilling posture: the camera close to the wall on the hole's normal (NSPG with the
// drilling force checked against the torque limits, the whole body moving) and the path
// there; the Cartesian alignment does the last centimetres, the way back is that path reversed.
void DrillEngine::align(const DrillPoint& point) {
  const std::optional<Sample> s = inputs_.latest_sample();
  motion_outcome_.reset();
  if (!s || !rig_) {
    motion_outcome_ = Outcome::failed("no joint state to align from");
    return;
  }
  if (hole_placing_) {  // a hole's placement cut short (a stop): the area's is the one kept
    hole_placing_ = false;
    placement_ = std::move(area_placement_);
    area_placement_ = Placement{};
  }
  point_ = point;
  looked_ = false;
  look_pushed_ = false;
  hole_replanned_ = false;
  body_replans_ = 0;
  tracked_frames_ = 0;
  tracked_.setZero();
  track_since_ns_ = inputs_.newest_stamp();
  // A blob where the area's last re-measure puts it (shift_area: odometry drifted since).
  for (const DrillPoint& p : area_points_) {
    if (p.marker < 0 && p.label == point.label) point_.frame = p.frame;
  }
  // The pattern as its marker was last seen (after a base move), not as first detected.
  if (const auto it = markers_seen_.find(point.marker); it != markers_seen_.end() && patterns_) {
    if (const std::optional<Eigen::Isometry3d> f = hole_of(point, it->second, *patterns_))
      point_.frame = *f;
  }
  const Eigen::VectorXd q = rig_->q(s->joints);
  const Eigen::Isometry3d camera = rig_->camera_in_base(q);
  const double camera_to_tip =
      (rig_->tip_in_base(q).translation() - camera.translation()).dot(camera.linear().col(2));
  PlanAsk r;
  hole_plan_request_ = next_request_++;
  r.request_id = hole_plan_request_;
  r.model_version = static_cast<std::uint32_t>(model_version_);
  r.end_effector = rig_->tool();
  r.goals.push_back(point_.frame);
  r.execute = true;
  // The bit's tip is put on the hole's axis (PlanRequest.tip_distance), so the posture the
  // planner checks is the one the bit drills from; the camera sees the hole from beside it.
  camera_to_tip_ = camera_to_tip;
  hole_distance_ = tuning_.motion.standoff + tuning_.hole.align_margin;
  // The arm alone first (Params::hole.attempts): the base stays where the area's approach put it, so
  // odometry does not drift between holes (3.5 deg over one whole-body move on the demo).
  hole_attempt_ = 0;
  // A hole the area's placement reached at a lighter thrust starts there (the full thrust's
  // attempts would find nothing from the placement, or move the whole body off it).
  for (std::size_t i = 0; i < placement_.holes.size() && i < placement_.placed.size(); ++i) {
    if (placement_.placed[i] && placement_.holes[i].label == point.label && placement_.lead < 1.0)
      hole_attempt_ = first_fixed_at(tuning_, placement_.lead);
  }
  if (placed_for_ == point.label && placed_lead_ && *placed_lead_ < 1.0)
    hole_attempt_ = first_fixed_at(tuning_, *placed_lead_);
  drilling_lead_ = 1.0;
  body_draws_ = 0;
  checked_look_ = 0;
  checked_path_ = {};
  set_hole_task(r, tuning_.hole.attempts[hole_attempt_], hole_distance_, hole_depth(), tuning_);
  hole_request_ = r;
  hole_request_write(true);  // the arm waits where the last hole or the placement left it
  hole_path_ = {};
  motion_ = Motion::kApproachHole;
}

// hole_request_ to the planner. A marker hole's whole-body posture is only planned: before the
// base moves, check_look() asks whether the camera can be turned onto the marker from it.
void DrillEngine::hole_request_write(bool may_rest) {
  hole_request_.execute = !(point_.marker >= 0 && patterns_ && !hole_request_.fixed_base);
  send_plan(hole_request_, may_rest);
}

double DrillEngine::hole_depth() const { return mission_ ? mission_->depth : tuning_.hole.default_depth; }

// "the bit 0.07 m", "the bit (reach unchecked) 0.07 m" or "the camera 0.23 m" (from the wall),
// for the log.
std::string hole_task_text(const PlanAsk& r) {
  std::ostringstream t;
  if (r.tip_distance > 0.0)
    t << "the bit " << (r.tip_reach > 0.0 ? "" : "(reach unchecked) ") << r.tip_distance << " m";
  else
    t << "the camera " << r.camera_distance << " m";
  return t.str();
}

void DrillEngine::start_align(const Sample& s) {
  base_T_world_ = rig_->base_in_world(s.odometry).inverse();
  drill_motion_ = DrillMotion(drilling_lead_ < 1.0 ? light_drilling(tuning_.motion, drilling_lead_)
                                                  : tuning_.motion);
  if (drilling_lead_ < 1.0)
    log_line("drill: " + point_.label + ": drilled" + thrust_text(drilling_lead_, tuning_.motion) +
             ": " + light_why_);
  drill_motion_.start_align(base_T_world_ * point_.frame, rig_->tip_in_base(rig_->q(s.joints)),
                            robot_time(s));
  motion_ = Motion::kAlign;
  servo_since_ns_ = inputs_.newest_stamp();
}

Outcome DrillEngine::alignment() { return motion_outcome_ ? *motion_outcome_ : Outcome::running(); }

void DrillEngine::drill(const DrillPoint& point, double depth) {
  const std::optional<Sample> s = inputs_.latest_sample();
  motion_outcome_.reset();
  if (!s || !rig_) {
    motion_outcome_ = Outcome::failed("no joint state to drill from");
    return;
  }
  point_ = point;
  drill_motion_.start_drill(depth, point.servo, rig_->tip_in_base(rig_->q(s->joints)), robot_time(*s));
  motion_ = Motion::kDrill;
}

Outcome DrillEngine::drilling() { return motion_outcome_ ? *motion_outcome_ : Outcome::running(); }

void DrillEngine::retract() {
  const std::optional<Sample> s = inputs_.latest_sample();
  motion_outcome_.reset();
  if (!s || !rig_) {
    motion_outcome_ = Outcome::failed("no joint state to retract from");
    return;
  }
  drill_motion_.start_retract(rig_->tip_in_base(rig_->q(s->joints)), robot_time(*s));
  motion_ = Motion::kRetractOut;
}

Outcome DrillEngine::retraction() { return motion_outcome_ ? *motion_outcome_ : Outcome::running(); }

void DrillEngine::stop() {
  if (nav_request_ != 0) sink_.cancel_navigation();
  nav_request_ = 0;
  home_request_ = 0;
  const bool at_hole = motion_ == Motion::kAlign || motion_ == Motion::kDrill || motion_ == Motion::kRetractOut;
  motion_ = Motion::kNone;
  unacknowledged_.clear();  // not sent again: a planner taking it now would move the robot
  held_requests_.clear();
  rest_request_ = 0;
  rest_return_ = 0;
  rest_since_ = -1.0;
  if (at_hole && !shutting_down_ && leave_allowed_ && start_leave()) return;
  send_hold();
}

bool DrillEngine::start_leave() {
  const std::optional<Sample> s = inputs_.latest_sample();
  if (!s || !rig_) return false;
  const Eigen::Isometry3d tip = rig_->tip_in_base(rig_->q(s->joints));
  const double depth = drill_motion_.depth_of(tip);
  drill_motion_.start_retract(tip, robot_time(*s));
  if (drill_motion_.phase() != DrillMotion::Phase::kRetracting) return false;  // clear of the wall
  motion_ = Motion::kLeave;
  motion_outcome_.reset();
  leave_paused_ = !inputs_.safety_running();
  std::ostringstream line;
  line.setf(std::ios::fixed);
  line.precision(1);
  line << "drill: leaving the wall: the bit " << std::abs(depth) * 1e3 << " mm "
       << (depth > 0.0 ? "behind" : "in front of") << " the surface, pulled back along the hole's axis to "
       << tuning_.motion.standoff * 1e3 << " mm in front of it"
       << (leave_paused_ ? " once the safety stop is reset" : "");
  log_line(line.str());
  return true;
}

// The leave's control period: the retract's reference on the robot's clock while the safety
// layer lets the robot move; a safety stop holds the robot, and the retract starts again from
// where the tip is when it is reset. Out (or out of time): the arm holds.
void DrillEngine::leave_step() {
  const std::optional<Sample> s = inputs_.latest_sample();
  if (!s || !rig_) {
    motion_ = Motion::kNone;
    return;
  }
  if (!inputs_.safety_running()) {
    leave_paused_ = true;
    return;
  }
  const Eigen::Isometry3d tip = rig_->tip_in_base(rig_->q(s->joints));
  if (leave_paused_) {
    leave_paused_ = false;
    drill_motion_.start_retract(tip, robot_time(*s));
    log_line("drill: the safety stop is reset: leaving the wall now");
  }
  const CartesianReference r = drill_motion_.update(tip, robot_time(*s));
  if (drill_motion_.phase() == DrillMotion::Phase::kRetracting) {
    send_cartesian(r);
    return;
  }
  if (drill_motion_.phase() == DrillMotion::Phase::kFailed) {
    log_line("drill: leaving the wall failed: " + drill_motion_.reason() + "; the arm holds where it is");
  } else {
    log_line("drill: the bit is out of the wall; the arm holds there");
  }
  motion_ = Motion::kNone;
  send_hold();
}

// The arm holds where it is (position mode at the measured positions); the base stops.
void DrillEngine::send_hold() {
  const std::optional<Sample> s = inputs_.latest_sample();
  if (!s || !rig_) return;
  JointPositions held;
  const model::ChainInfo* arm = nullptr;
  try {
    arm = &rig_->model().arm();
  } catch (const model::ModelError&) {
    return;
  }
  for (const std::string& joint : arm->joints) {
    const auto it = std::find(s->joints.names.begin(), s->joints.names.end(), joint);
    if (it == s->joints.names.end()) continue;
    held.names.push_back(joint);
    held.positions.push_back(s->joints.positions[static_cast<std::size_t>(it - s->joints.names.begin())]);
  }
  sink_.hold(static_cast<std::uint32_t>(model_version_), held);
}

void DrillEngine::send_cartesian(const CartesianReference& r) {
  sink_.cartesian(static_cast<std::uint32_t>(model_version_), rig_->tcp_frame(), r);
}

void DrillEngine::start_reanchor(Motion next) {
  reanchor_since_ns_ = inputs_.newest_stamp();
  motion_ = next;
}

// The whole body moved to the hole's drilling posture: the arm alone turns the camera onto the
// hole's mark (an ArUco hole's marker, a blob hole's blob as predicted; looks.attempts), where the
// hole is measured again.
void DrillEngine::look_at_hole(std::size_t first) {
  looked_ = true;
  if (!prepare_look()) {
    start_reanchor(Motion::kReanchor);
    return;
  }
  request_look(first);
}

// look_goal_, look_reach_ and hole_reached_ for a look at point_'s mark from hole_request_'s
// posture; false when the hole has no mark to look at.
bool DrillEngine::prepare_look() {
  std::optional<Eigen::Isometry3d> mark;
  if (point_.marker < 0)
    mark = point_.frame;
  else if (patterns_)
    mark = marker_of(point_, *patterns_);
  if (!mark) return false;
  look_goal_ = *mark;
  look_reach_ = 0.0;
  if (point_.marker < 0) {
    // The hole's blob and its nearest neighbour framed together, room left for the drift.
    if (const std::optional<BlobPairView> pair = blob_pair_view(point_, area_points_, tuning_.blobs.set_look_drift)) {
      look_goal_.translation() = pair->centre;
      look_reach_ = pair->radius;
    }
  } else if (patterns_) {
    // The whole marker in view, room left for the drift (marker_look_radius). The camera's
    // distance at the hole's posture alone puts the camera 0.22 m from the marker on morphology
    // A, where the marker fills the image past its edge: it is then not seen, and the hole is
    // drilled where odometry puts it.
    look_reach_ = marker_look_radius(patterns_->marker_size(), tuning_.looks.marker_drift);
  }
  // The camera's distance at the hole's posture.
  hole_reached_ = hole_request_.tip_distance > 0.0 ? hole_request_.tip_distance + camera_to_tip_
                                                     : hole_request_.camera_distance;
  return true;
}

void DrillEngine::shift_area(const Eigen::Vector3d& shift) {
  for (DrillPoint& p : area_points_) {
    if (p.marker < 0) p.frame.translation() += shift;
  }
}

// The blobs a view shows, in the predicted hole's frame (x, y on the wall, z out of it) [mm],
// for the log of a re-measure.
std::string blobs_seen(const CameraView& view, const Eigen::Isometry3d& predicted) {
  std::ostringstream t;
  t.setf(std::ios::fixed);
  t.precision(1);
  const std::vector<Blob> blobs = detect_blobs(*view.frame);
  t << blobs.size() << " blob" << (blobs.size() == 1 ? "" : "s") << " in view";
  for (const Blob& b : blobs) {
    const Eigen::Vector3d p = predicted.inverse() * (view.world_T_optical * b.position);
    t << " (" << p.x() * 1e3 << ", " << p.y() * 1e3 << ", " << p.z() * 1e3 << ")";
  }
  t << " mm from the prediction";
  return t.str();
}

void DrillEngine::track_area() {
  if (point_.marker >= 0 || hole_request_.fixed_base || area_points_.empty()) return;
  // The newest only: detection costs, and the drift is slow.
  const std::optional<CameraFrame> newest = inputs_.newest_frame(track_since_ns_);
  if (!newest) return;
  track_since_ns_ = newest->stamp_ns;
  const std::optional<AreaShift> shift =
      blob_shift(CameraView{&newest->frame, newest->world_T_optical}, area_points_, tuning_.blobs.match,
                 tuning_.blobs.track_window, tuning_.blobs.set_shift);
  if (!shift) return;
  shift_area(shift->by);
  point_.frame.translation() += shift->by;
  tracked_ += shift->by;
  ++tracked_frames_;
}

// The camera looks at the hole: back onto the whole body's posture (the way back from the hole
// then skips the look), where the alignment starts.
void DrillEngine::back_to_posture(const Sample& s, Motion next) {
  const PlannedPath look = hole_chain_.back();
  hole_chain_.pop_back();
  look_pushed_ = false;
  const PlannedPath& p = hole_chain_.back();
  // The look's planned path backwards (drill::back_from_look), not straight across.
  if (look.names == p.names && look.samples.size() >= 2) {
    trajectory_request_ = send_trajectory(p.names, back_from_look(look, p, s, path_timing(tuning_)));
  } else {
    trajectory_request_ = send_trajectory(p.names, settle_path(p, sample_here(p.names, s, p.samples.back())));
  }
  motion_ = next;
}

std::vector<PathSample> DrillEngine::settle_path(const PlannedPath& p, const PathSample& here) {
  const Settle settle = drill::settle_path(p, here, path_timing(tuning_));
  if (settle.base_kept && (settle.base_off > 0.002 || settle.base_turn > 0.002)) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line << std::setprecision(1) << "drill: " << point_.label << ": the base stays where it stands, "
         << settle.base_off * 1e3 << " mm and " << settle.base_turn * 1e3
         << " mrad from the posture's; the arm alone onto it";
    log_line(line.str());
  }
  return settle.samples;
}

void DrillEngine::replan_hole(bool reach, double further, double lead) {
  set_hole_task(hole_request_, {reach, true, 0.0, further, lead}, hole_distance_, hole_depth(),
                tuning_);
  request_hole_posture();
}

// The hole's posture (hole_request_'s task) asked for again at point_, where it was measured last.
void DrillEngine::request_hole_posture() {
  hole_plan_request_ = next_request_++;
  hole_request_.request_id = hole_plan_request_;
  hole_request_.goals.clear();
  hole_request_.goals.push_back(point_.frame);
  hole_request_write();
  hole_path_ = {};
  motion_ = Motion::kApproachHole;
}

// The whole body's posture planned again, at the hole as measured again: from here (the look
// posture or the posture reached), with the request that reached it. The hole is then measured
// again from there, looked at again (the base moved), and its arm-alone posture planned again.
void DrillEngine::replan_body() {
  ++body_replans_;
  hole_replanned_ = false;
  looked_ = false;
  look_pushed_ = false;
  hole_attempt_ = body_attempt_;
  body_draws_ = 0;
  checked_look_ = 0;
  checked_path_ = {};
  tracked_frames_ = 0;
  tracked_.setZero();
  track_since_ns_ = inputs_.newest_stamp();
  set_hole_task(hole_request_, tuning_.hole.attempts[hole_attempt_], hole_distance_, hole_depth(),
                tuning_);
  request_hole_posture();
}

// After a look at the hole's mark: its drilling posture planned again for the arm alone (the
// base stands where the whole body put it), at the distance that reached it, for the hole where
// the look measured it.
void DrillEngine::replan_after_look() {
  const HoleAttempt reached = tuning_.hole.attempts[hole_attempt_];
  const std::size_t from = hole_attempt_;
  hole_attempt_ = 0;
  while (hole_attempt_ + 1 < tuning_.hole.attempts.size() &&
         !(tuning_.hole.attempts[hole_attempt_].fixed_base && tuning_.hole.attempts[hole_attempt_].reach == reached.reach &&
           tuning_.hole.attempts[hole_attempt_].lead == reached.lead &&
           tuning_.hole.attempts[hole_attempt_].further >= reached.further - 1e-6))
    ++hole_attempt_;
  if (hole_attempt_ < from && !tuning_.hole.attempts[hole_attempt_].fixed_base) hole_attempt_ = from;
  replan_hole(reached.reach, reached.further, reached.lead);
}

// The camera's smaller field-of-view angle: from its newest frame's intrinsics, else the
// configured one.
double DrillEngine::camera_fov() const {
  const std::optional<hardware::CameraIntrinsics> k = inputs_.intrinsics();
  return k ? smaller_fov(*k) : tuning_.camera.fov;
}

void DrillEngine::request_look(std::size_t attempt) {
  look_attempt_ = attempt;
  PlanAsk r = look_plan(attempt);
  look_request_ = next_request_++;
  r.request_id = look_request_;
  r.execute = true;
  send_plan(r);
  look_path_ = {};
  motion_ = Motion::kLookAtHole;
}

// The look of looks.attempts[attempt] asked from the end of the whole body's candidate posture,
// planned only.
void DrillEngine::check_look(std::size_t attempt) {
  check_attempt_ = attempt;
  PlanAsk r = look_plan(attempt);
  check_request_ = next_request_++;
  r.request_id = check_request_;
  r.execute = false;
  r.start_names = body_candidate_.names;
  r.start_position = body_candidate_.samples.back().position;
  send_plan(r);
  motion_ = Motion::kCheckLook;
}

// The request turning the camera onto look_goal_ (looks.attempts[attempt]), the arm alone; its id,
// start and execution are the caller's.
PlanAsk DrillEngine::look_plan(std::size_t attempt) const {
  PlanAsk r = hole_request_;
  r.goals.clear();
  Eigen::Isometry3d goal = look_goal_;
  double distance = hole_reached_ + tuning_.looks.attempts[attempt].further;
  const double fov = camera_fov();
  if (point_.marker >= 0 && look_reach_ > 0.0) {
    // The whole marker in view first, then further out with each attempt.
    distance = std::max(hole_reached_, any_roll_distance(look_reach_, fov)) + tuning_.looks.attempts[attempt].further;
  } else if (look_reach_ > 0.0) {
    distance = std::max(distance, any_roll_distance(look_reach_, fov));
  }
  if (tuning_.looks.attempts[attempt].between) {
    goal.translation() = 0.5 * (look_goal_.translation() + point_.frame.translation());
    // The planner leaves the camera's roll about its axis free: the marker (its centre half
    // the hole's distance from the goal, plus its half-diagonal) must fit in the image's
    // smaller half-angle whichever way the image turns. Nearer, such a look does not see the
    // marker (scenario 3's rows).
    const double reach = (goal.translation() - look_goal_.translation()).norm() +
                         (patterns_ ? marker_look_radius(patterns_->marker_size(), 0.0) : 0.0);
    distance = std::max(distance, any_roll_distance(reach, fov));
  }
  const LookAttempt& attempt_row = tuning_.looks.attempts[attempt];
  r.view_slant = 0.0;
  r.view_near = 0.0;
  if (attempt_row.slant > 0.0 && !attempt_row.between) {
    // From any side: as near as frames the mark whichever way the camera rolls, out to
    // `further` beyond the posture's distance; the planner takes the axis through the mark.
    r.view_slant = attempt_row.slant;
    r.view_near = look_reach_ > 0.0 ? any_roll_distance(look_reach_, fov) : 0.0;
    distance = std::max(hole_reached_, r.view_near) + attempt_row.further;
  }
  r.goals.push_back(goal);
  r.tip_distance = 0.0;
  r.tip_reach = 0.0;
  r.camera_distance = distance;
  r.fixed_base = true;
  r.base_travel = 0.0;
  return r;
}

// A blob hole measured again with the camera turned onto it; true when the arm was sent back
// onto the whole body's posture (else the posture is planned again, the arm alone).
bool DrillEngine::remeasure_looked_blob(const CameraView& camera) {
  // The camera on the blob's axis sees its neighbours too: the area matched as a set.
  Eigen::Isometry3d predicted = point_.frame;
  if (const std::optional<AreaShift> shift =
          blob_shift(camera, area_points_, tuning_.blobs.match, tuning_.blobs.reanchor_distance, tuning_.blobs.set_shift))
    predicted.translation() += shift->by;
  // Within blobs.match of the prediction: no neighbour is taken for it.
  if (const std::optional<Eigen::Isometry3d> blob = track_blob(camera, predicted, tuning_.blobs.match)) {
    const Eigen::Vector3d moved = blob->translation() - point_.frame.translation();
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(1);
    line << "drill: " << point_.label
         << ": the blob seen again with the camera on it after the base moved: "
         << moved.norm() * 1e3 << " mm from where odometry put it ("
         << blobs_seen(camera, point_.frame) << ")";
    log_line(line.str());
    hole_seen_again(blob->translation());
    shift_area(moved);
    point_.frame = *blob;
    const std::optional<Sample> s = inputs_.latest_sample();
    if (moved.norm() <= tuning_.hole.replan_shift && look_pushed_ && hole_chain_.size() > 1 && s) {
      // Where the whole body's posture was planned for: back onto it, no new posture (the
      // arm waiting in the look posture while one is sought holds J3_E at its continuous
      // torque long enough for a safety stop).
      back_to_posture(*s);
      return true;
    }
  } else {
    log_line("drill: " + point_.label +
             ": the blob not seen from the look posture; measured from its drilling posture");
    keep_unseen_view(camera, predicted.translation());
  }
  // Without a posture for the arm alone there, the arm goes back onto the whole body's.
  hole_replanned_ = true;
  return false;
}

// An ArUco hole's pattern measured again with the camera turned onto its marker.
// False when the marker was not seen.
bool DrillEngine::remeasure_looked_marker(const CameraView& camera) {
  std::optional<Eigen::Isometry3d> marker;
  try {
    if (patterns_)
      marker = find_marker(camera, point_.marker,
                           marker_of(point_, *patterns_).value_or(point_.frame).translation(),
                           *patterns_);
  } catch (const DrillError&) {
    marker.reset();
  }
  std::optional<Eigen::Isometry3d> hole;
  if (marker) hole = hole_of_seen_marker(point_, *marker, *patterns_);
  if (!hole && patterns_)
    keep_unseen_view(camera, marker_of(point_, *patterns_).value_or(point_.frame).translation());
  if (hole) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(1);
    line << "drill: " << point_.label << ": marker " << point_.marker
         << " seen again after the base moved: the hole is "
         << (hole->translation() - point_.frame.translation()).norm() * 1e3
         << " mm from where odometry put it";
    log_line(line.str());
    hole_seen_again(hole->translation());
    point_.frame = *hole;
    if (const std::optional<Eigen::Isometry3d> m = marker_of(point_, *patterns_))
      markers_seen_[point_.marker] = *m;
    markers_seen_at_[point_.marker] = now_;
    return true;
  }
  return false;
}

void DrillEngine::keep_unseen_view(const CameraView& camera, const Eigen::Vector3d& mark) {
  if (params_.unseen_frames_dir.empty() || camera.frame == nullptr) return;
  // One file per view: mission, hole label (spaces to '-'), a count over the service's life.
  std::string label = point_.label;
  std::replace_if(label.begin(), label.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); }, '-');
  const std::string path = params_.unseen_frames_dir + "/" + std::to_string(mission_id_) + "-" +
                           label + "-" + std::to_string(++unseen_views_) + ".png";
  std::optional<Eigen::Vector2d> pixel;
  const Eigen::Vector3d in_optical = camera.world_T_optical.inverse() * mark;
  if (in_optical.z() > 0.0) pixel = project(camera.frame->intrinsics, in_optical);
  try {
    write_view_png(*camera.frame, path, pixel);
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(3);
    line << "drill: " << point_.label << ": the view written to " << path << " (the mark expected "
         << in_optical.z() << " m out, crossed)";
    log_line(line.str());
  } catch (const DrillError& e) {
    log_line("drill: " + point_.label + ": the view not kept: " + e.what());
  }
}

// The latest result of plan request `id`, if any has come.
std::optional<PlanReply> DrillEngine::plan_result(std::uint32_t id) const { return inputs_.plan(id); }

// The whole body's candidate posture (body_candidate_) sent to the robot by the drill.
void DrillEngine::move_to_candidate() {
  trajectory_request_ = send_trajectory(body_candidate_.names, body_candidate_.samples);
  motion_ = Motion::kBodyToHole;
}

// The drill's own trajectory (trajectory_request_): true once the robot ran it; refused or
// aborted, the hole fails ("robot: <what>: <reason>").
bool DrillEngine::trajectory_ran(const std::string& what) {
  const std::optional<MotionReply> status = inputs_.trajectory(trajectory_request_);
  if (!status || status->progress == Progress::kRunning) return false;
  if (status->progress == Progress::kSucceeded) return true;
  motion_outcome_ = Outcome::failed("robot: " + what + ": " + status->reason);
  motion_ = Motion::kNone;
  return false;
}

// The hole's posture reached (the planner's path or the drill's own, kBodyToHole): the hole is
// measured again, from a look at its mark or from the posture.
void DrillEngine::posture_reached() {
  // The posture holds the thrust it was checked with: drilled from it (or from the posture
  // it leads to) at that thrust.
  drilling_lead_ = lead_checked(tuning_, hole_request_);
  light_why_ = "the arm's torques hold no more in any posture found";
  if (!hole_request_.fixed_base) {
    body_attempt_ = hole_attempt_;
    body_goal_ = hole_request_.goals.front().translation();
  }
  if (tracked_frames_ > 0) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(1);
    line << "drill: " << point_.label << ": the area's blobs followed in " << tracked_frames_
         << " camera frames while the base moved: odometry drifted " << tracked_.norm() * 1e3
         << " mm";
    log_line(line.str());
    tracked_frames_ = 0;
    tracked_.setZero();
  }
  const auto seen_at = markers_seen_at_.find(point_.marker);
  const bool stale = seen_at == markers_seen_at_.end() || now_ - seen_at->second > tuning_.looks.marker_stale;
  const std::optional<Sample> s = inputs_.latest_sample();
  if (point_.marker >= 0 && !looked_ && !hole_request_.fixed_base && s &&
      !checked_path_.samples.empty() && prepare_look()) {
    // The look check_look() planned from the posture: the planner's look postures are drawn at
    // random, and a new request from here may find none where the check found one. It
    // starts where the robot stands, a tracking error from the planned posture.
    looked_ = true;
    // The arm alone: the base keeps the pose it stands at, not the one the check started from.
    std::vector<PathSample> path = checked_path_.samples;
    const PathSample here = sample_here(checked_path_.names, *s, checked_path_.samples.front());
    path.front() = here;
    keep_base(checked_path_.names, here, path);
    trajectory_request_ = send_trajectory(checked_path_.names, path);
    motion_ = Motion::kCheckedLook;
  } else if (point_.marker >= 0 && !looked_ && (!hole_request_.fixed_base || stale)) {
    look_at_hole(hole_request_.fixed_base ? 0 : checked_look_);
  } else {
    // The base moved: measure the hole again in frames taken from here.
    start_reanchor(Motion::kReanchor);
  }
}

// Every control period while a hole is worked on: the servo's new estimate of the blob from
// each new camera frame, the motion's reference to the robot, and the phase's outcome.
// The drilling motion's state machine: one step a tick of the state it is in; the Cartesian
// phases (align, drill, retract) last.
void DrillEngine::control_motion() {
  if (motion_ == Motion::kNone || motion_outcome_) return;
  if (motion_ == Motion::kLeave) {
    leave_step();
    return;
  }
  if (motion_ >= Motion::kPlaceCheck) {
    control_placement();
    return;
  }
  if (motion_ == Motion::kApproachHole) {
    hole_posture_step();
    return;
  }
  if (motion_ == Motion::kCheckLook) {
    check_look_step();
    return;
  }
  if (motion_ == Motion::kBodyToHole) {
    body_to_hole_step();
    return;
  }
  if (motion_ == Motion::kCheckedLook) {
    checked_look_step();
    return;
  }
  if (motion_ == Motion::kLookAtHole) {
    look_at_hole_step();
    return;
  }
  if (motion_ == Motion::kLookReanchor) {
    look_reanchor_step();
    return;
  }
  if (motion_ == Motion::kBackThenReplan) {
    back_then_replan_step();
    return;
  }
  if (motion_ == Motion::kReanchor) {
    reanchor_step();
    return;
  }
  if (motion_ == Motion::kBackForLook) {
    back_for_look_step();
    return;
  }
  if (motion_ == Motion::kSettle || motion_ == Motion::kBackToPosture) {
    settle_step();
    return;
  }
  cartesian_step();
}

// The Cartesian phases (DrillMotion): the hole followed as the base creeps, the blob servoed, the
// reference sent; out of the hole, back onto the drilling posture.
void DrillEngine::cartesian_step() {
  const std::optional<Sample> s = inputs_.latest_sample();
  if (!s) return;
  {
    // The hole stays where the world has it as the base moves: the wheels' velocity loops
    // yield to the drilling's steady thrust, and a base creeping back takes the hole's depth
    // with it (on morphology A a hole can end 12.4 mm deep where the arm advanced 30 mm).
    const Eigen::Isometry3d now_T_world = rig_->base_in_world(s->odometry).inverse();
    drill_motion_.move_base(now_T_world * base_T_world_.inverse());
    base_T_world_ = now_T_world;
  }
  if (point_.servo && (motion_ == Motion::kAlign || motion_ == Motion::kDrill)) {
    for (const CameraFrame& f : inputs_.frames_since(servo_since_ns_)) {
      servo_since_ns_ = f.stamp_ns;
      const Eigen::Isometry3d world_hole = base_T_world_.inverse() * drill_motion_.hole();
      const std::optional<Eigen::Isometry3d> seen = track_blob(
          CameraView{&f.frame, f.world_T_optical}, world_hole, tuning_.motion.servo_jump);
      if (seen) drill_motion_.observe(base_T_world_ * *seen);
    }
  }
  if (motion_ == Motion::kDrill) fold_thrust();
  const CartesianReference r = drill_motion_.update(rig_->tip_in_base(rig_->q(s->joints)), robot_time(*s));
  send_cartesian(r);
  if (drill_motion_.phase() == DrillMotion::Phase::kFailed) {
    motion_outcome_ = Outcome::failed(drill_motion_.reason());
    motion_ = Motion::kNone;
  } else if (drill_motion_.phase() == DrillMotion::Phase::kDone && motion_ == Motion::kRetractOut &&
             !hole_chain_.empty()) {
    // Out of the hole, the arm goes back onto the drilling posture the planner checked: the
    // Cartesian phases leave it a little off (up to 0.1 rad on the demo's arm, two of its links
    // then inside each other by the planner's shapes), and the next hole is planned from here.
    const PlannedPath& p = hole_chain_.back();
    const PathSample here = sample_here(p.names, *s, p.samples.back());
    const std::vector<PathSample> settle = settle_path(p, here);
    const PathSample& end = settle.back();
    const double t = end.time;
    if (t > tuning_.paths.settle_min) {
      std::ostringstream line;
      line << "drill: " << point_.label << ": back onto the drilling posture over " << t << " s";
      std::size_t far = 0;
      for (std::size_t i = 1; i < p.names.size() && i < here.position.size(); ++i) {
        if (std::abs(end.position[i] - here.position[i]) > std::abs(end.position[far] - here.position[far])) far = i;
      }
      if (far < p.names.size() && far < here.position.size())
        line << " (" << p.names[far] << " from " << here.position[far] << " to " << end.position[far] << ")";
      log_line(line.str());
    }
    trajectory_request_ = send_trajectory(p.names, settle);
    motion_ = Motion::kSettle;
  } else if (drill_motion_.phase() == DrillMotion::Phase::kDone) {
    if (motion_ == Motion::kDrill && drill_motion_.contact()) {
      std::ostringstream line;
      line.setf(std::ios::fixed);
      line.precision(1);
      line << "drill: " << point_.label << ": drilled " << drill_motion_.reached() * 1e3
           << " mm from where the bit met the wall, " << drill_motion_.contact_offset() * 1e3
           << " mm behind the surface the camera measured";
      log_line(line.str());
    }
    motion_outcome_ = Outcome::succeeded();
    // Keep holding the reference until the next motion (the loop re-sends the last one).
  }
}

void DrillEngine::hole_posture_step() {
  const std::optional<PlanReply> r = plan_result(hole_plan_request_);
  track_area();
  if (!r) return;
  // The trajectory comes with PLANNED and the execution updates; SUCCEEDED may arrive alone.
  if (!r->path.samples.empty()) hole_path_ = r->path;
  if (r->state == PlanState::kSucceeded && !hole_path_.samples.empty() && hole_request_.execute)
    hole_chain_.push_back(hole_path_);
  if (r->state == PlanState::kFailed && r->failure == PlanFailure::kExecutionAborted) {
    // The robot stopped on the way (a safety stop, its trajectory refused): the hole fails. No
    // other posture is asked for, and nothing is aligned from wherever the arm stopped.
    motion_outcome_ = Outcome::failed("planner: the hole's drilling posture: " + r->reason);
    motion_ = Motion::kNone;
    return;
  }
  if (r->state == PlanState::kFailed && hole_replanned_) {
    no_posture_after_remeasure(*r);
    return;
  }
  if (r->state == PlanState::kFailed &&
      (r->failure == PlanFailure::kUnreachable || r->failure == PlanFailure::kNoPath) &&
      hole_attempt_ + 1 < tuning_.hole.attempts.size()) {
    next_hole_attempt(*r);
  } else if (r->state == PlanState::kFailed) {
    motion_outcome_ = Outcome::failed("planner: the hole's drilling posture: " + r->reason);
    motion_ = Motion::kNone;
  } else if (r->state == PlanState::kSucceeded && !hole_request_.execute) {
    // Planned only (a marker hole's whole body): is a look at the marker possible from there?
    body_candidate_ = hole_path_;
    checked_path_ = {};
    ++body_draws_;
    if (body_candidate_.samples.empty() || !prepare_look()) {
      move_to_candidate();
    } else {
      check_look(0);
    }
  } else if (r->state == PlanState::kSucceeded) {
    posture_reached();
  }
}

// The hole's posture planned again after its re-measure found none for the arm alone: the whole
// body's posture once more (up to hole.body_replans), or the alignment from the posture reached.
void DrillEngine::no_posture_after_remeasure(const PlanReply& r) {
  const std::optional<Sample> s = inputs_.latest_sample();
  if (!s) return;
  const double shift = (point_.frame.translation() - body_goal_).norm();
  if (body_replans_ < tuning_.hole.body_replans && shift > tuning_.hole.replan_shift) {
    // Planned again after the re-measure, the arm alone found none: the whole body's
    // posture once more, for the hole where the camera saw it. Aligning from the posture
    // reached would stretch the arm that far unchecked: on the demo, a blob measured again
    // 34 mm away holds J3_E past its continuous torque while drilling (a safety stop).
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(1);
    line << "drill: " << point_.label << ": no posture for the arm alone at the hole measured "
         << "again " << shift * 1e3 << " mm from where the whole body's posture was planned ("
         << r.reason << "); the whole body's posture planned again for it";
    log_line(line.str());
    replan_body();
    return;
  }
  // The alignment's Cartesian move covers what is left of the shift.
  log_line("drill: " + point_.label + ": no posture for the arm alone at the hole measured " +
           "again (" + r.reason + "); aligning from the whole body's posture");
  if (shift > tuning_.hole.replan_shift && drilling_lead_ > tuning_.hole.lightest_lead) {
    // Past the posture the planner checked the torques of: the lightest thrust. Across
    // 26 mm at full thrust morphology A's J2_E goes past its continuous torque.
    std::ostringstream why;
    why.setf(std::ios::fixed);
    why.precision(1);
    why << "the alignment reaches " << shift * 1e3 << " mm past the posture checked";
    light_why_ = why.str();
    drilling_lead_ = tuning_.hole.lightest_lead;
  }
  if (looked_ && look_pushed_ && hole_chain_.size() > 1) {
    back_to_posture(*s);
    return;
  }
  start_align(*s);
}

// No posture for this attempt: the hole's next attempt (hole.attempts) asked.
void DrillEngine::next_hole_attempt(const PlanReply& r) {
  const double was_lead = tuning_.hole.attempts[hole_attempt_].lead;
  const HoleAttempt& next = tuning_.hole.attempts[++hole_attempt_];
  std::ostringstream line;
  const auto who = [](bool fixed, double travel) {
    std::ostringstream w;
    w << (fixed ? "the arm alone" : "the whole body");
    if (!fixed && travel > 0.0) w << " (the base within " << travel << " m and rad)";
    return w.str();
  };
  line << "drill: " << point_.label << ": no drilling posture for "
       << who(hole_request_.fixed_base, hole_request_.base_travel) << " with "
       << hole_task_text(hole_request_) << " from the wall" << thrust_text(was_lead, tuning_.motion)
       << " (" << r.reason << "); asking for " << who(next.fixed_base, next.base_travel)
       << " with ";
  hole_plan_request_ = next_request_++;
  hole_request_.request_id = hole_plan_request_;
  set_hole_task(hole_request_, next, hole_distance_, hole_depth(), tuning_);
  line << hole_task_text(hole_request_) << thrust_text(next.lead, tuning_.motion);
  log_line(line.str());
  body_draws_ = 0;
  hole_request_write(!look_pushed_);  // a look's path stays the last of hole_chain_
}

void DrillEngine::check_look_step() {
  const std::optional<PlanReply> r = plan_result(check_request_);
  if (!r || (r->state != PlanState::kSucceeded && r->state != PlanState::kFailed)) return;
  const std::string marker = "marker " + std::to_string(point_.marker);
  if (r->state == PlanState::kSucceeded) {
    checked_look_ = check_attempt_;
    checked_path_ = r->path;
    if (body_draws_ > 1)
      log_line("drill: " + point_.label + ": the camera can be turned onto " + marker +
               " from the whole body's posture drawn on try " + std::to_string(body_draws_) +
               " of " + std::to_string(tuning_.hole.body_draws));
  } else if (check_attempt_ + 1 < tuning_.looks.attempts.size()) {
    check_look(check_attempt_ + 1);
    return;
  } else if (body_draws_ < tuning_.hole.body_draws) {
    log_line("drill: " + point_.label + ": the camera could not be turned onto " + marker +
             " from the whole body's posture drawn (" + r->reason + "); another drawn");
    hole_plan_request_ = next_request_++;
    hole_request_.request_id = hole_plan_request_;
    hole_request_write();
    hole_path_ = {};
    motion_ = Motion::kApproachHole;
    return;
  } else if (tuning_.hole.place_unseen && placed_for_ != point_.label && patterns_ &&
             marker_of(point_, *patterns_)) {
    log_line("drill: " + point_.label + ": the camera could not be turned onto " + marker +
             " from any of " + std::to_string(body_draws_) +
             " whole-body postures drawn; the base placed for this hole alone, from further out");
    place_for_hole();
    return;
  } else {
    checked_look_ = 0;
    log_line("drill: " + point_.label + ": the camera could not be turned onto " + marker +
             " from any of " + std::to_string(body_draws_) +
             " whole-body postures drawn; the last one taken");
  }
  move_to_candidate();
}

void DrillEngine::body_to_hole_step() {
  if (!trajectory_ran("to the hole's drilling posture")) return;
  hole_chain_.push_back(body_candidate_);
  posture_reached();
}

void DrillEngine::checked_look_step() {
  if (!trajectory_ran("the camera onto the marker")) return;
  look_path_ = checked_path_;
  look_attempt_ = checked_look_;
  look_pushed_ = true;
  hole_chain_.push_back(look_path_);
  start_reanchor(Motion::kLookReanchor);
}

void DrillEngine::look_at_hole_step() {
  const std::optional<PlanReply> r = plan_result(look_request_);
  if (!r) return;
  if (!r->path.samples.empty()) look_path_ = r->path;
  if (r->state == PlanState::kFailed && r->failure == PlanFailure::kExecutionAborted) {
    // The robot stopped while turning the camera (a safety stop): the hole fails; no other
    // look is asked for.
    motion_outcome_ = Outcome::failed("planner: the look at the hole's mark: " + r->reason);
    motion_ = Motion::kNone;
    return;
  }
  if (r->state == PlanState::kSucceeded) {
    look_pushed_ = !look_path_.samples.empty();
    if (look_pushed_) hole_chain_.push_back(look_path_);
    start_reanchor(Motion::kLookReanchor);
  } else if (r->state == PlanState::kFailed &&
             look_attempt_ + 1 < tuning_.looks.attempts.size() &&
             (point_.marker >= 0 || (!tuning_.looks.attempts[look_attempt_ + 1].between &&
                                     tuning_.looks.attempts[look_attempt_ + 1].slant <= 0.0))) {
    request_look(look_attempt_ + 1);
  } else if (r->state == PlanState::kFailed) {
    log_line("drill: " + point_.label + ": the camera cannot be turned onto " +
             (point_.marker >= 0 ? "marker " + std::to_string(point_.marker) : "the blob") +
             " from here (" + r->reason + "); the hole is measured from its posture");
    start_reanchor(Motion::kReanchor);
  }
}

void DrillEngine::look_reanchor_step() {
  const std::optional<CameraFrame> view = inputs_.averaged_view(reanchor_since_ns_, tuning_.camera.reanchor_frames);
  if (!view) return;
  const CameraView camera{&view->frame, view->world_T_optical};
  if (point_.marker < 0) {
    if (remeasure_looked_blob(camera)) return;
  } else if (!remeasure_looked_marker(camera)) {
    const std::optional<Sample> s = inputs_.latest_sample();
    if (look_attempt_ + 1 < tuning_.looks.attempts.size() && look_pushed_ && hole_chain_.size() > 1 && s) {
      // From another look (a hole drilled where odometry puts it can be 2 cm off).
      log_line("drill: " + point_.label + ": marker " + std::to_string(point_.marker) +
               " not seen from the look posture; back onto the drilling posture for the next look");
      back_to_posture(*s, Motion::kBackForLook);
      return;
    }
    log_line("drill: " + point_.label + ": marker " + std::to_string(point_.marker) +
             " not seen from the look posture; the hole is drilled where odometry puts it");
  } else {
    // The base moved for this posture: without one for the arm alone at the hole measured
    // again, the whole body's is planned again (and the marker looked at again) or aligned
    // from, not the next whole-body attempt taken without a look (a row hole then lands
    // about 13 mm off).
    if (!hole_request_.fixed_base) hole_replanned_ = true;
  }
  // From the look back onto the drilling posture along the look's path reversed, not along a
  // path planned anew from the look posture: such a path can swing morphology A's J1_E through
  // 3.9 rad with the bit near the wall and press it on the wall (300 N m, a safety stop). A
  // posture of the arm alone planned within hole.replan_shift of
  // the hole as measured now is aligned from (the alignment covers the rest); otherwise the
  // posture is planned again from there.
  const std::optional<Sample> s = inputs_.latest_sample();
  if (look_pushed_ && hole_chain_.size() > 1 && s && !hole_request_.goals.empty()) {
    const double moved =
        (point_.frame.translation() - hole_request_.goals.front().translation()).norm();
    const bool keep = hole_request_.fixed_base && moved <= tuning_.hole.replan_shift;
    back_to_posture(*s, keep ? Motion::kBackToPosture : Motion::kBackThenReplan);
    return;
  }
  replan_after_look();
}

void DrillEngine::back_then_replan_step() {
  if (trajectory_ran("back onto the drilling posture")) replan_after_look();
}

void DrillEngine::reanchor_step() {
  const std::optional<CameraFrame> view = inputs_.averaged_view(reanchor_since_ns_, tuning_.camera.reanchor_frames);
  if (!view) return;
  static const PatternTable kNone;
  const CameraView camera{&view->frame, view->world_T_optical};
  DrillPoint predicted = point_;
  double within = tuning_.blobs.reanchor_distance;
  if (point_.marker < 0 && area_points_.size() > 1) {
    // Several blobs: which one is this hole's is told by the pattern they make together.
    const std::optional<AreaShift> shift =
        blob_shift(camera, area_points_, tuning_.blobs.match, tuning_.blobs.reanchor_distance, tuning_.blobs.set_shift);
    if (shift && shift->blobs < 2 && !hole_request_.fixed_base && !looked_) {
      // The base moved: one blob seen alone near its prediction may be the neighbour, odometry
      // having drifted as far as the blobs lie apart.
      log_line("drill: " + point_.label +
               ": one blob of the area's seen from its drilling posture, not the set (" +
               blobs_seen(camera, point_.frame) + "); the camera is turned onto the area");
      look_at_hole();
      return;
    }
    if (shift) {
      predicted.frame.translation() += shift->by;
      within = tuning_.blobs.match;
    } else if (!hole_request_.fixed_base && !looked_) {
      // The base moved and the camera, beside the bit, cannot tell the blob from a neighbour.
      log_line("drill: " + point_.label +
               ": its blob is not told from a neighbour from its drilling posture (" +
               blobs_seen(camera, point_.frame) + "); the camera is turned onto it");
      look_at_hole();
      return;
    } else if (!hole_request_.fixed_base) {
      within = tuning_.blobs.match;  // no neighbour is taken for it: the prediction stands
    }
  }
  const std::optional<Eigen::Isometry3d> seen =
      reanchor(camera, predicted, patterns_ ? *patterns_ : kNone, within);
  if (seen) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(1);
    line << "drill: " << point_.label << " measured again from its drilling posture: "
         << (seen->translation() - point_.frame.translation()).norm() * 1e3 << " mm, "
         << std::acos(
                std::clamp(seen->linear().col(2).dot(point_.frame.linear().col(2)), -1.0, 1.0)) *
                180.0 / M_PI
         << " deg from the prediction";
    const Eigen::Vector3d along = point_.frame.inverse() * seen->translation();
    line << " (" << along.x() * 1e3 << ", " << along.y() * 1e3 << " mm on the wall, "
         << along.z() * 1e3 << " mm out of it)";
    if (point_.marker < 0) line << " (" << blobs_seen(camera, point_.frame) << ")";
    log_line(line.str());
    const Eigen::Vector3d moved = seen->translation() - point_.frame.translation();
    hole_seen_again(seen->translation());
    if (point_.marker < 0) shift_area(moved);  // the area's other blobs moved as much
    point_.frame = *seen;
    if (!hole_request_.fixed_base && !hole_replanned_ && moved.norm() > tuning_.hole.replan_shift) {
      // The base moved and odometry drifted: the posture again, the arm alone, for the hole
      // where the camera sees it now.
      hole_replanned_ = true;
      replan_hole(tuning_.hole.attempts[hole_attempt_].reach, 0.0, tuning_.hole.attempts[hole_attempt_].lead);
      return;
    }
  }
  if (const std::optional<Sample> s = inputs_.latest_sample()) start_align(*s);
}

void DrillEngine::back_for_look_step() {
  if (trajectory_ran("back onto the drilling posture")) request_look(look_attempt_ + 1);
}

void DrillEngine::settle_step() {
  // Back onto a planned posture: after a retract (then the hole is done), or from the look
  // posture (then the alignment starts).
  if (!trajectory_ran("back onto the drilling posture")) return;
  if (motion_ == Motion::kSettle) {
    motion_outcome_ = Outcome::succeeded();
    motion_ = Motion::kNone;
  } else if (const std::optional<Sample> here = inputs_.latest_sample()) {
    start_align(*here);
  }
}

}  // namespace concert::drill
