#pragma once
// The wall in front of the robot from a planar range scan (the lidars' LaserScan): a line fitted
// by RANSAC (seeded) and refined by least squares on its inliers, among the points ahead of the
// base. No DDS.

#include <Eigen/Core>

#include <vector>

#include "surface_finish/types.hpp"

namespace concert::surface_finish {

struct WallFitParams {
  double sector{0.6};         ///< half-angle of the sector ahead searched [rad]
  double max_range{4.0};      ///< points farther are ignored [m]
  double inlier{0.02};        ///< RANSAC inlier distance [m]
  int iterations{200};
  int min_inliers{20};
  unsigned seed{11};
};

/// A fitted wall.
struct WallFit {
  WallFrame wall;
  int inliers{0};
  double rms{0.0};  ///< of the inliers' distances to the line [m]
};

/// Fits the wall to `points` (x, y in the base frame [m]); the floor is `standing_height` below
/// the base origin. Throws FinishError when fewer than min_inliers points support a line ahead.
WallFit fit_wall(const std::vector<Eigen::Vector2d>& points, double standing_height, const WallFitParams& params = {});

}  // namespace concert::surface_finish
