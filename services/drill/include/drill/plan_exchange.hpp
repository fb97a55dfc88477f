#pragma once
// What the drill asks the whole-body planner and what the planner answers, as the drill's
// decisions use them: concert/planner/request and concert/planner/result (idl/planning.idl)
// without the DDS; and the robot's and nav's word on the trajectories and goals the drill sent,
// and the safety state. The adapter converts these to and from the messages; the core decides
// with them. Poses are in the odometry frame, like the messages'.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drill/paths.hpp"
#include "drill/ports.hpp"

namespace concert::drill {

/// One planning request (msg::PlanRequest; the field comments there say what each one asks).
struct PlanAsk {
  std::uint32_t request_id{0};
  std::uint32_t model_version{0};
  std::string source;
  std::string end_effector;
  std::vector<Eigen::Isometry3d> goals;  ///< drilling-area frames, z along the outward normal
  bool execute{false};
  std::vector<std::string> start_names;  ///< empty: from the robot's current state
  std::vector<double> start_position;
  double camera_distance{0.0};      ///< [m]; <= 0: the planner's
  double view_slant{0.0};           ///< [rad] > 0: a look from any side within this of the normal
  double view_near{0.0};            ///< [m] with view_slant: the camera at least this far
  bool fixed_base{false};
  double environment_padding{0.0};  ///< [m]; <= 0: the planner's
  double base_travel{0.0};          ///< [m and rad]; <= 0: unbounded
  double tip_distance{0.0};         ///< [m] > 0: the tool's tip, not its camera, on the normal
  double tip_reach{0.0};            ///< [m] with tip_distance: the torques checked this far on
  double contact_force{0.0};        ///< [N]; <= 0: the planner's
  /// The odometry frame in the planner's map (x, y, yaw) from the marks seen again; none: nav's.
  std::optional<Eigen::Vector3d> odom_in_map;
  bool home{false};  ///< no goals: the arm to its homing posture, the base standing
};

enum class PlanState { kPlanning, kPlanned, kExecuting, kSucceeded, kFailed };
enum class PlanFailure {
  kOk,
  kNoModel,
  kStaleModel,
  kInvalidRequest,
  kInvalidStart,
  kUnreachable,
  kNoPath,
  kExecutionAborted
};

/// The planner's latest answer to one request (msg::PlanResult): its state, why it failed, and
/// the trajectory of the current goal (names and samples; empty while planning or failed).
struct PlanReply {
  std::uint32_t request_id{0};
  PlanState state{PlanState::kPlanning};
  PlanFailure failure{PlanFailure::kOk};
  std::string reason;
  Path path;
};

/// The robot's latest word on a trajectory the drill sent (concert/robot/trajectory_status), or
/// nav's on a goal (concert/nav/status): still running, done, or failed with how and why.
struct MotionReply {
  Progress progress{Progress::kRunning};
  std::string failure;  ///< when failed: "refused", "aborted", "failed" or "cancelled"
  std::string reason;   ///< the sender's reason
};

/// The safety service's state as the drill's health check reads it (concert/safety/state).
struct SafetyWord {
  bool running{false};
  std::vector<std::string> causes;  ///< why stopped
};

/// `incoming` taken into `kept`, the last answer for its request. The trajectory of an executed
/// plan comes once, with kPlanned, and the execution's updates and kSucceeded come without it,
/// so an answer without one keeps the trajectory (and its joint names) already there: otherwise
/// a hole's posture goes unrecorded whenever an update comes first, nothing goes back along it,
/// and the next area's approach, planned from where the last one ended, is aborted at its first
/// sample. kPlanning only ever opens a request's answers: one after a later state is a stale
/// acknowledgement and is not taken.
void merge_reply(PlanReply& kept, const PlanReply& incoming);

}  // namespace concert::drill
