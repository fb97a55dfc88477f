#include "concert/collision/link_shapes.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace concert::collision {
namespace {

using Type = model::CollisionShape::Type;

std::shared_ptr<fcl::CollisionGeometryd> geometry(const model::CollisionShape& s) {
  switch (s.type) {
    case Type::kBox:
      return std::make_shared<fcl::Boxd>(s.size.x(), s.size.y(), s.size.z());
    case Type::kCylinder:
      return std::make_shared<fcl::Cylinderd>(s.size.x(), s.size.z());
    case Type::kSphere:
      return std::make_shared<fcl::Sphered>(s.size.x());
    case Type::kMesh:
      break;
  }
  return nullptr;
}

// `s` grown by `pad` on every side; a bit (`tip_kept`, a cylinder whose tip is its +z end) grown
// sideways and backwards only, its origin moved back to stay centred.
model::CollisionShape grown(const model::CollisionShape& s, double pad, bool tip_kept) {
  model::CollisionShape g = s;
  switch (s.type) {
    case Type::kBox: g.size += Eigen::Vector3d::Constant(2.0 * pad); break;
    case Type::kCylinder:
      g.size.x() += pad;
      g.size.y() += pad;
      g.size.z() += tip_kept ? pad : 2.0 * pad;
      if (tip_kept) g.origin = s.origin * Eigen::Translation3d(0.0, 0.0, -0.5 * pad);
      break;
    case Type::kSphere: g.size.x() += pad; break;
    case Type::kMesh: break;
  }
  return g;
}

double bounding_radius(const model::CollisionShape& s) {
  switch (s.type) {
    case Type::kBox: return 0.5 * s.size.norm();
    case Type::kCylinder: return std::hypot(s.size.x(), 0.5 * s.size.z());
    case Type::kSphere: return s.size.x();
    case Type::kMesh: break;
  }
  return 0.0;
}

}  // namespace

std::vector<int> rigid_groups(const model::RobotModel& model, const std::vector<std::string>& joints) {
  const std::set<std::string> moving(joints.begin(), joints.end());
  const auto& links = model.links();
  std::vector<int> group(links.size(), -1);
  for (std::size_t l = 0; l < links.size(); ++l) {
    const model::Link& link = links[l];
    group[l] = link.parent >= 0 ? group[static_cast<std::size_t>(link.parent)] : -1;
    if (link.moving && moving.count(link.joint) > 0) group[l] = static_cast<int>(l);
  }
  return group;
}

struct LinkShapes::Impl {
  std::vector<Shape> shapes;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> exact;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> padded;
  std::vector<Eigen::Isometry3d> padded_origin;  // of each padded shape, in its link's frame
  std::vector<std::pair<int, int>> pairs;
  std::vector<int> links;
  std::vector<std::string> ignored;
  double padding = 0.0;
};

LinkShapes::LinkShapes(const model::RobotModel& model, const std::vector<int>& groups, double padding,
                       const std::map<int, std::vector<model::CollisionShape>>& extra)
    : impl_(std::make_unique<Impl>()) {
  const auto& links = model.links();
  if (groups.size() != links.size()) {
    throw std::invalid_argument("collision: " + std::to_string(groups.size()) + " rigid groups for " +
                                std::to_string(links.size()) + " links");
  }
  if (!(padding >= 0.0)) throw std::invalid_argument("collision: padding must be >= 0");
  impl_->padding = padding;
  for (std::size_t l = 0; l < links.size(); ++l) {
    bool any = false;
    std::vector<model::CollisionShape> own = links[l].shapes;
    const std::size_t model_shapes = own.size();
    if (const auto more = extra.find(static_cast<int>(l)); more != extra.end())
      own.insert(own.end(), more->second.begin(), more->second.end());
    for (std::size_t k = 0; k < own.size(); ++k) {
      const model::CollisionShape& c = own[k];
      if (c.type == Type::kMesh) {
        impl_->ignored.push_back(links[l].name + ": mesh");
        continue;
      }
      // An extra cylinder is a bit: not padded beyond its tip. The tip's way to a wall is the
      // task's (a drilling posture puts it a few cm in front of the wall the camera measured);
      // the padding is room for the odometry's drift across the wall.
      const model::CollisionShape padded = grown(c, padding, k >= model_shapes);
      impl_->shapes.push_back(Shape{static_cast<int>(l), c, bounding_radius(c), bounding_radius(padded)});
      impl_->exact.push_back(std::make_unique<fcl::CollisionObjectd>(geometry(c)));
      impl_->padded.push_back(std::make_unique<fcl::CollisionObjectd>(geometry(padded)));
      impl_->padded_origin.push_back(padded.origin);
      any = true;
    }
    if (any) impl_->links.push_back(static_cast<int>(l));
  }
  const std::set<std::pair<int, int>> disabled(model.disabled_pairs().begin(), model.disabled_pairs().end());
  for (std::size_t a = 0; a < impl_->shapes.size(); ++a) {
    for (std::size_t b = a + 1; b < impl_->shapes.size(); ++b) {
      const int la = std::min(impl_->shapes[a].link, impl_->shapes[b].link);
      const int lb = std::max(impl_->shapes[a].link, impl_->shapes[b].link);
      if (groups[static_cast<std::size_t>(la)] == groups[static_cast<std::size_t>(lb)]) continue;
      if (disabled.count({la, lb}) > 0 || disabled.count({lb, la}) > 0) continue;
      impl_->pairs.emplace_back(static_cast<int>(a), static_cast<int>(b));
    }
  }
}

LinkShapes::~LinkShapes() = default;
LinkShapes::LinkShapes(LinkShapes&&) noexcept = default;
LinkShapes& LinkShapes::operator=(LinkShapes&&) noexcept = default;

void LinkShapes::place(const std::vector<Eigen::Isometry3d>& link_poses) {
  for (std::size_t i = 0; i < impl_->shapes.size(); ++i) {
    const Shape& s = impl_->shapes[i];
    const fcl::Transform3d t(link_poses.at(static_cast<std::size_t>(s.link)) * s.primitive.origin);
    impl_->exact[i]->setTransform(t);
    impl_->exact[i]->computeAABB();
    impl_->padded[i]->setTransform(fcl::Transform3d(link_poses.at(static_cast<std::size_t>(s.link)) * impl_->padded_origin[i]));
    impl_->padded[i]->computeAABB();
  }
}

std::optional<std::pair<int, int>> LinkShapes::self_collision() const {
  const fcl::CollisionRequestd request;
  for (const auto& [a, b] : impl_->pairs) {
    const fcl::CollisionObjectd& oa = *impl_->exact[static_cast<std::size_t>(a)];
    const fcl::CollisionObjectd& ob = *impl_->exact[static_cast<std::size_t>(b)];
    if (!oa.getAABB().overlap(ob.getAABB())) continue;
    fcl::CollisionResultd result;
    fcl::collide(&oa, &ob, request, result);
    if (result.isCollision()) {
      const int la = impl_->shapes[static_cast<std::size_t>(a)].link;
      const int lb = impl_->shapes[static_cast<std::size_t>(b)].link;
      return std::make_pair(std::min(la, lb), std::max(la, lb));
    }
  }
  return std::nullopt;
}

const std::vector<Shape>& LinkShapes::shapes() const { return impl_->shapes; }
const fcl::CollisionObjectd& LinkShapes::exact(std::size_t i) const { return *impl_->exact.at(i); }
const fcl::CollisionObjectd& LinkShapes::padded(std::size_t i) const { return *impl_->padded.at(i); }
const std::vector<int>& LinkShapes::links_with_shapes() const { return impl_->links; }
const std::vector<std::pair<int, int>>& LinkShapes::pairs() const { return impl_->pairs; }
const std::vector<std::string>& LinkShapes::ignored() const { return impl_->ignored; }
double LinkShapes::padding() const { return impl_->padding; }

}  // namespace concert::collision
