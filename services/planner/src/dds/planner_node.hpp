#pragma once
// DDS adapter of the planner service: RobotModel in (reconfigure, status READY at the
// version), joint state and odometry in (start state), PlanRequest in; PlanResult out per
// request (planning, planned with the trajectory, executing with progress, succeeded/failed
// with the reason). Execution hands each planned trajectory (base x, y, yaw + arm) to the
// robot's loop as a JointTrajectoryCommand, which tracks it closed-loop; the robot's
// TrajectoryStatus becomes the PlanResult's progress and result, while later goals are still
// being planned (FIFO). The world topic (latched) replaces the planner's map of walls and
// obstacles whenever it changes.
//
// Frames: the world (walls, obstacles) is in the map frame; the robot's odometry, the start
// states and goals clients send and the trajectories the planner returns are in the odometry
// frame, as the robot executes them. Once the nav service has localised the base in a map
// (NavLocalisation), the planner plans in the map frame: start and goals go in through
// map_T_odom (mobile_base::MapFrame), trajectories come out through its inverse. Without a
// localisation the two frames are one (a world without a building).
//
// Map source (Params::environment_source): "world" (default) builds the map from the world
// topic; "sensors" from the robot's lidar revolutions (concert/sensors/lidar) and depth images
// (concert/sensors/camera/depth + info, the latest frames of each camera averaged), ray-cast
// every sensor_map_period from each sensor's model pose at the latest joint state and the
// odometry placed in the map, of periods in which the base and the joints stayed nearly still
// (SensorMapper); "both" publishes the world's obstacles and the sensors' together.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <thread>
#include <utility>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "concert/mobile_base/map_frame.hpp"
#include "concert/world/world.hpp"
#include "planner/planner.hpp"
#include "planner/sensor_map.hpp"
#include "sensors.h"

namespace concert::planner::dds {

/// Conversions between IDL and core types.
Eigen::Isometry3d to_core(const msg::Pose& pose);
/// The planner's boxes and cylinders of the world every service reads (libs/world).
World to_planner_world(const world::World& world);
msg::Pose to_msg(const Eigen::Isometry3d& pose);
msg::PlanFailure to_failure(Status status);
struct NodeOptions {
  /// How long after a trajectory's duration the robot's result may take (its settling time).
  std::chrono::milliseconds result_margin{10000};
  /// A request for a model version the planner does not have yet (it races the model after a
  /// hot swap) waits this long for that version before it is answered.
  std::chrono::milliseconds model_wait{5000};
  /// With the map from the sensors alone (environment_source: sensors), a request that comes
  /// before any lidar revolution or depth frame was integrated waits this long for the first
  /// one, then fails: planned in an empty map, the base could be sent into a wall.
  std::chrono::milliseconds map_wait{10000};
};

class PlannerNode {
 public:
  /// `participant` and `planner` must outlive the node. Reports STARTING until a model arrives.
  PlannerNode(concert::dds::Participant& participant, Planner& planner, NodeOptions options, std::ostream& log);
  ~PlannerNode();
  PlannerNode(const PlannerNode&) = delete;
  PlannerNode& operator=(const PlannerNode&) = delete;

  /// Handles requests until `stop` is set (checked every `poll`).
  void spin(const std::atomic<bool>& stop, std::chrono::milliseconds poll = std::chrono::milliseconds(50));
  /// Handles at most one request, waiting up to `timeout`; true if one was handled.
  bool spin_once(std::chrono::milliseconds timeout);
  /// Model version the node runs (0: none).
  [[nodiscard]] uint64_t model_version() const { return planner_.model_version(); }
  /// Inputs refused since start (models, requests), as the service status reports them.
  [[nodiscard]] uint32_t refusals() const { return status_.refusals(); }
  /// True once a joint state of the robot has arrived (plans start from the latest one).
  [[nodiscard]] bool has_joint_state() const {
    std::lock_guard lock(mutex_);
    return joint_state_.has_value();
  }

 private:
  struct Execution {
    msg::PlanResult result;  // planned goal (trajectory filled)
    std::shared_ptr<const PlanningModel> model;
    Trajectory trajectory;
    bool last = false;
  };
  void on_model(const msg::RobotModel& model);
  void handle(const msg::PlanRequest& request);
  /// Waits (bounded) for the model version `request` names and, with the map from the sensors
  /// alone, for their first map; why the request cannot be planned, or empty.
  std::string wait_for_inputs(const msg::PlanRequest& request);
  void publish(msg::PlanResult result);
  /// A request as it arrives: queued and acknowledged, unless taken already.
  void take(const msg::PlanRequest& request);
  [[nodiscard]] msg::PlanResult planning(const msg::PlanRequest& request) const;
  void execute_loop();
  void warm_up_loop();
  void log_line(const std::string& line);
  /// Empty on success, else why the robot did not execute it.
  std::string execute(Execution& e);
  void on_world(const msg::World& world);
  void sensor_map_loop();
  /// Integrates the pending lidar scans into the sensor map and publishes the map (sensor map
  /// thread only).
  void update_sensor_map();
  /// The robot's full state in the map frame (its joint state of `model`'s version, odometry
  /// placed with nav's frame), or none.
  [[nodiscard]] std::optional<Eigen::VectorXd> robot_in_map(const PlanningModel& model) const;
  /// Marks the period as moved if the base or a joint is faster than sensor_max_speed.
  void note_motion(const msg::Odometry& odometry);
  void note_motion(const msg::JointState& joints);
  /// Gives the planner the map of the configured source (world, sensors or both).
  void publish_environment();

  Planner& planner_;
  NodeOptions options_;
  std::ostream& log_;
  std::mutex log_mutex_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<msg::PlanRequest> requests_;
  // The requests taken lately (source, id), oldest first: a client's resend is not taken again.
  static constexpr std::size_t kTakenKept = 4096;
  std::set<std::pair<std::string, std::uint32_t>> taken_;
  std::deque<std::pair<std::string, std::uint32_t>> taken_order_;
  std::deque<Execution> executions_;
  std::optional<msg::JointState> joint_state_;
  std::optional<msg::Odometry> odometry_;
  bool stopping_ = false;
  mobile_base::MapFrame map_frame_;
  // Map from the sensors (environment_source sensors or both); before the readers, whose
  // callbacks (the latched world) may run while the node is being built.
  const bool use_world_;
  const bool use_sensors_;
  std::mutex map_mutex_;  // guards the members below
  std::map<std::string, msg::LidarScan> pending_scans_;  // newest revolution of each lidar not yet used
  std::map<std::string, std::deque<msg::Image>> pending_depth_;  // latest depth frames per camera
  std::map<std::string, msg::CameraInfo> camera_infos_;          // latest per camera
  bool moved_ = false;  // the base or a joint moved since the last map update
  Environment world_map_;
  Environment sensor_map_;
  std::size_t skipped_moving_ = 0;  // revolutions and frames, since the last map update line
  std::size_t skipped_version_ = 0;
  std::size_t sensor_maps_ = 0;  // map updates that integrated something (under mutex_)
  std::shared_ptr<const SensorMapper> mapper_;  // sensor map thread only
  uint64_t warm_version_ = 0;  // model version the warm-up thread should prepare (0: none)
  concert::dds::Writer<msg::PlanResult> results_;
  concert::dds::Writer<msg::JointTrajectoryCommand> trajectory_commands_;
  std::map<uint32_t, msg::TrajectoryStatus> trajectory_status_;  // by request id (under mutex_)
  uint32_t next_trajectory_id_ = static_cast<uint32_t>(
      std::chrono::steady_clock::now().time_since_epoch().count() & 0x7fffffff);  // executor thread only
  concert::dds::StatusReporter status_;
  concert::dds::Reader<msg::RobotModel> models_;
  concert::dds::Reader<msg::JointState> joint_states_;
  concert::dds::Reader<msg::Odometry> odometries_;
  concert::dds::Reader<msg::NavLocalisation> localisations_;
  concert::dds::Reader<msg::TrajectoryStatus> trajectory_statuses_;
  concert::dds::Reader<msg::World> worlds_;
  concert::dds::Reader<msg::PlanRequest> request_reader_;
  std::unique_ptr<concert::dds::Reader<msg::LidarScan>> lidars_;
  std::unique_ptr<concert::dds::Reader<msg::CameraInfo>> camera_info_reader_;
  std::unique_ptr<concert::dds::Reader<msg::Image>> depth_reader_;


  std::thread executor_;
  std::thread warmer_;
  std::thread sensor_mapper_;
};

}  // namespace concert::planner::dds
