#pragma once
// The planner's map of the surroundings (paper section 5.4.1): an OctoMap occupancy tree built
// from point clouds or from the world description (walls, boxes, cylinders).

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "planner/types.hpp"

namespace octomap {
class OcTree;
}

namespace concert::planner {

/// Occupancy map. Cheap to copy (the tree is shared and never modified after it is published
/// to a StateChecker: every insert makes a new tree).
class Environment {
 public:
  /// Empty map with `resolution` [m] voxels; throws PlannerError if resolution <= 0.
  explicit Environment(double resolution = 0.05);

  /// Marks every voxel whose centre lies inside the world's boxes and cylinders occupied.
  /// Throws PlannerError naming the item with a non-positive size.
  void add_world(const World& world);
  /// Ray-casts a point cloud (world frame) taken from `origin`: the end points become occupied,
  /// the cells along the rays free. Points farther than `max_range` [m] are cut (< 0: no cut).
  /// Non-finite points are errors naming their index.
  void insert_point_cloud(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& origin, double max_range = -1.0);

  [[nodiscard]] double resolution() const { return resolution_; }
  /// Number of occupied leaf cells.
  [[nodiscard]] std::size_t occupied_cells() const;
  /// True if the voxel containing `p` is occupied.
  [[nodiscard]] bool occupied(const Eigen::Vector3d& p) const;
  /// The tree (never null).
  [[nodiscard]] std::shared_ptr<const octomap::OcTree> octree() const { return tree_; }

 private:
  std::shared_ptr<octomap::OcTree> mutable_copy() const;
  double resolution_;
  std::shared_ptr<const octomap::OcTree> tree_;
};

}  // namespace concert::planner
