#pragma once
// Whole-body planner (paper section 5.4.2): NSPG goal postures, OMPL RRT-Connect over base
// (x, y, yaw) + arm joints, path simplification, time parameterisation. Goals in FIFO order.

#include <functional>
#include <list>
#include <map>
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
  int candidates = 0;         ///< seeds solved (each ends on the task or held off it)
  std::vector<Eigen::VectorXd> valid;  ///< every valid posture found (q among them)
  int next_seed = 0;          ///< index of the first seed not tried (resume from here)
};

/// Null-Space Posture Generator: the camera frame at Params::camera_distance in front of `area`
/// along its z axis, optical axis along -z of `area`, found by solving the task with the
/// inequalities (torque with the contact force, clearances) in its null space from the start
/// posture and seeded random ones, until Params::nspg_time; keeps the valid posture of least
/// cost. Seeded by `seed`.
/// `hints`: arm postures (planned joints after the base) to seed after the start posture,
/// best first (the planner passes postures that solved nearby areas before), followed by their
/// mirror images (PlanningModel::mirrored_arm). The start posture, the hints and the images
/// are then tried again with the first arm joint turned (the base placement follows, so the
/// posture reaches the area from another side) before random seeds.
/// `first_seed`: skip the seeds before this index (a previous result's next_seed: another
/// posture for the same goal, when no path reached the first one).
/// `keep_going` (or empty): asked before each seed; false ends the search there, as the budget
/// would (the warm-up's shutdown: a height's search costs seconds of CPU).
PostureResult generate_posture(const PlanningModel& model, StateChecker& checker, const Params& params,
                               const EndEffectorInfo& tool, const Eigen::VectorXd& q_start_full, const Eigen::Isometry3d& area,
                               uint64_t seed, const std::vector<Eigen::VectorXd>& hints = {}, int first_seed = 0,
                               const std::function<bool()>& keep_going = {});

/// Task error of a full q against a drilling area: (position error [m], axis error [rad]).
std::pair<double, double> task_error(const PlanningModel& model, const Params& params, const EndEffectorInfo& tool,
                                     const Eigen::VectorXd& q_full, const Eigen::Isometry3d& area);

/// The full q with `frame` moved `reach` [m] along the world direction `axis` (unit), its
/// orientation kept, by the arm joints alone within their limits (damped least squares; the
/// base and every other joint stand); nullopt when the arm cannot get within 0.1 mm and 0.1 mrad.
/// The drilling posture's reach (Params::tip_reach): where the bit ends in the hole.
std::optional<Eigen::VectorXd> reached_posture(const PlanningModel& model, const Eigen::VectorXd& q_full,
                                               const std::string& frame, const Eigen::Vector3d& axis,
                                               double reach);

/// The homing posture of `model` as planned joints: the base of `q_full`, every arm joint at
/// its SRDF `home` value (0 where the SRDF names none) clamped into its limits.
Eigen::VectorXd home_posture(const PlanningModel& model, const Eigen::VectorXd& q_full);

/// The planner of the planner service. Thread-safe: set_model/set_environment may come from
/// one thread while plan() runs in another (plan() uses the model it started with).
class Planner {
 public:
  explicit Planner(Params params = {});

  /// Rebuilds the configuration space for a new model version (also after a hot swap).
  /// Throws PlannerError and keeps the previous model on failure. The posture memory follows
  /// the model's content hash: a version of a model seen before (the drill swapped back on)
  /// gets back what that model remembered (Params::memory_models); a model without a hash
  /// starts empty.
  void set_model(const ModelDescription& description);
  /// Goal postures the current model's memory holds (seeds for later goals).
  [[nodiscard]] std::size_t remembered() const;
  /// Replaces the map.
  void set_environment(Environment environment);
  /// Current model version (0: none).
  [[nodiscard]] uint64_t model_version() const;
  [[nodiscard]] std::shared_ptr<const PlanningModel> model() const;
  [[nodiscard]] Environment environment() const;
  [[nodiscard]] const Params& params() const { return params_; }

  /// Fills the posture memory of the current model: goal postures for drilling areas on a bare
  /// wall (the model's first tool, camera axis horizontal) at heights `from`..`to` every `step`
  /// [m], each searched twice for up to `seconds_per_height` (once seeded by the neighbouring
  /// heights, once from random seeds for other posture families). Later goals near those
  /// heights start from them (the low, torque-bound areas otherwise cost the NSPG most of its
  /// budget). Stops early, within a height's search, if the model changes or `keep_going`
  /// returns false (a height cut short is searched again by the next warm-up). Returns the number of heights
  /// solved.
  int warm_up(double from, double to, double step, double seconds_per_height,
              const std::function<bool()>& keep_going = [] { return true; });

  /// Called after each goal is planned (FIFO), so its trajectory can be executed while the
  /// next goals are planned.
  using GoalCallback = std::function<void(const GoalResult&)>;
  /// Plans every goal of `request` in order, goal i starting where goal i-1 ends (the first
  /// from `q_start_full`, a full q of the request's model). A failed goal is reported and the
  /// next one starts from the last reached posture. Never throws for bad requests: the
  /// status and reason say what is wrong (no model, stale model version, bad start state...).
  PlanResult plan(const PlanRequest& request, const Eigen::VectorXd& q_start_full, const GoalCallback& on_goal = {});

  /// Plans a path between two planned-joint postures (src/core/path_search.hpp: direct, projected
  /// line, arm alone and drive, RRT-Connect; simplification), then its timing.
  /// `fixed_base`: the base joints keep their start values. `lead_in` (full q, or null): a
  /// state the trajectory starts from before `q_start_full` (a start moved out of the map).
  /// The arm from `start` (full q, valid) to its homing posture (home_posture), the base
  /// standing: a PlanRequest::home request.
  GoalResult plan_home(const PlanningModel& model, StateChecker& checker, const Eigen::VectorXd& start,
                       uint64_t seed, const Eigen::VectorXd* lead_in = nullptr) const;
  /// The arm from `start` (full q, valid) to `target` (planned q, the base's as start's), the
  /// base standing. A failure's reason starts with `request` ("home"); a target that is not free
  /// is named `posture` ("the homing posture") in it.
  GoalResult plan_posture(const PlanningModel& model, StateChecker& checker, const Eigen::VectorXd& start,
                          const Eigen::VectorXd& target, const std::string& request, const std::string& posture,
                          uint64_t seed, const Eigen::VectorXd* lead_in = nullptr) const;

  GoalResult plan_path(const PlanningModel& model, StateChecker& checker,
                       const Eigen::VectorXd& q_start_full, const Eigen::VectorXd& q_goal,
                       double time_budget, uint64_t seed, bool fixed_base = false,
                       const Eigen::VectorXd* lead_in = nullptr) const;

 private:
  /// Arm postures that solved earlier goals of this model, with their camera height (seeds for
  /// later goals at similar heights).
  struct Remembered {
    double height = 0.0;
    Eigen::VectorXd arm;
    std::vector<Eigen::VectorXd> arm_path;  // arm postures from the parked arm to `arm` (warm-up), or empty
  };
  /// One model's memory: its postures and the warm-up heights searched [mm] (with whether a
  /// posture was found), which a later warm-up of the same model skips.
  struct Memory {
    std::vector<Remembered> postures;
    std::map<long, bool> warmed;
  };
  std::vector<Eigen::VectorXd> hints_for(const PlanningModel& model, double height) const;
  void remember(const PlanningModel& model, double height, const Eigen::VectorXd& q, std::vector<Eigen::VectorXd> arm_path = {});
  // A remembered arm path that ends near `arm` or near its mirror image (all joints but the
  // first within 0.6 rad; the path is then mirrored, and the first joint's offset is added
  // along it), or empty.
  std::vector<Eigen::VectorXd> arm_path_to(const PlanningModel& model, const Eigen::VectorXd& arm) const;

  Params params_;
  mutable std::mutex mutex_;
  std::shared_ptr<const PlanningModel> model_;
  Environment environment_;
  std::string model_hash_;  // content hash of model_ ("" : none)
  Memory memory_;           // guarded by mutex_, for model_
  /// Other models' memories by content hash, most recently left first (guarded by mutex_).
  std::list<std::pair<std::string, Memory>> kept_;
};

}  // namespace concert::planner
