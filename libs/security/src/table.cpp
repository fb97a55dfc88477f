#include "concert/security/table.hpp"

#include <algorithm>
#include <array>

namespace concert::security {
namespace {

constexpr std::array<std::string_view, 10> kIdentities = {
    "robot", "safety", "discovery", "modelgen", "planner", "nav", "drill", "collab", "surface_finish", kOperator};
constexpr size_t kServices = kIdentities.size() - 1;

// Writer groups. A topic's row names one of them.
constexpr std::string_view kRobot[] = {"robot"};
constexpr std::string_view kSafety[] = {"safety"};
constexpr std::string_view kDiscovery[] = {"discovery"};
constexpr std::string_view kModelgen[] = {"modelgen"};
constexpr std::string_view kPlanner[] = {"planner"};
constexpr std::string_view kNav[] = {"nav"};
constexpr std::string_view kDrill[] = {"drill"};
constexpr std::string_view kCollab[] = {"collab"};
constexpr std::string_view kFinish[] = {"surface_finish"};
constexpr std::string_view kOperatorOnly[] = {kOperator};
/// Motion commands to the robot: the planner and the task services, never a tool.
constexpr std::string_view kCommanders[] = {"planner", "nav", "drill", "collab", "surface_finish"};
/// Requests to a service: the operator's tools and the task services that chain them.
constexpr std::string_view kOperatorAndDrill[] = {kOperator, "drill"};
/// Every service heartbeats its own status instance.
constexpr std::string_view kServicesOnly[] = {"robot", "safety", "discovery", "modelgen", "planner",
                                              "nav",   "drill",  "collab",    "surface_finish"};

constexpr std::string_view kState = "the service that owns this state";
constexpr std::string_view kMotion = "motion commands: the planner and the task services";
constexpr std::string_view kOperatorRule = "only the operator's tools";
constexpr std::string_view kRequest = "requests: the operator's tools and the drill service";
constexpr std::string_view kSim = "the simulator runs in the robot service";
constexpr std::string_view kSensors = "the robot service publishes the sensors";

constexpr std::array kRules = {
    WriteRule{"concert/ethercat/scan", kRobot, "the EtherCAT master runs in the robot service"},
    WriteRule{"concert/topology/module_tree", kDiscovery, kState},
    WriteRule{"concert/model/robot_model", kModelgen, kState},
    WriteRule{"concert/model/customisation", kOperatorOnly, kOperatorRule},
    WriteRule{"concert/robot/joint_state", kRobot, "only the robot service writes joint state"},
    WriteRule{"concert/robot/joint_command", kCommanders, kMotion},
    WriteRule{"concert/robot/cartesian_command", kCommanders, kMotion},
    WriteRule{"concert/robot/base_velocity", kCommanders, kMotion},
    WriteRule{"concert/robot/odometry", kRobot, kState},
    WriteRule{"concert/robot/ee_wrench", kRobot, kState},
    WriteRule{"concert/system/status", kServicesOnly, "every service, its own status"},
    WriteRule{"concert/safety/estop", kOperatorOnly, "only operator tools write e-stop inputs"},
    WriteRule{"concert/safety/state", kSafety, "only the safety service writes safety state"},
    WriteRule{"concert/safety/reset", kOperatorOnly, "only operator tools reset a safety stop"},
    WriteRule{"concert/planner/request", kOperatorAndDrill, kRequest},
    WriteRule{"concert/planner/result", kPlanner, kState},
    WriteRule{"concert/robot/trajectory_command", kCommanders, kMotion},
    WriteRule{"concert/robot/trajectory_status", kRobot, kState},
    WriteRule{"concert/world/world", kRobot, kSim},
    WriteRule{"concert/sim/command", kOperatorOnly, kOperatorRule},
    WriteRule{"concert/sim/reply", kRobot, kSim},
    WriteRule{"concert/sim/truth", kRobot, kSim},
    WriteRule{"concert/sensors/camera/rgb", kRobot, kSensors},
    WriteRule{"concert/sensors/camera/depth", kRobot, kSensors},
    WriteRule{"concert/sensors/camera/info", kRobot, kSensors},
    WriteRule{"concert/sensors/lidar", kRobot, kSensors},
    WriteRule{"concert/sensors/scan", kRobot, kSensors},
    WriteRule{"concert/sensors/sonar", kRobot, kSensors},
    WriteRule{"concert/sensors/imu", kRobot, kSensors},
    WriteRule{"concert/sensors/list", kRobot, kSensors},
    WriteRule{"concert/nav/goal", kOperatorAndDrill, kRequest},
    WriteRule{"concert/nav/cancel", kOperatorAndDrill, kRequest},
    WriteRule{"concert/nav/initial_pose", kOperatorOnly, kOperatorRule},
    WriteRule{"concert/nav/status", kNav, kState},
    WriteRule{"concert/nav/path", kNav, kState},
    WriteRule{"concert/nav/map", kNav, kState},
    WriteRule{"concert/nav/odometry", kNav, kState},
    WriteRule{"concert/nav/localisation", kNav, kState},
    WriteRule{"concert/nav/vehicle", kNav, kState},
    WriteRule{"concert/sim/holes", kRobot, kSim},
    WriteRule{"concert/drill/mission", kOperatorOnly, kOperatorRule},
    WriteRule{"concert/drill/abort", kOperatorOnly, kOperatorRule},
    WriteRule{"concert/drill/status", kDrill, kState},
    WriteRule{"concert/collab/command", kOperatorOnly, "only the operator's tools (voice, GUI, concert collab)"},
    WriteRule{"concert/collab/state", kCollab, kState},
    WriteRule{"concert/finish/areas", kFinish, kState},
    WriteRule{"concert/finish/command", kOperatorOnly, kOperatorRule},
    WriteRule{"concert/finish/status", kFinish, kState},
};

const WriteRule* find_rule(std::string_view topic) {
  for (const auto& r : kRules) {
    if (r.topic == topic) return &r;
  }
  return nullptr;
}

}  // namespace

std::span<const std::string_view> identities() { return kIdentities; }

bool is_service_identity(std::string_view name) {
  return std::find(kIdentities.begin(), kIdentities.begin() + kServices, name) !=
         kIdentities.begin() + kServices;
}

bool is_identity(std::string_view name) {
  return std::find(kIdentities.begin(), kIdentities.end(), name) != kIdentities.end();
}

std::span<const WriteRule> write_rules() { return kRules; }

std::vector<std::string_view> writers_of(std::string_view topic) {
  const WriteRule* r = find_rule(topic);
  if (r == nullptr) return {};
  return {r->writers.begin(), r->writers.end()};
}

bool may_write(std::string_view identity, std::string_view topic) {
  const WriteRule* r = find_rule(topic);
  return r != nullptr &&
         std::find(r->writers.begin(), r->writers.end(), identity) != r->writers.end();
}

std::vector<std::string_view> topics_written_by(std::string_view identity) {
  std::vector<std::string_view> topics;
  for (const auto& r : kRules) {
    if (std::find(r.writers.begin(), r.writers.end(), identity) != r.writers.end()) {
      topics.push_back(r.topic);
    }
  }
  return topics;
}

}  // namespace concert::security
