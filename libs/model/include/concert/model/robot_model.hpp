#pragma once
// The parsed robot model: built once per model version, immutable afterwards and shared by
// every thread of a service (Pinocchio's Model/Data split: per-thread scratch is a
// kinematics::Data made by kinematics().make_data()). Every service selects chains,
// end-effectors and sensors by role and kind through it, never by list position or by name.

#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "concert/kinematics/model.hpp"
#include "concert/model/description.hpp"
#include "concert/model/limits.hpp"

namespace concert::model {

/// A collision shape of a link, in the link frame.
struct CollisionShape {
  enum class Type { kBox, kCylinder, kSphere, kMesh };
  Type type = Type::kBox;
  /// Box: full extents; cylinder: (radius, radius, length) along its z; sphere: (r, r, r);
  /// mesh: scale [m].
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< link_T_shape
  std::string mesh;                                          ///< mesh file name (kMesh)
};

/// One URDF link, in topological order (parents first).
struct Link {
  std::string name;
  int parent = -1;         ///< index in RobotModel::links(); -1 for the root
  std::string joint;       ///< URDF joint from the parent (moving or fixed); empty at the root
  bool moving = false;     ///< the joint from the parent moves
  bool prismatic = false;  ///< ... and is prismatic
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< parent_T_joint at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();           ///< joint axis in the joint frame
  std::string chain;  ///< chain of the nearest moving joint at or above; "" for none
  double mass = 0.0;  ///< [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();  ///< centre of mass in the link frame [m]
  std::vector<CollisionShape> shapes;
};

/// A leg of the mobile base, as the robot's base controller needs it.
struct Leg {
  const ChainInfo* chain = nullptr;
  std::string steering_joint;  ///< turns the wheel about the vertical; empty for none
  std::string wheel_joint;     ///< drives the wheel
  std::string wheel_frame;     ///< wheel-centre link
  double wheel_radius = 0.0;   ///< [m], from the wheel link's collision cylinder
};

/// The parsed model of one version. Build with RobotModel::build; share the pointer.
class RobotModel {
 public:
  /// Parses and checks a description: URDF (kinematics, collision geometry), SRDF disabled
  /// pairs, chains, end-effectors, sensor frames and the limits table. Throws ModelError naming
  /// the version and what is wrong (URDF/SRDF parse errors, a listed joint, link or frame
  /// absent from the URDF, a bad limit).
  static std::shared_ptr<const RobotModel> build(ModelDescription description);

  [[nodiscard]] uint64_t version() const { return description_.version; }
  [[nodiscard]] const std::string& content_hash() const { return description_.content_hash; }
  /// The description it was built from (texts, lists as sent).
  [[nodiscard]] const ModelDescription& description() const { return description_; }
  /// "model version N" for error messages.
  [[nodiscard]] std::string where() const;

  /// Kinematics/dynamics with the base fixed to the world.
  [[nodiscard]] const kinematics::Model& kinematics() const { return fixed_; }
  /// Kinematics with a planar base: base_x, base_y, base_yaw first, then the URDF's joints.
  [[nodiscard]] const kinematics::Model& planar_kinematics() const { return planar_; }

  /// Every link with its collision shapes, parents first.
  [[nodiscard]] const std::vector<Link>& links() const { return links_; }
  /// Index of a link in links(), or -1.
  [[nodiscard]] int link_index(std::string_view name) const;
  /// Pairs of link indices (a < b) whose collisions the SRDF disables.
  [[nodiscard]] const std::vector<std::pair<int, int>>& disabled_pairs() const { return disabled_; }
  /// The SRDF's `home` group state, joint name -> position [rad or m] (the homing posture the
  /// model generator chose: the transport posture, where a new module's joint starts); empty
  /// when the SRDF has none.
  [[nodiscard]] const std::map<std::string, double>& home() const { return home_; }
  /// The `home` position of a joint, or nullopt when the SRDF gives none.
  [[nodiscard]] std::optional<double> home(std::string_view joint) const;
  /// The homing posture as joint positions of kinematics() (size dof()): each joint at its
  /// `home` value, 0 where the SRDF names none, clamped into its limits-table position range (a
  /// continuous joint into [-pi, pi], as the planner bounds it); virtual base joints at 0. The
  /// one posture nav drives with and the planner's `plan home` ends on.
  [[nodiscard]] Eigen::VectorXd home_posture() const;

  /// The limits table (one row per moving joint); see limits.hpp for the limits rule.
  [[nodiscard]] const LimitsTable& limits() const { return limits_; }

  [[nodiscard]] const std::vector<ChainInfo>& chains() const { return description_.chains; }
  /// Chains of a role, in model order (may be empty).
  [[nodiscard]] std::vector<const ChainInfo*> chains(ChainRole role) const;
  /// The chain called `name`; throws ModelError listing the chains.
  [[nodiscard]] const ChainInfo& chain(std::string_view name) const;
  /// The one arm; throws ModelError when the model has no arm or several (listing them).
  [[nodiscard]] const ChainInfo& arm() const;
  /// The legs (chains of role leg) with their steering and wheel joints and wheel radius.
  /// Throws ModelError naming a leg without a wheel.
  [[nodiscard]] std::vector<Leg> legs() const;

  [[nodiscard]] const std::vector<EndEffectorInfo>& end_effectors() const {
    return description_.end_effectors;
  }
  /// End-effectors of a kind, in model order (may be empty).
  [[nodiscard]] std::vector<const EndEffectorInfo*> end_effectors(EndEffectorKind kind) const;
  /// The end-effector called `name`; throws ModelError listing the end-effectors.
  [[nodiscard]] const EndEffectorInfo& end_effector(std::string_view name) const;
  /// The tool: the one end-effector at the tip of an arm chain (never a wheel). Throws
  /// ModelError when there is none or several, listing the end-effectors with their kinds.
  [[nodiscard]] const EndEffectorInfo& tool() const;
  /// The one arm tool of `kind`; throws ModelError listing the end-effectors with kinds.
  [[nodiscard]] const EndEffectorInfo& tool(EndEffectorKind kind) const;

  [[nodiscard]] const std::vector<SensorFrame>& sensor_frames() const {
    return description_.sensor_frames;
  }
  /// Sensor frames of a kind, in model order (may be empty).
  [[nodiscard]] std::vector<const SensorFrame*> sensor_frames(SensorKind kind) const;
  /// The sensor of `kind` on end-effector `ee`, or nullptr.
  [[nodiscard]] const SensorFrame* sensor_of(const EndEffectorInfo& ee, SensorKind kind) const;
  /// The sensor of `kind` on end-effector `ee`; throws ModelError naming what the
  /// end-effector carries.
  [[nodiscard]] const SensorFrame& sensor(const EndEffectorInfo& ee, SensorKind kind) const;

 private:
  RobotModel(ModelDescription description, kinematics::Model fixed, kinematics::Model planar);

  ModelDescription description_;
  kinematics::Model fixed_;
  kinematics::Model planar_;
  std::vector<Link> links_;
  std::vector<std::pair<int, int>> disabled_;
  std::map<std::string, double> home_;
  LimitsTable limits_;
};

}  // namespace concert::model
