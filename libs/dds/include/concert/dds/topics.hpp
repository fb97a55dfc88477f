#pragma once
// Typed handles of the catalogue's topics for Fast DDS code: topics::robot_model is the
// RobotModel topic, with the generated type bound at compile time. Writer/Reader check each
// handle against the catalogue when they are made (name, type name).

#include <string_view>

#include "collabPubSubTypes.h"
#include "drillPubSubTypes.h"
#include "ethercatPubSubTypes.h"
#include "finishPubSubTypes.h"
#include "modelPubSubTypes.h"
#include "navPubSubTypes.h"
#include "planningPubSubTypes.h"
#include "robotPubSubTypes.h"
#include "sensorsPubSubTypes.h"
#include "systemPubSubTypes.h"
#include "topologyPubSubTypes.h"
#include "worldPubSubTypes.h"

namespace concert::dds {

/// The generated Fast DDS TopicDataType of a message type.
template <class T> struct PubSubOf;

#define CONCERT_BIND_PUBSUB(Type) \
  template <> struct PubSubOf<::concert::msg::Type> { using type = ::concert::msg::Type##PubSubType; }
CONCERT_BIND_PUBSUB(EscScan);
CONCERT_BIND_PUBSUB(ModuleTree);
CONCERT_BIND_PUBSUB(RobotModel);
CONCERT_BIND_PUBSUB(ModelCustomisation);
CONCERT_BIND_PUBSUB(JointState);
CONCERT_BIND_PUBSUB(JointCommand);
CONCERT_BIND_PUBSUB(CartesianImpedanceCommand);
CONCERT_BIND_PUBSUB(BaseVelocityCommand);
CONCERT_BIND_PUBSUB(Odometry);
CONCERT_BIND_PUBSUB(EndEffectorWrench);
CONCERT_BIND_PUBSUB(ServiceStatus);
CONCERT_BIND_PUBSUB(EStopInput);
CONCERT_BIND_PUBSUB(SafetyState);
CONCERT_BIND_PUBSUB(SafetyReset);
CONCERT_BIND_PUBSUB(PlanRequest);
CONCERT_BIND_PUBSUB(PlanResult);
CONCERT_BIND_PUBSUB(JointTrajectoryCommand);
CONCERT_BIND_PUBSUB(TrajectoryStatus);
CONCERT_BIND_PUBSUB(World);
CONCERT_BIND_PUBSUB(SimCommand);
CONCERT_BIND_PUBSUB(SimCommandReply);
CONCERT_BIND_PUBSUB(SimTruth);
CONCERT_BIND_PUBSUB(Image);
CONCERT_BIND_PUBSUB(CameraInfo);
CONCERT_BIND_PUBSUB(LidarScan);
CONCERT_BIND_PUBSUB(LaserScan);
CONCERT_BIND_PUBSUB(SonarRanges);
CONCERT_BIND_PUBSUB(Imu);
CONCERT_BIND_PUBSUB(SensorList);
CONCERT_BIND_PUBSUB(NavGoal);
CONCERT_BIND_PUBSUB(NavCancel);
CONCERT_BIND_PUBSUB(NavInitialPose);
CONCERT_BIND_PUBSUB(NavStatus);
CONCERT_BIND_PUBSUB(NavPath);
CONCERT_BIND_PUBSUB(OccupancyGridMap);
CONCERT_BIND_PUBSUB(NavLocalisation);
CONCERT_BIND_PUBSUB(NavVehicle);
CONCERT_BIND_PUBSUB(SimHoles);
CONCERT_BIND_PUBSUB(DrillMission);
CONCERT_BIND_PUBSUB(DrillAbort);
CONCERT_BIND_PUBSUB(DrillStatus);
CONCERT_BIND_PUBSUB(CollabCommand);
CONCERT_BIND_PUBSUB(CollabState);
CONCERT_BIND_PUBSUB(FinishAreas);
CONCERT_BIND_PUBSUB(FinishCommand);
CONCERT_BIND_PUBSUB(FinishStatus);
#undef CONCERT_BIND_PUBSUB

/// A catalogue topic carrying T.
template <class T> struct TopicHandle {
  using Type = T;
  std::string_view name;
};

namespace topics {
inline constexpr TopicHandle<msg::EscScan> esc_scan{"concert/ethercat/scan"};
inline constexpr TopicHandle<msg::ModuleTree> module_tree{"concert/topology/module_tree"};
inline constexpr TopicHandle<msg::RobotModel> robot_model{"concert/model/robot_model"};
inline constexpr TopicHandle<msg::ModelCustomisation> customisation{"concert/model/customisation"};
inline constexpr TopicHandle<msg::JointState> joint_state{"concert/robot/joint_state"};
inline constexpr TopicHandle<msg::JointCommand> joint_command{"concert/robot/joint_command"};
inline constexpr TopicHandle<msg::CartesianImpedanceCommand> cartesian_command{"concert/robot/cartesian_command"};
inline constexpr TopicHandle<msg::BaseVelocityCommand> base_velocity{"concert/robot/base_velocity"};
inline constexpr TopicHandle<msg::Odometry> odometry{"concert/robot/odometry"};
inline constexpr TopicHandle<msg::EndEffectorWrench> ee_wrench{"concert/robot/ee_wrench"};
inline constexpr TopicHandle<msg::ServiceStatus> status{"concert/system/status"};
inline constexpr TopicHandle<msg::EStopInput> estop{"concert/safety/estop"};
inline constexpr TopicHandle<msg::SafetyState> safety_state{"concert/safety/state"};
inline constexpr TopicHandle<msg::SafetyReset> safety_reset{"concert/safety/reset"};
inline constexpr TopicHandle<msg::PlanRequest> plan_request{"concert/planner/request"};
inline constexpr TopicHandle<msg::PlanResult> plan_result{"concert/planner/result"};
inline constexpr TopicHandle<msg::JointTrajectoryCommand> trajectory_command{"concert/robot/trajectory_command"};
inline constexpr TopicHandle<msg::TrajectoryStatus> trajectory_status{"concert/robot/trajectory_status"};
inline constexpr TopicHandle<msg::World> world{"concert/world/world"};
inline constexpr TopicHandle<msg::SimCommand> sim_command{"concert/sim/command"};
inline constexpr TopicHandle<msg::SimCommandReply> sim_reply{"concert/sim/reply"};
inline constexpr TopicHandle<msg::SimTruth> sim_truth{"concert/sim/truth"};
inline constexpr TopicHandle<msg::Image> camera_rgb{"concert/sensors/camera/rgb"};
inline constexpr TopicHandle<msg::Image> camera_depth{"concert/sensors/camera/depth"};
inline constexpr TopicHandle<msg::CameraInfo> camera_info{"concert/sensors/camera/info"};
inline constexpr TopicHandle<msg::LidarScan> lidar{"concert/sensors/lidar"};
inline constexpr TopicHandle<msg::LaserScan> scan{"concert/sensors/scan"};
inline constexpr TopicHandle<msg::SonarRanges> sonar{"concert/sensors/sonar"};
inline constexpr TopicHandle<msg::Imu> imu{"concert/sensors/imu"};
inline constexpr TopicHandle<msg::SensorList> sensor_list{"concert/sensors/list"};
inline constexpr TopicHandle<msg::NavGoal> nav_goal{"concert/nav/goal"};
inline constexpr TopicHandle<msg::NavCancel> nav_cancel{"concert/nav/cancel"};
inline constexpr TopicHandle<msg::NavInitialPose> nav_initial_pose{"concert/nav/initial_pose"};
inline constexpr TopicHandle<msg::NavStatus> nav_status{"concert/nav/status"};
inline constexpr TopicHandle<msg::NavPath> nav_path{"concert/nav/path"};
inline constexpr TopicHandle<msg::OccupancyGridMap> nav_map{"concert/nav/map"};
inline constexpr TopicHandle<msg::Odometry> nav_odometry{"concert/nav/odometry"};
inline constexpr TopicHandle<msg::NavLocalisation> nav_localisation{"concert/nav/localisation"};
inline constexpr TopicHandle<msg::NavVehicle> nav_vehicle{"concert/nav/vehicle"};
inline constexpr TopicHandle<msg::SimHoles> sim_holes{"concert/sim/holes"};
inline constexpr TopicHandle<msg::DrillMission> drill_mission{"concert/drill/mission"};
inline constexpr TopicHandle<msg::DrillAbort> drill_abort{"concert/drill/abort"};
inline constexpr TopicHandle<msg::DrillStatus> drill_status{"concert/drill/status"};
inline constexpr TopicHandle<msg::CollabCommand> collab_command{"concert/collab/command"};
inline constexpr TopicHandle<msg::CollabState> collab_state{"concert/collab/state"};
inline constexpr TopicHandle<msg::FinishAreas> finish_areas{"concert/finish/areas"};
inline constexpr TopicHandle<msg::FinishCommand> finish_command{"concert/finish/command"};
inline constexpr TopicHandle<msg::FinishStatus> finish_status{"concert/finish/status"};
}  // namespace topics

/// Calls f(handle) for every typed topic handle (e.g. to dispatch on a topic name).
template <class F> void for_each_topic(F&& f) {
  f(topics::esc_scan);
  f(topics::module_tree);
  f(topics::robot_model);
  f(topics::customisation);
  f(topics::joint_state);
  f(topics::joint_command);
  f(topics::cartesian_command);
  f(topics::base_velocity);
  f(topics::odometry);
  f(topics::ee_wrench);
  f(topics::status);
  f(topics::estop);
  f(topics::safety_state);
  f(topics::safety_reset);
  f(topics::plan_request);
  f(topics::plan_result);
  f(topics::trajectory_command);
  f(topics::trajectory_status);
  f(topics::world);
  f(topics::sim_command);
  f(topics::sim_reply);
  f(topics::sim_truth);
  f(topics::camera_rgb);
  f(topics::camera_depth);
  f(topics::camera_info);
  f(topics::lidar);
  f(topics::scan);
  f(topics::sonar);
  f(topics::imu);
  f(topics::sensor_list);
  f(topics::nav_goal);
  f(topics::nav_cancel);
  f(topics::nav_initial_pose);
  f(topics::nav_status);
  f(topics::nav_path);
  f(topics::nav_map);
  f(topics::nav_odometry);
  f(topics::nav_localisation);
  f(topics::nav_vehicle);
  f(topics::sim_holes);
  f(topics::drill_mission);
  f(topics::drill_abort);
  f(topics::drill_status);
  f(topics::collab_command);
  f(topics::collab_state);
  f(topics::finish_areas);
  f(topics::finish_command);
  f(topics::finish_status);
}

}  // namespace concert::dds
