#include "planner/planner.hpp"

#include <ompl/base/samplers/UniformValidStateSampler.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <mutex>
#include <optional>
#include <sstream>

#include "planner/trajectory.hpp"
#include "posture_problem.hpp"

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace concert::planner {
namespace {

using Clock = std::chrono::steady_clock;

// Remembered postures whose camera height is within this of a new goal's seed it [m], at most
// kHints of them (nearest first).
constexpr double kHintHeight = 0.3;
constexpr std::size_t kHints = 8;

// Largest joint change [rad or m] between the states of a projected straight line.
constexpr double kLineStep = 0.15;
// Warm-up: search time for the arm's path to each remembered posture.
constexpr double kWarmUpPathTime = 0.5;
// A remembered arm path serves a goal whose arm joints after the first are this close [rad].
constexpr double kArmPathReuse = 0.6;
// Arm postures whose joints after the first are this close [rad] have the same shape (the
// first joint only turns the arm about the vertical).
constexpr double kSameShape = 0.3;
// Remembered postures this close [m of height, rad] are the same posture.
constexpr double kSamePosture = 1e-3;
// Share of a path attempt's remaining time for each order of the arm-alone-and-drive search
// (arm first, then drive first, each of what is left); the rest is whole-body RRT-Connect's.
constexpr double kArmShare = 0.5;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// OMPL's uniform sampler with a per-plan seed, so plans are reproducible. Every other sample
// is pulled toward the feasible set by a few Gauss-Newton steps on the posture problem's
// inequality rows (gravity torque, self collision, floor, map obstacles): with a long arm the
// torque-feasible states are a thin subset of the joint box, and uniform samples alone
// rarely land in it, so RRT-Connect's trees stop growing (morphology B).
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, uint64_t seed, detail::PostureProblem* feasible, int iterations, const bool* active)
      : ob::RealVectorStateSampler(space), feasible_(feasible), iterations_(iterations), active_(active) {
    rng_.setLocalSeed(static_cast<std::uint_fast32_t>(seed));
    const auto& bounds = space->as<ob::RealVectorStateSpace>()->getBounds();
    lo_ = Eigen::Map<const Eigen::VectorXd>(bounds.low.data(), static_cast<Eigen::Index>(bounds.low.size()));
    hi_ = Eigen::Map<const Eigen::VectorXd>(bounds.high.data(), static_cast<Eigen::Index>(bounds.high.size()));
  }
  void sampleUniform(ob::State* state) override {
    ob::RealVectorStateSampler::sampleUniform(state);
    if (feasible_ == nullptr || !*active_ || (count_++ % 2) == 0) return;
    auto* v = state->as<ob::RealVectorStateSpace::StateType>();
    Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(v->values, lo_.size());
    Eigen::VectorXd r;
    detail::solve(*feasible_, q, lo_, hi_, iterations_, 1.0, r);
    for (Eigen::Index i = 0; i < q.size(); ++i) v->values[i] = q[i];
  }

 private:
  detail::PostureProblem* feasible_;
  int iterations_;
  const bool* active_;  // off during OMPL's set-up (its sanity checks draw many samples)
  Eigen::VectorXd lo_, hi_;
  unsigned long count_ = 0;
};

Eigen::VectorXd to_eigen(const ob::State* s, int n);
void from_eigen(const Eigen::VectorXd& q, ob::State* s);

// RRT-Connect over the planned joints [first, first + count) alone, the others held as in
// `from`, within [lo, hi]: the chain of planned states from `from` to `to` (which differ only
// in those joints), or none within `budget`.
std::vector<Eigen::VectorXd> subspace_rrt(const PlanningModel& model, StateChecker& checker, const Eigen::VectorXd& full_template,
                                          double check_resolution, int first, int count, const Eigen::VectorXd& lo,
                                          const Eigen::VectorXd& hi, const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                          double budget, uint64_t seed, Validity* last_rejection) {
  // Both ends must be valid (e.g. the goal's arm posture where the base stands at the start
  // may hit the wall); OMPL would otherwise report it as an error and search in vain.
  for (const Eigen::VectorXd* end : {&from, &to}) {
    const Validity v = checker.check(model.to_full(*end, full_template));
    if (!v.valid()) {
      if (last_rejection != nullptr) *last_rejection = v;
      return {};
    }
  }
  static const bool kActive = true;
  auto sub = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned>(count));
  ob::RealVectorBounds sub_bounds(static_cast<unsigned>(count));
  for (int i = 0; i < count; ++i) {
    sub_bounds.setLow(static_cast<unsigned>(i), lo[first + i]);
    sub_bounds.setHigh(static_cast<unsigned>(i), hi[first + i]);
  }
  sub->setBounds(sub_bounds);
  sub->setStateSamplerAllocator(
      [seed](const ob::StateSpace* s) { return std::make_shared<SeededSampler>(s, seed, nullptr, 0, &kActive); });
  auto sub_si = std::make_shared<ob::SpaceInformation>(sub);
  Eigen::VectorXd q = from;
  sub_si->setStateValidityChecker([&](const ob::State* s) {
    q.segment(first, count) = to_eigen(s, count);
    const Validity v = checker.check(model.to_full(q, full_template));
    if (!v.valid() && last_rejection != nullptr) *last_rejection = v;
    return v.valid();
  });
  sub_si->setStateValidityCheckingResolution(check_resolution / sub->getMaximumExtent());
  sub_si->setup();
  ob::ScopedState<> a(sub), b(sub);
  from_eigen(from.segment(first, count), a.get());
  from_eigen(to.segment(first, count), b.get());
  auto pdef = std::make_shared<ob::ProblemDefinition>(sub_si);
  pdef->setStartAndGoalStates(a, b);
  og::RRTConnect rrt(sub_si);
  rrt.setProblemDefinition(pdef);
  rrt.setup();
  if (rrt.solve(ob::timedPlannerTerminationCondition(budget)) != ob::PlannerStatus::EXACT_SOLUTION) return {};
  const auto& path = *pdef->getSolutionPath()->as<og::PathGeometric>();
  std::vector<Eigen::VectorXd> out;
  for (std::size_t i = 0; i < path.getStateCount(); ++i) {
    q.segment(first, count) = to_eigen(path.getState(static_cast<unsigned>(i)), count);
    out.push_back(q);
  }
  return out;
}

Eigen::VectorXd to_eigen(const ob::State* s, int n) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = v->values[i];
  return q;
}

void from_eigen(const Eigen::VectorXd& q, ob::State* s) {
  auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  for (Eigen::Index i = 0; i < q.size(); ++i) v->values[i] = q[i];
}

}  // namespace

Planner::Planner(Params params) : params_(std::move(params)), environment_(params_.octomap_resolution) {
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
  memory_.clear();
}

int Planner::warm_up(double from, double to, double step, double seconds_per_height, const std::function<bool()>& keep_going) {
  const std::shared_ptr<const PlanningModel> model = this->model();
  if (!model || !(step > 0.0)) return 0;
  const EndEffectorSpec* tool = nullptr;
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
    // A wall facing the robot 2 m ahead, the area at height z.
    Eigen::Isometry3d area = Eigen::Isometry3d::Identity();
    area.linear() << 0, 0, -1, 0, 1, 0, 1, 0, 0;  // z along -x (the wall's outward normal)
    area.translation() = Eigen::Vector3d(2.0, 0.0, z);
    const double height = z;  // the camera stays at the area's height (horizontal axis)
    // Twice: seeded with the neighbouring heights' postures (one family followed up the
    // wall), then from the start posture and random seeds only, for other families: near an
    // obstacle the one that fits is often another family.
    bool found = false;
    for (const bool seeded : {true, false}) {
      params.nspg_enough = seeded ? 1 : 2;
      const uint64_t seed = params.seed + 31u * static_cast<uint64_t>(index) + (seeded ? 0u : 17u);
      const PostureResult p = generate_posture(*model, checker, params, *tool, start, area, seed,
                                               seeded ? hints_for(*model, height) : std::vector<Eigen::VectorXd>{});
      for (const Eigen::VectorXd& q : p.valid) {
        // The arm's way from the start posture to it, where the map cannot interfere: later
        // plans replay it (checked against their map) instead of searching for it.
        Eigen::VectorXd parked = model->to_planned(start);
        parked.head<3>() = q.head<3>();
        std::vector<Eigen::VectorXd> path = subspace_rrt(*model, checker, start, params.check_resolution, 3, model->dof() - 3, model->lower(),
                                                         model->upper(), parked, q, kWarmUpPathTime, seed, nullptr);
        std::vector<Eigen::VectorXd> arms;
        for (const Eigen::VectorXd& w : path) arms.push_back(w.tail(w.size() - 3));
        remember(*model, height, q, std::move(arms));
      }
      found = found || p.found;
    }
    if (found) solved += 1;
  }
  return solved;
}

std::vector<Eigen::VectorXd> Planner::hints_for(const PlanningModel& model, double height) const {
  std::vector<std::pair<double, Eigen::VectorXd>> near;
  {
    std::lock_guard lock(mutex_);
    if (model_.get() != &model) return {};
    for (const Remembered& m : memory_) {
      if (std::abs(m.height - height) <= kHintHeight) near.emplace_back(std::abs(m.height - height), m.arm);
    }
  }
  std::sort(near.begin(), near.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::VectorXd> out;
  for (std::size_t i = 0; i < near.size() && out.size() < kHints; ++i) out.push_back(near[i].second);
  return out;
}

void Planner::remember(const PlanningModel& model, double height, const Eigen::VectorXd& q, std::vector<Eigen::VectorXd> arm_path) {
  if (params_.nspg_memory <= 0) return;
  std::lock_guard lock(mutex_);
  if (model_.get() != &model) return;
  const Eigen::VectorXd arm = q.tail(q.size() - 3);
  for (Remembered& m : memory_) {
    // The same posture again (both warm-up passes, or a plan that started from it): one entry.
    if (std::abs(m.height - height) < kSamePosture && (m.arm - arm).cwiseAbs().maxCoeff() < kSamePosture) {
      if (m.arm_path.empty()) m.arm_path = std::move(arm_path);
      return;
    }
  }
  if (static_cast<int>(memory_.size()) >= params_.nspg_memory) memory_.erase(memory_.begin());
  memory_.push_back({height, arm, std::move(arm_path)});
}

std::vector<Eigen::VectorXd> Planner::arm_path_to(const PlanningModel& model, const Eigen::VectorXd& arm) const {
  std::lock_guard lock(mutex_);
  if (model_.get() != &model) return {};
  // The goal's arm is compared with each remembered posture and with its mirror image (the
  // path then mirrored too: the robot's torques and self collisions are nearly symmetric, and
  // the replay is checked anyway).
  const std::optional<Eigen::VectorXd> goal_mirror = model.mirrored_arm(arm);
  const Remembered* best = nullptr;
  bool best_mirrored = false;
  double best_d = kArmPathReuse;
  const auto distance = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return (a.tail(a.size() - 1) - b.tail(b.size() - 1)).cwiseAbs().maxCoeff();
  };
  for (const Remembered& m : memory_) {
    if (m.arm_path.empty()) continue;
    for (const bool mirrored : {false, true}) {
      if (mirrored && !goal_mirror) continue;
      const double d = distance(m.arm, mirrored ? *goal_mirror : arm);
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
  const double turn = arm[0] - out.back()[0];  // the path ends at the remembered posture (or its image)
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

GoalResult Planner::plan_path(const PlanningModel& model, StateChecker& checker, const Eigen::VectorXd& q_start_full,
                              const Eigen::VectorXd& q_goal_in, double time_budget, uint64_t seed) const {
  const auto t0 = Clock::now();
  GoalResult r;
  const int n = model.dof();
  const Eigen::VectorXd q_start = model.to_planned(q_start_full);
  Eigen::VectorXd q_goal = q_goal_in;
  q_goal[2] = q_start[2] + std::remainder(q_goal[2] - q_start[2], 2.0 * M_PI);
  r.goal_q = q_goal;

  auto space = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned>(n));
  ob::RealVectorBounds bounds(static_cast<unsigned>(n));
  for (int i = 0; i < n; ++i) {
    const auto u = static_cast<unsigned>(i);
    if (i < 2) {
      bounds.setLow(u, std::min(q_start[i], q_goal[i]) - params_.base_range);
      bounds.setHigh(u, std::max(q_start[i], q_goal[i]) + params_.base_range);
    } else if (i == 2) {
      bounds.setLow(u, std::min(q_start[i], q_goal[i]) - M_PI);
      bounds.setHigh(u, std::max(q_start[i], q_goal[i]) + M_PI);
    } else {
      bounds.setLow(u, model.lower()[i]);
      bounds.setHigh(u, model.upper()[i]);
    }
  }
  space->setBounds(bounds);
  // Inequalities only: no task, gravity alone (no drilling force while moving).
  detail::PostureProblem feasible(model, params_, nullptr, q_start_full, std::nullopt, checker.distance_field());
  feasible.set_force_scale(0.0);
  const int iterations = params_.sample_iterations;
  bool planning = false;
  space->setStateSamplerAllocator([seed, &feasible, iterations, &planning](const ob::StateSpace* s) {
    return std::make_shared<SeededSampler>(s, seed, iterations > 0 ? &feasible : nullptr, iterations, &planning);
  });
  auto si = std::make_shared<ob::SpaceInformation>(space);
  Validity last_rejection;
  si->setStateValidityChecker([&](const ob::State* s) {
    const Validity v = checker.check(model.to_full(to_eigen(s, n), q_start_full));
    if (!v.valid()) last_rejection = v;
    return v.valid();
  });
  si->setStateValidityCheckingResolution(params_.check_resolution / space->getMaximumExtent());
  si->setup();
  planning = true;

  ob::ScopedState<> start(space);
  ob::ScopedState<> goal(space);
  from_eigen(q_start, start.get());
  from_eigen(q_goal, goal.get());
  const Validity vs = checker.check(q_start_full);
  if (!vs.valid()) {
    r.status = Status::kInvalidStart;
    r.reason = std::string("start state rejected by ") + to_string(vs.constraint) + ": " + vs.detail;
    return r;
  }

  std::vector<Eigen::VectorXd> waypoints;
  const Eigen::VectorXd box_lo = Eigen::Map<const Eigen::VectorXd>(bounds.low.data(), n);  // the planning space's bounds
  const Eigen::VectorXd box_hi = Eigen::Map<const Eigen::VectorXd>(bounds.high.data(), n);
  // A straight line whose intermediate states are pulled into the feasible set (each from
  // its point on the line, by the inequality rows): for a long arm the straight joint-space
  // line usually swings the arm out past its torque limits, and a slight fold on the way is
  // all it needs. Cheap compared with RRT-Connect, so it is tried first.
  auto projected_line = [&](const Eigen::VectorXd& from, const Eigen::VectorXd& target) -> std::vector<Eigen::VectorXd> {
    if (params_.sample_iterations <= 0) return {};
    Eigen::VectorXd residual;
    ob::ScopedState<> a(space), b(space);
    auto motion_ok = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
      from_eigen(x, a.get());
      from_eigen(y, b.get());
      return si->checkMotion(a.get(), b.get());
    };
    std::vector<Eigen::VectorXd> line{from};
    // Appends a feasible chain from line.back() to `to`: the direct motion, else a projected
    // midpoint and the two halves (bounded depth).
    std::function<bool(const Eigen::VectorXd&, int)> reach = [&](const Eigen::VectorXd& to, int depth) {
      if (motion_ok(line.back(), to)) {
        line.push_back(to);
        return true;
      }
      if (depth == 0) return false;
      Eigen::VectorXd mid = 0.5 * (line.back() + to);
      detail::solve(feasible, mid, box_lo, box_hi, 3 * params_.sample_iterations, 1.0, residual);
      return reach(mid, depth - 1) && reach(to, depth - 1);
    };
    const Eigen::VectorXd delta = target - from;
    const int segments = std::max(2, static_cast<int>(std::ceil(delta.cwiseAbs().maxCoeff() / kLineStep)));
    for (int k = 1; k <= segments; ++k) {
      // From the previous state moved by one step of the line, so a fold made on the way is
      // kept; the last segments steer back onto the target.
      const double left = static_cast<double>(segments - k + 1);
      Eigen::VectorXd q = k == segments ? target : Eigen::VectorXd(line.back() + (target - line.back()) / left);
      if (k < segments) detail::solve(feasible, q, box_lo, box_hi, 3 * params_.sample_iterations, 1.0, residual);
      if (!reach(q, 3)) return {};
    }
    return line;
  };
  // RRT-Connect over the joints [first, first + count) with the others held.
  auto subspace_path = [&](int first, int count, const Eigen::VectorXd& from, const Eigen::VectorXd& to, double budget) {
    return subspace_rrt(model, checker, q_start_full, params_.check_resolution, first, count, box_lo, box_hi, from, to, budget, seed,
                        &last_rejection);
  };
  // The arm's moves with the base held: a path remembered by the warm-up for a posture like the
  // goal's (checked here against the map), else RRT-Connect over the arm's joints.
  bool replayed = false;  // the arm's path came from the memory
  auto arm_path = [&](const Eigen::VectorXd& from, const Eigen::VectorXd& to, double budget) -> std::vector<Eigen::VectorXd> {
    const std::vector<Eigen::VectorXd> known = arm_path_to(model, to.tail(n - 3));
    if (!known.empty()) {
      std::vector<Eigen::VectorXd> chain{from};
      for (const Eigen::VectorXd& arm : known) {
        Eigen::VectorXd q = from;
        q.tail(n - 3) = arm;
        chain.push_back(q);
      }
      chain.push_back(to);
      bool ok = true;
      ob::ScopedState<> a(space), b(space);
      for (std::size_t i = 1; i < chain.size() && ok; ++i) {
        from_eigen(chain[i - 1], a.get());
        from_eigen(chain[i], b.get());
        ok = si->checkMotion(a.get(), b.get());
      }
      if (ok) {
        replayed = true;
        return chain;
      }
    }
    return subspace_path(3, n - 3, from, to, budget);
  };
  // The drive alone (x, y, yaw; the arm held): the projected line, else RRT-Connect over the
  // base's three joints around the obstacles.
  auto drive = [&](const Eigen::VectorXd& from, const Eigen::VectorXd& to, double budget) {
    std::vector<Eigen::VectorXd> line = projected_line(from, to);
    return line.empty() ? subspace_path(0, 3, from, to, budget) : line;
  };
  // The arm alone, its path found by RRT-Connect in the arm's joint space with the base
  // standing still (the environment still checked), and a drive before or after it: first
  // the arm at the start's base pose then a drive with the goal's arm posture, else a drive
  // with the start's arm posture then the arm at the goal's base pose. A long arm holding a
  // low area sits in a narrow pocket of torque-feasible, self-collision-free arm postures; the
  // pocket is cheap to enter in the arm's 6 dimensions and rarely entered by a whole-body tree
  // that also drives (on the benchmark's low areas for morphology B: arm-only 0.03-1.3 s,
  // whole-body 2 of 12 in 8 s). Half the budget for each part.
  auto arm_and_drive = [&](bool reach_first, double budget) -> std::vector<Eigen::VectorXd> {
    replayed = false;
    const auto t_order = Clock::now();
    const auto rest = [&] { return std::max(0.0, budget - seconds_since(t_order)); };
    Eigen::VectorXd turn = q_start;  // where the arm moves: the start's or the goal's base pose
    if (!reach_first) turn.head<3>() = q_goal.head<3>();
    Eigen::VectorXd turned = turn;
    turned.tail(n - 3) = q_goal.tail(n - 3);
    std::vector<Eigen::VectorXd> first = reach_first ? arm_path(q_start, turned, 0.5 * budget) : drive(q_start, turn, 0.5 * budget);
    if (first.empty()) return {};
    std::vector<Eigen::VectorXd> second = reach_first ? drive(turned, q_goal, rest()) : arm_path(turn, q_goal, rest());
    if (second.empty()) return {};
    first.insert(first.end(), second.begin() + 1, second.end());
    return first;
  };
  // A path shortcut and thinned in the whole-body space (shortcuts join the arm's and the
  // base's moves where they can go together), as waypoints.
  auto simplified_path = [&](og::PathGeometric& path) {
    const auto steps = static_cast<unsigned>(params_.simplify_iterations);
    og::PathSimplifier simplifier(si);
    simplifier.shortcutPath(path, steps, steps);
    simplifier.reduceVertices(path, steps);
    simplifier.collapseCloseVertices(path);
    std::vector<Eigen::VectorXd> out;
    for (std::size_t i = 0; i < path.getStateCount(); ++i) out.push_back(to_eigen(path.getState(static_cast<unsigned>(i)), n));
    return out;
  };
  auto simplified = [&](const std::vector<Eigen::VectorXd>& line) {
    og::PathGeometric path(si);
    for (const Eigen::VectorXd& q : line) {
      ob::ScopedState<> st(space);
      from_eigen(q, st.get());
      path.append(st.get());
    }
    return simplified_path(path);
  };
  std::vector<Eigen::VectorXd> line;
  if (si->checkMotion(start.get(), goal.get())) {
    waypoints = {q_start, q_goal};
    r.path_method = "direct";
  } else if (line = projected_line(q_start, q_goal); !line.empty()) {
    waypoints = simplified(line);
    r.path_method = "projected line";
  } else if (line = arm_and_drive(true, kArmShare * std::max(0.0, time_budget - seconds_since(t0))), !line.empty()) {
    waypoints = simplified(line);
    r.path_method = replayed ? "remembered arm path, then drive" : "arm, then drive";
  } else if (line = arm_and_drive(false, kArmShare * std::max(0.0, time_budget - seconds_since(t0))), !line.empty()) {
    waypoints = simplified(line);
    r.path_method = replayed ? "drive, then remembered arm path" : "drive, then arm";
  } else {
    r.path_method = "RRT-Connect";
    auto pdef = std::make_shared<ob::ProblemDefinition>(si);
    pdef->setStartAndGoalStates(start, goal);
    og::RRTConnect rrt(si);
    rrt.setProblemDefinition(pdef);
    rrt.setup();
    const double budget = std::max(0.0, time_budget - seconds_since(t0));
    const ob::PlannerStatus st = rrt.solve(ob::timedPlannerTerminationCondition(budget));
    if (st != ob::PlannerStatus::EXACT_SOLUTION) {
      r.status = Status::kNoPath;
      std::ostringstream s;
      s << "no collision-free path (direct, projected line, arm alone before or after driving, then RRT-Connect for "
        << budget << " s)";
      if (!last_rejection.valid()) s << " (last rejection: " << to_string(last_rejection.constraint) << ": " << last_rejection.detail << ")";
      r.reason = s.str();
      r.plan_seconds = seconds_since(t0);
      return r;
    }
    waypoints = simplified_path(*pdef->getSolutionPath()->as<og::PathGeometric>());
  }
  r.trajectory = time_parameterize(waypoints, model.joint_names(), motion_limits(model, params_), params_.sample_period);
  r.status = Status::kSucceeded;
  r.plan_seconds = seconds_since(t0);
  return r;
}

PlanResult Planner::plan(const PlanRequest& request, const Eigen::VectorXd& q_start_full, const GoalCallback& on_goal) {
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
    return fail(Status::kStaleModel, "request made for model version " + std::to_string(request.model_version) +
                                         " but the planner runs model version " + std::to_string(model->version()));
  }
  if (request.goals.empty()) return fail(Status::kInvalidRequest, "request has no goals");
  if (q_start_full.size() != model->full_dof() || !q_start_full.allFinite()) {
    return fail(Status::kInvalidStart, "start state has " + std::to_string(q_start_full.size()) + " joints, model version " +
                                           std::to_string(model->version()) + " has " + std::to_string(model->full_dof()));
  }
  const EndEffectorSpec* tool = nullptr;
  try {
    tool = &model->tool(request.end_effector);
    (void)model->camera_frame(*tool);
  } catch (const PlannerError& e) {
    return fail(Status::kInvalidRequest, e.what());
  }
  for (std::size_t g = 0; g < request.goals.size(); ++g) {
    const Eigen::Isometry3d& a = request.goals[g].area;
    if (!a.matrix().allFinite() || std::abs(a.linear().determinant() - 1.0) > 1e-3) {
      return fail(Status::kInvalidRequest, "goal " + std::to_string(g) + ": drilling area frame is not a finite rigid transform");
    }
  }

  StateChecker checker(model, env, params_, params_.environment_padding);
  const Validity start_ok = checker.check(q_start_full);
  if (!start_ok.valid()) {
    return fail(Status::kInvalidStart,
                std::string("start state rejected by ") + to_string(start_ok.constraint) + ": " + start_ok.detail);
  }
  Eigen::VectorXd current = q_start_full;
  out.status = Status::kSucceeded;
  for (std::size_t g = 0; g < request.goals.size(); ++g) {
    const auto t0 = Clock::now();
    const uint64_t seed = params_.seed + 7919u * request.request_id + 104729u * g;
    // Goal posture, then a path to it; when no path is found within the attempt's share of
    // the budget, another goal posture is tried while time remains (the posture search goes on
    // from the seed after the one that gave the previous posture): with a long arm some goal
    // postures sit in torque-feasible pockets no path reaches.
    GoalResult r;
    double nspg = 0.0;
    const double height = (request.goals[g].area * Eigen::Vector3d(0.0, 0.0, params_.camera_distance)).z();
    const std::vector<Eigen::VectorXd> hints = hints_for(*model, height);
    int next_seed = 0;
    // The arm shapes no path reached: the posture search's next seeds are often the same
    // posture with the first joint turned, whose arm shape no path reaches either (on the
    // benchmark, morphology B's low areas: four such attempts in a row used up the budget).
    std::vector<Eigen::VectorXd> unreached;
    const auto like_unreached = [&](const Eigen::VectorXd& q) {
      const Eigen::Index n = q.size() - 4;  // arm joints after the first
      return std::any_of(unreached.begin(), unreached.end(),
                         [&](const Eigen::VectorXd& arm) { return (arm.tail(n) - q.tail(n)).cwiseAbs().maxCoeff() < kSameShape; });
    };
    for (int attempt = 0;; ++attempt) {
      const auto t_posture = Clock::now();
      Params attempt_params = params_;
      PostureResult posture;
      do {
        attempt_params.nspg_time = std::min(params_.nspg_time, params_.planning_time - seconds_since(t0));
        posture = generate_posture(*model, checker, attempt_params, *tool, current, request.goals[g].area,
                                   seed + 7777u * static_cast<uint64_t>(attempt), hints, next_seed);
        next_seed = posture.next_seed;
      } while (posture.found && like_unreached(posture.q) && params_.planning_time - seconds_since(t0) > 0.05);
      nspg += seconds_since(t_posture);
      if (!posture.found) {
        if (attempt > 0) break;  // keep the previous attempt's "no path"
        r.status = Status::kUnreachable;
        r.reason = "no feasible posture puts camera '" + model->camera_frame(*tool) + "' " +
                   std::to_string(params_.camera_distance) + " m in front of the drilling area (" + std::to_string(posture.candidates) +
                   " seeds solved; " + posture.reason + ")";
        break;
      }
      const double remaining = params_.planning_time - seconds_since(t0);
      r = plan_path(*model, checker, current, posture.q, std::min(remaining, params_.path_attempt_time), seed);
      r.nspg_seconds = nspg;
      if (r.status == Status::kSucceeded) remember(*model, height, posture.q);
      if (r.status == Status::kNoPath) unreached.push_back(posture.q.tail(posture.q.size() - 3));
      if (r.status != Status::kNoPath || params_.planning_time - seconds_since(t0) < 0.05) break;
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
