#include "drill/odometry_drift.hpp"

namespace concert::drill {

void OdometryDrift::first_seen(const std::string& key, const Eigen::Vector3d& in_odom) {
  marks_.emplace(key, to_map(in_odom));
}

std::optional<double> OdometryDrift::seen_again(const std::string& key, const Eigen::Vector3d& in_odom) {
  const auto it = marks_.find(key);
  if (it == marks_.end()) return std::nullopt;
  const Eigen::Vector2d drift = (it->second - in_odom).head<2>();
  const double moved = (drift - drift_).norm();
  drift_ = drift;
  corrected_ = true;
  return moved;
}

std::optional<double> OdometryDrift::surface_seen(const Eigen::Vector3d& first_in_map,
                                                  const Eigen::Vector3d& normal,
                                                  const Eigen::Vector3d& now_in_odom) {
  Eigen::Vector2d n = normal.head<2>();
  if (n.norm() < 0.3) return std::nullopt;
  n.normalize();
  // The surface's offset along n in the map, and where the drift puts the one measured now.
  const double along = n.dot((first_in_map - to_map(now_in_odom)).head<2>());
  drift_ += along * n;
  corrected_ = true;
  return std::abs(along);
}

}  // namespace concert::drill
