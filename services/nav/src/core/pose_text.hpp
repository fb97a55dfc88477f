#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <string>

namespace concert::nav::detail {

/// "(x, y, theta deg)" of a pose (x [m], y [m], theta [rad]) for error messages.
inline std::string pose_text(const Eigen::Vector3d& pose) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.3f, %.3f, %.1f deg)", pose.x(), pose.y(),
                pose.z() * 180.0 / M_PI);
  return buf;
}

}  // namespace concert::nav::detail
