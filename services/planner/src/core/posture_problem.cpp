// The posture problem's residuals and solver (see posture_problem.hpp).

#include "posture_problem.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace concert::planner::detail {
namespace {

// Residual weights: the task must win over the inequalities (1 mm of task error weighs as much
// as 1 cm of penetration).
constexpr double kTorqueWeight = 3.0;
constexpr double kClearanceWeight = 1.0;
// Torque utilisation the smooth problem aims under at most (the checker allows 1.0 x
// torque_margin); PostureProblem::kPreferredTorqueTarget is tried first.
constexpr double kTorqueTarget = 0.97;
// The same for a drilling posture whose reach is checked (Params::tip_reach): the bit goes on
// 5-20 cm from it, and a posture at 0.97 of a shoulder's continuous torque is past it there
// (the demo robot's J2_E: 166-168 N m of 160 with the bit 0.1-0.17 m further). At 0.8 there is
// no such posture for the demo robot's blobs; at 0.9 the postures hold 0.97-1.0 there.
constexpr double kReachTorqueTarget = 0.9;
// Extra clearance the smooth problem keeps, so the exact checks pass [m].
constexpr double kClearanceSlack = 0.015;
// Clearance kept between the robot's own links (FCL counts touching as colliding) [m].
constexpr double kSelfSlack = 0.005;
constexpr double kMaxStep = 0.3;  // [rad or m] per LM iteration
constexpr double kFiniteDifference = 1e-6;

// Signed distance of a collision primitive (pose `t`) from the plane (point o, normal n): the
// smallest n.(x - o) over the shape. Exact for boxes, cylinders and spheres.
double plane_distance(const LinkShape& s, const Eigen::Isometry3d& t, const Eigen::Vector3d& o, const Eigen::Vector3d& n) {
  const double centre = (t.translation() - o).dot(n);
  switch (s.type) {
    case LinkShape::Type::kBox: {
      double extent = 0.0;
      for (int k = 0; k < 3; ++k) extent += 0.5 * s.size[k] * std::abs(t.linear().col(k).dot(n));
      return centre - extent;
    }
    case LinkShape::Type::kCylinder: {
      const double c = std::abs(t.linear().col(2).dot(n));
      return centre - (s.size.x() * std::sqrt(std::max(0.0, 1.0 - c * c)) + 0.5 * s.size.z() * c);
    }
    case LinkShape::Type::kSphere:
      return centre - s.size.x();
  }
  return centre;
}

// Signed distance from a point to a primitive, the point given in the primitive's frame:
// negative inside.
double signed_distance(const LinkShape& s, const Eigen::Vector3d& local) {
  switch (s.type) {
    case LinkShape::Type::kBox: {
      const Eigen::Vector3d q = local.cwiseAbs() - 0.5 * s.size;
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    case LinkShape::Type::kCylinder: {
      const Eigen::Vector2d q(local.head<2>().norm() - s.size.x(), std::abs(local.z()) - 0.5 * s.size.z());
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    case LinkShape::Type::kSphere:
      return local.norm() - s.size.x();
  }
  return 0.0;
}

void add_line(std::vector<Sphere>& out, const Eigen::Isometry3d& origin, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
              double radius) {
  const double length = (to - from).norm();
  const int count = length < 1e-9 ? 1 : static_cast<int>(std::ceil(2.0 * length / radius)) + 1;
  for (int i = 0; i < count; ++i) {
    const double f = count == 1 ? 0.5 : static_cast<double>(i) / (count - 1);
    out.push_back({origin * (from + f * (to - from)), radius});
  }
}

// Spheres inside a primitive, spaced at most half a radius apart (their union then dips at
// most 3 % of the radius below the primitive's surface), plus radius-0 points at box corners
// and edge midpoints and on cylinder rims, where the spheres leave gaps.
std::vector<Sphere> sphere_cover(const LinkShape& s) {
  std::vector<Sphere> out;
  switch (s.type) {
    case LinkShape::Type::kSphere:
      out.push_back({s.origin.translation(), s.size.x()});
      break;
    case LinkShape::Type::kCylinder: {
      const double r = s.size.x();
      const double half = 0.5 * s.size.z();
      if (half >= r) {
        add_line(out, s.origin, Eigen::Vector3d(0, 0, -(half - r)), Eigen::Vector3d(0, 0, half - r), r);
      } else {
        // A disc (wheel): spheres of its half thickness on a ring and at the centre.
        out.push_back({s.origin.translation(), half});
        const int ring = std::max(6, static_cast<int>(std::ceil(2.0 * M_PI * (r - half) / half)));
        for (int i = 0; i < ring; ++i) {
          const double a = 2.0 * M_PI * i / ring;
          out.push_back({s.origin * Eigen::Vector3d((r - half) * std::cos(a), (r - half) * std::sin(a), 0.0), half});
        }
      }
      break;
    }
    case LinkShape::Type::kBox: {
      const double r = 0.5 * s.size.minCoeff();
      int count[3];
      for (int k = 0; k < 3; ++k) count[k] = std::max(1, static_cast<int>(std::ceil(2.0 * (s.size[k] - 2.0 * r) / r)) + 1);
      for (int i = 0; i < count[0]; ++i) {
        for (int j = 0; j < count[1]; ++j) {
          for (int k = 0; k < count[2]; ++k) {
            Eigen::Vector3d p;
            const int idx[3] = {i, j, k};
            for (int d = 0; d < 3; ++d) {
              const double span = s.size[d] - 2.0 * r;
              p[d] = count[d] == 1 ? 0.0 : -0.5 * span + span * idx[d] / (count[d] - 1);
            }
            out.push_back({s.origin * p, r});
          }
        }
      }
      // Corners and edge midpoints (radius 0): the spheres do not reach a box's edges.
      for (int i = -1; i <= 1; ++i) {
        for (int j = -1; j <= 1; ++j) {
          for (int k = -1; k <= 1; ++k) {
            if ((i != 0) + (j != 0) + (k != 0) < 2) continue;
            out.push_back({s.origin * Eigen::Vector3d(0.5 * i * s.size.x(), 0.5 * j * s.size.y(), 0.5 * k * s.size.z()), 0.0});
          }
        }
      }
      break;
    }
  }
  // Rims of a cylinder (radius 0), where its axis spheres leave gaps.
  if (s.type == LinkShape::Type::kCylinder) {
    for (const double end : {-0.5, 0.5}) {
      for (int i = 0; i < 8; ++i) {
        const double a = 2.0 * M_PI * i / 8.0;
        out.push_back({s.origin * Eigen::Vector3d(s.size.x() * std::cos(a), s.size.x() * std::sin(a), end * s.size.z()), 0.0});
      }
    }
  }
  return out;
}

}  // namespace

PostureProblem::PostureProblem(const PlanningModel& model, const Params& params, const EndEffectorInfo* tool,
                 const Eigen::VectorXd& full_template, std::optional<Task> task, std::shared_ptr<const DistanceField> field)
      : model_(model),
        params_(params),
        tool_(tool != nullptr ? model.link_index(tool->frame) : -1),
        template_(full_template),
        task_(std::move(task)),
        field_(std::move(field)) {
    camera_ = tool != nullptr ? model.link_index(model.task_frame(*tool, params.tip_task)) : -1;
    const auto& links = model.links();
    // The surface term keeps the robot in front of the drilled surface; legs stand on the
    // floor, so they are left out when the surface is the floor itself.
    const bool floor_like = task_ && task_->normal.z() > 0.7;
    for (std::size_t l = 0; l < links.size(); ++l) {
      for (const LinkShape& s : links[l].shapes) {
        if (task_ && !(floor_like && links[l].leg)) surface_shapes_.emplace_back(static_cast<int>(l), &s);
        if (!links[l].leg && links[l].rigid_group >= 0) floor_shapes_.emplace_back(static_cast<int>(l), &s);
        for (const Sphere& sp : sphere_cover(s)) spheres_.emplace_back(static_cast<int>(l), sp);
      }
    }
    std::vector<std::vector<int>> by_link(links.size());
    for (std::size_t i = 0; i < spheres_.size(); ++i) by_link[static_cast<std::size_t>(spheres_[i].first)].push_back(static_cast<int>(i));
    bounds_.resize(links.size());
    for (std::size_t l = 0; l < links.size(); ++l) {
      if (by_link[l].empty()) continue;
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (const int i : by_link[l]) centre += spheres_[static_cast<std::size_t>(i)].second.centre;
      centre /= static_cast<double>(by_link[l].size());
      double radius = 0.0;
      for (const int i : by_link[l]) {
        const Sphere& sp = spheres_[static_cast<std::size_t>(i)].second;
        radius = std::max(radius, (sp.centre - centre).norm() + sp.radius);
      }
      bounds_[l] = {centre, radius};
    }
    for (std::size_t a = 0; a < links.size(); ++a) {
      if (!by_link[a].empty()) obstacle_links_.emplace_back(static_cast<int>(a), by_link[a]);
      for (std::size_t b = a + 1; b < links.size(); ++b) {
        if (by_link[a].empty() || by_link[b].empty() || model.pair_disabled(static_cast<int>(a), static_cast<int>(b))) continue;
        self_pairs_.push_back({static_cast<int>(a), static_cast<int>(b), by_link[a], by_link[b]});
      }
    }
    const auto& idx = model.planned_indices();
    arm_joints_ = static_cast<int>(idx.size()) - 3;
    size_ = 6 + 2 * arm_joints_ +
            static_cast<int>(surface_shapes_.size() + floor_shapes_.size() + self_pairs_.size() + obstacle_links_.size());
    // The map's voxels may stand up to a voxel in front of the surface they were made from.
    clearance_ = params.environment_padding + params.octomap_resolution + kClearanceSlack;
    obstacle_clearance_ = params.environment_padding + kClearanceSlack;
  }

Eigen::VectorXd PostureProblem::place(const Eigen::VectorXd& arm, double yaw_hint) {
  Eigen::VectorXd q(arm.size() + 3);
  q.head<3>().setZero();
  q.tail(arm.size()) = arm;
  model_.link_poses(model_.to_full(q, template_), poses_);
  const Eigen::Isometry3d& cam = poses_[static_cast<std::size_t>(camera_)];
  const Eigen::Vector3d a = cam.linear().col(2);
  double yaw = yaw_hint;
  if (a.head<2>().norm() > 1e-3 && task_->axis.head<2>().norm() > 1e-3) {
    yaw = std::atan2(task_->axis.y(), task_->axis.x()) - std::atan2(a.y(), a.x());
    yaw = yaw_hint + std::remainder(yaw - yaw_hint, 2.0 * M_PI);
  }
  const Eigen::Rotation2Dd rot(yaw);
  q[2] = yaw;
  q.head<2>() = task_->position.head<2>() - rot * cam.translation().head<2>();
  // Rotating about the vertical through the origin and shifting in x/y moves every link
  // pose the same way (the base height is along the rotation axis).
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  base.translation() = Eigen::Vector3d(q[0], q[1], 0.0);
  for (Eigen::Isometry3d& p : poses_) p = base * p;
  return q;
}

void PostureProblem::evaluate(const Eigen::VectorXd& q, Eigen::VectorXd& r) {
  r.resize(size_);
  model_.link_poses(model_.to_full(q, template_), poses_);
  if (task_) {
    const Eigen::Isometry3d& cam = poses_[static_cast<std::size_t>(camera_)];
    r.head<6>() = kTaskWeight * task_residual(*task_, cam);
  } else {
    r.head<6>().setZero();
  }
  int row = 6;
  const auto& idx = model_.planned_indices();
  // Gravity + drilling force (the surface pushes back along -z of the tool frame), then
  // gravity alone.
  const bool contact = tool_ >= 0 && params_.contact_force != 0.0 && force_scale_ != 0.0;
  const Eigen::Vector3d force =
      contact ? Eigen::Vector3d(-force_scale_ * params_.contact_force * poses_[static_cast<std::size_t>(tool_)].linear().col(2))
              : Eigen::Vector3d::Zero();
  const double torque_target = std::min(torque_target_, limit_torque_target());
  for (const bool drilling : {true, false}) {
    model_.static_torques(poses_, drilling && contact ? tool_ : -1, force, tau_);
    for (std::size_t i = 3; i < idx.size(); ++i) {
      const double lim = params_.torque_margin * model_.torque_limits()[idx[i]];
      r[row++] = lim > 0.0 ? kTorqueWeight * std::max(0.0, std::abs(tau_[idx[i]]) / lim - torque_target) : 0.0;
    }
  }
  for (const auto& [link, shape] : surface_shapes_) {
    const double d = plane_distance(*shape, poses_[static_cast<std::size_t>(link)] * shape->origin, task_->surface, task_->normal);
    r[row++] = kClearanceWeight * std::max(0.0, clearance_ - d);
  }
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d floor(0.0, 0.0, params_.floor_height);
  for (const auto& [link, shape] : floor_shapes_) {
    const double d = plane_distance(*shape, poses_[static_cast<std::size_t>(link)] * shape->origin, floor, up);
    r[row++] = kClearanceWeight * std::max(0.0, params_.floor_clearance + kClearanceSlack - d);
  }
  world_spheres_.resize(spheres_.size());
  for (std::size_t i = 0; i < spheres_.size(); ++i) {
    world_spheres_[i] = poses_[static_cast<std::size_t>(spheres_[i].first)] * spheres_[i].second.centre;
  }
  for (const LinkPair& p : self_pairs_) {
    double sum = 0.0;
    // Bounding spheres of the two links first: most pairs are far apart.
    const Eigen::Vector3d ca = poses_[static_cast<std::size_t>(p.a)] * bounds_[static_cast<std::size_t>(p.a)].centre;
    const Eigen::Vector3d cb = poses_[static_cast<std::size_t>(p.b)] * bounds_[static_cast<std::size_t>(p.b)].centre;
    const double reach = bounds_[static_cast<std::size_t>(p.a)].radius + bounds_[static_cast<std::size_t>(p.b)].radius;
    if ((ca - cb).squaredNorm() < reach * reach) {
      // The spheres of each link against the exact primitives of the other: penetration
      // depth, both ways (inscribed spheres alone leave gaps at flat faces and edges).
      for (const auto& [mine, other] : {std::pair{p.a, p.b}, std::pair{p.b, p.a}}) {
        const auto& shapes = model_.links()[static_cast<std::size_t>(other)].shapes;
        const Eigen::Vector3d& other_centre = other == p.a ? ca : cb;
        const double other_radius = bounds_[static_cast<std::size_t>(other)].radius + kSelfSlack;
        for (std::size_t k = 0; k < shapes.size(); ++k) {
          // World to shape frame, once per shape (rigid: R^T (x - t)).
          const Eigen::Isometry3d t = poses_[static_cast<std::size_t>(other)] * shapes[k].origin;
          const Eigen::Matrix3d rt = t.linear().transpose();
          for (const int i : mine == p.a ? p.spheres_a : p.spheres_b) {
            const double radius = spheres_[static_cast<std::size_t>(i)].second.radius;
            const double reach_i = radius + other_radius;
            if ((world_spheres_[static_cast<std::size_t>(i)] - other_centre).squaredNorm() > reach_i * reach_i) continue;
            const double d =
                signed_distance(shapes[k], rt * (world_spheres_[static_cast<std::size_t>(i)] - t.translation())) - kSelfSlack;
            if (d < radius) sum += (radius - d) * (radius - d);
          }
        }
      }
    }
    r[row++] = kClearanceWeight * std::sqrt(sum);
  }
  // Obstacles of the map (distance field): every sphere of a link clear by the padding.
  for (const auto& [link, spheres] : obstacle_links_) {
    double sum = 0.0;
    const Eigen::Vector3d c = poses_[static_cast<std::size_t>(link)] * bounds_[static_cast<std::size_t>(link)].centre;
    if (field_->distance(c) < bounds_[static_cast<std::size_t>(link)].radius + obstacle_clearance_) {
      for (const int i : spheres) {
        const double need = spheres_[static_cast<std::size_t>(i)].second.radius + obstacle_clearance_;
        const double d = field_->distance(world_spheres_[static_cast<std::size_t>(i)]);
        if (d < need) sum += (need - d) * (need - d);
      }
    }
    r[row++] = kClearanceWeight * std::sqrt(sum);
  }
}

double PostureProblem::limit_torque_target() const {
  return params_.tip_task && params_.tip_reach > 0.0 ? kReachTorqueTarget : kTorqueTarget;
}

Term PostureProblem::term_of_row(int row) const {
  if (row < 6) return Term::kTask;
  row -= 6;
  if (row < 2 * arm_joints_) return Term::kTorque;
  row -= 2 * arm_joints_;
  if (row < static_cast<int>(surface_shapes_.size())) return Term::kSurface;
  row -= static_cast<int>(surface_shapes_.size());
  if (row < static_cast<int>(floor_shapes_.size())) return Term::kFloor;
  row -= static_cast<int>(floor_shapes_.size());
  return row < static_cast<int>(self_pairs_.size()) ? Term::kSelf : Term::kObstacle;
}

// Two-priority Gauss-Newton with Levenberg-Marquardt damping and a forward-difference
// Jacobian, steps clamped to [lo, hi]: each step first reduces the task error (damped
// pseudo-inverse of the task Jacobian), then the inequality residuals within the task's null
// space, so the inequalities never trade off against the task (the NSPG's null-space motion).
// Leaves the final residual vector in `r`.
void solve(PostureProblem& problem, Eigen::VectorXd& q, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, int iterations,
           double tolerance, Eigen::VectorXd& r) {
  const Eigen::Index n = q.size();
  q = q.cwiseMax(lo).cwiseMin(hi);  // a seed outside the box (a placed base when the base is fixed) starts on it
  problem.evaluate(q, r);
  const Eigen::Index m = r.size() - 6;
  auto merit = [](const Eigen::VectorXd& v) { return 100.0 * v.head<6>().squaredNorm() + v.tail(v.size() - 6).squaredNorm(); };
  double f = merit(r);
  double lambda = 1e-3;
  Eigen::MatrixXd jac(r.size(), n);
  Eigen::VectorXd ri;
  for (int it = 0; it < iterations; ++it) {
    const bool on_task = r.head<6>().norm() < kTaskWeight * tolerance;
    if (on_task && r.tail(m).isZero()) return;
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::VectorXd qi = q;
      qi[i] += kFiniteDifference;
      problem.evaluate(qi, ri);
      jac.col(i) = (ri - r) / kFiniteDifference;
    }
    const Eigen::MatrixXd jt = jac.topRows<6>();
    const Eigen::MatrixXd jh = jac.bottomRows(m);
    // Task step and null-space projector from the SVD (the axis rows have rank 2).
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(jt, Eigen::ComputeFullV);
    const Eigen::VectorXd& sv = svd.singularValues();
    const Eigen::MatrixXd& v = svd.matrixV();
    Eigen::MatrixXd null = Eigen::MatrixXd::Identity(n, n);
    for (Eigen::Index k = 0; k < sv.size(); ++k) {
      if (sv[k] > 1e-6 * std::max(1.0, sv[0])) null -= v.col(k) * v.col(k).transpose();
    }
    const Eigen::MatrixXd a = jh * null;
    const Eigen::MatrixXd h = a.transpose() * a;
    bool improved = false;
    for (int attempt = 0; attempt < 6 && !improved; ++attempt) {
      // Damped least-squares task step, then the inequalities in the task's null space.
      const Eigen::Matrix<double, 6, 6> jjt = jt * jt.transpose() + lambda * Eigen::Matrix<double, 6, 6>::Identity();
      const Eigen::VectorXd dq1 = jt.transpose() * jjt.ldlt().solve(-r.head<6>());
      Eigen::MatrixXd hh = h;
      hh.diagonal().array() += lambda * (h.diagonal().array() + 1e-9);
      const Eigen::VectorXd dq2 = null * hh.ldlt().solve(a.transpose() * (-r.tail(m) - jh * dq1));
      Eigen::VectorXd dq = dq1 + dq2;
      const double big = dq.cwiseAbs().maxCoeff();
      if (!std::isfinite(big)) break;
      if (big > kMaxStep) dq *= kMaxStep / big;
      const Eigen::VectorXd trial = (q + dq).cwiseMax(lo).cwiseMin(hi);
      problem.evaluate(trial, ri);
      const double ft = merit(ri);
      if (ft < f) {
        q = trial;
        r = ri;
        f = ft;
        lambda = std::max(1e-7, lambda * 0.2);
        improved = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) return;
  }
}

}  // namespace concert::planner::detail
