#include "planner/state_checker.hpp"

#include <fcl/fcl.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <sstream>

#include "concert/collision/link_shapes.hpp"

namespace concert::planner {

struct StateChecker::Impl {
  kinematics::Data data;
  collision::LinkShapes shapes;  // padded copies against the environment, exact against each other
  std::unique_ptr<fcl::CollisionObjectd> octree;
  fcl::AABBd octree_box;
  bool octree_empty = true;
  std::vector<Eigen::Isometry3d> poses;
  Eigen::VectorXd tau;
  std::shared_ptr<const DistanceField> field;
};

StateChecker::StateChecker(std::shared_ptr<const PlanningModel> model, const Environment& environment, const Params& params,
                           double padding)
    : model_(std::move(model)), environment_(environment), params_(params), padding_(padding) {
  std::vector<int> groups;
  for (const LinkNode& link : model_->links()) groups.push_back(link.rigid_group);
  impl_.reset(new Impl{model_->kinematics().make_data(), collision::LinkShapes(model_->robot(), groups, padding, model_->added_shapes()), nullptr, {}, true, {}, {},
                       nullptr});
  const std::shared_ptr<const octomap::OcTree> tree = environment.octree();
  if (tree->size() > 0) {
    auto geometry = std::make_shared<fcl::OcTreed>(tree);
    impl_->octree = std::make_unique<fcl::CollisionObjectd>(geometry);
    impl_->octree->computeAABB();
    impl_->octree_box = impl_->octree->getAABB();
    impl_->octree_empty = false;
    impl_->field = environment.distance_field();
  }
}

StateChecker::~StateChecker() = default;

Eigen::VectorXd StateChecker::required_torques(const Eigen::VectorXd& q, const std::string& contact_frame) {
  model_->link_poses(q, impl_->poses);
  Eigen::VectorXd tau;
  torques_at_poses(contact_frame, tau);
  return tau;
}

void StateChecker::torques_at_poses(const std::string& contact_frame, Eigen::VectorXd& tau) {
  int link = -1;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  if (!contact_frame.empty() && params_.contact_force != 0.0) {
    link = model_->link_index(contact_frame);
    if (link < 0) throw PlannerError("no contact frame '" + contact_frame + "' in model version " + std::to_string(model_->version()));
    // The surface pushes back on the tool along -z of the contact frame.
    force = -params_.contact_force * impl_->poses[static_cast<std::size_t>(link)].linear().col(2);
  }
  model_->static_torques(impl_->poses, link, force, tau);
}

Validity StateChecker::torque_validity(const std::string& contact_frame) const {
  const PlanningModel& m = *model_;
  const auto& planned = m.planned_indices();
  const Eigen::VectorXd& tau = impl_->tau;
  const Eigen::VectorXd& limit = m.torque_limits();
  for (std::size_t i = 3; i < planned.size(); ++i) {
    const int fi = planned[i];
    if (limit[fi] > 0.0 && std::abs(tau[fi]) > params_.torque_margin * limit[fi]) {
      std::ostringstream s;
      s << m.joint_names()[i] << " needs " << std::abs(tau[fi]) << " N m > " << params_.torque_margin * limit[fi]
        << " N m continuous" << (contact_frame.empty() ? "" : " (with contact force)");
      return {Constraint::kTorqueLimit, s.str()};
    }
  }
  return {};
}

StateChecker::TorqueUse StateChecker::heaviest_torque(const Eigen::VectorXd& q, const std::string& contact_frame) {
  model_->link_poses(q, impl_->poses);
  torques_at_poses(contact_frame, impl_->tau);
  const PlanningModel& m = *model_;
  const auto& planned = m.planned_indices();
  TorqueUse worst;
  for (std::size_t i = 3; i < planned.size(); ++i) {
    const int fi = planned[i];
    const double limit = m.torque_limits()[fi];
    if (limit <= 0.0) continue;
    const double use = std::abs(impl_->tau[fi]) / limit;
    if (use > worst.fraction) worst = {use, m.joint_names()[i]};
  }
  return worst;
}

Validity StateChecker::check_torques(const Eigen::VectorXd& q, const std::string& contact_frame) {
  model_->link_poses(q, impl_->poses);
  torques_at_poses(contact_frame, impl_->tau);
  return torque_validity(contact_frame);
}

Validity StateChecker::check(const Eigen::VectorXd& q, const std::string& contact_frame) {
  checks_ += 1;
  const PlanningModel& m = *model_;
  const auto& planned = m.planned_indices();
  for (std::size_t i = 3; i < planned.size(); ++i) {
    const double v = q[planned[i]];
    const auto ii = static_cast<Eigen::Index>(i);
    if (!(v >= m.lower()[ii] - 1e-9 && v <= m.upper()[ii] + 1e-9)) {
      std::ostringstream s;
      s << m.joint_names()[i] << " = " << v << " rad outside [" << m.lower()[ii] << ", " << m.upper()[ii] << "]";
      return {Constraint::kJointLimit, s.str()};
    }
  }
  m.link_poses(q, impl_->poses);
  torques_at_poses(contact_frame, impl_->tau);
  if (Validity v = torque_validity(contact_frame); !v.valid()) return v;

  const auto& links = m.links();
  collision::LinkShapes& shapes = impl_->shapes;
  shapes.place(impl_->poses);
  for (std::size_t i = 0; i < shapes.shapes().size(); ++i) {
    // Legs touch the floor and the base body stands on them: only the arm can hit the floor.
    const LinkNode& link = links[static_cast<std::size_t>(shapes.shapes()[i].link)];
    if (link.leg || link.rigid_group < 0) continue;
    const double bottom = shapes.exact(i).getAABB().min_.z();
    if (bottom < params_.floor_height + params_.floor_clearance) {
      std::ostringstream s;
      s << link.name << " reaches z = " << bottom << " m";
      return {Constraint::kFloor, s.str()};
    }
  }
  if (!impl_->octree_empty) {
    fcl::CollisionRequestd request;
    const DistanceField& field = *impl_->field;
    // The distance field is a lower bound of the distance to the occupied voxels up to its
    // interpolation error (one cell diagonal): shapes clear of it by more skip FCL's octree
    // traversal, which is most of the cost of a check.
    const double field_error = std::sqrt(3.0) * field.resolution();
    for (std::size_t i = 0; i < shapes.shapes().size(); ++i) {
      const fcl::CollisionObjectd& padded = shapes.padded(i);
      if (!padded.getAABB().overlap(impl_->octree_box)) continue;
      if (field.distance(padded.getTranslation()) - field_error > shapes.shapes()[i].padded_radius) continue;
      fcl::CollisionResultd result;
      fcl::collide(&padded, impl_->octree.get(), request, result);
      if (result.isCollision()) {
        const Eigen::Vector3d at = padded.getTranslation();
        std::ostringstream s;
        s << links[static_cast<std::size_t>(shapes.shapes()[i].link)].name << " hits the map near (" << at.x() << ", " << at.y()
          << ", " << at.z() << ")";
        return {Constraint::kEnvironmentCollision, s.str()};
      }
    }
  }
  if (const auto hit = shapes.self_collision()) {
    return {Constraint::kSelfCollision,
            links[static_cast<std::size_t>(hit->first)].name + " and " + links[static_cast<std::size_t>(hit->second)].name};
  }
  return {};
}

}  // namespace concert::planner
