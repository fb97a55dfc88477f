#pragma once
// The goal-posture problem of the planner (paper section 5.4.2, NSPG) as residuals over the
// planned joints (base x, y, yaw + arm), and its solver. Internal to concert_planner_core:
// nspg.cpp solves it for goal postures, planner.cpp uses its inequality part (torque, self
// collision, floor, obstacles) to pull RRT-Connect's samples into the feasible set.
//
// Rows: the camera task (position, optical axis) as equalities, and hinge residuals for the
// inequalities: torque limits (gravity + drilling force, and gravity alone), clearance from
// the drilled surface, from the floor, between the robot's own links (inscribed spheres and
// corner points against the other link's exact primitives) and from the map (signed distance
// field). The exact checker (StateChecker: FCL, OctoMap, torques) still judges every result;
// the smooth terms only lead the solver to where it will pass.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "planner/environment.hpp"
#include "planner/planning_model.hpp"

namespace concert::planner::detail {

// Weight of the task rows (the solver's tolerance on them is kTaskWeight x tolerance).
constexpr double kTaskWeight = 10.0;

struct Task {
  Eigen::Vector3d position;  // camera target [m] (a view: where seeds place the camera)
  Eigen::Vector3d axis;      // camera z target (unit)
  Eigen::Vector3d surface;   // a point of the drilled surface [m]
  Eigen::Vector3d normal;    // its outward normal (unit)
  // A view (Params::view_slant): the camera's axis through `surface` from `near` to `far` away,
  // within the slant whose cosine is `cos_slant`; position and axis then only seed the solver.
  bool view = false;
  double near = 0.0;
  double far = 0.0;
  double cos_slant = 1.0;
};

inline Task make_task(const Params& params, const Eigen::Isometry3d& area) {
  const Eigen::Vector3d n = area.linear().col(2).normalized();
  Task task{area.translation() + params.camera_distance * n, -n, area.translation(), n};
  if (params.view_slant > 0.0 && !params.tip_task) {
    task.view = true;
    task.near = params.view_near;
    task.far = params.camera_distance;
    task.cos_slant = std::cos(params.view_slant);
    task.position = area.translation() + 0.5 * (task.near + task.far) * n;
  }
  return task;
}

// The task's residuals (6, unweighted) of a camera pose: position and axis, or for a view the
// distance below near and beyond far, the cosine short of the slant's, and the axis off the
// line to the centre.
inline Eigen::Matrix<double, 6, 1> task_residual(const Task& task, const Eigen::Isometry3d& camera) {
  Eigen::Matrix<double, 6, 1> r;
  const Eigen::Vector3d a = camera.linear().col(2);
  if (!task.view) {
    r.head<3>() = camera.translation() - task.position;
    // The axis as a difference, not a cross product: a cross product is zero for the camera
    // looking away from the wall too, and the solver can converge there (a hole posture on the
    // demo robot would pass every check with the camera turned 180 deg from the hole).
    r.tail<3>() = a - task.axis;
    return r;
  }
  const Eigen::Vector3d to = task.surface - camera.translation();
  const double d = to.norm();
  const Eigen::Vector3d u = d > 1e-9 ? Eigen::Vector3d(to / d) : task.axis;
  r[0] = std::max(0.0, task.near - d);
  r[1] = std::max(0.0, d - task.far);
  r[2] = std::max(0.0, task.cos_slant - (-u).dot(task.normal));
  r.tail<3>() = a - u;
  return r;
}

// A sphere of a link's smooth stand-in for its collision primitives (self collision and
// obstacle terms: distances to spheres are differentiable, FCL's boolean answer is not).
struct Sphere {
  Eigen::Vector3d centre;  // in the link frame
  double radius = 0.0;
};

enum class Term { kTask, kTorque, kSurface, kFloor, kSelf, kObstacle };
// Residual vector of the posture problem over the planned joints.
class PostureProblem {
 public:
  // `tool` and `task` may be absent together (path sampling: no task, no contact force).
  PostureProblem(const PlanningModel& model, const Params& params, const EndEffectorInfo* tool,
                 const Eigen::VectorXd& full_template, std::optional<Task> task, std::shared_ptr<const DistanceField> field);

  [[nodiscard]] int size() const { return size_; }
  /// Fraction of the contact force in the "drilling" torque rows (0: both rows gravity only,
  /// as for states on a path).
  void set_force_scale(double scale) { force_scale_ = scale; }
  /// Torque utilisation (fraction of Params::torque_margin x continuous torque) the torque rows
  /// pull the joints under, capped at the mode's limit (0.97; 0.9 for a drilling posture whose
  /// reach is checked, the bit then going on into the wall).
  void set_torque_target(double target) { torque_target_ = target; }
  [[nodiscard]] double limit_torque_target() const;
  /// What a goal posture aims under first: a posture is where the arm waits (an area's approach
  /// at 0.89 of the demo robot's J2_E continuous torque holds it there for the 17 s the drill
  /// takes to ask for its holes' postures) and whence the arm alone must still reach the holes
  /// at a fraction of that load (from such an approach it reaches none). generate_posture()
  /// solves a seed again with the limit when the torques alone kept it off the task.
  static constexpr double kPreferredTorqueTarget = 0.8;

  // The planned q for arm joints `arm`: the base is placed where that arm posture reaches the
  // task (yaw turns the camera axis onto the task axis about the vertical, x/y then bring the
  // camera onto the target; yaw stays `yaw_hint` when either axis is vertical). Leaves the
  // world link poses in poses_.
  Eigen::VectorXd place(const Eigen::VectorXd& arm, double yaw_hint);

  // Residuals at planned q.
  void evaluate(const Eigen::VectorXd& q, Eigen::VectorXd& r);

  /// Which term a residual row belongs to.
  [[nodiscard]] Term term_of_row(int row) const;

 private:
  const PlanningModel& model_;
  const Params& params_;
  int tool_ = -1;
  Eigen::VectorXd template_;
  std::optional<Task> task_;  // none: only the inequalities (path sampling)
  int camera_ = -1;
  int arm_joints_ = 0;
  int size_ = 0;
  double clearance_ = 0.0;
  std::vector<std::pair<int, const LinkShape*>> surface_shapes_;
  std::vector<std::pair<int, const LinkShape*>> floor_shapes_;
  std::vector<std::pair<int, Sphere>> spheres_;
  struct LinkPair {
    int a, b;
    std::vector<int> spheres_a, spheres_b;
  };
  std::vector<LinkPair> self_pairs_;
  std::vector<Sphere> bounds_;  // per link, in the link frame
  std::vector<std::pair<int, std::vector<int>>> obstacle_links_;
  std::shared_ptr<const DistanceField> field_;
  double obstacle_clearance_ = 0.0;
  double force_scale_ = 1.0;
  double torque_target_ = 1.0;  // capped at limit_torque_target()
  Eigen::VectorXd tau_;
  std::vector<Eigen::Isometry3d> poses_;
  std::vector<Eigen::Vector3d> world_spheres_;
};

// Two-priority Gauss-Newton with Levenberg-Marquardt damping and a forward-difference
// Jacobian, steps clamped to [lo, hi]: each step first reduces the task error (damped
// pseudo-inverse of the task Jacobian), then the inequality residuals within the task's null
// space, so the inequalities never trade off against the task (the NSPG's null-space motion).
// Leaves the final residual vector in `r`.
void solve(PostureProblem& problem, Eigen::VectorXd& q, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, int iterations,
           double tolerance, Eigen::VectorXd& r);

}  // namespace concert::planner::detail
