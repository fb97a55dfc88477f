#pragma once
// DDS adapter of the nav service: RobotModel in (reconfigure the vehicle, status READY at the
// version, or ERROR naming why the model cannot navigate); wheel odometry, IMU and the planar
// scan in; goals, cancels and initial poses in; safety state in (a stop cancels the goal); the
// joint state in (the posture whose drives bound the base's accelerations, the latest only).
// Out: base velocity commands while a goal runs, goal status (feedback and result, one
// instance per goal), the path and the storey map (latched), the filtered odometry, the
// localisation (map -> odom) and the vehicle set-up (latched).
//
// DDS callbacks only queue; one control thread owns the Navigator and runs at its rate.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <thread>

#include "concert/common/command_once.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "nav/navigator.hpp"

namespace concert::nav::dds {

/// Conversions between IDL and core types.
msg::Pose2D to_msg(const Pose2& pose);
Pose2 to_core(const msg::Pose2D& pose);
GoalRequest to_core(const msg::NavGoal& goal);
msg::NavStatus to_msg(const GoalStatus& status, std::int64_t stamp_ns);
msg::OccupancyGridMap to_msg(const bim::OccupancyGrid& grid, const std::string& name,
                             const std::string& source);
msg::NavVehicle to_msg(const VehicleConfig& vehicle);
/// The planar scan (base frame) of a LaserScan.
PlanarScan to_core(const msg::LaserScan& scan);

class NavNode {
 public:
  /// `participant` and `navigator` must outlive the node. `map_source` names where the map
  /// came from (published with it).
  NavNode(concert::dds::Participant& participant, Navigator& navigator, std::string map_source,
          std::ostream& log);
  ~NavNode();
  NavNode(const NavNode&) = delete;
  NavNode& operator=(const NavNode&) = delete;

  /// Runs the control loop until `stop` is set.
  void spin(const std::atomic<bool>& stop);
  /// Inputs refused since start (models, goals), as the service status reports them.
  [[nodiscard]] uint32_t refusals() const { return status_.refusals(); }
  /// Odometry and IMU samples dropped because they came too late for the filter
  /// (LateMeasurement: a loaded host, not bad input; logged, not refused).
  [[nodiscard]] std::uint64_t late_samples() const { return late_samples_.load(); }

 private:
  struct Inbox {
    std::optional<msg::RobotModel> model;
    std::deque<msg::Odometry> odometry;
    std::deque<msg::Imu> imu;
    std::optional<msg::LaserScan> scan;
    std::deque<msg::NavGoal> goals;
    std::deque<msg::NavCancel> cancels;
    std::optional<msg::NavInitialPose> initial_pose;
    std::optional<msg::SafetyState> safety;
    std::optional<msg::JointState> joints;
  };
  void tick();
  /// Hands what arrived since the last tick to the navigator (model, safety, pose, sensors, goals).
  void take_inputs(const Inbox& in);
  /// The filtered odometry every tick; the localisation at 10 Hz.
  void publish_odometry();
  void apply_model(const msg::RobotModel& model);
  void publish_status();
  void publish_map();
  void log_line(const std::string& line);
  void dropped_late(const std::string& what, const std::exception& e);

  Navigator& navigator_;
  std::string map_source_;
  std::ostream& log_;
  std::mutex log_mutex_;
  std::mutex mutex_;
  Inbox inbox_;
  concert::CommandOnce goals_seen_;  // (request id, stamp) of the goals taken; under mutex_
  std::int64_t last_stamp_ns_{0};  // robot clock: the latest odometry stamp
  std::atomic<std::uint64_t> late_samples_{0};
  std::uint64_t model_version_{0};
  std::string model_hash_;
  std::chrono::steady_clock::time_point last_localisation_{};
  concert::dds::StatusReporter status_;
  concert::dds::Writer<msg::BaseVelocityCommand> base_;
  concert::dds::Writer<msg::NavStatus> statuses_;
  concert::dds::Writer<msg::NavPath> paths_;
  concert::dds::Writer<msg::OccupancyGridMap> maps_;
  concert::dds::Writer<msg::Odometry> odometry_out_;
  concert::dds::Writer<msg::NavLocalisation> localisation_out_;
  concert::dds::Writer<msg::NavVehicle> vehicles_;
  concert::dds::Reader<msg::RobotModel> models_;
  concert::dds::Reader<msg::Odometry> odometry_in_;
  concert::dds::Reader<msg::Imu> imu_in_;
  concert::dds::Reader<msg::LaserScan> scan_in_;
  concert::dds::Reader<msg::SafetyState> safety_in_;
  concert::dds::Reader<msg::JointState> joints_in_;
  concert::dds::Reader<msg::NavGoal> goals_in_;
  concert::dds::Reader<msg::NavCancel> cancels_in_;
  concert::dds::Reader<msg::NavInitialPose> initial_pose_in_;
};

}  // namespace concert::nav::dds
