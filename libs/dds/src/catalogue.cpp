#include "concert/dds/catalogue.hpp"

#include <array>
#include <charconv>
#include <cstdlib>
#include <initializer_list>
#include <stdexcept>

namespace concert::dds {
namespace {

constexpr std::array kTopics = {
    TopicInfo{"concert/ethercat/scan", "concert::msg::EscScan", QosClass::kLatched,
              "robot: raw EtherCAT scan, one sample per (re)scan of the ring"},
    TopicInfo{"concert/topology/module_tree", "concert::msg::ModuleTree", QosClass::kLatched,
              "discovery: module tree rebuilt from the last good scan"},
    TopicInfo{"concert/model/robot_model", "concert::msg::RobotModel", QosClass::kLatched,
              "modelgen: versioned URDF/SRDF/config every service reconfigures from"},
    TopicInfo{"concert/model/customisation", "concert::msg::ModelCustomisation", QosClass::kCommand,
              "users/tools: homing posture and add-ons for the next model version"},
    TopicInfo{"concert/robot/joint_state", "concert::msg::JointState", QosClass::kStream,
              "robot: measured joint state, every control cycle (1 kHz)"},
    TopicInfo{"concert/robot/joint_command", "concert::msg::JointCommand", QosClass::kCommand,
              "tasks: joint position/velocity/effort/impedance command"},
    TopicInfo{"concert/robot/cartesian_command", "concert::msg::CartesianImpedanceCommand", QosClass::kCommand,
              "tasks: Cartesian impedance/admittance of an end-effector"},
    TopicInfo{"concert/robot/base_velocity", "concert::msg::BaseVelocityCommand", QosClass::kCommand,
              "nav/collab: mobile base velocity command"},
    TopicInfo{"concert/robot/odometry", "concert::msg::Odometry", QosClass::kStream,
              "robot: wheel odometry of the mobile base"},
    TopicInfo{"concert/robot/ee_wrench", "concert::msg::EndEffectorWrench", QosClass::kStream,
              "robot: external end-effector wrench estimated from joint torques"},
    TopicInfo{"concert/system/status", "concert::msg::ServiceStatus", QosClass::kLatched,
              "every service: state, model version and last error (one instance per service)"},
    TopicInfo{"concert/safety/estop", "concert::msg::EStopInput", QosClass::kLatched,
              "buttons, wireless receiver, software: e-stop inputs (one instance per source)"},
    TopicInfo{"concert/safety/state", "concert::msg::SafetyState", QosClass::kLatched,
              "safety: running or stopped, and why"},
    TopicInfo{"concert/safety/reset", "concert::msg::SafetyReset", QosClass::kCommand,
              "operator/tools: reset a latched safety stop once every e-stop input is released"},
    TopicInfo{"concert/planner/request", "concert::msg::PlanRequest", QosClass::kCommand,
              "tasks/tools: drilling-area goals for whole-body planning (and execution)"},
    TopicInfo{"concert/planner/result", "concert::msg::PlanResult", QosClass::kLatched,
              "planner: progress, trajectory or failure reason, one instance per request"},
    TopicInfo{"concert/robot/trajectory_command", "concert::msg::JointTrajectoryCommand", QosClass::kCommand,
              "planner/tasks: a joint trajectory (joints and planar base) for the robot's loop to track"},
    TopicInfo{"concert/robot/trajectory_status", "concert::msg::TrajectoryStatus", QosClass::kLatched,
              "robot: progress and result (succeeded, aborted or refused with the reason) per request"},
    TopicInfo{"concert/world/world", "concert::msg::World", QosClass::kLatched,
              "simulator (robot service): the world every service reads (walls, obstacles)"},
    TopicInfo{"concert/sim/command", "concert::msg::SimCommand", QosClass::kCommand,
              "tools: mount another assembly on the simulated robot, or change the simulated world"},
    TopicInfo{"concert/sim/reply", "concert::msg::SimCommandReply", QosClass::kLatched,
              "simulator (robot service): accepted or refused with the reason, one instance per request"},
    TopicInfo{"concert/sim/truth", "concert::msg::SimTruth", QosClass::kStream,
              "robot (simulation only): the base's true pose in the world, for tests and benchmarks"},
    TopicInfo{"concert/sensors/camera/rgb", "concert::msg::Image", QosClass::kLargeStream,
              "robot: colour image (rgb8) of each RGB-D camera, one instance per camera"},
    TopicInfo{"concert/sensors/camera/depth", "concert::msg::Image", QosClass::kLargeStream,
              "robot: depth image (16UC1, registered to the colour image) of each RGB-D camera"},
    TopicInfo{"concert/sensors/camera/info", "concert::msg::CameraInfo", QosClass::kStream,
              "robot: intrinsics and depth range of each camera, with every frame"},
    TopicInfo{"concert/sensors/lidar", "concert::msg::LidarScan", QosClass::kStream,
              "robot: one revolution of each 3D lidar (rings x columns), one instance per lidar"},
    TopicInfo{"concert/sensors/scan", "concert::msg::LaserScan", QosClass::kStream,
              "robot: planar scan derived from the lidars, for navigation"},
    TopicInfo{"concert/sensors/sonar", "concert::msg::SonarRanges", QosClass::kStream,
              "robot: every ultrasound range sensor, read at the same instant"},
    TopicInfo{"concert/sensors/imu", "concert::msg::Imu", QosClass::kStream,
              "robot: angular velocity and specific force of each IMU, one instance per IMU"},
    TopicInfo{"concert/sensors/list", "concert::msg::SensorList", QosClass::kLatched,
              "robot: the mounted sensors (name, kind, frame, rate) at a model version"},
    TopicInfo{"concert/nav/goal", "concert::msg::NavGoal", QosClass::kCommand,
              "operator/tasks: drive the base to a map pose or in front of a BIM wall"},
    TopicInfo{"concert/nav/cancel", "concert::msg::NavCancel", QosClass::kCommand,
              "operator/tasks: cancel a navigation goal (0: whatever runs)"},
    TopicInfo{"concert/nav/initial_pose", "concert::msg::NavInitialPose", QosClass::kCommand,
              "operator: the robot's pose in the map to (re)start localisation from"},
    TopicInfo{"concert/nav/status", "concert::msg::NavStatus", QosClass::kLatched,
              "nav: feedback and result of each goal, one instance per request"},
    TopicInfo{"concert/nav/path", "concert::msg::NavPath", QosClass::kLatched,
              "nav: the current global path in the map frame"},
    TopicInfo{"concert/nav/map", "concert::msg::OccupancyGridMap", QosClass::kLatched,
              "nav: the storey's occupancy grid (nav2 conventions)"},
    TopicInfo{"concert/nav/odometry", "concert::msg::Odometry", QosClass::kStream,
              "nav: odometry filtered from wheel odometry and the IMU, with covariance"},
    TopicInfo{"concert/nav/localisation", "concert::msg::NavLocalisation", QosClass::kStream,
              "nav: the base pose in the map and map -> odom, from the lidars"},
    TopicInfo{"concert/nav/vehicle", "concert::msg::NavVehicle", QosClass::kLatched,
              "nav: drive type, footprint and sensors recognised in the current model"},
    TopicInfo{"concert/sim/holes", "concert::msg::SimHoles", QosClass::kLatched,
              "robot (simulation only): every hole the drill bits cut, for tests and benchmarks"},
    TopicInfo{"concert/drill/mission", "concert::msg::DrillMission", QosClass::kCommand,
              "tools: a drilling mission (the mission file's YAML) for the drill service"},
    TopicInfo{"concert/drill/abort", "concert::msg::DrillAbort", QosClass::kCommand,
              "tools/operator: stop the running drilling mission"},
    TopicInfo{"concert/drill/status", "concert::msg::DrillStatus", QosClass::kLatched,
              "drill: the mission's active behaviour-tree node, areas, holes and time split, per mission"},
    TopicInfo{"concert/collab/command", "concert::msg::CollabCommand", QosClass::kCommand,
              "tools/GUI/voice: a collaborative-transport command (\"hey concert follow me\" or a mode)"},
    TopicInfo{"concert/collab/state", "concert::msg::CollabState", QosClass::kLatched,
              "collab: the Fig. 12 state, the last command and why it was ignored, follow-me figures"},
    TopicInfo{"concert/finish/areas", "concert::msg::FinishAreas", QosClass::kLatched,
              "surface_finish: the predetermined wall areas of the current model and tool"},
    TopicInfo{"concert/finish/command", "concert::msg::FinishCommand", QosClass::kCommand,
              "tools/operator: spray or sand an area, or abort"},
    TopicInfo{"concert/finish/status", "concert::msg::FinishStatus", QosClass::kLatched,
              "surface_finish: a run's state, progress and spray report, per request"},
};

}  // namespace

QosSpec qos_spec(QosClass qos) {
  switch (qos) {
    case QosClass::kLatched: return {true, true, 1};
    case QosClass::kStream: return {false, false, 1};
    case QosClass::kCommand: return {true, false, 8};
    case QosClass::kLargeStream: return {false, false, 1, true};
  }
  throw std::logic_error("unknown QosClass");
}

std::string_view to_string(QosClass qos) {
  switch (qos) {
    case QosClass::kLatched: return "latched (reliable, transient-local, keep-last 1)";
    case QosClass::kStream: return "stream (best-effort, volatile, keep-last 1)";
    case QosClass::kCommand: return "command (reliable, volatile, keep-last 8)";
    case QosClass::kLargeStream: return "large stream (best-effort, volatile, keep-last 1, asynchronous writes)";
  }
  return "?";
}

std::span<const TopicInfo> catalogue() { return kTopics; }

std::optional<TopicInfo> find_topic(std::string_view name) {
  for (const auto& t : kTopics) {
    if (t.name == name) return t;
  }
  return std::nullopt;
}

int32_t parse_domain_id(std::string_view text, std::string_view what) {
  int32_t id = -1;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (ec != std::errc() || ptr != text.data() + text.size() || id < 0 || id > 232) {
    throw std::invalid_argument(std::string(what) + ": '" + std::string(text) +
                                "' is not a DDS domain id (an integer from 0 to 232)");
  }
  return id;
}

std::string domain_port_warning(int32_t domain_id, long low, long high) {
  const long first = 7400L + 250L * domain_id;
  const long last = first + 249;
  if (last < low || first > high) return "";
  std::string text = "concert dds: domain " + std::to_string(domain_id) + " uses UDP ports " +
                     std::to_string(first) + "-" + std::to_string(last) +
                     ", inside this machine's ephemeral port range " + std::to_string(low) + "-" +
                     std::to_string(high) +
                     ": another program's socket may take one of them, and a Cyclone DDS "
                     "participant of another domain may then join this one; use a domain whose "
                     "ports lie below that range";
  if (low >= 7650) text += " (0 to " + std::to_string((low - 7650) / 250) + " here)";
  return text + " or reserve them (sysctl -w net.ipv4.ip_local_reserved_ports=" +
         std::to_string(first) + "-" + std::to_string(last) + ")";
}

int32_t domain_id_from_env() {
  const char* env = std::getenv("CONCERT_DOMAIN_ID");
  if (env == nullptr || *env == '\0') return 0;
  return parse_domain_id(env, "CONCERT_DOMAIN_ID");
}

namespace {
/// FNV-1a 32-bit over the concatenation of `parts`.
uint32_t fnv1a(std::initializer_list<std::string_view> parts) {
  uint32_t h = 2166136261u;
  for (std::string_view s : parts) {
    for (unsigned char c : s) {
      h ^= c;
      h *= 16777619u;
    }
  }
  return h;
}
}  // namespace

uint32_t status_instance_id(std::string_view service, std::string_view host) {
  return fnv1a({service, "@", host});
}

uint32_t sensor_id(std::string_view sensor) { return fnv1a({sensor}); }

}  // namespace concert::dds
