// Null-Space Posture Generator (Rossini et al. 2021, paper section 5.4.2).
//
// The goal posture solves the posture problem of posture_problem.hpp: the camera task as the
// first priority, and within the task's null space the inequalities (torque limits with and
// without the drilling force, clearance from the drilled surface, the floor, the robot's own
// links and the map's obstacles). Seeds: the start posture with the base placed for it, the
// start posture as it is, the hints (remembered postures) and their mirror images, the start
// posture, the hints and their images with the first arm joint turned, then random arm
// postures (the best of a few draws, base placed for each). Every converged posture is judged by
// the exact StateChecker; the valid one of least cost (distance to the start, inverse
// manipulability) is kept.
//
// The solver is hand-written instead of a library's (Ipopt is in Debian): 9-12 variables and
// a few hundred cheap residual rows, a dense two-priority Gauss-Newton step with a
// finite-difference Jacobian is a few dozen lines, and an NLP solver would need the same
// residuals plus derivatives and a problem adapter without being faster at this size.

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>

#include "cpu_clock.hpp"
#include "planner/planner.hpp"
#include "posture_problem.hpp"

namespace concert::planner {
namespace {

using detail::kTaskWeight;
using detail::make_task;
using detail::PostureProblem;
using detail::solve;
using detail::Task;
using detail::Term;

// Yoshikawa manipulability of the arm joints for the camera frame.
double manipulability(const PlanningModel& model, kinematics::Data& data,
                      const Eigen::VectorXd& full, const std::string& camera) {
  const Eigen::MatrixXd j_full = model.kinematics().frame_jacobian(data, full, camera);
  const auto& idx = model.planned_indices();
  Eigen::MatrixXd j(6, static_cast<Eigen::Index>(idx.size()) - 3);
  for (std::size_t i = 3; i < idx.size(); ++i)
    j.col(static_cast<Eigen::Index>(i) - 3) = j_full.col(idx[i]);
  return std::sqrt(std::max(0.0, (j * j.transpose()).determinant()));
}

}  // namespace

std::optional<Eigen::VectorXd> reached_posture(const PlanningModel& model, const Eigen::VectorXd& q_full,
                                               const std::string& frame, const Eigen::Vector3d& axis,
                                               double reach) {
  const auto& idx = model.planned_indices();
  const auto arm = static_cast<Eigen::Index>(idx.size()) - 3;
  kinematics::Data data = model.kinematics().make_data();
  Eigen::VectorXd q = q_full;
  Eigen::Isometry3d target = model.link_pose(q, frame);
  target.translation() += reach * axis;
  Eigen::MatrixXd j(6, arm);
  Eigen::Matrix<double, 6, 1> e;
  for (int it = 0; it < 50; ++it) {
    const Eigen::Isometry3d now = model.link_pose(q, frame);
    e.head<3>() = target.translation() - now.translation();
    const Eigen::AngleAxisd turn(target.linear() * now.linear().transpose());
    e.tail<3>() = turn.angle() * turn.axis();
    if (e.head<3>().norm() < 1e-4 && e.tail<3>().norm() < 1e-4) return q;
    const Eigen::MatrixXd j_full = model.kinematics().frame_jacobian(data, q, frame);
    for (Eigen::Index i = 0; i < arm; ++i) j.col(i) = j_full.col(idx[static_cast<std::size_t>(i) + 3]);
    Eigen::Matrix<double, 6, 6> jjt = j * j.transpose();
    jjt.diagonal().array() += 1e-4;
    const Eigen::VectorXd step = j.transpose() * jjt.ldlt().solve(e);
    for (Eigen::Index i = 0; i < arm; ++i) {
      const int fi = idx[static_cast<std::size_t>(i) + 3];
      q[fi] = std::clamp(q[fi] + step[i], model.lower()[i + 3], model.upper()[i + 3]);
    }
  }
  return std::nullopt;
}

namespace {

// The drill's reach beyond a drilling posture (Params::tip_reach): the bit moved that far along
// the task axis (reached_posture). Returns why the static torques there (with and without the
// contact force, within Params::torque_margin of the continuous torque) fail, or "" when they
// hold. The posture is where the planner can check collisions; the bit then goes into the wall,
// where only the arm's load can be checked. Without this, morphology A's shoulder J2_E goes past
// its continuous torque while drilling from postures that hold it at 0.7 of it.
std::string reach_torque_failure(const PlanningModel& model, StateChecker& checker,
                                 const Eigen::VectorXd& full, const EndEffectorInfo& tool,
                                 const Task& task, const Params& params) {
  const std::optional<Eigen::VectorXd> reached =
      reached_posture(model, full, tool.frame, task.axis, params.tip_reach);
  if (!reached) {
    std::ostringstream s;
    s << "the bit cannot reach " << params.tip_reach << " m along the hole from the posture";
    return s.str();
  }
  for (const std::string& contact : {tool.frame, std::string()}) {
    if (const Validity v = checker.check_torques(*reached, contact); !v.valid()) {
      std::ostringstream s;
      s << v.detail << " with the bit " << params.tip_reach << " m further";
      return s.str();
    }
  }
  return {};
}

// True when the solved residuals `r` are off the task and a torque row is the largest
// inequality holding them off.
bool off_task_by_torques(const PostureProblem& problem, const Eigen::VectorXd& r,
                         double tolerance) {
  if (r.head<6>().norm() < kTaskWeight * tolerance) return false;
  Eigen::Index row = 0;
  return r.tail(r.size() - 6).maxCoeff(&row) > 0.0 &&
         problem.term_of_row(static_cast<int>(row) + 6) == Term::kTorque;
}

// Turned seeds: the first arm joint turned by +-kTurnStep, +-2 kTurnStep, ... (kTurns each way).
// On one of the benchmark's low areas beside a pillar (seed 7, #01; A) 34 of 234 turned
// bare-wall postures converged to valid ones, 1 of 150 random arm postures.
constexpr double kTurnStep = 0.6;
constexpr int kTurns = 5;

}  // namespace

std::pair<double, double> task_error(const PlanningModel& model, const Params& params,
                                     const EndEffectorInfo& tool, const Eigen::VectorXd& q_full,
                                     const Eigen::Isometry3d& area) {
  const Task task = make_task(params, area);
  const Eigen::Isometry3d pose = model.link_pose(q_full, model.task_frame(tool, params.tip_task));
  const Eigen::Matrix<double, 6, 1> r = detail::task_residual(task, pose);
  // The axis residual is a chord of the unit sphere: 2 asin(chord / 2) is its angle.
  const double angle = 2.0 * std::asin(std::clamp(0.5 * r.tail<3>().norm(), 0.0, 1.0));
  return {r.head<3>().norm(), angle};
}

PostureResult generate_posture(const PlanningModel& model, StateChecker& checker,
                               const Params& params, const EndEffectorInfo& tool,
                               const Eigen::VectorXd& q_start_full, const Eigen::Isometry3d& area,
                               uint64_t seed, const std::vector<Eigen::VectorXd>& hints,
                               int first_seed, const std::function<bool()>& keep_going) {
  const auto t0 = detail::ThreadCpuClock::now();
  const auto out_of_time = [&] {
    return detail::cpu_seconds_since(t0) > params.nspg_time || (keep_going && !keep_going());
  };
  const Task task = make_task(params, area);
  const int n = model.dof();
  const Eigen::VectorXd start = model.to_planned(q_start_full);
  Eigen::VectorXd lo = model.lower();
  Eigen::VectorXd hi = model.upper();
  // The arm joints' room for the Cartesian phases that start at the posture (posture_limit_margin).
  for (int i = 3; i < n; ++i) {
    if (!std::isfinite(lo[i]) || !std::isfinite(hi[i]) || hi[i] <= lo[i]) continue;
    const double margin = std::min(params.posture_limit_margin, 0.1 * (hi[i] - lo[i]));
    lo[i] += margin;
    hi[i] -= margin;
  }
  // The base may go anywhere within base_range of the start or of the camera target.
  lo.head<2>() = start.head<2>().cwiseMin(task.position.head<2>()).array() - params.base_range;
  hi.head<2>() = start.head<2>().cwiseMax(task.position.head<2>()).array() + params.base_range;
  lo[2] = start[2] - 2.0 * M_PI;
  hi[2] = start[2] + 2.0 * M_PI;
  if (params.fixed_base) {
    lo.head<3>() = start.head<3>();
    hi.head<3>() = start.head<3>();
  } else if (params.base_travel > 0.0) {
    lo.head<3>() = start.head<3>().array() - params.base_travel;
    hi.head<3>() = start.head<3>().array() + params.base_travel;
  }
  const double yaw_hint = start[2];

  PostureProblem problem(model, params, &tool, q_start_full, task, checker.distance_field());
  const std::string camera = model.task_frame(tool, params.tip_task);
  kinematics::Data data = model.kinematics().make_data();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  // The best of a few random arm postures (base placed for each): the one with the smallest
  // residual (camera height and axis elevation, torques, clearances) seeds the solver.
  Eigen::VectorXd r;
  auto random_seed = [&] {
    Eigen::VectorXd best;
    double best_score = std::numeric_limits<double>::infinity();
    for (int k = 0; k < params.nspg_screen; ++k) {
      Eigen::VectorXd arm(n - 3);
      for (int i = 0; i < n - 3; ++i) arm[i] = lo[i + 3] + (hi[i + 3] - lo[i + 3]) * unit(rng);
      const Eigen::VectorXd q = problem.place(arm, yaw_hint);
      problem.evaluate(q, r);
      const double score = r.squaredNorm();
      if (score < best_score) {
        best_score = score;
        best = q;
      }
    }
    return best;
  };

  PostureResult out;
  std::map<std::string, int> rejections;
  auto reject = [&](const std::string& key, const std::string& detail) {
    if (rejections[key]++ == 0 && out.reason.empty())
      out.reason = key + (detail.empty() ? "" : ": " + detail);
  };
  // Seeds in order: the start posture with the base placed for it, the start posture as it
  // is, the hints and their mirror images (the base then stands on the area's other side), then
  // the start posture, the hints and the images with the first arm joint turned (the same
  // posture seen from another side of the area: the base placement follows it around, past an
  // obstacle that blocked the original), then random arm postures; the base placed for each.
  std::vector<Eigen::VectorXd> arms;
  arms.push_back(start.tail(n - 3));
  arms.insert(arms.end(), hints.begin(), hints.end());
  // On one benchmark problem (seed 99, #02, A: a low area between two crates) the memory holds
  // one side's posture family and only its mirror image fits: found at 0.1 s, against 3.1 s
  // of random seeds.
  std::vector<Eigen::VectorXd> mirrored;
  for (const Eigen::VectorXd& arm : hints) {
    if (std::optional<Eigen::VectorXd> m = model.mirrored_arm(arm))
      mirrored.push_back(std::move(*m));
  }
  arms.insert(arms.end(), mirrored.begin(), mirrored.end());
  std::vector<Eigen::VectorXd> turned;
  for (int step = 1; step <= kTurns; ++step) {
    for (const double sign : {1.0, -1.0}) {
      for (const Eigen::VectorXd& arm : arms) {
        Eigen::VectorXd a = arm;
        a[0] += sign * kTurnStep * step;
        if (a[0] >= lo[3] && a[0] <= hi[3]) turned.push_back(std::move(a));
      }
    }
  }
  int valid_found = 0;
  int on_task = 0;
  int k = std::max(0, first_seed);
  for (; k < params.nspg_seeds && valid_found < params.nspg_enough && !out_of_time(); ++k) {
    const auto hint = static_cast<std::size_t>(k - 2);  // index into arms[1...]
    const std::size_t turn = hint - (arms.size() - 1);
    // The preferred load first (seeds screened and solved); when the torques alone held the
    // seed off the task, the seed again with the mode's limit
    // (PostureProblem::kPreferredTorqueTarget). (Not from where the preferred load pulled the
    // base: from there the demo robot's approach at 1.4 m finds none, the base in the wall.)
    problem.set_torque_target(PostureProblem::kPreferredTorqueTarget);
    Eigen::VectorXd q = k == 0                   ? problem.place(arms[0], yaw_hint)
                        : k == 1                 ? start
                        : hint + 1 < arms.size() ? problem.place(arms[hint + 1], yaw_hint)
                        : turn < turned.size()   ? problem.place(turned[turn], yaw_hint)
                                                 : random_seed();
    const Eigen::VectorXd seed_q = q;
    solve(problem, q, lo, hi, params.nspg_iterations, params.nspg_tolerance, r);
    if (off_task_by_torques(problem, r, params.nspg_tolerance)) {
      problem.set_torque_target(problem.limit_torque_target());
      q = seed_q;
      solve(problem, q, lo, hi, params.nspg_iterations, params.nspg_tolerance, r);
    }
    out.candidates += 1;
    if (r.head<6>().norm() >= kTaskWeight * params.nspg_tolerance) {
      // Off the task: name the inequality that held it off, if any.
      Eigen::Index row = 0;
      if (r.tail(r.size() - 6).maxCoeff(&row) > 0.0) {
        switch (problem.term_of_row(static_cast<int>(row) + 6)) {
          case Term::kTorque:
            reject(to_string(Constraint::kTorqueLimit), "torques kept the camera off the task");
            break;
          case Term::kSurface:
            reject(to_string(Constraint::kEnvironmentCollision),
                   "the drilled surface kept the camera off the task");
            break;
          case Term::kFloor:
            reject(to_string(Constraint::kFloor), "the floor kept the camera off the task");
            break;
          case Term::kSelf:
            reject(to_string(Constraint::kSelfCollision),
                   "the robot's own links kept the camera off the task");
            break;
          case Term::kObstacle:
            reject(to_string(Constraint::kEnvironmentCollision),
                   "obstacles kept the camera off the task");
            break;
          case Term::kTask:
            break;
        }
      } else {
        reject("off the task", "");
      }
      continue;
    }
    on_task += 1;
    const Eigen::VectorXd full = model.to_full(q, q_start_full);
    // It must hold both while drilling (contact force on the tool) and while approaching.
    Validity v = checker.check(full, tool.frame);
    if (v.valid()) v = checker.check(full);
    if (!v.valid()) {
      reject(to_string(v.constraint), v.detail);
      continue;
    }
    if (params.tip_task && params.tip_reach > 0.0) {
      const std::string why = reach_torque_failure(model, checker, full, tool, task, params);
      if (!why.empty()) {
        reject(why.rfind("the bit cannot reach", 0) == 0 ? "bit reach" : to_string(Constraint::kTorqueLimit), why);
        continue;
      }
    }
    valid_found += 1;
    out.valid.push_back(q);
    const double cost =
        params.nspg_distance_weight * (q - start).norm() +
        params.nspg_singularity_weight / (manipulability(model, data, full, camera) + 1e-3);
    if (!out.found || cost < out.cost) {
      out.found = true;
      out.cost = cost;
      out.q = q;
    }
  }
  out.next_seed = k;
  if (out.found) {
    out.reason.clear();
  } else if (on_task == 0 && rejections.size() == 1 && rejections.count("off the task") > 0) {
    out.reason = std::string(params.tip_task ? "tip" : "camera") + " frame cannot reach the task pose (kinematically unreachable)";
  } else {
    std::string counts;
    for (const auto& [what, count] : rejections)
      counts += (counts.empty() ? "" : ", ") + what + " x" + std::to_string(count);
    out.reason = "rejected: " + counts + "; first: " + out.reason;
  }
  return out;
}

}  // namespace concert::planner
