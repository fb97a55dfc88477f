#pragma once
// Whole-body planner (paper section 5.4.2): NSPG goal postures, OMPL RRT-Connect over base
// (x, y, yaw) + arm joints, path simplification, time parameterisation. Goals in FIFO order.

#include <functional>
#include <memory>
#include <mutex>

#include "planner/environment.hpp"
#include "planner/planning_model.hpp"
#include "planner/state_checker.hpp"

namespace concert::planner {

/// Result of the Null-Space Posture Generator.
struct PostureResult {
  bool found = false;
  Eigen::VectorXd q;          ///< planned joints; valid when found
  double cost = 0.0;          ///< distance to start + singularity cost
  std::string reason;         ///< why nothing was found (most frequent rejection)
  int candidates = 0;         ///< postures on the task manifold examined
};

/// Null-Space Posture Generator: from `q_start_full`, converge the camera frame onto the task
/// (camera at Params::camera_distance in front of `area` along its z axis, optical axis
/// along -z of `area`) by weighted damped least squares, then random-walk in the task's null
/// space; keep the valid posture (contact force on the tool checked) of least cost. Seeded
/// by `seed`.
PostureResult generate_posture(const PlanningModel& model, StateChecker& checker, const Params& params,
                               const EndEffectorSpec& tool, const Eigen::VectorXd& q_start_full, const Eigen::Isometry3d& area,
                               uint64_t seed);

/// Task error of a full q against a drilling area: (position error [m], axis error [rad]).
std::pair<double, double> task_error(const PlanningModel& model, const Params& params, const EndEffectorSpec& tool,
                                     const Eigen::VectorXd& q_full, const Eigen::Isometry3d& area);

/// The planner of the planner service. Thread-safe: set_model/set_environment may come from
/// one thread while plan() runs in another (plan() uses the model it started with).
class Planner {
 public:
  explicit Planner(Params params = {});

  /// Rebuilds the configuration space for a new model version (also after a hot swap).
  /// Throws PlannerError and keeps the previous model on failure.
  void set_model(const ModelDescription& description);
  /// Replaces the map.
  void set_environment(Environment environment);
  /// Current model version (0: none).
  [[nodiscard]] uint64_t model_version() const;
  [[nodiscard]] std::shared_ptr<const PlanningModel> model() const;
  [[nodiscard]] Environment environment() const;
  [[nodiscard]] const Params& params() const { return params_; }

  /// Called after each goal is planned (FIFO), so its trajectory can be executed while the
  /// next goals are planned.
  using GoalCallback = std::function<void(const GoalResult&)>;
  /// Plans every goal of `request` in order, goal i starting where goal i-1 ends (the first
  /// from `q_start_full`, a full q of the request's model). A failed goal is reported and the
  /// next one starts from the last reached posture. Never throws for bad requests: the
  /// status and reason say what is wrong (no model, stale model version, bad start state...).
  PlanResult plan(const PlanRequest& request, const Eigen::VectorXd& q_start_full, const GoalCallback& on_goal = {});

  /// Plans a path between two planned-joint postures (RRT-Connect, simplification, timing).
  GoalResult plan_path(const PlanningModel& model, StateChecker& checker, const Eigen::VectorXd& q_start_full,
                       const Eigen::VectorXd& q_goal, double time_budget, uint64_t seed) const;

 private:
  Params params_;
  mutable std::mutex mutex_;
  std::shared_ptr<const PlanningModel> model_;
  Environment environment_;
};

}  // namespace concert::planner
