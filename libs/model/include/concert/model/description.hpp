#pragma once
// The robot model as plain data: exactly what the RobotModel message carries (idl/model.idl),
// with roles and kinds as enums. Built by model generation, converted to and from the message
// by concert_model_dds, parsed once per version into a RobotModel (robot_model.hpp). No DDS.

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace concert::model {

/// A model that cannot be used, or a selection that does not exist; what() names the model
/// version, what was asked for and the candidates.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What a kinematic chain is for.
enum class ChainRole {
  kArm,    ///< moving joints carrying a tool (or ending in a free flange)
  kLeg,    ///< a steering + wheel leg of the mobile base
  kTool,   ///< a tool mounted without moving joints of its own chain
  kOther,  ///< passive links only
};

/// What an end-effector is; from the module database's semantic tags.
enum class EndEffectorKind { kDrill, kGripper, kSanding, kSpraying, kCamera, kWheel, kOther };

/// What a sensor frame carries.
enum class SensorKind { kCamera, kLidar, kSonar, kImu, kForceTorque, kOther };

/// "arm", "leg", "tool", "other".
std::string_view to_string(ChainRole role);
/// "drill", "gripper", "sanding", "spraying", "camera", "wheel", "other".
std::string_view to_string(EndEffectorKind kind);
/// "camera", "lidar", "sonar", "imu", "force_torque", "other".
std::string_view to_string(SensorKind kind);
/// Inverse of to_string; throws ModelError naming `what` (e.g. "chains[2].role") and the
/// accepted names for an unknown name.
ChainRole chain_role_from_string(std::string_view name, const std::string& what);
EndEffectorKind end_effector_kind_from_string(std::string_view name, const std::string& what);
SensorKind sensor_kind_from_string(std::string_view name, const std::string& what);

/// One row of the limits table: every limit of a moving joint, in one place.
/// See README.md "The limits rule" for which consumer enforces which column.
struct JointLimits {
  std::string name;
  std::string chain;                                        ///< chain tag ("A", "B", ...)
  double lower = -std::numeric_limits<double>::infinity();  ///< position [rad] ([m] prismatic)
  double upper = std::numeric_limits<double>::infinity();   ///< position [rad] ([m] prismatic)
  double velocity = 0.0;                                    ///< |qd| limit [rad/s] ([m/s])
  double peak_torque = 0.0;        ///< |tau| the drive can deliver briefly [N m] ([N])
  double continuous_torque = 0.0;  ///< |tau| the drive sustains thermally [N m] ([N]); <= peak
  bool operator==(const JointLimits&) const = default;
};

/// A kinematic chain.
struct ChainInfo {
  std::string name;  ///< tag "A", "B", ...
  ChainRole role = ChainRole::kOther;
  std::string base_link;
  std::string tip_link;
  std::vector<std::string> joints;  ///< moving joints, root to tip
  bool operator==(const ChainInfo&) const = default;
};

/// An end-effector (tools, grippers; wheels are the end-effectors of legs).
struct EndEffectorInfo {
  std::string name;        ///< e.g. "drill_E", "wheel_A"
  std::string chain;       ///< chain tag
  std::string frame;       ///< TCP or wheel-centre link
  std::string module_key;  ///< module-database key of the end-effector module
  EndEffectorKind kind = EndEffectorKind::kOther;
  bool operator==(const EndEffectorInfo&) const = default;
};

/// A frame a sensor is mounted at (the drill's camera; lidars, sonars, IMUs next).
struct SensorFrame {
  std::string name;  ///< e.g. "camera_E"
  SensorKind kind = SensorKind::kOther;
  std::string frame;         ///< URDF link of the sensor
  std::string chain;         ///< chain tag; empty on the root hub
  std::string end_effector;  ///< end-effector it belongs to; empty for none
  std::string module_key;    ///< module (or add-on) the sensor comes with
  bool operator==(const SensorFrame&) const = default;
};

/// The model as the RobotModel message carries it.
struct ModelDescription {
  uint64_t version = 0;       ///< strictly increasing; 0 = not published
  std::string content_hash;   ///< "sha256:<hex>" of urdf + srdf + config text
  uint64_t tree_version = 0;  ///< ModuleTree version it was generated from
  std::string urdf;
  std::string srdf;
  std::string config_yaml;           ///< controller configuration
  std::vector<std::string> modules;  ///< module keys in tree order
  std::vector<JointLimits> joints;   ///< the limits table, one row per moving joint
  std::vector<ChainInfo> chains;
  std::vector<EndEffectorInfo> end_effectors;
  std::vector<SensorFrame> sensor_frames;
  bool operator==(const ModelDescription&) const = default;
};

}  // namespace concert::model
