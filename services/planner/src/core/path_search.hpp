#pragma once
// The path search between two postures (paper section 5.4.2), internal to
// concert_planner_core: Planner::plan_path runs one PathSearch per goal posture, the warm-up
// uses subspace_rrt for the arm's paths. The methods, cheapest first:
//
//   1. the direct motion;
//   2. a projected line: a straight line whose states are pulled into the feasible set by the
//      posture problem's inequality rows (torque, self collision, floor, obstacles);
//   3. the arm alone at the start's base pose, then a drive; 4. a drive, then the arm alone at
//      the goal's base pose (the arm's path remembered by the warm-up, else RRT-Connect over
//      the arm's joints; each drive the projected line, else RRT-Connect over x, y, yaw);
//   5. OMPL RRT-Connect over the whole body, every other sample pulled toward feasibility.
//
// Every path is shortcut and thinned in the whole-body space; motions are checked every
// Params::check_resolution.

#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>

#include <Eigen/Core>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cpu_clock.hpp"
#include "planner/planning_model.hpp"
#include "planner/state_checker.hpp"
#include "posture_problem.hpp"

namespace concert::planner::detail {

// RRT-Connect over the planned joints [first, first + count) alone, the others held as in
// `from`, within [lo, hi]: the chain of planned states from `from` to `to` (which differ only
// in those joints), or none within `budget` [s]. Returns at once when an end is invalid.
std::vector<Eigen::VectorXd> subspace_rrt(const PlanningModel& model, StateChecker& checker,
                                          const Eigen::VectorXd& full_template,
                                          double check_resolution, int first, int count,
                                          const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                                          const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                          double budget, uint64_t seed, Validity* last_rejection);

class PathSearch {
 public:
  // The arm's remembered path (arm joints, from the parked arm) to an arm posture like the
  // given one, or empty.
  using RememberedArmPath = std::function<std::vector<Eigen::VectorXd>(const Eigen::VectorXd& arm)>;

  // From the full start state to the planned goal posture (its yaw taken within pi of the
  // start's). The search space: the base within Params::base_range of both ends, the arm
  // within its joint limits.
  PathSearch(const PlanningModel& model, StateChecker& checker, const Params& params,
             const Eigen::VectorXd& q_start_full, const Eigen::VectorXd& q_goal, uint64_t seed,
             RememberedArmPath remembered);
  PathSearch(const PathSearch&) = delete;  // OMPL's callbacks hold `this`
  PathSearch& operator=(const PathSearch&) = delete;

  // Planned waypoints from start to goal, shortcut and thinned, or empty when no method found
  // a path before `deadline`.
  std::vector<Eigen::VectorXd> run(ThreadCpuClock::time_point deadline);

  [[nodiscard]] const Eigen::VectorXd& goal() const { return q_goal_; }
  // The method that found the path (GoalResult::path_method), or the last one tried.
  [[nodiscard]] const std::string& method() const { return method_; }
  // Why no path was found (after run() returned empty).
  [[nodiscard]] const std::string& reason() const { return reason_; }

 private:
  using Path = std::vector<Eigen::VectorXd>;
  [[nodiscard]] double seconds_left() const;
  bool motion_ok(const Eigen::VectorXd& from, const Eigen::VectorXd& to);
  Path projected_line(const Eigen::VectorXd& from, const Eigen::VectorXd& target);
  Path subspace(int first, int count, const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                double budget);
  Path arm_path(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double budget);
  Path drive(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double budget);
  Path arm_and_drive(bool reach_first, double budget);
  Path whole_body_rrt(double budget);
  Path simplified(ompl::geometric::PathGeometric& path);
  Path simplified(const Path& chain);

  const PlanningModel& model_;
  StateChecker& checker_;
  const Params& params_;
  const Eigen::VectorXd q_start_full_;
  const uint64_t seed_;
  const RememberedArmPath remembered_;
  const int n_;
  Eigen::VectorXd q_start_, q_goal_;
  Eigen::VectorXd lo_, hi_;  // the search space's bounds
  PostureProblem
      feasible_;  // inequalities only: no task, gravity alone (no drilling force while moving)
  bool sampling_ = false;  // samples pulled toward feasibility (off during OMPL's set-up)
  std::shared_ptr<ompl::base::RealVectorStateSpace> space_;
  std::shared_ptr<ompl::base::SpaceInformation> si_;
  Validity last_rejection_;
  bool replayed_ = false;  // the arm's path came from the memory
  ThreadCpuClock::time_point deadline_;
  std::string method_;
  std::string reason_;
};

}  // namespace concert::planner::detail
