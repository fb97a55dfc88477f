#include "surface_finish/wall_fit.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <string>

namespace concert::surface_finish {

// A line fit of a few hundred scan points: RANSAC and a 2x2 eigen decomposition are a few lines
// here, PCL's sample consensus would bring its point types for no gain.
WallFit fit_wall(const std::vector<Eigen::Vector2d>& points, double standing_height, const WallFitParams& params) {
  std::vector<Eigen::Vector2d> ahead;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite() || p.x() <= 0.0 || p.norm() > params.max_range) continue;
    if (std::abs(std::atan2(p.y(), p.x())) <= params.sector) ahead.push_back(p);
  }
  if (static_cast<int>(ahead.size()) < params.min_inliers) {
    throw FinishError("no wall ahead: " + std::to_string(ahead.size()) + " scan points within " +
                      std::to_string(params.max_range).substr(0, 4) + " m ahead (at least " +
                      std::to_string(params.min_inliers) + " needed)");
  }
  std::mt19937 rng(params.seed);
  std::uniform_int_distribution<std::size_t> pick(0, ahead.size() - 1);
  std::vector<char> best_in;
  int best = -1;
  for (int it = 0; it < params.iterations; ++it) {
    const Eigen::Vector2d a = ahead[pick(rng)], b = ahead[pick(rng)];
    if ((b - a).norm() < 0.05) continue;
    const Eigen::Vector2d d = (b - a).normalized();
    const Eigen::Vector2d n(-d.y(), d.x());
    std::vector<char> in(ahead.size(), 0);
    int count = 0;
    for (std::size_t i = 0; i < ahead.size(); ++i) {
      if (std::abs((ahead[i] - a).dot(n)) <= params.inlier) {
        in[i] = 1;
        ++count;
      }
    }
    if (count > best) {
      best = count;
      best_in = std::move(in);
    }
  }
  if (best < params.min_inliers) {
    throw FinishError("no wall ahead: the best line holds " + std::to_string(std::max(best, 0)) + " of " +
                      std::to_string(ahead.size()) + " scan points (at least " + std::to_string(params.min_inliers) + " needed)");
  }
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < ahead.size(); ++i) {
    if (best_in[i]) mean += ahead[i];
  }
  mean /= best;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (std::size_t i = 0; i < ahead.size(); ++i) {
    if (best_in[i]) cov += (ahead[i] - mean) * (ahead[i] - mean).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  Eigen::Vector2d n = eig.eigenvectors().col(0);  // smallest eigenvalue: the line's normal
  if (n.dot(mean) > 0.0) n = -n;                  // towards the robot
  WallFit fit;
  fit.inliers = best;
  double ss = 0.0;
  for (std::size_t i = 0; i < ahead.size(); ++i) {
    if (best_in[i]) ss += std::pow((ahead[i] - mean).dot(n), 2);
  }
  fit.rms = std::sqrt(ss / best);
  fit.wall = WallFrame::from_plane(Eigen::Vector3d(mean.x(), mean.y(), 0.0), Eigen::Vector3d(n.x(), n.y(), 0.0),
                                   standing_height);
  return fit;
}

}  // namespace concert::surface_finish
