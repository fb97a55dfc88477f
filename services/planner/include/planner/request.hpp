#pragma once
// What the service decides for a client's request before and after the planner runs it: the
// start state (the request's own, the robot's measured one, or the model's zero posture), the
// frame the goals are planned in (the map, placed by nav's localisation or by the client's
// odom_in_map) and the way back into the odometry frame the robot executes in, and the line the
// service logs. The DDS adapter converts messages into these types and forwards the answers.
// Plain C++, no DDS.

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "planner/planning_model.hpp"
#include "planner/types.hpp"

namespace concert::planner {

/// The robot as last measured: its joint state (of the model version it reports) and odometry
/// (x, y, yaw).
struct MeasuredRobot {
  struct Joints {
    std::uint64_t model_version = 0;
    std::vector<std::string> names;
    std::vector<double> positions;
  };
  std::optional<Joints> joints;
  std::optional<Eigen::Vector3d> odometry;
};

/// A client's request as received: goals and start in the odometry frame.
struct ClientRequest {
  PlanRequest plan;                      ///< goals in the odometry frame
  std::vector<std::string> start_names;  ///< empty: start where the robot stands
  std::vector<double> start_position;
  bool execute = false;
  std::vector<double> odom_in_map;  ///< the odometry frame in the map as the client measured it (x, y, yaw); empty: none
};

/// Where the service knows the odometry frame to lie in the map.
struct FrameKnowledge {
  Eigen::Vector3d map_T_odom = Eigen::Vector3d::Zero();  ///< x, y, yaw (identity until nav localises)
  bool localised = false;         ///< nav has placed the odometry frame in the map
  bool map_from_sensors = false;  ///< the map is built from the sensors, placed with nav's frame
};

/// What the planner is given for a request, or why the service refuses it first.
struct PreparedRequest {
  /// kSucceeded: plan it; kInvalidStart or kInvalidRequest: refused with `reason`.
  Status refusal = Status::kSucceeded;
  std::string reason;
  PlanRequest plan;       ///< goals in the map frame
  /// Full start state in the map frame; empty when the model is missing or of another version
  /// (the planner then answers "no model" or "stale model" itself).
  Eigen::VectorXd start;
  Eigen::Vector3d map_T_odom = Eigen::Vector3d::Zero();  ///< the frame the trajectories go back through
  /// Added to every planned base yaw on the way back: minus the frame's turn, plus any whole
  /// turn wrapping the start's map yaw took away; one offset per request, so its trajectories
  /// join up.
  double yaw_offset = 0.0;
  std::string frame_note;  ///< how the frame was chosen when the client gave one (for the log)
  [[nodiscard]] bool refused() const { return refusal != Status::kSucceeded; }
};

/// What the planner is given for `request` with `model` (null: none yet), from what was
/// measured; refused (kInvalidStart) when the start state cannot be had (a start state the
/// request gives that names an unknown joint or a non-finite value, no joint state of this
/// model to execute from) and (kInvalidRequest) for a malformed odom_in_map.
PreparedRequest prepare_request(const ClientRequest& request, const PlanningModel* model,
                                const MeasuredRobot& robot, const FrameKnowledge& frame);

/// A trajectory planned in the map frame, in the odometry frame whose pose in the map is
/// `map_T_odom` (x, y, yaw): the base's positions and velocities turned and shifted; the yaw
/// shifted by `yaw_offset`, not wrapped, so it stays continuous and starts where the robot's
/// odometry yaw is.
Trajectory to_odometry_frame(Trajectory trajectory, const Eigen::Vector3d& map_T_odom, double yaw_offset);

/// The service's log line for a request the planner ran: its status, how its frame was chosen
/// and each planned goal's time, path method and load.
std::string describe(const PlanResult& result, const PreparedRequest& prepared, const FrameKnowledge& frame);

}  // namespace concert::planner
