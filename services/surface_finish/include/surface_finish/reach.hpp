#pragma once
// Where the arm of one model version can hold its finishing tool against a wall without moving
// the base: inverse kinematics of the tool's TCP (libs/model + libs/kinematics, orocos-kdl),
// self-collision (FCL on the links' collision primitives, the SRDF's disabled pairs and links
// moved by the same joint skipped), distance from singularities (the smallest singular value
// of the arm's Jacobian) and joint continuity between neighbouring poses. No DDS.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "concert/model/robot_model.hpp"
#include "surface_finish/types.hpp"

namespace concert::surface_finish {

/// Limits of an acceptable pose.
struct ReachParams {
  double position_tolerance{1e-3};     ///< IK position error accepted [m]
  double orientation_tolerance{5e-3};  ///< IK orientation error accepted [rad]
  /// Smallest singular value of the arm's 6 x n TCP Jacobian (rows m/rad and rad/rad) below
  /// which a pose counts as near-singular [-].
  double min_singular_value{0.05};
  /// Largest change of any arm joint between neighbouring poses (grid cells 5 cm apart, path
  /// samples 1 cm apart) before the motion counts as discontinuous [rad].
  double max_joint_step{0.35};
  /// Joints kept this far inside their position limits [rad].
  double limit_margin{0.02};
  /// An optional side wall: a vertical plane at lateral wall coordinate side_wall_x [m] (x < 0:
  /// on the left, > 0: on the right); every link origin and the tool keep side_clearance [m]
  /// from it. NaN: none.
  double side_wall_x{std::numeric_limits<double>::quiet_NaN()};
  double side_clearance{0.15};
  /// Static torques (gravity, plus the contact force pushing back along the TCP's -z) of every
  /// arm joint stay within this fraction of its continuous torque (libs/model's planning limit:
  /// the robot can hold the posture indefinitely, and safety's thermal-window check never trips
  /// on a slow serpentine) [-].
  double torque_margin{1.0};
  double contact_force{0.0};  ///< [N]: the sanding force; 0 for spraying
  /// IK restarts from seeded random postures when the given seed does not converge.
  int restarts{6};
  unsigned seed{7};
};

/// One solved pose, or why there is none.
struct ReachPose {
  bool ok{false};
  Eigen::VectorXd q;   ///< fixed-base q (every joint of the model; only the arm's move)
  std::string reason;  ///< empty when ok: "IK 12 mm short", "self collision: link_3 / base", ...
};

/// The tool of one model version in front of a wall. Not thread-safe (holds scratch data).
class Reach {
 public:
  /// The arm's tool of `kind` (kSpraying or kSanding). Throws FinishError naming what the arm
  /// carries when it has no such tool.
  Reach(std::shared_ptr<const model::RobotModel> model, model::EndEffectorKind kind, ReachParams params = {});
  ~Reach();
  Reach(const Reach&) = delete;
  Reach& operator=(const Reach&) = delete;

  [[nodiscard]] const model::RobotModel& model() const { return *model_; }
  [[nodiscard]] const std::shared_ptr<const model::RobotModel>& model_ptr() const { return model_; }
  [[nodiscard]] const ReachParams& params() const { return params_; }
  [[nodiscard]] const std::string& tool_name() const { return tool_; }
  [[nodiscard]] const std::string& tcp_frame() const { return tcp_; }
  /// Indices of the arm's joints in the fixed-base q, root to tip.
  [[nodiscard]] const std::vector<int>& arm_joints() const { return arm_; }
  /// Height of the base origin above the floor when it stands on its wheels [m].
  [[nodiscard]] double standing_height() const { return standing_height_; }
  /// Links with collision primitives (and the mesh shapes left out, as "link: mesh").
  [[nodiscard]] const std::vector<std::string>& ignored_shapes() const { return ignored_; }

  /// The TCP target on `wall` at (x, y) and `standoff` [m], its z into the wall and its x
  /// turned `roll` [rad] from the wall's y (up) about the normal.
  [[nodiscard]] static Eigen::Isometry3d target(const WallFrame& wall, double x, double y, double standoff,
                                                double roll);

  /// Solves the arm for `tcp` from `seed` (restarts from seeded random postures if
  /// `restarts`), then checks limits, singularity, self-collision, the side wall and, when
  /// `previous` is given, continuity with it.
  [[nodiscard]] ReachPose solve(const Eigen::Isometry3d& tcp, const WallFrame& wall, const Eigen::VectorXd& seed,
                                const Eigen::VectorXd* previous = nullptr, bool restarts = false);

  /// First self-collision of q as "link_a / link_b", or nullopt.
  [[nodiscard]] std::optional<std::string> self_collision(const Eigen::VectorXd& q);
  /// How far the arm's collision primitives (the tool's among them) keep from the plane of
  /// `wall` at q [m], negative when one reaches through it; the link of the nearest one in
  /// `nearest` (when given). A tilted tool's rim is nearer the wall than its TCP. +inf when the
  /// arm has no primitive (mesh shapes are not counted: ignored_shapes()).
  [[nodiscard]] double wall_clearance(const Eigen::VectorXd& q, const WallFrame& wall, std::string* nearest = nullptr);
  /// Smallest singular value of the arm's TCP Jacobian at q.
  [[nodiscard]] double singular_value(const Eigen::VectorXd& q);
  /// TCP pose in the base frame.
  [[nodiscard]] Eigen::Isometry3d tcp_pose(const Eigen::VectorXd& q);
  /// A neutral starting posture: every arm joint at the middle of its limits clamped to +-0.5 rad
  /// (the zero posture where limits allow).
  [[nodiscard]] Eigen::VectorXd neutral() const;

  struct Impl;

 private:
  std::shared_ptr<const model::RobotModel> model_;
  ReachParams params_;
  std::string tool_, tcp_;
  std::vector<int> arm_;
  double standing_height_{0.0};
  std::vector<std::string> ignored_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::surface_finish
