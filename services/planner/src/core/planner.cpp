#include "planner/planner.hpp"

#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <variant>

#include "path_search.hpp"
#include "posture_problem.hpp"
#include "planner/trajectory.hpp"

namespace concert::planner {
namespace {

using Clock = std::chrono::steady_clock;  // what results report (wall time)
using detail::cpu_seconds_since;
using detail::ThreadCpuClock;  // what budgets are measured in (see cpu_clock.hpp)

// Remembered postures whose camera height is within this of a new goal's seed it [m], at most
// kHints of them (nearest first).
constexpr double kHintHeight = 0.3;
constexpr std::size_t kHints = 8;

// A remembered arm path serves a goal whose arm joints after the first are this close [rad].
constexpr double kArmPathReuse = 0.6;
// Arm postures whose joints after the first are this close [rad] have the same shape (the
// first joint only turns the arm about the vertical).
constexpr double kSameShape = 0.3;
// Remembered postures this close [m of height, rad] are the same posture.
constexpr double kSamePosture = 1e-3;

// How far apart two arm postures' shapes are: the largest change of the joints after the
// first [rad] (the first only turns the arm about the vertical).
double shape_distance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a.tail(a.size() - 1) - b.tail(b.size() - 1)).cwiseAbs().maxCoeff();
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The goal posture's heaviest static load, as a fraction of the joint's continuous torque
// (Params::torque_margin applies on top), with or without the drilling force, whichever is
// heavier: for the log and the result, e.g. "J2_E 0.91 with the drilling force, 0.97 with the
// bit 0.1 m further". What an operator looks at when the safety layer stops a joint on its
// sustained torque.
std::string load_summary(const PlanningModel& model, StateChecker& checker,
                         const Eigen::VectorXd& q_full, const EndEffectorInfo& tool,
                         const Eigen::Isometry3d& area, const Params& params) {
  const auto heaviest = [&](const Eigen::VectorXd& q) {
    const StateChecker::TorqueUse without = checker.heaviest_torque(q, std::string());
    const StateChecker::TorqueUse with = params.contact_force != 0.0
                                             ? checker.heaviest_torque(q, tool.frame)
                                             : StateChecker::TorqueUse{};
    const bool drilling = with.fraction > without.fraction;
    const StateChecker::TorqueUse& worst = drilling ? with : without;
    std::ostringstream s;
    s << worst.joint << " " << std::fixed << std::setprecision(2) << worst.fraction
      << (drilling ? " with the drilling force" : " without the drilling force");
    return s.str();
  };
  std::string s = heaviest(q_full);
  if (params.tip_task && params.tip_reach > 0.0) {
    const Eigen::Vector3d axis = -(area.linear().col(2));
    if (const auto reached = reached_posture(model, q_full, tool.frame, axis, params.tip_reach)) {
      std::ostringstream r;
      r << ", " << heaviest(*reached) << " with the bit " << params.tip_reach << " m further";
      s += r.str();
    }
  }
  return s;
}

}  // namespace

Planner::Planner(Params params)
    : params_(std::move(params)), environment_(params_.octomap_resolution) {
  static std::once_flag once;
  std::call_once(once, [&] {
    ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
    ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(params_.seed));
  });
}

void Planner::set_model(const ModelDescription& description) {
  auto model = PlanningModel::build(description, params_);
  std::lock_guard lock(mutex_);
  model_ = std::move(model);
  if (description.content_hash == model_hash_ && !model_hash_.empty()) return;  // a new version, the same model
  if (!model_hash_.empty()) kept_.emplace_front(model_hash_, std::move(memory_));
  memory_ = {};
  model_hash_ = description.content_hash;
  const auto same = std::find_if(kept_.begin(), kept_.end(),
                                 [&](const auto& k) { return k.first == model_hash_; });
  if (same != kept_.end() && !model_hash_.empty()) {
    memory_ = std::move(same->second);
    kept_.erase(same);
  }
  while (!kept_.empty() && static_cast<int>(kept_.size()) >= params_.memory_models) kept_.pop_back();
}

std::size_t Planner::remembered() const {
  std::lock_guard lock(mutex_);
  return memory_.postures.size();
}

int Planner::warm_up(double from, double to, double step, double seconds_per_height,
                     const std::function<bool()>& keep_going) {
  const std::shared_ptr<const PlanningModel> model = this->model();
  if (!model || !(step > 0.0)) return 0;
  const EndEffectorInfo* tool = nullptr;
  try {
    tool = &model->tool("");
  } catch (const PlannerError&) {
    return 0;  // no tool with a camera: nothing to drill with
  }
  Params params = params_;
  params.nspg_time = seconds_per_height;
  const Environment empty(params.octomap_resolution);
  StateChecker checker(model, empty, params, params.environment_padding);
  const Eigen::VectorXd start = Eigen::VectorXd::Zero(model->full_dof());
  int solved = 0;
  int index = 0;
  for (double z = from; z <= to + 1e-9; z += step, ++index) {
    if (this->model() != model || !keep_going()) break;  // a new model arrived, or shutdown
    const long height_mm = std::lround(z * 1000.0);
    {
      // Searched by an earlier warm-up of this model (a version swapped back on): kept.
      std::lock_guard lock(mutex_);
      if (model_ != model) break;
      if (const auto w = memory_.warmed.find(height_mm); w != memory_.warmed.end()) {
        solved += w->second ? 1 : 0;
        continue;
      }
    }
    // A wall facing the robot 2 m ahead, the area at height z.
    Eigen::Isometry3d area = Eigen::Isometry3d::Identity();
    area.linear() << 0, 0, -1, 0, 1, 0, 1, 0, 0;  // z along -x (the wall's outward normal)
    area.translation() = Eigen::Vector3d(2.0, 0.0, z);
    const double height = z;  // the camera stays at the area's height (horizontal axis)
    // Twice: seeded with the neighbouring heights' postures (one family followed up the
    // wall), then from the start posture and random seeds only, for other families: near an
    // obstacle the one that fits is often another family.
    bool found = false;
    bool cut = false;
    for (const bool seeded : {true, false}) {
      params.nspg_enough = seeded ? 1 : 2;
      const uint64_t seed = params.seed + 31u * static_cast<uint64_t>(index) + (seeded ? 0u : 17u);
      const PostureResult p =
          generate_posture(*model, checker, params, *tool, start, area, seed,
                           seeded ? hints_for(*model, height) : std::vector<Eigen::VectorXd>{}, 0,
                           [&] { return this->model() == model && keep_going(); });
      for (const Eigen::VectorXd& q : p.valid) {
        // The arm's way from the start posture to it, where the map cannot interfere: later
        // plans replay it (checked against their map) instead of searching for it.
        Eigen::VectorXd parked = model->to_planned(start);
        parked.head<3>() = q.head<3>();
        std::vector<Eigen::VectorXd> path = detail::subspace_rrt(
            *model, checker, start, params.check_resolution, 3, model->dof() - 3, model->lower(),
            model->upper(), parked, q, params.warm_up_path_time, seed, nullptr);
        std::vector<Eigen::VectorXd> arms;
        for (const Eigen::VectorXd& w : path) arms.push_back(w.tail(w.size() - 3));
        remember(*model, height, q, std::move(arms));
      }
      found = found || p.found;
      cut = this->model() != model || !keep_going();
      if (cut) break;
    }
    if (cut) break;  // the height not searched in full: not recorded
    if (found) solved += 1;
    std::lock_guard lock(mutex_);
    if (model_ == model) memory_.warmed[height_mm] = found;
  }
  return solved;
}

std::vector<Eigen::VectorXd> Planner::hints_for(const PlanningModel& model, double height) const {
  std::vector<std::pair<double, Eigen::VectorXd>> near;
  {
    std::lock_guard lock(mutex_);
    if (model_.get() != &model) return {};
    for (const Remembered& m : memory_.postures) {
      if (std::abs(m.height - height) <= kHintHeight)
        near.emplace_back(std::abs(m.height - height), m.arm);
    }
  }
  std::sort(near.begin(), near.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::VectorXd> out;
  for (std::size_t i = 0; i < near.size() && out.size() < kHints; ++i)
    out.push_back(near[i].second);
  return out;
}

void Planner::remember(const PlanningModel& model, double height, const Eigen::VectorXd& q,
                       std::vector<Eigen::VectorXd> arm_path) {
  if (params_.nspg_memory <= 0) return;
  std::lock_guard lock(mutex_);
  if (model_.get() != &model) return;
  const Eigen::VectorXd arm = q.tail(q.size() - 3);
  for (Remembered& m : memory_.postures) {
    // The same posture again (both warm-up passes, or a plan that started from it): one entry.
    if (std::abs(m.height - height) < kSamePosture &&
        (m.arm - arm).cwiseAbs().maxCoeff() < kSamePosture) {
      if (m.arm_path.empty()) m.arm_path = std::move(arm_path);
      return;
    }
  }
  if (static_cast<int>(memory_.postures.size()) >= params_.nspg_memory)
    memory_.postures.erase(memory_.postures.begin());
  memory_.postures.push_back({height, arm, std::move(arm_path)});
}

std::vector<Eigen::VectorXd> Planner::arm_path_to(const PlanningModel& model,
                                                  const Eigen::VectorXd& arm) const {
  std::lock_guard lock(mutex_);
  if (model_.get() != &model) return {};
  // The goal's arm is compared with each remembered posture and with its mirror image (the
  // path then mirrored too: the robot's torques and self collisions are nearly symmetric, and
  // the replay is checked anyway).
  const std::optional<Eigen::VectorXd> goal_mirror = model.mirrored_arm(arm);
  const Remembered* best = nullptr;
  bool best_mirrored = false;
  double best_d = kArmPathReuse;
  for (const Remembered& m : memory_.postures) {
    if (m.arm_path.empty()) continue;
    for (const bool mirrored : {false, true}) {
      if (mirrored && !goal_mirror) continue;
      const double d = shape_distance(m.arm, mirrored ? *goal_mirror : arm);
      if (d < best_d) {
        best_d = d;
        best = &m;
        best_mirrored = mirrored;
      }
    }
  }
  if (best == nullptr) return {};
  std::vector<Eigen::VectorXd> out;
  for (const Eigen::VectorXd& a : best->arm_path) {
    std::optional<Eigen::VectorXd> w = best_mirrored ? model.mirrored_arm(a) : a;
    if (!w) return {};  // the image leaves the joint limits
    out.push_back(std::move(*w));
  }
  const double turn =
      arm[0] - out.back()[0];  // the path ends at the remembered posture (or its image)
  for (Eigen::VectorXd& a : out) a[0] += turn;
  return out;
}

void Planner::set_environment(Environment environment) {
  // The posture solver's distance field is part of the map update, not of each plan.
  (void)environment.distance_field();
  std::lock_guard lock(mutex_);
  environment_ = std::move(environment);
}

uint64_t Planner::model_version() const {
  std::lock_guard lock(mutex_);
  return model_ ? model_->version() : 0;
}

std::shared_ptr<const PlanningModel> Planner::model() const {
  std::lock_guard lock(mutex_);
  return model_;
}

Environment Planner::environment() const {
  std::lock_guard lock(mutex_);
  return environment_;
}

namespace {

// The nearest base pose (x, y within `tolerance` [m], yaw within `tolerance` [rad]) at which
// `q` is clear of the map for `checker`, or none. Candidates on rings of 1 cm, 16 directions,
// yaw steps of 0.01 rad, cheapest first (distance + yaw x 1 m); deterministic.
std::optional<Eigen::VectorXd> base_out_of_map(StateChecker& checker, const Eigen::VectorXd& q,
                                               double tolerance) {
  struct Candidate {
    double cost;
    Eigen::Vector3d d;
  };
  std::vector<Candidate> candidates;
  const int rings = static_cast<int>(std::floor(tolerance / 0.01 + 1e-9));
  for (int r = 0; r <= rings; ++r) {
    const int directions = r == 0 ? 1 : 16;
    for (int k = 0; k < directions; ++k) {
      const double a = 2.0 * M_PI * k / directions;
      for (int y = -rings; y <= rings; ++y) {
        if (r == 0 && y == 0) continue;
        const Eigen::Vector3d d(0.01 * r * std::cos(a), 0.01 * r * std::sin(a), 0.01 * y);
        candidates.push_back({0.01 * r + std::abs(d.z()), d});
      }
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  Eigen::VectorXd moved = q;
  for (const Candidate& c : candidates) {
    moved.head<3>() = q.head<3>() + c.d;
    if (checker.check(moved).constraint != Constraint::kEnvironmentCollision) return moved;
  }
  return std::nullopt;
}

// A valid state with the planned arm joints of `q` moved by at most `tolerance` [rad or m]
// each, or none: one joint at a time first, the smallest move (5 mrad steps; the demo's arm
// can stand 50 mrad of J3_E inside its posture's shapes, the joint's deflection under gravity),
// then seeded random moves of every joint within growing bounds, as MoveIt's
// FixStartStateCollision does; clamped to the joint limits.
std::optional<Eigen::VectorXd> arm_out_of_self_collision(const PlanningModel& model,
                                                         StateChecker& checker,
                                                         const Eigen::VectorXd& q, double tolerance,
                                                         uint64_t seed) {
  const std::vector<int>& planned = model.planned_indices();
  const auto clamp = [&](std::size_t j, double v) {
    return std::clamp(v, model.lower()[static_cast<Eigen::Index>(j)],
                      model.upper()[static_cast<Eigen::Index>(j)]);
  };
  Eigen::VectorXd moved = q;
  const int steps = static_cast<int>(std::floor(tolerance / 0.005 + 1e-9));
  for (int k = 1; k <= steps; ++k) {
    for (std::size_t j = 3; j < planned.size(); ++j) {
      const int i = planned[j];
      for (const double sign : {1.0, -1.0}) {
        moved[i] = clamp(j, q[i] + sign * 0.005 * k);
        if (checker.check(moved).valid()) return moved;
      }
      moved[i] = q[i];
    }
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int round = 1; round <= 8; ++round) {
    const double bound = tolerance * round / 8.0;
    for (int attempt = 0; attempt < 40; ++attempt) {
      for (std::size_t j = 3; j < planned.size(); ++j) {
        const int i = planned[j];
        moved[i] = clamp(j, q[i] + bound * unit(rng));
      }
      if (checker.check(moved).valid()) return moved;
    }
  }
  return std::nullopt;
}

}  // namespace

GoalResult Planner::plan_path(const PlanningModel& model, StateChecker& checker,
                              const Eigen::VectorXd& q_start_full, const Eigen::VectorXd& q_goal,
                              double time_budget, uint64_t seed, bool fixed_base,
                              const Eigen::VectorXd* lead_in) const {
  const auto t0 = Clock::now();
  const auto cpu0 = ThreadCpuClock::now();
  GoalResult r;
  const Validity vs = checker.check(q_start_full);
  if (!vs.valid()) {
    r.goal_q = q_goal;
    r.status = Status::kInvalidStart;
    r.reason =
        std::string("start state rejected by ") + to_string(vs.constraint) + ": " + vs.detail;
    return r;
  }
  Params params = params_;
  params.fixed_base = fixed_base;
  detail::PathSearch search(model, checker, params, q_start_full, q_goal, seed,
                            [&](const Eigen::VectorXd& arm) { return arm_path_to(model, arm); });
  std::vector<Eigen::VectorXd> waypoints =
      search.run(cpu0 + std::chrono::duration_cast<ThreadCpuClock::duration>(
                            std::chrono::duration<double>(time_budget)));
  r.goal_q = search.goal();
  r.path_method = search.method();
  r.plan_seconds = seconds_since(t0);
  if (waypoints.empty()) {
    r.status = Status::kNoPath;
    r.reason = search.reason();
    return r;
  }
  if (lead_in) waypoints.insert(waypoints.begin(), model.to_planned(*lead_in));
  DriveLimits drives;
  if (params_.drive_torque_fraction > 0.0) {
    drives.model = &model;
    drives.q_start_full = q_start_full;
    drives.fraction = params_.drive_torque_fraction;
    drives.max_stretch = params_.max_drive_stretch;
  }
  DriveReport load;
  r.trajectory = time_parameterize(waypoints, model.joint_names(), motion_limits(model, params_),
                                   params_.sample_period, drives, &load);
  r.drives = load.summary();
  r.plan_seconds = seconds_since(t0);
  if (!load.within) {
    r.status = Status::kNoPath;
    char b[120];
    std::snprintf(b, sizeof b, "the arm's drives cannot sustain the path even %.1f times slower: ",
                  params_.max_drive_stretch);
    r.reason = b + r.drives;
    return r;
  }
  r.status = Status::kSucceeded;
  r.plan_seconds = seconds_since(t0);
  return r;
}

Eigen::VectorXd home_posture(const PlanningModel& model, const Eigen::VectorXd& q_full) {
  Eigen::VectorXd home = model.to_planned(q_full);
  // Nav's transport posture too; indexed by the fixed-base kinematics, the planner's has the
  // base's virtual joints first.
  const Eigen::VectorXd full_home = model.robot().home_posture();
  const kinematics::Model& fixed = model.robot().kinematics();
  for (Eigen::Index j = 3; j < home.size(); ++j)
    home[j] = full_home[fixed.joint_index_or_throw(model.joint_names()[static_cast<std::size_t>(j)])];
  return home;
}

GoalResult Planner::plan_home(const PlanningModel& model, StateChecker& checker, const Eigen::VectorXd& start,
                              uint64_t seed, const Eigen::VectorXd* lead_in) const {
  return plan_posture(model, checker, start, home_posture(model, start), "home", "the homing posture", seed,
                      lead_in);
}

GoalResult Planner::plan_posture(const PlanningModel& model, StateChecker& checker, const Eigen::VectorXd& start,
                                 const Eigen::VectorXd& target, const std::string& request,
                                 const std::string& posture, uint64_t seed, const Eigen::VectorXd* lead_in) const {
  GoalResult r;
  if (const Validity v = checker.check(model.to_full(target, start)); !v.valid()) {
    r.goal_q = target;
    r.status = Status::kUnreachable;
    r.reason = request + ": " + posture + " is rejected where the robot stands by " + to_string(v.constraint) + ": " +
               v.detail;
    return r;
  }
  r = plan_path(model, checker, start, target, params_.planning_time, seed, true, lead_in);
  r.index = 0;
  if (r.status != Status::kSucceeded) r.reason = request + ": " + r.reason;
  return r;
}

namespace {

/// The planned posture a PlanRequest::posture asks for from `start` (full q), or the reason it
/// is malformed (a name that is no arm joint the planner moves, twice, or beyond its limits).
std::variant<Eigen::VectorXd, std::string> requested_posture(const PlanningModel& model,
                                                             const Eigen::VectorXd& start,
                                                             const std::vector<std::pair<std::string, double>>& posture) {
  Eigen::VectorXd q = model.to_planned(start);
  const std::vector<std::string>& names = model.joint_names();
  std::vector<bool> named(names.size(), false);
  for (const auto& [name, value] : posture) {
    const auto it = std::find(names.begin() + 3, names.end(), name);
    if (it == names.end()) {
      std::string known;
      for (auto n = names.begin() + 3; n != names.end(); ++n) known += (known.empty() ? "" : ", ") + *n;
      return "posture: '" + name + "' is not an arm joint of model version " + std::to_string(model.version()) +
             " (its arm joints: " + known + ")";
    }
    const auto j = static_cast<Eigen::Index>(it - names.begin());
    if (named[static_cast<std::size_t>(j)]) return "posture: joint '" + name + "' is named twice";
    named[static_cast<std::size_t>(j)] = true;
    if (!std::isfinite(value) || value < model.lower()[j] || value > model.upper()[j]) {
      std::ostringstream why;
      why << "posture: joint '" << name << "' to " << value << " is beyond its limits [" << model.lower()[j]
          << ", " << model.upper()[j] << "]";
      return why.str();
    }
    q[j] = value;
  }
  return q;
}

}  // namespace

PlanResult Planner::plan(const PlanRequest& request, const Eigen::VectorXd& q_start_full,
                         const GoalCallback& on_goal) {
  PlanResult out;
  out.request_id = request.request_id;
  const std::shared_ptr<const PlanningModel> model = this->model();
  const Environment env = environment();
  out.model_version = model ? model->version() : 0;
  auto fail = [&](Status s, std::string why) {
    out.status = s;
    out.reason = std::move(why);
    return out;
  };
  if (!model) return fail(Status::kNoModel, "no robot model received yet");
  if (request.model_version != model->version()) {
    return fail(Status::kStaleModel,
                "request made for model version " + std::to_string(request.model_version) +
                    " but the planner runs model version " + std::to_string(model->version()));
  }
  if (request.home && !request.goals.empty()) {
    return fail(Status::kInvalidRequest, "a home request has no goals (the arm goes home, nothing else)");
  }
  if (!request.posture.empty() && (request.home || !request.goals.empty())) {
    return fail(Status::kInvalidRequest,
                "a posture request has no goals and is no home request (the arm goes to the posture, nothing else)");
  }
  if (!request.home && request.posture.empty() && request.goals.empty())
    return fail(Status::kInvalidRequest, "request has no goals");
  if (std::isnan(request.tip_distance) || std::isinf(request.tip_distance)) {
    return fail(Status::kInvalidRequest, "tip_distance must be a finite number of metres");
  }
  // Past about 80 deg the camera would look along the surface, not at it.
  constexpr double kMaxSlant = 1.4;
  if (!(request.view_slant >= 0.0 && request.view_slant <= kMaxSlant)) {
    return fail(Status::kInvalidRequest, "view_slant must be within [0, 1.4] rad");
  }
  if (request.view_slant > 0.0) {
    const double far = request.camera_distance > 0.0 ? request.camera_distance : params_.camera_distance;
    if (request.tip_distance > 0.0) {
      return fail(Status::kInvalidRequest,
                  "view_slant is a look with the camera; tip_distance puts the tool on the area's normal");
    }
    if (!(request.view_near >= 0.0 && request.view_near < far)) {
      return fail(Status::kInvalidRequest, "view_near must be at least 0 m and below camera_distance (" +
                                               std::to_string(far) + " m)");
    }
  }
  if (!(request.tip_reach >= 0.0 && request.tip_reach <= 1.0)) {
    return fail(Status::kInvalidRequest, "tip_reach must be within [0, 1] m");
  }
  // A drill or a sander pushes with tens to a few hundred newtons; more is a unit error.
  constexpr double kMaxContactForce = 2000.0;
  if (std::isnan(request.contact_force) || request.contact_force > kMaxContactForce) {
    return fail(Status::kInvalidRequest, "contact_force must be a number of newtons up to " +
                                             std::to_string(static_cast<int>(kMaxContactForce)));
  }
  if (q_start_full.size() != model->full_dof() || !q_start_full.allFinite()) {
    return fail(Status::kInvalidStart, "start state has " + std::to_string(q_start_full.size()) +
                                           " joints, model version " +
                                           std::to_string(model->version()) + " has " +
                                           std::to_string(model->full_dof()));
  }
  const EndEffectorInfo* tool = nullptr;
  try {
    if (!request.home && request.posture.empty()) {
      tool = &model->tool(request.end_effector);
      (void)model->camera_frame(*tool);
    }
  } catch (const PlannerError& e) {
    return fail(Status::kInvalidRequest, e.what());
  }
  if (!request.posture.empty()) {
    const auto posture = requested_posture(*model, q_start_full, request.posture);
    if (const auto* why = std::get_if<std::string>(&posture)) return fail(Status::kInvalidRequest, *why);
  }
  for (std::size_t g = 0; g < request.goals.size(); ++g) {
    const Eigen::Isometry3d& a = request.goals[g].area;
    if (!a.matrix().allFinite() || std::abs(a.linear().determinant() - 1.0) > 1e-3) {
      return fail(
          Status::kInvalidRequest,
          "goal " + std::to_string(g) + ": drilling area frame is not a finite rigid transform");
    }
  }

  const double padding =
      request.environment_padding > 0.0 ? request.environment_padding : params_.environment_padding;
  // The request's force on the tool, else the configured one, in every torque check.
  Params request_params = params_;
  if (request.contact_force > 0.0) request_params.contact_force = request.contact_force;
  auto checker_ptr = std::make_unique<StateChecker>(model, env, request_params, padding);
  Validity start_ok = checker_ptr->check(q_start_full);
  // A start a few centimetres inside the map or its padding (the base's odometry drifts: on the
  // demo a leg can be 2-4 cm inside the wall after a hole's whole-body move), or with two
  // links a hair inside each other (the planner's shapes are conservative, and the drill's
  // Cartesian motions leave the arm a little off the posture the planner checked): the nearest
  // state clear of both is planned from, and the move there is prepended to the path (what
  // MoveIt's FixStartStateCollision adapter does). First with the padding; if the start cannot
  // be moved clear of that, a start clear of the map itself is planned without the padding, and
  // one inside the map is moved out of the map itself. A start over a joint or torque limit, or
  // on the floor, is refused.
  std::optional<Eigen::VectorXd> lead_in;
  Eigen::VectorXd start = q_start_full;
  // A start a hair past a joint's limit (a drive holds a few mrad beyond the limit a trajectory
  // ended on, e.g. J1_E at -2.7504 rad of +-2.75 on the demo; refused, the drill could not turn
  // its camera) is clamped onto the limit first, as MoveIt's FixStartStateBounds does; a joint more
  // than start_joint_tolerance out is refused below.
  std::string clamped_note;
  if (start_ok.constraint == Constraint::kJointLimit) {
    Eigen::VectorXd clamped = q_start_full;
    const std::vector<int>& planned = model->planned_indices();
    double worst = 0.0;
    std::string worst_joint;
    for (std::size_t j = 3; j < planned.size(); ++j) {
      const auto jj = static_cast<Eigen::Index>(j);
      const double v = q_start_full[planned[j]];
      const double c = std::clamp(v, model->lower()[jj], model->upper()[jj]);
      if (std::abs(v - c) > worst) {
        worst = std::abs(v - c);
        worst_joint = model->joint_names()[j];
      }
      clamped[planned[j]] = c;
    }
    if (worst <= params_.start_joint_tolerance) {
      std::ostringstream note;
      note << "the start is past a joint limit (" << start_ok.detail << "): " << worst_joint
           << " moved onto its limit by " << std::round(worst * 1e4) / 1e4 << " rad, first";
      clamped_note = note.str();
      lead_in = q_start_full;
      start = clamped;
      start_ok = checker_ptr->check(start);
    }
  }
  const Eigen::VectorXd q_from = start;  // the start, on its joint limits
  const auto move_out = [&](StateChecker& checker) -> std::optional<std::string> {
    std::optional<Eigen::VectorXd> moved = q_from;
    std::vector<std::string> what;
    Validity v = checker.check(*moved);
    if (v.constraint == Constraint::kEnvironmentCollision && params_.start_tolerance > 0.0) {
      moved = base_out_of_map(checker, *moved, params_.start_tolerance);
      if (!moved) return std::nullopt;
      const Eigen::Vector3d d = moved->head<3>() - q_from.head<3>();
      std::ostringstream s;
      s << "inside the map (" << v.detail << "): the base moved out by "
        << std::round(1e3 * std::hypot(d.x(), d.y())) << " mm and "
        << std::round(10.0 * d.z() * 180.0 / M_PI) / 10.0 << " deg";
      what.push_back(s.str());
      v = checker.check(*moved);
    }
    if (v.constraint == Constraint::kSelfCollision && params_.start_joint_tolerance > 0.0) {
      const std::string detail = v.detail;
      const Eigen::VectorXd before = *moved;
      moved = arm_out_of_self_collision(*model, checker, before, params_.start_joint_tolerance,
                                        params_.seed + request.request_id);
      if (!moved) return std::nullopt;
      std::ostringstream s;
      s << "in self collision (" << detail << "): the arm moved out by "
        << std::round(1e3 * (*moved - before).cwiseAbs().maxCoeff()) / 1e3 << " rad at most";
      what.push_back(s.str());
      v = checker.check(*moved);
    }
    if (!v.valid() || what.empty()) return std::nullopt;
    std::string note = "the start is";
    for (std::size_t i = 0; i < what.size(); ++i) note += (i ? "; and " : " ") + what[i];
    lead_in = q_start_full;
    start = *moved;
    return note + ", first";
  };
  const auto add_note = [&](const std::string& note) {
    out.note = out.note.empty() ? note : out.note + "; " + note;
  };
  if (!clamped_note.empty()) add_note(clamped_note);
  if (start_ok.constraint == Constraint::kEnvironmentCollision ||
      start_ok.constraint == Constraint::kSelfCollision) {
    if (auto note = move_out(*checker_ptr)) {
      add_note(*note);
      start_ok = {};
    } else if (padding > 0.0) {
      auto unpadded = std::make_unique<StateChecker>(model, env, request_params, 0.0);
      if (const Validity v = unpadded->check(q_from); v.valid()) {
        add_note("the start is within the environment padding (" + start_ok.detail +
                 "): planned without it");
        checker_ptr = std::move(unpadded);
        start_ok = v;
      } else if (auto unpadded_note = move_out(*unpadded)) {
        add_note(*unpadded_note + " (planned without the padding)");
        checker_ptr = std::move(unpadded);
        start_ok = {};
      }
    }
  }
  if (start_ok.constraint == Constraint::kTorqueLimit) {
    // The robot stands where it is: a start a hair above the continuous torque (a posture held
    // after a stop, 160.4 N m against 160 in the chaos test) is planned from with the limit
    // raised by kStartTorqueTolerance, inside the 10 % the safety service allows on the RMS
    // torque, rather than refusing every request from there for ever.
    constexpr double kStartTorqueTolerance = 0.05;
    Params lenient_params = request_params;
    lenient_params.torque_margin *= 1.0 + kStartTorqueTolerance;
    auto lenient = std::make_unique<StateChecker>(model, env, lenient_params, padding);
    if (const Validity v = lenient->check(q_from); v.valid()) {
      add_note("the start needs more than the continuous torque (" + start_ok.detail +
               "): planned with the torque limit raised by 5 %");
      checker_ptr = std::move(lenient);
      start_ok = v;
    }
  }
  StateChecker& checker = *checker_ptr;
  if (!start_ok.valid()) {
    return fail(Status::kInvalidStart, std::string("start state rejected by ") +
                                           to_string(start_ok.constraint) + ": " + start_ok.detail);
  }
  Eigen::VectorXd current = start;
  out.status = Status::kSucceeded;
  if (request.home || !request.posture.empty()) {
    const uint64_t seed = params_.seed + 7919u * request.request_id;
    GoalResult r = request.home ? plan_home(*model, checker, start, seed, lead_in ? &*lead_in : nullptr)
                                : plan_posture(*model, checker, start,
                                               std::get<Eigen::VectorXd>(requested_posture(*model, start, request.posture)),
                                               "posture", "the posture", seed,
                                               lead_in ? &*lead_in : nullptr);
    if (r.status != Status::kSucceeded) {
      out.status = r.status;
      out.reason = r.reason;
    }
    if (on_goal) on_goal(r);
    out.goals.push_back(std::move(r));
    return out;
  }
  for (std::size_t g = 0; g < request.goals.size(); ++g) {
    const auto t0 = ThreadCpuClock::now();
    const uint64_t seed = params_.seed + 7919u * request.request_id + 104729u * g;
    // Goal posture, then a path to it; when no path is found within the attempt's share of
    // the budget, another goal posture is tried while time remains (the posture search goes on
    // from the seed after the one that gave the previous posture): with a long arm some goal
    // postures sit in torque-feasible pockets no path reaches.
    GoalResult r;
    double nspg = 0.0;
    const bool tip = request.tip_distance > 0.0;
    const double distance = tip                            ? request.tip_distance
                            : request.camera_distance > 0.0 ? request.camera_distance
                                                            : params_.camera_distance;
    Params task_params = request_params;
    task_params.camera_distance = distance;
    task_params.view_slant = tip ? 0.0 : request.view_slant;
    task_params.view_near = request.view_near;
    task_params.tip_task = tip;
    const double height = detail::make_task(task_params, request.goals[g].area).position.z();
    const std::vector<Eigen::VectorXd> hints = hints_for(*model, height);
    int next_seed = 0;
    // The arm shapes no path reached: the posture search's next seeds are often the same
    // posture with the first joint turned, whose arm shape no path reaches either (on the
    // benchmark's low areas for morphology B, four such attempts in a row can use up the budget).
    std::vector<Eigen::VectorXd> unreached;
    const auto like_unreached = [&](const Eigen::VectorXd& q) {
      const Eigen::VectorXd arm = q.tail(q.size() - 3);
      return std::any_of(unreached.begin(), unreached.end(), [&](const Eigen::VectorXd& u) {
        return shape_distance(u, arm) < kSameShape;
      });
    };
    for (int attempt = 0;; ++attempt) {
      const auto t_posture = Clock::now();
      Params attempt_params = task_params;
      attempt_params.fixed_base = request.fixed_base;
      attempt_params.base_travel = request.base_travel;
      attempt_params.tip_reach = tip ? request.tip_reach : 0.0;
      PostureResult posture;
      do {
        attempt_params.nspg_time =
            std::min(params_.nspg_time, params_.planning_time - cpu_seconds_since(t0));
        posture =
            generate_posture(*model, checker, attempt_params, *tool, current, request.goals[g].area,
                             seed + 7777u * static_cast<uint64_t>(attempt), hints, next_seed);
        next_seed = posture.next_seed;
      } while (posture.found && like_unreached(posture.q) &&
               params_.planning_time - cpu_seconds_since(t0) > 0.05);
      nspg += seconds_since(t_posture);
      if (!posture.found) {
        if (attempt > 0) break;  // keep the previous attempt's "no path"
        r.status = Status::kUnreachable;
        std::ostringstream what;
        if (task_params.view_slant > 0.0) {
          what << "no feasible posture lets camera '" << model->task_frame(*tool, false) << "' see the area's centre from "
               << task_params.view_near << "-" << distance << " m within " << task_params.view_slant
               << " rad of its normal";
        } else {
          what << "no feasible posture puts " << (tip ? "tip '" : "camera '") << model->task_frame(*tool, tip) << "' "
               << std::to_string(distance) << " m in front of the drilling area";
        }
        r.reason = what.str() + " (" + std::to_string(posture.candidates) + " seeds solved; " + posture.reason + ")";
        break;
      }
      const double remaining = params_.planning_time - cpu_seconds_since(t0);
      r = plan_path(*model, checker, current, posture.q,
                    std::min(remaining, params_.path_attempt_time), seed, request.fixed_base,
                    g == 0 && lead_in ? &*lead_in : nullptr);
      r.nspg_seconds = nspg;
      if (r.status == Status::kSucceeded) {
        remember(*model, height, posture.q);
        r.load = load_summary(*model, checker, model->to_full(posture.q, current), *tool,
                              request.goals[g].area, attempt_params);
      }
      if (r.status == Status::kNoPath) unreached.push_back(posture.q.tail(posture.q.size() - 3));
      if (r.status != Status::kNoPath || params_.planning_time - cpu_seconds_since(t0) < 0.05)
        break;
    }
    if (r.status != Status::kSucceeded) r.reason = "goal " + std::to_string(g) + ": " + r.reason;
    r.index = g;
    if (r.status == Status::kSucceeded) {
      current = model->to_full(r.trajectory.points.back().q, current);
    } else if (out.status == Status::kSucceeded) {
      out.status = r.status;
      out.reason = r.reason;
    }
    if (on_goal) on_goal(r);
    out.goals.push_back(std::move(r));
  }
  return out;
}

}  // namespace concert::planner
