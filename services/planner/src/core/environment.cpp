#include "planner/environment.hpp"

#include <octomap/OcTree.h>

#include <cmath>

namespace concert::planner {

Environment::Environment(double resolution) : resolution_(resolution) {
  if (!(resolution > 0.0)) throw PlannerError("environment: octomap resolution must be > 0, got " + std::to_string(resolution));
  tree_ = std::make_shared<octomap::OcTree>(resolution);
}

std::shared_ptr<octomap::OcTree> Environment::mutable_copy() const { return std::make_shared<octomap::OcTree>(*tree_); }

void Environment::add_world(const World& world) {
  auto tree = mutable_copy();
  const double r = resolution_;
  // Fills the voxels of a bounding region whose centres pass `inside`.
  auto fill = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, auto inside) {
    for (double x = std::floor(lo.x() / r) * r + 0.5 * r; x < hi.x(); x += r) {
      for (double y = std::floor(lo.y() / r) * r + 0.5 * r; y < hi.y(); y += r) {
        for (double z = std::floor(lo.z() / r) * r + 0.5 * r; z < hi.z(); z += r) {
          if (inside(Eigen::Vector3d(x, y, z))) tree->updateNode(octomap::point3d(float(x), float(y), float(z)), true, true);
        }
      }
    }
  };
  for (std::size_t i = 0; i < world.boxes.size(); ++i) {
    const WorldBox& b = world.boxes[i];
    if ((b.size.array() <= 0.0).any()) {
      throw PlannerError("world: box " + std::to_string(i) + " '" + b.name + "': size must be positive in x, y and z");
    }
    const Eigen::Matrix3d rot = Eigen::AngleAxisd(b.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d half = 0.5 * b.size;
    const Eigen::Vector3d ext = rot.cwiseAbs() * half;
    // Half a voxel of slack so a thin wall still fills at least one voxel layer.
    const Eigen::Vector3d grown = half + Eigen::Vector3d::Constant(0.5 * r);
    fill(b.position - ext - Eigen::Vector3d::Constant(r), b.position + ext + Eigen::Vector3d::Constant(r), [&](const Eigen::Vector3d& p) {
      const Eigen::Vector3d local = rot.transpose() * (p - b.position);
      return (local.cwiseAbs().array() <= grown.array()).all();
    });
  }
  for (std::size_t i = 0; i < world.cylinders.size(); ++i) {
    const WorldCylinder& c = world.cylinders[i];
    if (!(c.radius > 0.0) || !(c.height > 0.0)) {
      throw PlannerError("world: cylinder " + std::to_string(i) + " '" + c.name + "': radius and height must be positive");
    }
    const Eigen::Vector3d ext(c.radius + r, c.radius + r, 0.5 * c.height + r);
    fill(c.position - ext, c.position + ext, [&](const Eigen::Vector3d& p) {
      return (p - c.position).head<2>().norm() <= c.radius + 0.5 * r && std::abs(p.z() - c.position.z()) <= 0.5 * (c.height + r);
    });
  }
  tree->updateInnerOccupancy();
  tree->prune();
  tree_ = tree;
}

void Environment::insert_point_cloud(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& origin, double max_range) {
  octomap::Pointcloud cloud;
  cloud.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) throw PlannerError("point cloud: point " + std::to_string(i) + " is not finite");
    cloud.push_back(float(points[i].x()), float(points[i].y()), float(points[i].z()));
  }
  if (!origin.allFinite()) throw PlannerError("point cloud: sensor origin is not finite");
  auto tree = mutable_copy();
  tree->insertPointCloud(cloud, octomap::point3d(float(origin.x()), float(origin.y()), float(origin.z())), max_range);
  tree->updateInnerOccupancy();
  tree->prune();
  tree_ = tree;
}

std::size_t Environment::occupied_cells() const {
  std::size_t n = 0;
  for (auto it = tree_->begin_leafs(); it != tree_->end_leafs(); ++it) {
    if (tree_->isNodeOccupied(*it)) n += 1;
  }
  return n;
}

bool Environment::occupied(const Eigen::Vector3d& p) const {
  const octomap::OcTreeNode* node = tree_->search(p.x(), p.y(), p.z());
  return node != nullptr && tree_->isNodeOccupied(node);
}

}  // namespace concert::planner
