// The path search between two postures (see path_search.hpp).

#include "path_search.hpp"

#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

namespace concert::planner::detail {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using Clock = ThreadCpuClock;

// Largest joint change [rad or m] between the states of a projected straight line.
constexpr double kLineStep = 0.15;
// Share of a path attempt's remaining time for each order of the arm-alone-and-drive search
// (arm first, then drive first, each of what is left); the rest is whole-body RRT-Connect's.
constexpr double kArmShare = 0.5;

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

// OMPL's uniform sampler with a per-plan seed, so plans are reproducible. Every other sample
// is pulled toward the feasible set by a few Gauss-Newton steps on the posture problem's
// inequality rows (gravity torque, self collision, floor, map obstacles): with a long arm the
// torque-feasible states are a thin subset of the joint box, and uniform samples alone
// rarely land in it, so RRT-Connect's trees stop growing (morphology B).
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, uint64_t seed, PostureProblem* feasible,
                int iterations, const bool* active)
      : ob::RealVectorStateSampler(space),
        feasible_(feasible),
        iterations_(iterations),
        active_(active) {
    rng_.setLocalSeed(static_cast<std::uint_fast32_t>(seed));
    const auto& bounds = space->as<ob::RealVectorStateSpace>()->getBounds();
    lo_ = Eigen::Map<const Eigen::VectorXd>(bounds.low.data(),
                                            static_cast<Eigen::Index>(bounds.low.size()));
    hi_ = Eigen::Map<const Eigen::VectorXd>(bounds.high.data(),
                                            static_cast<Eigen::Index>(bounds.high.size()));
  }
  void sampleUniform(ob::State* state) override {
    ob::RealVectorStateSampler::sampleUniform(state);
    if (feasible_ == nullptr || !*active_ || (count_++ % 2) == 0) return;
    auto* v = state->as<ob::RealVectorStateSpace::StateType>();
    Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(v->values, lo_.size());
    Eigen::VectorXd r;
    solve(*feasible_, q, lo_, hi_, iterations_, 1.0, r);
    for (Eigen::Index i = 0; i < q.size(); ++i) v->values[i] = q[i];
  }

 private:
  PostureProblem* feasible_;
  int iterations_;
  const bool* active_;  // off during OMPL's set-up (its sanity checks draw many samples)
  Eigen::VectorXd lo_, hi_;
  unsigned long count_ = 0;
};

// RRT-Connect from `a` to `b` within `budget` [s of this thread's CPU time]: the path, or none.
std::optional<og::PathGeometric> rrt_connect(const ob::SpaceInformationPtr& si,
                                             const ob::ScopedState<>& a, const ob::ScopedState<>& b,
                                             double budget) {
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->setStartAndGoalStates(a, b);
  og::RRTConnect rrt(si);
  rrt.setProblemDefinition(pdef);
  rrt.setup();
  const Clock::time_point deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                        std::chrono::duration<double>(budget));
  const ob::PlannerTerminationCondition out_of_time([deadline] { return Clock::now() > deadline; });
  if (rrt.solve(out_of_time) != ob::PlannerStatus::EXACT_SOLUTION) return std::nullopt;
  return *pdef->getSolutionPath()->as<og::PathGeometric>();
}

}  // namespace

std::vector<Eigen::VectorXd> subspace_rrt(const PlanningModel& model, StateChecker& checker,
                                          const Eigen::VectorXd& full_template,
                                          double check_resolution, int first, int count,
                                          const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                                          const Eigen::VectorXd& from, const Eigen::VectorXd& to,
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
  sub->setStateSamplerAllocator([seed](const ob::StateSpace* s) {
    return std::make_shared<SeededSampler>(s, seed, nullptr, 0, &kActive);
  });
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
  const std::optional<og::PathGeometric> path = rrt_connect(sub_si, a, b, budget);
  if (!path) return {};
  std::vector<Eigen::VectorXd> out;
  for (std::size_t i = 0; i < path->getStateCount(); ++i) {
    q.segment(first, count) = to_eigen(path->getState(static_cast<unsigned>(i)), count);
    out.push_back(q);
  }
  return out;
}

PathSearch::PathSearch(const PlanningModel& model, StateChecker& checker, const Params& params,
                       const Eigen::VectorXd& q_start_full, const Eigen::VectorXd& q_goal,
                       uint64_t seed, RememberedArmPath remembered)
    : model_(model),
      checker_(checker),
      params_(params),
      q_start_full_(q_start_full),
      seed_(seed),
      remembered_(std::move(remembered)),
      n_(model.dof()),
      q_start_(model.to_planned(q_start_full)),
      q_goal_(q_goal),
      feasible_(model, params, nullptr, q_start_full, std::nullopt, checker.distance_field()) {
  q_goal_[2] = q_start_[2] + std::remainder(q_goal_[2] - q_start_[2], 2.0 * M_PI);
  feasible_.set_force_scale(0.0);
  lo_.resize(n_);
  hi_.resize(n_);
  for (int i = 0; i < n_; ++i) {
    const double margin = params.fixed_base && i < 3 ? 0.0 : i < 2 ? params.base_range : M_PI;
    lo_[i] = i < 3 ? std::min(q_start_[i], q_goal_[i]) - margin : model.lower()[i];
    hi_[i] = i < 3 ? std::max(q_start_[i], q_goal_[i]) + margin : model.upper()[i];
  }
  space_ = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned>(n_));
  ob::RealVectorBounds bounds(static_cast<unsigned>(n_));
  for (int i = 0; i < n_; ++i) {
    bounds.setLow(static_cast<unsigned>(i), lo_[i]);
    bounds.setHigh(static_cast<unsigned>(i), hi_[i]);
  }
  space_->setBounds(bounds);
  PostureProblem* pull = params.sample_iterations > 0 ? &feasible_ : nullptr;
  const int iterations = params.sample_iterations;
  const bool* active = &sampling_;
  space_->setStateSamplerAllocator([seed, pull, iterations, active](const ob::StateSpace* s) {
    return std::make_shared<SeededSampler>(s, seed, pull, iterations, active);
  });
  si_ = std::make_shared<ob::SpaceInformation>(space_);
  si_->setStateValidityChecker([this](const ob::State* s) {
    const Validity v = checker_.check(model_.to_full(to_eigen(s, n_), q_start_full_));
    if (!v.valid()) last_rejection_ = v;
    return v.valid();
  });
  si_->setStateValidityCheckingResolution(params.check_resolution / space_->getMaximumExtent());
  si_->setup();
  sampling_ = true;
}

double PathSearch::seconds_left() const {
  return std::max(0.0, std::chrono::duration<double>(deadline_ - Clock::now()).count());
}

bool PathSearch::motion_ok(const Eigen::VectorXd& from, const Eigen::VectorXd& to) {
  ob::ScopedState<> a(space_), b(space_);
  from_eigen(from, a.get());
  from_eigen(to, b.get());
  return si_->checkMotion(a.get(), b.get());
}

// A straight line whose intermediate states are pulled into the feasible set (each from its
// point on the line, by the inequality rows): for a long arm the straight joint-space line
// usually swings the arm out past its torque limits, and a slight fold on the way is all it
// needs. Cheap compared with RRT-Connect, so it is tried first.
PathSearch::Path PathSearch::projected_line(const Eigen::VectorXd& from,
                                            const Eigen::VectorXd& target) {
  if (params_.sample_iterations <= 0) return {};
  Eigen::VectorXd residual;
  Path line{from};
  // Appends a feasible chain from line.back() to `to`: the direct motion, else a projected
  // midpoint and the two halves (bounded depth).
  std::function<bool(const Eigen::VectorXd&, int)> reach = [&](const Eigen::VectorXd& to,
                                                               int depth) {
    if (motion_ok(line.back(), to)) {
      line.push_back(to);
      return true;
    }
    if (depth == 0) return false;
    Eigen::VectorXd mid = 0.5 * (line.back() + to);
    solve(feasible_, mid, lo_, hi_, 3 * params_.sample_iterations, 1.0, residual);
    return reach(mid, depth - 1) && reach(to, depth - 1);
  };
  const Eigen::VectorXd delta = target - from;
  const int segments =
      std::max(2, static_cast<int>(std::ceil(delta.cwiseAbs().maxCoeff() / kLineStep)));
  for (int k = 1; k <= segments; ++k) {
    // From the previous state moved by one step of the line, so a fold made on the way is
    // kept; the last segments steer back onto the target.
    const double left = static_cast<double>(segments - k + 1);
    Eigen::VectorXd q =
        k == segments ? target : Eigen::VectorXd(line.back() + (target - line.back()) / left);
    if (k < segments) solve(feasible_, q, lo_, hi_, 3 * params_.sample_iterations, 1.0, residual);
    if (!reach(q, 3)) return {};
  }
  return line;
}

// RRT-Connect over the joints [first, first + count) with the others held.
PathSearch::Path PathSearch::subspace(int first, int count, const Eigen::VectorXd& from,
                                      const Eigen::VectorXd& to, double budget) {
  return subspace_rrt(model_, checker_, q_start_full_, params_.check_resolution, first, count, lo_,
                      hi_, from, to, budget, seed_, &last_rejection_);
}

// The arm's moves with the base held: a path remembered by the warm-up for a posture like the
// goal's (checked here against the map), else RRT-Connect over the arm's joints.
PathSearch::Path PathSearch::arm_path(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                      double budget) {
  const Path known = remembered_ ? remembered_(to.tail(n_ - 3)) : Path{};
  if (!known.empty()) {
    Path chain{from};
    for (const Eigen::VectorXd& arm : known) {
      Eigen::VectorXd q = from;
      q.tail(n_ - 3) = arm;
      chain.push_back(q);
    }
    chain.push_back(to);
    bool ok = true;
    for (std::size_t i = 1; i < chain.size() && ok; ++i) ok = motion_ok(chain[i - 1], chain[i]);
    if (ok) {
      replayed_ = true;
      return chain;
    }
  }
  return subspace(3, n_ - 3, from, to, budget);
}

// The drive alone (x, y, yaw; the arm held): the projected line, else RRT-Connect over the
// base's three joints around the obstacles.
PathSearch::Path PathSearch::drive(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                   double budget) {
  Path line = projected_line(from, to);
  return line.empty() ? subspace(0, 3, from, to, budget) : line;
}

// The arm alone, its path found by RRT-Connect in the arm's joint space with the base standing
// still (the environment still checked), and a drive before or after it: first the arm at the
// start's base pose then a drive with the goal's arm posture, else a drive with the start's
// arm posture then the arm at the goal's base pose. A long arm holding a low area sits in a
// narrow pocket of torque-feasible, self-collision-free arm postures; the pocket is cheap to
// enter in the arm's 6 dimensions and rarely entered by a whole-body tree that also drives (on
// the benchmark's low areas for morphology B: arm-only 0.03-1.3 s, whole-body 2 of 12 in 8 s).
// Half the budget for each part.
PathSearch::Path PathSearch::arm_and_drive(bool reach_first, double budget) {
  replayed_ = false;
  const auto t_order = Clock::now();
  const auto rest = [&] { return std::max(0.0, budget - cpu_seconds_since(t_order)); };
  Eigen::VectorXd turn = q_start_;  // where the arm moves: the start's or the goal's base pose
  if (!reach_first) turn.head<3>() = q_goal_.head<3>();
  Eigen::VectorXd turned = turn;
  turned.tail(n_ - 3) = q_goal_.tail(n_ - 3);
  Path first =
      reach_first ? arm_path(q_start_, turned, 0.5 * budget) : drive(q_start_, turn, 0.5 * budget);
  if (first.empty()) return {};
  Path second = reach_first ? drive(turned, q_goal_, rest()) : arm_path(turn, q_goal_, rest());
  if (second.empty()) return {};
  first.insert(first.end(), second.begin() + 1, second.end());
  return first;
}

PathSearch::Path PathSearch::whole_body_rrt(double budget) {
  ob::ScopedState<> start(space_), goal(space_);
  from_eigen(q_start_, start.get());
  from_eigen(q_goal_, goal.get());
  std::optional<og::PathGeometric> path = rrt_connect(si_, start, goal, budget);
  return path ? simplified(*path) : Path{};
}

// A path shortcut and thinned in the whole-body space (shortcuts join the arm's and the base's
// moves where they can go together), as waypoints.
PathSearch::Path PathSearch::simplified(og::PathGeometric& path) {
  const auto steps = static_cast<unsigned>(params_.simplify_iterations);
  og::PathSimplifier simplifier(si_);
  simplifier.shortcutPath(path, steps, steps);
  simplifier.reduceVertices(path, steps);
  simplifier.collapseCloseVertices(path);
  Path out;
  for (std::size_t i = 0; i < path.getStateCount(); ++i)
    out.push_back(to_eigen(path.getState(static_cast<unsigned>(i)), n_));
  return out;
}

PathSearch::Path PathSearch::simplified(const Path& chain) {
  og::PathGeometric path(si_);
  for (const Eigen::VectorXd& q : chain) {
    ob::ScopedState<> st(space_);
    from_eigen(q, st.get());
    path.append(st.get());
  }
  return simplified(path);
}

std::vector<Eigen::VectorXd> PathSearch::run(Clock::time_point deadline) {
  deadline_ = deadline;
  Path line;
  if (motion_ok(q_start_, q_goal_)) {
    method_ = "direct";
    return {q_start_, q_goal_};
  }
  if (line = projected_line(q_start_, q_goal_); !line.empty()) {
    method_ = "projected line";
    return simplified(line);
  }
  if (line = arm_and_drive(true, kArmShare * seconds_left()); !line.empty()) {
    method_ = replayed_ ? "remembered arm path, then drive" : "arm, then drive";
    return simplified(line);
  }
  if (line = arm_and_drive(false, kArmShare * seconds_left()); !line.empty()) {
    method_ = replayed_ ? "drive, then remembered arm path" : "drive, then arm";
    return simplified(line);
  }
  method_ = "RRT-Connect";
  const double budget = seconds_left();
  if (line = whole_body_rrt(budget); !line.empty()) return line;
  std::ostringstream s;
  s << "no collision-free path (direct, projected line, arm alone before or after driving, then "
       "RRT-Connect for "
    << budget << " s)";
  if (!last_rejection_.valid())
    s << " (last rejection: " << to_string(last_rejection_.constraint) << ": "
      << last_rejection_.detail << ")";
  reason_ = s.str();
  return {};
}

}  // namespace concert::planner::detail
