// The map's signed distance field against brute force over the OctoMap's occupied voxels: the
// posture solver leans on its values and the state checker skips FCL where it says "far", so
// it must never claim more clearance than there is (beyond its stated interpolation error).

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <random>

#include "planner/environment.hpp"

using namespace concert::planner;

namespace {

// Distance from p to the nearest occupied voxel cube (0 inside one), by brute force.
double true_distance(const octomap::OcTree& tree, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
    const Eigen::Vector3d d = ((p - c).cwiseAbs() - Eigen::Vector3d::Constant(0.5 * it.getSize())).cwiseMax(0.0);
    best = std::min(best, d.norm());
  }
  return best;
}

}  // namespace

TEST(DistanceField, NeverClaimsMoreClearanceThanThereIs) {
  Environment env(0.05);
  World world;
  world.boxes.push_back({"wall", Eigen::Vector3d(0.2, 3.0, 2.0), Eigen::Vector3d(2.1, 0.0, 1.0), 0.0});
  world.boxes.push_back({"pallet", Eigen::Vector3d(0.6, 0.4, 0.5), Eigen::Vector3d(1.0, 0.8, 0.25), 0.4});
  world.cylinders.push_back({"pillar", 0.15, 2.5, Eigen::Vector3d(0.8, -0.9, 1.25)});
  env.add_world(world);
  const auto field = env.distance_field();
  ASSERT_GT(field->cells(), 1000u);
  const double error = std::sqrt(3.0) * field->resolution();
  std::mt19937 rng(21u);
  std::uniform_real_distribution<double> x(-0.5, 3.0), y(-2.0, 2.0), z(-0.2, 2.5);
  int inside = 0, near = 0;
  for (int i = 0; i < 1500; ++i) {
    const Eigen::Vector3d p(x(rng), y(rng), z(rng));
    const double truth = true_distance(*env.octree(), p);
    const double d = field->distance(p);
    // The state checker's skip test: field - error must not exceed the true clearance.
    EXPECT_LE(d - error, truth + 1e-9) << "at " << p.transpose();
    // And it is informative outside obstacles: within a few cells of the truth where the grid
    // covers the point (inside, it is a negative depth).
    if (truth > 0.0 && truth < field->margin() - 0.2) {
      EXPECT_GE(d, truth - 3.0 * field->resolution()) << "at " << p.transpose();
      near += 1;
    }
    if (env.occupied(p)) {
      EXPECT_LT(d, 0.5 * error) << "inside an obstacle at " << p.transpose();
      inside += 1;
    }
  }
  EXPECT_GT(inside, 10);  // the sample hit obstacles
  EXPECT_GT(near, 300);
  // Far from everything the field reads its margin.
  EXPECT_DOUBLE_EQ(field->distance(Eigen::Vector3d(30.0, 0.0, 1.0)), field->margin());
  // An empty map is all margin.
  EXPECT_DOUBLE_EQ(Environment(0.05).distance_field()->distance(Eigen::Vector3d::Zero()), Environment(0.05).distance_field()->margin());
}
