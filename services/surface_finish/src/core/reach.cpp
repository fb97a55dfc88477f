#include "surface_finish/reach.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <map>

#include "concert/collision/link_shapes.hpp"
#include "concert/mobile_base/base_kinematics.hpp"

namespace concert::surface_finish {

namespace {

std::string mm(double metres) {
  char b[32];
  std::snprintf(b, sizeof b, "%.0f mm", metres * 1000.0);
  return b;
}

}  // namespace

struct Reach::Impl {
  kinematics::Data data;
  collision::LinkShapes shapes;  // the arm's joints move, the base and the legs stand
  std::vector<Eigen::Isometry3d> poses;
  std::mt19937 rng;
};

Reach::Reach(std::shared_ptr<const model::RobotModel> model, model::EndEffectorKind kind, ReachParams params)
    : model_(std::move(model)), params_(params) {
  if (!model_) throw FinishError("no robot model");
  try {
    const model::EndEffectorInfo& tool = model_->tool(kind);
    tool_ = tool.name;
    tcp_ = tool.frame;
  } catch (const model::ModelError& e) {
    throw FinishError(model_->where() + " cannot " +
                      (kind == model::EndEffectorKind::kSanding ? std::string("sand") : std::string("spray")) + ": " +
                      e.what());
  }
  const kinematics::Model& k = model_->kinematics();
  const model::ChainInfo& arm = model_->arm();
  for (const std::string& j : arm.joints) arm_.push_back(k.joint_index_or_throw(j));
  standing_height_ = mobile_base::standing_height(*model_);

  impl_ = std::make_unique<Impl>(Impl{k.make_data(), collision::LinkShapes(*model_, collision::rigid_groups(*model_, arm.joints)),
                                      std::vector<Eigen::Isometry3d>(model_->links().size(), Eigen::Isometry3d::Identity()),
                                      std::mt19937(params_.seed)});
  ignored_ = impl_->shapes.ignored();
}

Reach::~Reach() = default;

Eigen::Isometry3d Reach::target(const WallFrame& wall, double x, double y, double standoff, double roll) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = wall.point(x, y, standoff);
  const Eigen::Vector3d z = -wall.pose.linear().col(2);  // into the wall
  const Eigen::Vector3d up = wall.pose.linear().col(1);
  const Eigen::Vector3d side = wall.pose.linear().col(0);
  const Eigen::Vector3d xa = std::cos(roll) * up + std::sin(roll) * side;
  t.linear().col(0) = xa;
  t.linear().col(1) = z.cross(xa);
  t.linear().col(2) = z;
  return t;
}

Eigen::VectorXd Reach::neutral() const {
  const kinematics::Model& k = model_->kinematics();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(k.dof());
  for (int i : arm_) {
    const kinematics::JointLimits& l = k.joint_limits()[static_cast<std::size_t>(i)];
    if (l.has_position_limits) q[i] = std::clamp(0.0, l.lower + params_.limit_margin, l.upper - params_.limit_margin);
  }
  return q;
}

Eigen::Isometry3d Reach::tcp_pose(const Eigen::VectorXd& q) { return model_->kinematics().frame_pose(impl_->data, q, tcp_); }

double Reach::singular_value(const Eigen::VectorXd& q) {
  const Eigen::MatrixXd j = model_->kinematics().frame_jacobian(impl_->data, q, tcp_);
  Eigen::MatrixXd ja(6, static_cast<Eigen::Index>(arm_.size()));
  for (std::size_t c = 0; c < arm_.size(); ++c) ja.col(static_cast<Eigen::Index>(c)) = j.col(arm_[c]);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(ja);
  const auto& s = svd.singularValues();
  // A 6-row Jacobian of a shorter arm has fewer singular values than rows: its smallest is 0.
  return ja.cols() < 6 ? 0.0 : s[s.size() - 1];
}

std::optional<std::string> Reach::self_collision(const Eigen::VectorXd& q) {
  const kinematics::Model& k = model_->kinematics();
  const auto& links = model_->links();
  for (int l : impl_->shapes.links_with_shapes())
    impl_->poses[static_cast<std::size_t>(l)] = k.frame_pose(impl_->data, q, links[static_cast<std::size_t>(l)].name);
  impl_->shapes.place(impl_->poses);
  const auto hit = impl_->shapes.self_collision();
  if (!hit) return std::nullopt;
  return links[static_cast<std::size_t>(hit->first)].name + " / " + links[static_cast<std::size_t>(hit->second)].name;
}

double Reach::wall_clearance(const Eigen::VectorXd& q, const WallFrame& wall, std::string* nearest) {
  const kinematics::Model& k = model_->kinematics();
  const auto& links = model_->links();
  const Eigen::Vector3d n = wall.pose.linear().col(2);  // the wall's normal, towards the robot
  double best = std::numeric_limits<double>::infinity();
  for (const collision::Shape& shape : impl_->shapes.shapes()) {
    const model::Link& link = links[static_cast<std::size_t>(shape.link)];
    if (link.chain.empty() || model_->chain(link.chain).role != model::ChainRole::kArm) continue;
    const Eigen::Isometry3d pose = k.frame_pose(impl_->data, q, link.name) * shape.primitive.origin;
    const Eigen::Matrix3d& r = pose.linear();
    const Eigen::Vector3d& size = shape.primitive.size;
    // Half the shape's extent along the normal: its support distance towards the wall.
    double reach = 0.0;
    switch (shape.primitive.type) {
      case model::CollisionShape::Type::kBox:
        for (int i = 0; i < 3; ++i) reach += 0.5 * size[i] * std::abs(r.col(i).dot(n));
        break;
      case model::CollisionShape::Type::kCylinder: {
        const double along = std::abs(r.col(2).dot(n));
        reach = size.x() * std::sqrt(std::max(0.0, 1.0 - along * along)) + 0.5 * size.z() * along;
        break;
      }
      case model::CollisionShape::Type::kSphere:
        reach = size.x();
        break;
      case model::CollisionShape::Type::kMesh:
        continue;
    }
    const double clearance = wall.coordinates(pose.translation()).z() - reach;
    if (clearance < best) {
      best = clearance;
      if (nearest != nullptr) *nearest = link.name;
    }
  }
  return best;
}

ReachPose Reach::solve(const Eigen::Isometry3d& tcp, const WallFrame& wall, const Eigen::VectorXd& seed,
                       const Eigen::VectorXd* previous, bool restarts) {
  const kinematics::Model& k = model_->kinematics();
  kinematics::IkOptions opt;
  opt.joints = arm_;
  opt.position_tolerance = 0.1 * params_.position_tolerance;
  opt.orientation_tolerance = 0.1 * params_.orientation_tolerance;
  opt.max_iterations = 300;
  kinematics::IkResult best = k.inverse_kinematics(impl_->data, tcp_, tcp, seed, opt);
  auto good = [&](const kinematics::IkResult& r) {
    return r.position_error <= params_.position_tolerance && r.orientation_error <= params_.orientation_tolerance;
  };
  if (!good(best) && restarts) {
    for (int attempt = 0; attempt < params_.restarts && !good(best); ++attempt) {
      Eigen::VectorXd s = seed;
      for (int i : arm_) {
        const kinematics::JointLimits& l = k.joint_limits()[static_cast<std::size_t>(i)];
        const double lo = l.has_position_limits ? std::max(l.lower, -M_PI) : -M_PI;
        const double hi = l.has_position_limits ? std::min(l.upper, M_PI) : M_PI;
        s[i] = std::uniform_real_distribution<double>(lo, hi)(impl_->rng);
      }
      kinematics::IkResult r = k.inverse_kinematics(impl_->data, tcp_, tcp, s, opt);
      if (r.position_error + 0.1 * r.orientation_error < best.position_error + 0.1 * best.orientation_error) best = r;
    }
  }
  ReachPose out;
  out.q = best.q;
  if (!good(best)) {
    out.reason = best.position_error > params_.position_tolerance
                     ? "IK " + mm(best.position_error) + " short"
                     : "IK orientation " + std::to_string(best.orientation_error) + " rad off";
    return out;
  }
  for (int i : arm_) {
    const kinematics::JointLimits& l = k.joint_limits()[static_cast<std::size_t>(i)];
    if (l.has_position_limits &&
        (best.q[i] < l.lower + params_.limit_margin || best.q[i] > l.upper - params_.limit_margin)) {
      out.reason = k.joint_names()[static_cast<std::size_t>(i)] + " at its limit";
      return out;
    }
  }
  if (previous != nullptr) {
    for (int i : arm_) {
      if (std::abs(best.q[i] - (*previous)[i]) > params_.max_joint_step) {
        char b[160];
        std::snprintf(b, sizeof b, "%s jumps %.2f rad from its neighbour (discontinuous)",
                      k.joint_names()[static_cast<std::size_t>(i)].c_str(), std::abs(best.q[i] - (*previous)[i]));
        out.reason = b;
        return out;
      }
    }
  }
  {
    std::map<std::string, Eigen::Matrix<double, 6, 1>> wrench;
    if (params_.contact_force != 0.0) {
      Eigen::Matrix<double, 6, 1> f = Eigen::Matrix<double, 6, 1>::Zero();
      f.head<3>() = -params_.contact_force * tcp.linear().col(2);
      wrench[tcp_] = f;
    }
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(k.dof());
    const Eigen::VectorXd tau = k.inverse_dynamics(impl_->data, best.q, zero, zero, wrench);
    for (int i : arm_) {
      const std::string& name = k.joint_names()[static_cast<std::size_t>(i)];
      const double limit = params_.torque_margin * model::planning_torque_limit(model_->limits().at(name));
      if (limit > 0.0 && std::abs(tau[i]) > limit) {
        char b[160];
        std::snprintf(b, sizeof b, "%s needs %.0f N m > %.0f N m (continuous torque x %.2f)", name.c_str(),
                      std::abs(tau[i]), limit, params_.torque_margin);
        out.reason = b;
        return out;
      }
    }
  }
  const double sv = singular_value(best.q);
  if (sv < params_.min_singular_value) {
    char b[96];
    std::snprintf(b, sizeof b, "near a singularity (singular value %.3f < %.3f)", sv, params_.min_singular_value);
    out.reason = b;
    return out;
  }
  if (auto hit = self_collision(best.q)) {
    out.reason = "self collision " + *hit;
    return out;
  }
  if (std::isfinite(params_.side_wall_x)) {
    const auto& links = model_->links();
    for (const model::Link& link : links) {
      if (link.chain.empty() || model_->chain(link.chain).role != model::ChainRole::kArm) continue;
      const double x = wall.coordinates(k.frame_pose(impl_->data, best.q, link.name).translation()).x();
      const double room = params_.side_wall_x > 0 ? params_.side_wall_x - x : x - params_.side_wall_x;
      if (room < params_.side_clearance) {
        out.reason = link.name + " " + mm(room) + " from the side wall";
        return out;
      }
    }
  }
  out.ok = true;
  return out;
}

}  // namespace concert::surface_finish
