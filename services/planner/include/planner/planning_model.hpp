#pragma once
// The planner's view of one robot model version, built on the parsed model of libs/model:
// whole-body configuration space (planar base x, y, yaw + the arm joints), link geometry for
// FCL, SRDF-disabled pairs, limits (with the limits rule: static torques within the continuous
// torque). Immutable once built (Model/Data split: per-thread state lives in StateChecker).

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "concert/kinematics/model.hpp"
#include "concert/model/robot_model.hpp"
#include "planner/types.hpp"

namespace concert::planner {

/// A collision primitive of a link, in the link frame.
struct LinkShape {
  enum class Type { kBox, kCylinder, kSphere };
  Type type = Type::kBox;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: full extents; cylinder: (r, r, length); sphere: (r, r, r) [m]
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
};

/// A link of the URDF tree in topological order (parents first).
struct LinkNode {
  std::string name;
  int parent = -1;                  ///< index in PlanningModel::links(); -1 for the root
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< parent_T_joint at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< joint axis in the joint frame
  int full_index = -1;              ///< index of the joint in the full q; -1: fixed joint
  bool prismatic = false;
  std::vector<LinkShape> shapes;    ///< collision primitives
  bool leg = false;                 ///< belongs to a leg chain (touches the floor)
  int rigid_group = -1;             ///< link of the nearest planned arm joint at or above it (-1: base group; collision::rigid_groups)
  double mass = 0.0;                ///< URDF inertial mass [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();  ///< centre of mass in the link frame [m]
};

/// One model version, ready for planning. Build with PlanningModel::build.
class PlanningModel {
 public:
  /// Builds from a parsed model. Throws PlannerError naming what is wrong (no arm chain; mesh
  /// collision shapes are reported in ignored_shapes()).
  static std::shared_ptr<const PlanningModel> build(std::shared_ptr<const model::RobotModel> robot, const Params& params);
  /// Parses `description` (model::RobotModel::build) and builds from it; model errors (URDF
  /// parse error, joint listed but absent from the URDF...) become PlannerError.
  static std::shared_ptr<const PlanningModel> build(const ModelDescription& description, const Params& params);

  [[nodiscard]] uint64_t version() const { return robot_->version(); }
  [[nodiscard]] const ModelDescription& description() const { return robot_->description(); }
  /// The parsed model it was built on.
  [[nodiscard]] const model::RobotModel& robot() const { return *robot_; }
  /// orocos-kdl model with a planar base (base_x, base_y, base_yaw first).
  [[nodiscard]] const kinematics::Model& kinematics() const { return kinematics_; }
  /// Size of the full joint vector (kinematics().dof()).
  [[nodiscard]] int full_dof() const { return kinematics_.dof(); }
  /// Planned joints: base_x, base_y, base_yaw, then the arm joints (chains of role "arm").
  [[nodiscard]] int dof() const { return static_cast<int>(planned_.size()); }
  [[nodiscard]] const std::vector<std::string>& joint_names() const { return planned_names_; }
  /// Index in the full q of each planned joint.
  [[nodiscard]] const std::vector<int>& planned_indices() const { return planned_; }
  /// Position limits of the planned joints (base: +-infinity) [m, rad].
  [[nodiscard]] const Eigen::VectorXd& lower() const { return lower_; }
  [[nodiscard]] const Eigen::VectorXd& upper() const { return upper_; }
  /// Velocity limits of the planned joints [m/s, rad/s] (base from Params).
  [[nodiscard]] const Eigen::VectorXd& velocity_limits() const { return velocity_; }
  /// Torque limit of the static load per full joint [N m]: the continuous torque
  /// (model::planning_torque_limit); 0: not limited (virtual, legs).
  [[nodiscard]] const Eigen::VectorXd& torque_limits() const { return torque_; }
  /// World z of the base link [m].
  [[nodiscard]] double base_height() const { return base_height_; }
  [[nodiscard]] const std::vector<LinkNode>& links() const { return links_; }
  /// Pairs of link indices never checked against each other (SRDF or rigidly attached).
  [[nodiscard]] bool pair_disabled(int a, int b) const;
  /// Collision elements the model has but the planner ignores (meshes), as "link: reason".
  [[nodiscard]] const std::vector<std::string>& ignored_shapes() const { return ignored_; }
  /// Collision primitives the planner adds to the model's (by link index): each drill's bit
  /// (Params::drill_bit_radius). Also in links()' shapes.
  [[nodiscard]] const std::map<int, std::vector<model::CollisionShape>>& added_shapes() const { return added_; }

  /// The tool end-effector: `name`, or the arm's tool (model::RobotModel::tool) when empty;
  /// throws PlannerError listing the candidates.
  [[nodiscard]] const EndEffectorInfo& tool(const std::string& name) const;
  /// Frame of the camera sensor on a tool; throws PlannerError naming what the tool carries.
  [[nodiscard]] std::string camera_frame(const EndEffectorInfo& tool) const;
  /// Frame the posture task places: the tool's TCP frame when `tip`, else its camera frame.
  [[nodiscard]] std::string task_frame(const EndEffectorInfo& tool, bool tip) const {
    return tip ? tool.frame : camera_frame(tool);
  }

  /// World pose of every link (links() order) for a full q [m, rad].
  void link_poses(const Eigen::VectorXd& q_full, std::vector<Eigen::Isometry3d>& poses) const;
  /// World pose of one link (with the base height).
  [[nodiscard]] Eigen::Isometry3d link_pose(const Eigen::VectorXd& q_full, const std::string& link) const;
  /// Joint torques [N m] (full q order; forces [N] for prismatic joints) that hold the robot
  /// still at the link poses `poses` (from link_poses) against gravity and, when `contact_link`
  /// >= 0, against `force` [N, world frame] that the environment applies at that link's origin:
  /// tau_j = -a_j . sum (r x f) over the external forces beyond joint j; 0 for the virtual base
  /// joints (the floor holds the base). One pass over the link
  /// tree, no allocation besides `tau` (the planner evaluates it thousands of times per goal;
  /// equal to KDL's RNE with zero velocities, see StaticTorquesAgreeWithKdl).
  void static_torques(const std::vector<Eigen::Isometry3d>& poses, int contact_link, const Eigen::Vector3d& force,
                      Eigen::VectorXd& tau) const;
  /// Index of a link in links(), or -1.
  [[nodiscard]] int link_index(const std::string& name) const;

  /// The mirror image of an arm posture (planned arm joints, base excluded) about the
  /// vertical plane through the arm's first joint, or none: when the model's arm has an
  /// oblique joint axis, or the image leaves the joint limits. Exact for modules whose
  /// offsets lie in that plane, approximate otherwise (a seed: results are always checked);
  /// mirrored_arm(mirrored_arm(a)) == a.
  [[nodiscard]] std::optional<Eigen::VectorXd> mirrored_arm(const Eigen::VectorXd& arm) const;

  /// Full q from planned q, other joints from `full_template`.
  [[nodiscard]] Eigen::VectorXd to_full(const Eigen::VectorXd& planned, const Eigen::VectorXd& full_template) const;
  /// Planned part of a full q.
  [[nodiscard]] Eigen::VectorXd to_planned(const Eigen::VectorXd& full) const;
  /// Full q from joint names and positions (missing joints 0; unknown names are errors) and a
  /// base pose (x, y, yaw).
  [[nodiscard]] Eigen::VectorXd full_from_named(const std::vector<std::string>& names, const std::vector<double>& positions,
                                                const Eigen::Vector3d& base) const;

 private:
  explicit PlanningModel(kinematics::Model kinematics) : kinematics_(std::move(kinematics)) {}

  std::shared_ptr<const model::RobotModel> robot_;
  kinematics::Model kinematics_;
  std::vector<int> planned_;
  std::vector<std::string> planned_names_;
  Eigen::VectorXd lower_, upper_, velocity_, torque_;
  double base_height_ = 0.0;
  std::map<int, std::vector<model::CollisionShape>> added_;
  void add_drill_bits(double radius);
  std::vector<LinkNode> links_;
  Eigen::Vector3d gravity_ = Eigen::Vector3d(0.0, 0.0, -9.81);
  std::vector<std::vector<bool>> disabled_;
  std::vector<std::string> ignored_;
  std::optional<Eigen::VectorXd> arm_mirror_;  // per arm joint: +1 or -1 (see mirrored_arm)
};

}  // namespace concert::planner
