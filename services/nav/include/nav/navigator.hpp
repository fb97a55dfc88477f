#pragma once
// The navigation service's core (paper section 5.3), without DDS: the vehicle set-up of the
// current model (recognise_vehicle), the storey map (costmap, and the BIM walls for wall goals),
// the odometry filter (wheels + IMU), the localiser (lidar scans in the map), the global planner
// and the local controller, and the goal's life: accepted or refused -> planning -> following
// (replanning when blocked by what the lidars see) -> reached / failed / cancelled.
//
// Frames: "map" is the storey's plan frame (the IFC model's x, y); "odom" the robot service's
// odometry frame; "base" the URDF root. Times are seconds on the caller's clock (the robot's
// stamps). One thread owns a Navigator (the adapter's control loop); it is not thread-safe.

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "concert/bim/model.hpp"
#include "concert/bim/occupancy_grid.hpp"
#include "concert/model/drive_budget.hpp"
#include "concert/model/robot_model.hpp"
#include "nav/costmap.hpp"
#include "nav/global_planner.hpp"
#include "nav/local_controller.hpp"
#include "nav/localiser.hpp"
#include "nav/odometry_filter.hpp"
#include "nav/vehicle.hpp"

namespace concert::nav {

/// Every parameter of the service (config/nav.yaml lists them with their defaults).
struct NavParams {
  VehicleParams vehicle;
  OdometryFilterParams odometry;
  LocaliserParams localiser;
  CostmapParams costmap;
  PlannerParams planner;
  ControllerParams controller;
  double control_rate{20.0};     ///< control loop [Hz]
  double cruise_speed{0.5};      ///< along the path, capped by the vehicle's limits [m/s]
  /// The base's accelerations [m/s^2, rad/s^2]: what the platform may do. Scaled down, at the
  /// posture the base carries, to what every drive sustains (model::DriveBudget).
  double max_acceleration{0.5};
  double max_angular_acceleration{1.0};
  /// Base accelerations keep every joint's and wheel's torque within this fraction of its
  /// continuous torque, the posture's static load included (0, 1] [-].
  double drive_torque_fraction{1.0};
  /// A goal is refused while an arm joint stands farther than this from its transport posture
  /// (the SRDF home) [rad or m]: the footprint the base plans with and the drive budget hold
  /// the arm there, and an arm out in front (a drilling posture) sweeps past the footprint and
  /// loads its drives while the base accelerates. 0: not checked.
  double arm_home_tolerance{0.05};
  int max_replans{10};          ///< blocked this often -> the goal fails
  double initial_std_xy{0.2};   ///< default spread of an initial pose [m]
  double initial_std_yaw{0.1};  ///< [rad]
  double wall_standoff{0.0};    ///< base centre to wall face for wall goals [m]; 0: from the model
  double wall_clearance{0.25};  ///< with wall_standoff 0: footprint front edge to the face [m]
  double scan_period{0.1};      ///< localise at most this often [s]
};

/// Loads config/nav.yaml-style parameters. Throws std::runtime_error naming the file and key.
NavParams load_params(const std::string& path);

/// A planar pose (map or odom frame).
struct Pose2 {
  double x{0.0}, y{0.0}, yaw{0.0};  ///< [m, m, rad]
};

/// A goal as a client sends it.
struct GoalRequest {
  std::uint32_t id{0};
  std::uint64_t model_version{0};
  enum class Kind { kPose, kWall } kind{Kind::kPose};
  Pose2 pose;        ///< kPose: map frame
  std::string wall;  ///< kWall: IFC GlobalId
  double s{0.0};     ///< kWall: along the wall's axis from its start [m]
  double h{0.0};     ///< kWall: above the storey floor [m]
};

enum class GoalState { kIdle, kPlanning, kFollowing, kReached, kFailed, kCancelled, kRefused };
const char* to_string(GoalState state);

/// Feedback and result of the current (or last) goal.
struct GoalStatus {
  std::uint32_t id{0};
  std::uint64_t model_version{0};
  GoalState state{GoalState::kIdle};
  std::string reason;
  Pose2 goal;                             ///< the base goal in the map frame
  std::optional<Eigen::Isometry3d> area;  ///< wall goals: the area frame (map frame)
  Pose2 pose;                             ///< current estimate
  double distance_remaining{0.0};         ///< [m]
  std::uint32_t replans{0};
  double position_error{0.0};  ///< [m] from the goal
  double heading_error{0.0};   ///< [rad]
};

/// The localisation as published.
struct LocalisationStatus {
  LocaliserStatus state{LocaliserStatus::kUninitialised};
  bool converging{false};  ///< tracking, but the particles are still spread (covariance large)
  Pose2 pose;              ///< base in the map
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Zero()};
  Pose2 map_to_odom;
};

/// One control step's output.
struct StepOutput {
  bool drive{false};  ///< a goal runs (or just ended): send `command` (zero included) to the base
  BaseTwist command;  ///< base frame
  bool path_changed{false};
};

class Navigator {
 public:
  /// Throws std::invalid_argument naming a bad parameter.
  explicit Navigator(NavParams params, std::uint64_t seed = 1);

  // --- inputs -----------------------------------------------------------------------------
  /// Reconfigures to a model: recognises the vehicle, rebuilds the costmap and controller. The
  /// running goal is cancelled ("model changed"). Throws VehicleError (the previous set-up stays
  /// when it was for the same version; otherwise the navigator has no vehicle until a good model).
  const VehicleConfig& set_model(const model::RobotModel& model);
  /// The storey map (and the BIM model with its walls for wall goals; null: pose goals only).
  /// The running goal is cancelled; localisation restarts from its last pose estimate.
  void set_map(bim::OccupancyGrid grid, std::string name,
               std::shared_ptr<const bim::BimModel> bim = nullptr);
  /// Restarts localisation around `pose` (std <= 0: the defaults).
  void set_initial_pose(const Pose2& pose, double std_xy, double std_yaw);
  /// Wheel odometry from the robot service: the base twist (vx, vy [m/s], wz [rad/s]) at
  /// `stamp` [s]. The odometry filter integrates it (with the gyro); the robot's own
  /// integrated pose is not needed.
  void on_wheel_odometry(double stamp, const Eigen::Vector3d& twist);
  /// IMU angular rate about the base z axis [rad/s].
  void on_gyro(double stamp, double yaw_rate);
  /// An IMU sample's angular velocity in its own frame [rad/s]: turned into the base frame by
  /// the vehicle's IMU of that sensor name or URDF frame (as mounted; unknown: taken as aligned
  /// with the base), its z given to on_gyro.
  void on_imu(double stamp, const std::string& sensor, const std::string& frame,
              const Eigen::Vector3d& angular_velocity);
  /// A planar scan in the base frame, taken at `stamp` [s].
  void on_scan(double stamp, PlanarScan scan);
  /// The robot's joint positions (names and positions alike indexed; joints of another model
  /// are ignored): the posture whose drives bound the base's accelerations. Until the first
  /// sample, each joint is taken at 0 within its limits.
  void on_joint_positions(const std::vector<std::string>& names, const std::vector<double>& positions);

  // --- goals --------------------------------------------------------------------------------
  /// Accepts (state kPlanning) or refuses (kRefused with the reason: no vehicle, stale model
  /// version, no map, not localised, goal outside the map / in collision, unknown wall ...).
  /// A new goal replaces the running one (cancelled).
  GoalStatus submit(const GoalRequest& goal);
  /// Cancels the running goal (id 0: whatever runs); false if it did not run.
  bool cancel(std::uint32_t id, const std::string& reason);
  /// A safety stop: cancels the running goal with `reason`; goals are refused until cleared.
  void set_safety_stop(bool stopped, const std::string& reason);

  // --- the loop -----------------------------------------------------------------------------
  /// Localises with the latest scan, plans, and runs the controller at `stamp` [s].
  StepOutput step(double stamp);
  /// Goal statuses to publish since the last call, oldest first: every state change (a goal
  /// replaced by a new one included) and periodic feedback while a goal runs.
  std::vector<GoalStatus> take_updates();
  /// A line for the log when the drives' budget for base motion changed (the share of the
  /// configured accelerations allowed and the joint that sets it); empty otherwise.
  std::string take_budget_note();

  // --- state --------------------------------------------------------------------------------
  [[nodiscard]] std::uint64_t model_version() const { return model_version_; }
  [[nodiscard]] const VehicleConfig* vehicle() const { return vehicle_ ? &*vehicle_ : nullptr; }
  [[nodiscard]] bool has_map() const { return map_ != nullptr; }
  [[nodiscard]] const bim::OccupancyGrid* map() const { return map_.get(); }
  [[nodiscard]] const std::string& map_name() const { return map_name_; }
  [[nodiscard]] const GoalStatus& status() const { return status_; }
  [[nodiscard]] const Path& path() const { return path_; }
  [[nodiscard]] LocalisationStatus localisation() const;
  [[nodiscard]] FilteredOdometry odometry() const { return filter_.estimate(); }
  /// The base pose in the map now (map_to_odom applied to the filtered odometry).
  [[nodiscard]] Pose2 pose() const;
  [[nodiscard]] const NavParams& params() const { return params_; }
  /// Base centre to wall face for wall goals with the current vehicle [m].
  [[nodiscard]] double wall_standoff() const;
  /// Why the current model cannot navigate ("" when it can or there is no model).
  [[nodiscard]] const std::string& vehicle_error() const { return vehicle_error_; }
  /// The drives' budget for base motion at the latest posture (scale 1 without a model).
  [[nodiscard]] const model::BaseBudget& drive_budget() const { return budget_; }
  /// The costmap (null without a vehicle or a map).
  [[nodiscard]] const Costmap* costmap() const { return costmap_.get(); }

 private:
  void rebuild();
  // Scales the controller's accelerations to the drives' budget at the current posture; fails
  // a running goal when the posture leaves the base no acceleration.
  void apply_drive_budget();
  // Why a goal may not start with the arm where it is (an arm joint farther than
  // arm_home_tolerance from its transport posture), or "".
  [[nodiscard]] std::string arm_away_from_home() const;
  void update_drive_budget();
  void set_state(GoalState state, std::string reason);
  void localise();
  void plan_path(double stamp);
  [[nodiscard]] Eigen::Vector3d odom_at(double stamp) const;
  [[nodiscard]] Eigen::Vector3d map_pose_of(const Eigen::Vector3d& odom) const;

  NavParams params_;
  std::uint64_t seed_;
  std::optional<VehicleConfig> vehicle_;
  std::string vehicle_error_;
  std::uint64_t model_version_{0};  // the model set last (even one that cannot navigate)
  std::shared_ptr<const bim::OccupancyGrid> map_;
  std::shared_ptr<const LikelihoodField> field_;
  std::string map_name_;
  std::shared_ptr<const bim::BimModel> bim_;
  std::unique_ptr<Costmap> costmap_;
  std::unique_ptr<Localiser> localiser_;
  GlobalPlanner planner_;
  std::unique_ptr<LocalController> controller_;
  std::unique_ptr<model::DriveBudget> drives_;
  Eigen::VectorXd posture_;  // in drives_->joint_names() order
  Eigen::VectorXd home_;     // the transport posture, same order
  std::vector<bool> arm_joint_;  // same order: the joint belongs to an arm chain
  bool posture_measured_{false};  // a joint state of this model arrived
  bool budget_stale_{true};
  model::BaseBudget budget_;
  std::string budget_note_;
  double noted_scale_{1.0};
  std::string noted_joint_;
  OdometryFilter filter_;
  bool have_odometry_{false};
  // Filtered odometry poses (stamp, x, y, yaw) of the last second, to place each scan in time.
  std::vector<std::pair<double, Eigen::Vector3d>> history_;
  struct Scan {
    double stamp{0.0};
    PlanarScan beams;
  };
  std::optional<Scan> scan_;
  std::optional<Eigen::Vector3d> pending_initial_;  // given before the map: x, y, yaw
  Eigen::Vector3d pending_sigma_{Eigen::Vector3d::Zero()};
  Eigen::Vector3d map_to_odom_{Eigen::Vector3d::Zero()};
  bool safety_stop_{false};
  GoalStatus status_;
  std::optional<GoalRequest> goal_;
  Path path_;
  bool path_changed_{false};
  bool stop_sent_{true};     // a zero command went out after the last goal ended
  double lost_since_{-1.0};  // stamp the localiser was first seen lost while a goal ran
  double last_feedback_{-1e9};
  double now_{0.0};
  std::vector<GoalStatus> updates_;
};

}  // namespace concert::nav
