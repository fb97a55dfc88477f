#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace concert::kinematics {

/// Any problem building or querying a model (bad URDF, unknown frame, wrong vector size).
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Limits of one joint as written in the URDF (`<limit>`); virtual base joints are unlimited.
struct JointLimits {
  bool has_position_limits{false};  ///< false for continuous joints and virtual base joints
  double lower{0.0};                ///< [rad] or [m]
  double upper{0.0};                ///< [rad] or [m]
  double velocity{0.0};             ///< [rad/s] or [m/s]; 0 means "not given"
  double effort{0.0};               ///< [Nm] or [N]; 0 means "not given"
};

/// Kind of a movable joint.
enum class JointType { kRevolute, kContinuous, kPrismatic };

/// Options for building a model.
struct ModelOptions {
  /// Put three virtual joints (x, y, yaw: prismatic x, prismatic y, revolute z) between the
  /// world and the URDF root link: a planar mobile base. They come first in the joint order.
  bool planar_base{false};
  std::string virtual_x_joint{"base_x"};
  std::string virtual_y_joint{"base_y"};
  std::string virtual_yaw_joint{"base_yaw"};
  /// Gravity in the world frame [m/s^2].
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
};

class Data;

/// Options of Model::inverse_kinematics.
struct IkOptions {
  int max_iterations{200};
  double position_tolerance{1e-6};     ///< [m]
  double orientation_tolerance{1e-6};  ///< [rad]
  double damping{1e-3};                ///< damped least squares lambda [-]
  double max_step{0.2};                ///< largest joint change per iteration [rad] or [m]
  bool position_only{false};           ///< ignore the orientation
  /// Joints the solver may move (indices in q); empty: every joint moving the frame
  /// (virtual planar-base joints included).
  std::vector<int> joints;
};

/// Outcome of Model::inverse_kinematics.
struct IkResult {
  Eigen::VectorXd q;            ///< best joint positions found (within position limits)
  bool converged{false};
  int iterations{0};
  double position_error{0.0};     ///< [m]
  double orientation_error{0.0};  ///< [rad]
};

/// Immutable kinematic/dynamic model of a robot tree, built from URDF through orocos-kdl.
///
/// Joint order: virtual base joints (if any), then the URDF's movable joints in depth-first
/// order from the root (children in URDF order). Fixed joints are not in the joint vector;
/// every URDF link is a frame. All computations take a per-thread `Data` (scratch space)
/// created by `make_data()`; the model itself is never modified, so one model can be
/// shared by many threads, each with its own Data.
class Model {
 public:
  /// Parses `urdf_xml`; throws ModelError naming what is wrong (parse error, floating or
  /// planar URDF joints, mimic joints, zero-mass tree...).
  static Model from_urdf_string(const std::string& urdf_xml, const ModelOptions& options = {});
  /// Reads and parses a URDF file; throws ModelError naming the file on failure.
  static Model from_urdf_file(const std::string& path, const ModelOptions& options = {});

  /// Robot name from the URDF.
  [[nodiscard]] const std::string& name() const;
  /// Number of movable joints (including virtual base joints) = size of q.
  [[nodiscard]] int dof() const;
  [[nodiscard]] const std::vector<std::string>& joint_names() const;
  [[nodiscard]] const std::vector<JointLimits>& joint_limits() const;
  [[nodiscard]] const std::vector<JointType>& joint_types() const;
  /// Index of a joint in q, or nullopt.
  [[nodiscard]] std::optional<int> joint_index(std::string_view joint) const;
  /// Index of a joint in q; throws ModelError listing known joints if absent.
  [[nodiscard]] int joint_index_or_throw(std::string_view joint) const;
  /// True for the three virtual planar-base joints.
  [[nodiscard]] bool is_virtual_joint(int index) const;
  /// Names of the virtual joints first (may be empty).
  [[nodiscard]] int num_virtual_joints() const;
  /// Every link of the URDF (= every frame that can be queried), plus "world".
  [[nodiscard]] const std::vector<std::string>& frame_names() const;
  [[nodiscard]] bool has_frame(std::string_view frame) const;
  /// Name of the URDF root link.
  [[nodiscard]] const std::string& root_link() const;
  /// Parent link and child link of a movable joint.
  [[nodiscard]] const std::string& joint_parent_link(int index) const;
  [[nodiscard]] const std::string& joint_child_link(int index) const;
  /// Joint axis in the joint's child-link frame (unit vector).
  [[nodiscard]] const Eigen::Vector3d& joint_axis(int index) const;
  /// Links whose pose depends on joint `index` (the joint's child subtree).
  [[nodiscard]] std::vector<std::string> subtree_links(int index) const;
  /// Movable joints below `index` in the tree (not including it).
  [[nodiscard]] std::vector<int> descendant_joints(int index) const;
  /// Total mass of all links [kg].
  [[nodiscard]] double total_mass() const;
  [[nodiscard]] const Eigen::Vector3d& gravity() const;
  /// The URDF text the model was built from.
  [[nodiscard]] const std::string& urdf() const;

  /// Fresh scratch data for this model (one per thread).
  [[nodiscard]] Data make_data() const;

  /// Pose of `frame` in the world frame for joint positions `q` (size dof()).
  [[nodiscard]] Eigen::Isometry3d frame_pose(Data& data, const Eigen::VectorXd& q,
                                             std::string_view frame) const;
  /// Pose of `frame` relative to `reference` frame.
  [[nodiscard]] Eigen::Isometry3d relative_pose(Data& data, const Eigen::VectorXd& q,
                                                std::string_view reference,
                                                std::string_view frame) const;
  /// Geometric Jacobian (6 x dof) of `frame`'s origin: rows [linear; angular], expressed
  /// in world-aligned axes, so that [v; w] = J * qdot with v [m/s] of the frame origin.
  [[nodiscard]] Eigen::MatrixXd frame_jacobian(Data& data, const Eigen::VectorXd& q,
                                               std::string_view frame) const;
  /// Gravity torques g(q) [Nm / N] (size dof()): the torques that hold the robot still.
  [[nodiscard]] Eigen::VectorXd gravity_torques(Data& data, const Eigen::VectorXd& q) const;
  /// Inverse dynamics by recursive Newton-Euler: tau = M(q) qdd + C(q, qd) qd + g(q) - sum J_i^T f_i.
  /// `external_wrenches` maps a frame to the wrench [fx fy fz tx ty tz] applied ON the robot
  /// at that frame's origin, expressed in world-aligned axes [N, Nm].
  [[nodiscard]] Eigen::VectorXd inverse_dynamics(
      Data& data, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
      const std::map<std::string, Eigen::Matrix<double, 6, 1>>& external_wrenches = {}) const;
  /// Pose of `frame` reaching `target` (world frame) from `seed`, by damped least squares on
  /// the frame Jacobian with position limits respected. Never throws for unreachable
  /// targets: check IkResult::converged.
  [[nodiscard]] IkResult inverse_kinematics(Data& data, std::string_view frame, const Eigen::Isometry3d& target,
                                            const Eigen::VectorXd& seed, const IkOptions& options = {}) const;
  /// Real-time variants for control loops: no allocation and no checks (q, qd, qdd of size
  /// dof(), `out` already sized: 6 x dof for the Jacobian, dof for torques; `frame` must be a
  /// frame of the model). Same results as frame_pose(), frame_jacobian(), inverse_dynamics()
  /// without external wrenches.
  void frame_pose_into(Data& data, const Eigen::VectorXd& q, const std::string& frame, Eigen::Isometry3d& out) const;
  void frame_jacobian_into(Data& data, const Eigen::VectorXd& q, const std::string& frame, Eigen::MatrixXd& out) const;
  void inverse_dynamics_into(Data& data, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                             const Eigen::VectorXd& qdd, Eigen::VectorXd& out) const;
  /// Joint-space inertia matrix M(q) (dof x dof) [kg m^2], from dof RNE passes.
  [[nodiscard]] Eigen::MatrixXd mass_matrix(Data& data, const Eigen::VectorXd& q) const;

  struct Impl;

 private:
  explicit Model(std::shared_ptr<const Impl> impl);
  std::shared_ptr<const Impl> impl_;
  friend class Data;
};

/// Per-thread scratch data of a Model (KDL solvers and work arrays). Not thread-safe; cheap
/// to create. Keeps the model's internals alive, so it may outlive the Model object.
class Data {
 public:
  Data(Data&&) noexcept;
  Data& operator=(Data&&) noexcept;
  Data(const Data&) = delete;
  Data& operator=(const Data&) = delete;
  ~Data();

  struct Impl;

 private:
  explicit Data(std::shared_ptr<const Model::Impl> model);
  std::unique_ptr<Impl> impl_;
  friend class Model;
};

}  // namespace concert::kinematics
