#pragma once
// The planner's map of the surroundings (paper section 5.4.1): an OctoMap occupancy tree built
// from point clouds or from the world description (walls, boxes, cylinders).

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "planner/types.hpp"

namespace octomap {
class OcTree;
}

namespace concert::planner {

/// Signed Euclidean distance to the occupied voxels of a map, on a grid of the map's voxels over
/// the occupied extent grown by `margin` on every side. Positive outside obstacles, negative
/// inside. Points off the grid read as `margin` (at least that far from anything occupied).
/// The planner's posture solver uses it to push the robot off obstacles smoothly; the exact
/// collision check stays FCL against the OctoMap. (The octomap package's DynamicEDT3D is not
/// packaged in Debian; an exact transform over a bounded grid is a few dozen lines.)
class DistanceField {
 public:
  DistanceField(const octomap::OcTree& tree, double margin);
  /// Distance [m] from `p` to the nearest occupied voxel centre minus the voxel's half diagonal
  /// (so never more than the distance to the voxel), trilinear between grid points.
  [[nodiscard]] double distance(const Eigen::Vector3d& p) const;
  [[nodiscard]] double margin() const { return margin_; }
  /// Grid spacing [m] (the map's, or coarser for a huge map).
  [[nodiscard]] double resolution() const { return resolution_; }
  /// Grid size (cells).
  [[nodiscard]] std::size_t cells() const { return values_.size(); }

 private:
  [[nodiscard]] double at(long i, long j, long k) const;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  // centre of cell (0, 0, 0)
  double resolution_ = 0.0;
  double margin_ = 0.0;
  long nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<float> values_;  // signed distance of each cell centre [m]
};

/// Rays from one sensor origin (map frame, [m]) for Environment::insert_rays.
struct RayBundle {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> hits;    ///< ends that become occupied
  std::vector<Eigen::Vector3d> clears;  ///< ends that only clear their ray (their cell too)
};

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
  /// Ray-casts from `origin` (map frame, [m]) with OctoMap's key rays: every cell along a ray to
  /// a point of `hits` or of `clears` is a miss, the cell of each hit a hit (a cell both passed
  /// and hit in the same call counts as hit, as in OctoMap's insertPointCloud); the end cells of
  /// `clears` are misses too (returns that must never become obstacles: the floor, beams cut at
  /// a maximum range). Non-finite input throws PlannerError naming it, the map unchanged.
  void insert_rays(const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3d>& hits,
                   const std::vector<Eigen::Vector3d>& clears);
  /// The same for several sensors at once: one copy of the tree for all of them (a cell passed
  /// by one sensor's ray and hit by another's counts as hit). Errors name the bundle.
  void insert_rays(const std::vector<RayBundle>& bundles);
  /// Marks the centre of every occupied leaf of `other` occupied here (the union of two maps,
  /// e.g. the world's and the sensors'). Throws PlannerError if the resolutions differ.
  void add_occupied(const Environment& other);

  [[nodiscard]] double resolution() const { return resolution_; }
  /// Number of occupied leaf cells.
  [[nodiscard]] std::size_t occupied_cells() const;
  /// True if the voxel containing `p` is occupied.
  [[nodiscard]] bool occupied(const Eigen::Vector3d& p) const;
  /// The tree (never null).
  [[nodiscard]] std::shared_ptr<const octomap::OcTree> octree() const { return tree_; }
  /// Signed distance field of the map (grid margin 0.6 m), computed on first use and shared
  /// by copies of this map; thread-safe.
  [[nodiscard]] std::shared_ptr<const DistanceField> distance_field() const;

 private:
  std::shared_ptr<octomap::OcTree> mutable_copy() const;
  struct LazyField;
  double resolution_;
  std::shared_ptr<const octomap::OcTree> tree_;
  std::shared_ptr<LazyField> field_;  // reset whenever the tree changes
};

}  // namespace concert::planner
