#pragma once
// Plain C++ description of one CONCERT module (paper section 4.3.1) and of add-ons (section 4.4),
// independent of the file format it was read from (the project's YAML database or the public
// CoBRA/Timor JSON database). Lengths in m, angles in rad, masses in kg, inertia in kg m^2.

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "concert/topology/types.hpp"

namespace concert::module_db {

/// Rigid transform; `a_T_b` maps coordinates in frame b to frame a.
using Pose = Eigen::Isometry3d;

/// Thrown for unreadable or invalid database content; what() names the file and the field,
/// e.g. `module_joint_elbow_A_concert.json: joints[0].limits.velocity: missing`.
class ModuleDbError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What the module is, as far as model generation is concerned.
enum class ModuleType { kJoint, kHub, kMobileBase, kLink, kBaseLink, kEndEffector, kWheel };

/// Lower-case name of a type ("joint", "hub", "mobile_base", "link", "base_link",
/// "end_effector", "wheel").
std::string to_string(ModuleType type);
/// Inverse of to_string; throws std::invalid_argument for an unknown name.
ModuleType module_type_from_string(const std::string& name);

/// Mass properties of one body.
struct Inertial {
  double mass = 0.0;                                   ///< kg
  Eigen::Vector3d com = Eigen::Vector3d::Zero();       ///< centre of mass in the body frame, m
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();   ///< about the CoM, body-frame axes, kg m^2
};

/// A visual or collision shape placed in its body's frame.
struct Shape {
  enum class Kind { kMesh, kBox, kCylinder, kSphere };
  Kind kind = Kind::kMesh;
  std::string mesh;                                     ///< mesh path or package:// URI (kMesh)
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();      ///< mesh scale (kMesh)
  Eigen::Vector3d size = Eigen::Vector3d::Zero();       ///< box edge lengths, m (kBox)
  double radius = 0.0;                                  ///< m (kCylinder, kSphere)
  double length = 0.0;                                  ///< m (kCylinder)
  Pose pose = Pose::Identity();                         ///< body_T_shape
  std::string material;                                 ///< material name, may be empty
  std::optional<Eigen::Vector4d> rgba;                  ///< colour, 0..1
};

/// One rigid body of a module (a joint module has a proximal and a distal body).
struct Body {
  std::string name;
  Inertial inertial;
  std::vector<Shape> visuals;
  std::vector<Shape> collisions;
};

/// Role of a connector. Outputs accept child modules; TCP connectors close a chain.
enum class ConnectorRole { kInput, kOutput, kTcp, kBase };

/// An electro-mechanical interface (EMI) or tool flange of a module.
struct Connector {
  std::string name;
  ConnectorRole role = ConnectorRole::kOutput;
  int body = 0;                     ///< index into ModuleDescription::bodies
  std::string type;                 ///< mechanical type, e.g. "clamp"
  std::string size;                 ///< e.g. "large"; mating connectors must have equal sizes
  Pose pose = Pose::Identity();     ///< body_T_connector; z points downstream
};

/// Limits of an actuated joint (paper Table 1).
struct JointLimits {
  double lower = 0.0;               ///< rad (m for prismatic)
  double upper = 0.0;               ///< rad (m for prismatic)
  double velocity = 0.0;            ///< rad/s (m/s)
  double peak_torque = 0.0;         ///< N m (N)
  std::optional<double> continuous_torque;  ///< N m (N); absent in the public database
};

/// Default low-level control of a joint, used for the controller configuration.
struct ControlParams {
  std::string mode;                 ///< "position", "velocity", "impedance"; empty = by module type
  double stiffness = 0.0;           ///< N m/rad
  double damping = 0.0;             ///< N m s/rad
  double kp = 0.0;                  ///< position PID gains
  double ki = 0.0;
  double kd = 0.0;
};

enum class JointType { kRevolute, kContinuous, kPrismatic, kFixed };
/// URDF name of a joint type ("revolute", "continuous", "prismatic", "fixed").
std::string to_string(JointType type);
/// Inverse of to_string; throws std::invalid_argument for an unknown name.
JointType joint_type_from_string(const std::string& name);

/// A joint between two bodies of the same module. Frames: parent body -> pose_parent -> joint
/// frame (axis = joint-frame axis, normally z) -> motion(q) -> pose_child -> child body.
struct JointDescription {
  std::string name;
  JointType type = JointType::kRevolute;
  int parent_body = 0;
  int child_body = 1;
  Pose pose_parent = Pose::Identity();   ///< parent_body_T_joint
  Pose pose_child = Pose::Identity();    ///< joint_T_child_body (after the motion)
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit axis in the joint frame
  JointLimits limits;
  double gear_ratio = 1.0;
  double motor_inertia = 0.0;       ///< kg m^2
  double friction_viscous = 0.0;    ///< N m s/rad
  ControlParams control;
  bool actuated() const { return type != JointType::kFixed; }
};

/// Kind of a named frame of a module (paper section 4.3.2). Sensor frames (camera, lidar,
/// sonar, imu) become the robot model's sensor frames; camera frames are optical frames (z
/// along the optical axis, x right, y down), lidar and sonar frames have x along the beam at
/// azimuth 0 / the cone axis (hardware/sensors.hpp).
enum class FrameKind { kInput, kJoint, kOutput, kTcp, kWheel, kCamera, kLidar, kSonar, kImu, kOther };
std::string to_string(FrameKind kind);

/// A named frame fixed to one body, beyond connectors and joints (e.g. a camera, a lidar).
struct Frame {
  std::string name;
  FrameKind kind = FrameKind::kOther;
  int body = 0;
  Pose pose = Pose::Identity();     ///< body_T_frame
};

/// One module type of the database.
struct ModuleDescription {
  std::string key;                  ///< database key; for the public DB the file stem
  std::string label;                ///< human-readable name
  std::string source;               ///< file it was read from
  ModuleType type = ModuleType::kLink;
  std::optional<topology::EscIdentity> esc;  ///< identity of the module's upstream ESC
  std::vector<Body> bodies;
  std::vector<Connector> connectors;
  std::vector<JointDescription> joints;
  std::vector<Frame> frames;        ///< extra frames (camera, ...); connectors/joints not repeated
  std::vector<std::string> tags;    ///< semantic tags ("arm", "gripper", "drill", ...)
  std::vector<std::string> addon_types;  ///< add-on types this module accepts ("drillbit", ...)
  /// Actuator family (paper Table 1) and its mass in kg, where the database names it.
  struct Actuator {
    std::string name;
    double mass = 0.0;
  };
  std::optional<Actuator> actuator;

  /// Index of the body that carries the input (or base) connector: the module's root body.
  int root_body() const;
  /// Index into connectors of the input connector, or -1 (root-only modules such as bases).
  int input_connector() const;
  /// Indices into connectors of the output connectors in file order. Output connector n
  /// (1-based, as in topology::ModuleNode::parent_connector) is output_connectors()[n-1].
  std::vector<int> output_connectors() const;
  /// Indices into connectors of TCP connectors (tool centre points, wheel centres).
  std::vector<int> tcp_connectors() const;
  /// Every frame of the module (paper section 4.3.2), each on its body: input, joint (on the
  /// parent body, at pose_parent), outputs, TCP or wheel centre, then the extra frames.
  std::vector<Frame> named_frames() const;
  /// Sum of body masses, kg.
  double mass() const;
  /// True if any joint moves.
  bool actuated() const;
  /// True for end-effector and wheel modules (they close a chain).
  bool is_end_effector() const { return type == ModuleType::kEndEffector || type == ModuleType::kWheel; }
  /// True for hubs (new chains start at their outputs).
  bool is_hub() const { return type == ModuleType::kHub || type == ModuleType::kMobileBase; }
};

/// An add-on the network cannot see (drill bit, handle, sensor), chosen per model (section 4.4).
struct AddonDescription {
  std::string key;                  ///< database key (file stem)
  std::string type;                 ///< "drillbit", "handle", "sensor", ...
  std::string label;
  std::string source;
  double mass = 0.0;                ///< kg, added to the module body it is mounted on
  Eigen::Vector3d com = Eigen::Vector3d::Zero();  ///< CoM in the mounting (TCP) frame, m
  double tcp_offset = 0.0;          ///< TCP moves this far along the TCP z axis, m
  std::optional<Frame> frame;       ///< extra frame it adds (sensors), pose in the TCP frame
  std::map<std::string, double> parameters;  ///< raw numeric parameters from the file
};

}  // namespace concert::module_db
