#pragma once
// State validity (paper section 5.4.2): joint limits, self-collision (FCL, SRDF-disabled pairs
// skipped), collision with the OctoMap environment and the floor, torque limits (static gravity
// torques plus the expected contact force under each continuous torque).

#include <memory>
#include <string>

#include "planner/environment.hpp"
#include "planner/planning_model.hpp"

namespace concert::planner {

/// Per-thread checker of one model version and one environment (holds FCL objects and KDL
/// scratch data). Not thread-safe; make one per thread.
class StateChecker {
 public:
  /// `padding` [m] grows the robot shapes against the environment (not against themselves).
  StateChecker(std::shared_ptr<const PlanningModel> model, const Environment& environment, const Params& params, double padding);
  ~StateChecker();
  StateChecker(const StateChecker&) = delete;
  StateChecker& operator=(const StateChecker&) = delete;

  /// Checks a full q. With `contact_frame` non-empty, the expected contact force
  /// (Params::contact_force) pushes back on that frame along its -z axis in the torque check.
  /// Returns the first constraint violated, in the order joint limit, torque, floor,
  /// environment, self collision.
  [[nodiscard]] Validity check(const Eigen::VectorXd& q_full, const std::string& contact_frame = {});
  /// The torque check of check() alone (no joint limits, no collisions): a posture whose
  /// shapes are meant to be in contact, e.g. the drill's bit in its hole.
  [[nodiscard]] Validity check_torques(const Eigen::VectorXd& q_full, const std::string& contact_frame);
  /// Joint torques the state needs (gravity + contact) [N m], full q order
  /// (PlanningModel::static_torques). Throws PlannerError for an unknown contact frame.
  [[nodiscard]] Eigen::VectorXd required_torques(const Eigen::VectorXd& q_full, const std::string& contact_frame);
  /// The planned joint whose static torque (gravity, plus the contact force with
  /// `contact_frame`) is the largest fraction of its continuous torque, and that fraction.
  struct TorqueUse {
    double fraction = 0.0;
    std::string joint;
  };
  [[nodiscard]] TorqueUse heaviest_torque(const Eigen::VectorXd& q_full, const std::string& contact_frame);
  /// Number of check() calls so far.
  [[nodiscard]] std::size_t checks() const { return checks_; }
  [[nodiscard]] const PlanningModel& model() const { return *model_; }
  /// Signed distance field of the environment the checker was made with (Environment::distance_field).
  [[nodiscard]] std::shared_ptr<const DistanceField> distance_field() const { return environment_.distance_field(); }

  struct Impl;

 private:
  void torques_at_poses(const std::string& contact_frame, Eigen::VectorXd& tau);
  /// The torque limits against impl_->tau (torques_at_poses' result).
  [[nodiscard]] Validity torque_validity(const std::string& contact_frame) const;
  std::shared_ptr<const PlanningModel> model_;
  Environment environment_;
  Params params_;
  std::unique_ptr<Impl> impl_;
  double padding_ = 0.0;
  std::size_t checks_ = 0;
};

}  // namespace concert::planner
