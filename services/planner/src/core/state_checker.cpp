#include "planner/state_checker.hpp"

#include <fcl/fcl.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <sstream>

namespace concert::planner {
namespace {

std::shared_ptr<fcl::CollisionGeometryd> make_geometry(const LinkShape& s, double pad) {
  switch (s.type) {
    case LinkShape::Type::kBox:
      return std::make_shared<fcl::Boxd>(s.size.x() + 2 * pad, s.size.y() + 2 * pad, s.size.z() + 2 * pad);
    case LinkShape::Type::kCylinder:
      return std::make_shared<fcl::Cylinderd>(s.size.x() + pad, s.size.z() + 2 * pad);
    case LinkShape::Type::kSphere:
      return std::make_shared<fcl::Sphered>(s.size.x() + pad);
  }
  return nullptr;
}

struct ShapeObject {
  int link = -1;
  double bounding_radius = 0.0;  // about the shape origin [m]
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  std::unique_ptr<fcl::CollisionObjectd> exact;
  std::unique_ptr<fcl::CollisionObjectd> padded;
};

}  // namespace

struct StateChecker::Impl {
  kinematics::Data data;
  std::vector<ShapeObject> shapes;
  std::vector<std::pair<int, int>> pairs;  // indices into shapes
  std::unique_ptr<fcl::CollisionObjectd> octree;
  fcl::AABBd octree_box;
  bool octree_empty = true;
  std::vector<Eigen::Isometry3d> poses;
  Eigen::VectorXd tau;
  std::shared_ptr<const DistanceField> field;
};

StateChecker::StateChecker(std::shared_ptr<const PlanningModel> model, const Environment& environment, const Params& params,
                           double padding)
    : model_(std::move(model)), environment_(environment), params_(params), impl_(new Impl{model_->kinematics().make_data(), {}, {}, nullptr, {}, true, {}, {}, nullptr}), padding_(padding) {
  const auto& links = model_->links();
  for (std::size_t l = 0; l < links.size(); ++l) {
    for (const LinkShape& s : links[l].shapes) {
      ShapeObject o;
      o.link = static_cast<int>(l);
      o.origin = s.origin;
      o.bounding_radius = s.type == LinkShape::Type::kBox        ? 0.5 * s.size.norm()
                          : s.type == LinkShape::Type::kCylinder ? std::hypot(s.size.x(), 0.5 * s.size.z())
                                                                 : s.size.x();
      o.exact = std::make_unique<fcl::CollisionObjectd>(make_geometry(s, 0.0));
      o.padded = std::make_unique<fcl::CollisionObjectd>(make_geometry(s, padding));
      impl_->shapes.push_back(std::move(o));
    }
  }
  for (std::size_t a = 0; a < impl_->shapes.size(); ++a) {
    for (std::size_t b = a + 1; b < impl_->shapes.size(); ++b) {
      if (!model_->pair_disabled(impl_->shapes[a].link, impl_->shapes[b].link)) {
        impl_->pairs.emplace_back(static_cast<int>(a), static_cast<int>(b));
      }
    }
  }
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
  for (ShapeObject& o : impl_->shapes) {
    const fcl::Transform3d t(impl_->poses[static_cast<std::size_t>(o.link)] * o.origin);
    o.exact->setTransform(t);
    o.exact->computeAABB();
    o.padded->setTransform(t);
    o.padded->computeAABB();
  }
  for (const ShapeObject& o : impl_->shapes) {
    // Legs touch the floor and the base body stands on them: only the arm can hit the floor.
    if (links[static_cast<std::size_t>(o.link)].leg || links[static_cast<std::size_t>(o.link)].rigid_group < 0) continue;
    const double bottom = o.exact->getAABB().min_.z();
    if (bottom < params_.floor_height + params_.floor_clearance) {
      std::ostringstream s;
      s << links[static_cast<std::size_t>(o.link)].name << " reaches z = " << bottom << " m";
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
    for (const ShapeObject& o : impl_->shapes) {
      if (!o.padded->getAABB().overlap(impl_->octree_box)) continue;
      if (field.distance(o.padded->getTranslation()) - field_error > o.bounding_radius + padding_) continue;
      fcl::CollisionResultd result;
      fcl::collide(o.padded.get(), impl_->octree.get(), request, result);
      if (result.isCollision()) {
        const Eigen::Vector3d at = o.padded->getTranslation();
        std::ostringstream s;
        s << links[static_cast<std::size_t>(o.link)].name << " hits the map near (" << at.x() << ", " << at.y() << ", " << at.z()
          << ")";
        return {Constraint::kEnvironmentCollision, s.str()};
      }
    }
  }
  fcl::CollisionRequestd request;
  for (const auto& [a, b] : impl_->pairs) {
    const ShapeObject& oa = impl_->shapes[static_cast<std::size_t>(a)];
    const ShapeObject& ob = impl_->shapes[static_cast<std::size_t>(b)];
    if (!oa.exact->getAABB().overlap(ob.exact->getAABB())) continue;
    fcl::CollisionResultd result;
    fcl::collide(oa.exact.get(), ob.exact.get(), request, result);
    if (result.isCollision()) {
      return {Constraint::kSelfCollision,
              links[static_cast<std::size_t>(oa.link)].name + " and " + links[static_cast<std::size_t>(ob.link)].name};
    }
  }
  return {};
}

}  // namespace concert::planner
