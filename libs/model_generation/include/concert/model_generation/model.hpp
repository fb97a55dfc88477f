#pragma once
// The robot model generated from a module tree (paper section 4.3.3): the physical tree phi,
// URDF/SRDF/controller-configuration texts and the joint/chain/end-effector/sensor lists that
// become the model description (libs/model) the RobotModel message carries. Plain C++/Eigen;
// no DDS.

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/model/description.hpp"
#include "concert/module_db/module_description.hpp"

namespace concert::model_generation {

using module_db::Pose;

/// A tree that cannot be modelled (unknown module, connector mismatch, bad customisation...).
/// what() names the module (index, key) and what is wrong.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A body (node) of the physical tree phi = one URDF link.
struct PhysicalBody {
  std::string name;                ///< URDF link name (section 4.3.3 naming)
  int module = -1;                 ///< index into the module tree; -1 for none
  int module_body = -1;            ///< body index in the module description; -1 for frames
  std::string chain;               ///< chain tag ("A", "B", ...); empty for the root hub
  bool massless = false;           ///< TCP/wheel/camera frames carry no inertia
  module_db::Inertial inertial;    ///< in the link frame (CoM and inertia axes rotated into it)
  std::vector<module_db::Shape> visuals;     ///< poses in the link frame
  std::vector<module_db::Shape> collisions;  ///< poses in the link frame
};

/// An edge of phi = one URDF joint. Moving joints carry the module's limits and control data.
struct PhysicalJoint {
  std::string name;
  module_db::JointType type = module_db::JointType::kFixed;
  int parent = 0;                  ///< index into PhysicalTree::bodies
  int child = 0;                   ///< index into PhysicalTree::bodies
  Pose origin = Pose::Identity();  ///< parent_link_T_child_link at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< in the child link frame
  int module = -1;
  std::string chain;
  bool connection = false;         ///< true: static joint made by two mating connectors (eq. 1)
  const module_db::JointDescription* description = nullptr;  ///< moving joints: the module's joint
};

/// The physical tree phi. bodies[0] is the root; joints are ordered parents first.
struct PhysicalTree {
  std::vector<PhysicalBody> bodies;
  std::vector<PhysicalJoint> joints;
  /// Index of the body called `name`, or -1.
  int body_index(const std::string& name) const;
  /// Sum of body masses, kg.
  double mass() const;
};

/// A moving joint with everything the generator knows of it (the description keeps the limits).
struct JointInfo {
  std::string name;
  std::string chain;
  int module = -1;
  std::string module_key;
  /// The module's robot_id (its drive board's, from the scan): the EtherCAT master binds the
  /// joint to the board by it. -1: the tree gave none (hand-made trees).
  int32_t robot_id = -1;
  module_db::JointType type = module_db::JointType::kRevolute;
  double lower = 0.0;              ///< rad (m)
  double upper = 0.0;              ///< rad (m)
  double velocity = 0.0;           ///< rad/s (m/s)
  double peak_torque = 0.0;        ///< N m (N)
  double continuous_torque = 0.0;  ///< N m; the peak torque where the database gives none
  double gear_ratio = 1.0;
  std::string control_mode;        ///< "position", "velocity" or "impedance"
  module_db::ControlParams gains;
  double home = 0.0;               ///< homing position, rad (m)
};

/// A kinematic chain.
struct ChainInfo {
  std::string name;                ///< tag "A", "B", ...
  model::ChainRole role = model::ChainRole::kOther;
  std::string base_link;
  std::string tip_link;
  std::vector<std::string> joints; ///< moving joints, root to tip
  std::vector<int> modules;        ///< module indices in the chain, root to tip
};

/// An end-effector; wheels count as end-effectors of legs.
struct EndEffectorInfo {
  std::string name;                ///< e.g. "drill_E"
  std::string chain;
  std::string frame;               ///< TCP or wheel-centre link
  std::string module_key;
  model::EndEffectorKind kind = model::EndEffectorKind::kOther;  ///< from the module's tags
  int module = -1;
  std::vector<std::string> addons; ///< add-on keys mounted on it
};

/// One add-on choice of a customisation (section 4.4).
struct AddonChoice {
  std::string module_name;         ///< end-effector name ("drill_E") or URDF body name
  std::string addon;               ///< add-on key, e.g. "drillbit_12_SDSmax"
  bool operator==(const AddonChoice&) const = default;
};

/// What the network cannot discover: homing posture and add-ons.
struct Customisation {
  std::map<std::string, double> home;  ///< joint name -> homing position, rad (m)
  std::vector<AddonChoice> addons;
  bool operator==(const Customisation&) const = default;
};

/// How the default homing posture was chosen (ModelGenerator::generate).
struct RestingPosture {
  /// False: every arm joint rests at the database's zero (clamped into its limits) or at the
  /// customisation's home. True: the zero posture overloaded a drive, so the free arm joints
  /// were moved to a posture the drives hold.
  bool moved = false;
  /// Largest gravity torque of an arm joint at the homing posture, as a fraction of that
  /// joint's continuous torque [-], and that joint ("" without an arm).
  double static_load = 0.0;
  std::string joint;
};

/// One line for a log on how the arm's homing posture was chosen, or "" when it rests at the
/// database's zero within `fraction` (Params::home_torque_fraction) of every continuous torque.
std::string describe(const RestingPosture& resting, double fraction);

/// A generated model. Texts contain no version or time, so equal content gives an equal hash.
struct GeneratedModel {
  uint64_t version = 0;            ///< assigned by ModelVersioner; 0 = not published
  uint64_t tree_version = 0;       ///< version of the module tree it was built from
  std::string content_hash;        ///< "sha256:<hex>" of urdf + '\0' + srdf + '\0' + config_yaml
  std::string urdf;
  std::string srdf;
  std::string config_yaml;
  std::vector<std::string> modules;  ///< module keys in tree order
  std::vector<JointInfo> joints;
  std::vector<ChainInfo> chains;
  std::vector<EndEffectorInfo> end_effectors;
  std::vector<model::SensorFrame> sensor_frames;  ///< camera frames of modules, add-on frames
  Customisation customisation;     ///< the customisation applied
  RestingPosture resting;          ///< how the homing posture was chosen
  PhysicalTree tree;               ///< phi

  /// What the RobotModel message carries: version, hash, texts and the lists, with the
  /// limits table (position, velocity, peak and continuous torque per moving joint).
  [[nodiscard]] model::ModelDescription description() const;
};

/// Options of the generator.
struct Params {
  std::string robot_name = "concert";
  /// Gains used when the database gives none for a joint of that control mode.
  double default_stiffness = 1000.0;  ///< N m/rad
  double default_damping = 20.0;      ///< N m s/rad
  double default_kp = 500.0;
  double default_kd = 10.0;
  double default_velocity_kp = 5.0;
  /// The arms' default homing posture keeps each arm joint's gravity torque within this share
  /// of its continuous torque, leaving the rest for motion (the safety layer stops the robot
  /// when a joint's torque RMS exceeds its continuous torque).
  double home_torque_fraction = 0.5;
};

}  // namespace concert::model_generation
