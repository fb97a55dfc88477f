// Null-Space Posture Generator (Rossini et al. 2021, paper section 5.4.2).

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "planner/planner.hpp"

namespace concert::planner {
namespace {

constexpr double kDamping = 1e-2;
constexpr double kMaxStep = 0.2;  // [rad or m] per iteration

struct Task {
  Eigen::Vector3d position;  // camera target [m]
  Eigen::Vector3d axis;      // camera z target (unit)
};

class TaskSolver {
 public:
  TaskSolver(const PlanningModel& model, const Params& params, std::string camera, const Eigen::VectorXd& full_template,
             Eigen::VectorXd lo, Eigen::VectorXd hi)
      : model_(model),
        params_(params),
        camera_(std::move(camera)),
        template_(full_template),
        data_(model.kinematics().make_data()),
        lo_(std::move(lo)),
        hi_(std::move(hi)) {
    // Moving the base costs more than moving the arm, so postures stay near the start base.
    weights_ = Eigen::VectorXd::Ones(model.dof());
    weights_.head<3>() << 0.2, 0.2, 0.2;
  }

  // Task error (6: position, axis cross product) and task Jacobian over the planned joints.
  void evaluate(const Eigen::VectorXd& q, const Task& task, Eigen::Matrix<double, 6, 1>& error, Eigen::MatrixXd& jac) {
    const Eigen::VectorXd full = model_.to_full(q, template_);
    const Eigen::Isometry3d pose = model_.link_pose(full, camera_);
    const Eigen::Vector3d z = pose.linear().col(2);
    error.head<3>() = task.position - pose.translation();
    error.tail<3>() = z.cross(task.axis);
    const Eigen::MatrixXd j_full = model_.kinematics().frame_jacobian(data_, full, camera_);
    jac.resize(6, model_.dof());
    const auto& idx = model_.planned_indices();
    const Eigen::Matrix3d proj = Eigen::Matrix3d::Identity() - z * z.transpose();
    for (std::size_t i = 0; i < idx.size(); ++i) {
      jac.col(static_cast<Eigen::Index>(i)).head<3>() = j_full.col(idx[i]).head<3>();
      jac.col(static_cast<Eigen::Index>(i)).tail<3>() = proj * j_full.col(idx[i]).tail<3>();
    }
  }

  // Weighted damped least squares onto the task; true when within tolerance.
  bool converge(Eigen::VectorXd& q, const Task& task, int iterations) {
    Eigen::Matrix<double, 6, 1> e;
    Eigen::MatrixXd j;
    for (int it = 0; it < iterations; ++it) {
      evaluate(q, task, e, j);
      if (e.head<3>().norm() < params_.nspg_tolerance && e.tail<3>().norm() < params_.nspg_tolerance) return true;
      const Eigen::MatrixXd jw = j * weights_.asDiagonal();
      const Eigen::Matrix<double, 6, 6> a = jw * j.transpose() + kDamping * kDamping * Eigen::Matrix<double, 6, 6>::Identity();
      Eigen::VectorXd dq = weights_.asDiagonal() * (j.transpose() * a.ldlt().solve(e));
      const double big = dq.cwiseAbs().maxCoeff();
      if (big > kMaxStep) dq *= kMaxStep / big;
      q = (q + dq).cwiseMax(lo_).cwiseMin(hi_);
    }
    evaluate(q, task, e, j);
    return e.head<3>().norm() < params_.nspg_tolerance && e.tail<3>().norm() < params_.nspg_tolerance;
  }

  // A random step in the null space of the task Jacobian at q.
  Eigen::VectorXd null_step(const Eigen::VectorXd& q, const Task& task, const Eigen::VectorXd& random) {
    Eigen::Matrix<double, 6, 1> e;
    Eigen::MatrixXd j;
    evaluate(q, task, e, j);
    const Eigen::MatrixXd pinv = j.completeOrthogonalDecomposition().pseudoInverse();
    const Eigen::MatrixXd n = Eigen::MatrixXd::Identity(model_.dof(), model_.dof()) - pinv * j;
    return n * random;
  }

  // Secondary task: torque utilisation sum((tau_i / limit_i)^2) over the arm joints, with the
  // contact force on the tool.
  double torque_cost(const Eigen::VectorXd& q, StateChecker& checker, const std::string& tool_frame) {
    const Eigen::VectorXd full = model_.to_full(q, template_);
    const Eigen::VectorXd tau = checker.required_torques(full, tool_frame);
    const auto& idx = model_.planned_indices();
    double c = 0.0;
    for (std::size_t i = 3; i < idx.size(); ++i) {
      const double lim = model_.torque_limits()[idx[i]];
      if (lim > 0.0) c += (tau[idx[i]] / lim) * (tau[idx[i]] / lim);
    }
    return c;
  }

  // Descends the torque cost in the null space of the task, staying on the task.
  void relieve_torques(Eigen::VectorXd& q, const Task& task, StateChecker& checker, const std::string& tool_frame, int iterations) {
    Eigen::Matrix<double, 6, 1> e;
    Eigen::MatrixXd j;
    double c = torque_cost(q, checker, tool_frame);
    for (int it = 0; it < iterations; ++it) {
      Eigen::VectorXd grad(q.size());
      for (Eigen::Index i = 0; i < q.size(); ++i) {
        Eigen::VectorXd qi = q;
        qi[i] += 1e-4;
        grad[i] = (torque_cost(qi, checker, tool_frame) - c) / 1e-4;
      }
      evaluate(q, task, e, j);
      const Eigen::MatrixXd pinv = j.completeOrthogonalDecomposition().pseudoInverse();
      Eigen::VectorXd step = -(Eigen::MatrixXd::Identity(q.size(), q.size()) - pinv * j) * grad;
      const double big = step.cwiseAbs().maxCoeff();
      if (big < 1e-6) return;
      bool improved = false;
      for (double len = 0.2; len > 0.02; len *= 0.4) {
        Eigen::VectorXd trial = (q + step * (len / big)).cwiseMax(lo_).cwiseMin(hi_);
        if (!converge(trial, task, 20)) continue;
        const double ct = torque_cost(trial, checker, tool_frame);
        if (ct < c) {
          q = trial;
          c = ct;
          improved = true;
          break;
        }
      }
      if (!improved) return;
    }
  }

  // Yoshikawa manipulability of the arm joints for the camera frame.
  double manipulability(const Eigen::VectorXd& q) {
    const Eigen::VectorXd full = model_.to_full(q, template_);
    const Eigen::MatrixXd j_full = model_.kinematics().frame_jacobian(data_, full, camera_);
    const auto& idx = model_.planned_indices();
    Eigen::MatrixXd j(6, static_cast<Eigen::Index>(idx.size()) - 3);
    for (std::size_t i = 3; i < idx.size(); ++i) j.col(static_cast<Eigen::Index>(i) - 3) = j_full.col(idx[i]);
    return std::sqrt(std::max(0.0, (j * j.transpose()).determinant()));
  }

 private:
  const PlanningModel& model_;
  const Params& params_;
  std::string camera_;
  Eigen::VectorXd template_;
  kinematics::Data data_;
  Eigen::VectorXd lo_, hi_;
  Eigen::VectorXd weights_;
};

Task make_task(const Params& params, const Eigen::Isometry3d& area) {
  const Eigen::Vector3d n = area.linear().col(2).normalized();
  return {area.translation() + params.camera_distance * n, -n};
}

}  // namespace

std::pair<double, double> task_error(const PlanningModel& model, const Params& params, const EndEffectorSpec& tool,
                                     const Eigen::VectorXd& q_full, const Eigen::Isometry3d& area) {
  const Task task = make_task(params, area);
  const Eigen::Isometry3d pose = model.link_pose(q_full, model.camera_frame(tool));
  const double angle = std::acos(std::clamp(pose.linear().col(2).dot(task.axis), -1.0, 1.0));
  return {(pose.translation() - task.position).norm(), angle};
}

PostureResult generate_posture(const PlanningModel& model, StateChecker& checker, const Params& params,
                               const EndEffectorSpec& tool, const Eigen::VectorXd& q_start_full, const Eigen::Isometry3d& area,
                               uint64_t seed) {
  const Task task = make_task(params, area);
  const int n = model.dof();
  const Eigen::VectorXd start = model.to_planned(q_start_full);
  Eigen::VectorXd lo = model.lower();
  Eigen::VectorXd hi = model.upper();
  lo.head<2>() = start.head<2>().array() - params.base_range;
  hi.head<2>() = start.head<2>().array() + params.base_range;
  // The target may lie farther than base_range: let the base reach it.
  lo.head<2>() = lo.head<2>().cwiseMin(task.position.head<2>() - Eigen::Vector2d::Constant(params.base_range));
  hi.head<2>() = hi.head<2>().cwiseMax(task.position.head<2>() + Eigen::Vector2d::Constant(params.base_range));
  lo[2] = start[2] - 2.0 * M_PI;
  hi[2] = start[2] + 2.0 * M_PI;
  TaskSolver solver(model, params, model.camera_frame(tool), q_start_full, lo, hi);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);

  PostureResult out;
  std::map<std::string, int> rejections;
  auto cost_of = [&](const Eigen::VectorXd& q) {
    Eigen::VectorXd d = q - start;
    return params.nspg_distance_weight * d.norm() + params.nspg_singularity_weight / (solver.manipulability(q) + 1e-3);
  };
  auto reject = [&](const Validity& v) {
    const std::string key = to_string(v.constraint);
    if (rejections[key]++ == 0 && out.reason.empty()) out.reason = key + ": " + v.detail;
  };
  std::vector<Eigen::VectorXd> on_task;  // converged postures
  int valid_found = 0;
  // Infeasible postures are ranked (collision worse than torque excess) so the null-space
  // walks climb from the least infeasible one.
  Eigen::VectorXd best_invalid;
  double best_invalid_score = std::numeric_limits<double>::infinity();
  auto score = [&](const Eigen::VectorXd& full, const Validity& v) {
    if (v.constraint != Constraint::kTorqueLimit) return 10.0;
    double excess = 0.0;
    const auto& idx = model.planned_indices();
    for (const std::string& frame : {tool.frame, std::string()}) {
      const Eigen::VectorXd tau = checker.required_torques(full, frame);
      for (std::size_t i = 3; i < idx.size(); ++i) {
        const double lim = params.torque_margin * model.torque_limits()[idx[i]];
        if (lim > 0.0) excess = std::max(excess, std::abs(tau[idx[i]]) / lim - 1.0);
      }
    }
    return excess;
  };
  // A posture on the task: lower its torques in the null space, then it must hold both while
  // approaching (gravity only) and while drilling (gravity + contact force on the tool).
  auto consider = [&](Eigen::VectorXd q) {
    out.candidates += 1;
    auto validity = [&](const Eigen::VectorXd& full) {
      Validity v = checker.check(full, tool.frame);
      return v.valid() ? checker.check(full) : v;
    };
    Validity v = validity(model.to_full(q, q_start_full));
    if (v.constraint == Constraint::kTorqueLimit) {
      // Only torque-limited postures are worth the (costly) null-space torque descent.
      solver.relieve_torques(q, task, checker, tool.frame, params.nspg_torque_iterations);
      v = validity(model.to_full(q, q_start_full));
    }
    on_task.push_back(q);
    const Eigen::VectorXd full = model.to_full(q, q_start_full);
    if (!v.valid()) {
      reject(v);
      const double sc = score(full, v);
      if (sc < best_invalid_score) {
        best_invalid_score = sc;
        best_invalid = q;
      }
      return;
    }
    valid_found += 1;
    const double c = cost_of(q);
    if (!out.found || c < out.cost) {
      out.found = true;
      out.cost = c;
      out.q = q;
    }
  };

  // Seeds from sampled arm postures: keep those whose camera axis and height already match
  // the task, place the base analytically (yaw aligns the axis, x/y the position) and rank
  // them by torque utilisation (with and without the contact force). Forward kinematics is
  // cheap, so thousands of arm postures cost a few milliseconds.
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const std::string camera = model.camera_frame(tool);
  auto screen = [&](int count) {
    std::vector<std::pair<double, Eigen::VectorXd>> ranked;
    const auto& idx = model.planned_indices();
    Eigen::VectorXd full = q_start_full;
    for (int k = 0; k < count; ++k) {
      Eigen::VectorXd q = start;
      q.head<3>().setZero();
      for (int i = 3; i < n; ++i) q[i] = lo[i] + (hi[i] - lo[i]) * unit(rng);
      full = model.to_full(q, q_start_full);
      const Eigen::Isometry3d cam = model.link_pose(full, camera);
      const Eigen::Vector3d a = cam.linear().col(2);
      if (std::abs(a.z() - task.axis.z()) > 0.25 || std::abs(cam.translation().z() - task.position.z()) > 0.25) continue;
      if (a.head<2>().norm() < 1e-3 || task.axis.head<2>().norm() < 1e-3) continue;
      const double yaw = std::atan2(task.axis.y(), task.axis.x()) - std::atan2(a.y(), a.x());
      const Eigen::Rotation2Dd rot(yaw);
      q[2] = start[2] + std::remainder(yaw - start[2], 2.0 * M_PI);
      q.head<2>() = task.position.head<2>() - rot * cam.translation().head<2>();
      full = model.to_full(q, q_start_full);
      double worst = 0.0;
      for (const std::string& frame : {tool.frame, std::string()}) {
        const Eigen::VectorXd tau = checker.required_torques(full, frame);
        for (std::size_t i = 3; i < idx.size(); ++i) {
          const double lim = model.torque_limits()[idx[i]];
          if (lim > 0.0) worst = std::max(worst, std::abs(tau[idx[i]]) / lim);
        }
      }
      if (worst >= 1.5) continue;
      const Constraint c = checker.check(full).constraint;
      if (c == Constraint::kNone || c == Constraint::kTorqueLimit) ranked.emplace_back(worst, q);
    }
    std::sort(ranked.begin(), ranked.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    return ranked;
  };
  const auto t0 = std::chrono::steady_clock::now();
  const auto out_of_time = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > params.nspg_time;
  };
  // In two rounds: a small screening first (easy goals end here, fast), the rest only when
  // it found nothing valid.
  for (const int round : {0, 1}) {
    if (valid_found > 0 || out_of_time()) break;
    const int count = round == 0 ? params.nspg_arm_samples / 8 : params.nspg_arm_samples - params.nspg_arm_samples / 8;
    const int tries = round == 0 ? std::max(1, params.nspg_ranked_seeds / 8) : params.nspg_ranked_seeds;
    const auto ranked = screen(count);
    for (std::size_t i = 0; i < ranked.size() && i < static_cast<std::size_t>(tries); ++i) {
      Eigen::VectorXd s = ranked[i].second;
      if (solver.converge(s, task, 60)) consider(s);
      if (valid_found >= params.nspg_enough || out_of_time()) break;
    }
  }

  // Seeds: the start posture; then the base facing the area with the arm mount at a few
  // stand-offs from the camera target, with the start arm and random arm postures.
  std::vector<Eigen::VectorXd> seeds{start};
  const Eigen::Vector2d n_xy = -task.axis.head<2>();
  if (n_xy.norm() > 1e-6) {
    const Eigen::Vector2d nrm = n_xy.normalized();
    const int first_arm = model.planned_indices()[3];
    Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.full_dof());
    const double mount = model.link_pose(zero, model.kinematics().joint_parent_link(first_arm)).translation().x();
    const double yaw = std::atan2(-nrm.y(), -nrm.x());
    // Facing the wall, and sideways: then the shoulder pitch axis lies along the normal and
    // the drilling force loads it least (its moment about a joint axis parallel to it is 0).
    for (int arm = 0; arm < params.nspg_arm_seeds; ++arm) {
      for (const double turn : {0.0, M_PI / 2, -M_PI / 2}) {
      for (double standoff : {0.7, 0.45, 0.95}) {
        Eigen::VectorXd s = start;
        const Eigen::Vector2d side(-nrm.y(), nrm.x());
        s.head<2>() = task.position.head<2>() + nrm * (standoff + (turn == 0.0 ? mount : 0.0)) + (turn == 0.0 ? 0.0 : (turn > 0 ? -mount : mount)) * side;
        s[2] = start[2] + std::remainder(yaw + turn - start[2], 2.0 * M_PI);
        if (arm > 0) {
          for (int i = 3; i < n; ++i) s[i] = lo[i] + (hi[i] - lo[i]) * (0.2 + 0.6 * unit(rng));
        }
        seeds.push_back(s);
      }
      }
    }
  }
  for (Eigen::VectorXd s : seeds) {
    if (valid_found >= params.nspg_enough || out_of_time()) break;
    if (solver.converge(s, task, 60)) consider(s);
    if (valid_found >= params.nspg_enough || out_of_time()) break;
  }
  for (int k = 0; k < params.nspg_samples && !on_task.empty() && valid_found < params.nspg_enough && !out_of_time(); ++k) {
    // Walk from the best valid posture, else climb from the least infeasible one (and now and
    // then from any posture on the task, to leave a local minimum).
    Eigen::VectorXd q = out.found ? out.q : (k % 4 == 3 || best_invalid.size() == 0) ? on_task[rng() % on_task.size()] : best_invalid;
    Eigen::VectorXd r(n);
    for (int i = 0; i < n; ++i) r[i] = gauss(rng);
    Eigen::VectorXd step = solver.null_step(q, task, r);
    const double big = step.cwiseAbs().maxCoeff();
    if (big < 1e-9) continue;
    step *= params.nspg_step * std::uniform_real_distribution<double>(0.2, 1.0)(rng) / big;
    q = (q + step).cwiseMax(lo).cwiseMin(hi);
    if (solver.converge(q, task, 30)) consider(q);
  }
  if (!rejections.empty()) {
    std::string counts;
    for (const auto& [what, count] : rejections) counts += (counts.empty() ? "" : ", ") + what + " x" + std::to_string(count);
    out.reason = "rejected: " + counts + "; first: " + out.reason;
  }
  if (on_task.empty()) out.reason = "camera frame cannot reach the task pose (kinematically unreachable)";
  if (out.found) out.reason.clear();
  return out;
}

}  // namespace concert::planner
