#include "surface_finish/types.hpp"

#include <cmath>
#include <cstdio>

namespace concert::surface_finish {

const char* to_string(Task task) { return task == Task::kSpray ? "spray" : "sand"; }

WallFrame WallFrame::ahead(double distance, double standing_height) {
  return from_plane(Eigen::Vector3d(distance, 0.0, 0.0), -Eigen::Vector3d::UnitX(), standing_height);
}

WallFrame WallFrame::from_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double standing_height) {
  Eigen::Vector3d n(normal.x(), normal.y(), 0.0);
  if (!(n.norm() > 0.5 * normal.norm()) || !std::isfinite(n.norm())) {
    char b[160];
    std::snprintf(b, sizeof b, "wall normal (%.3f, %.3f, %.3f) is not horizontal enough for a wall", normal.x(),
                  normal.y(), normal.z());
    throw FinishError(b);
  }
  n.normalize();
  // The foot of the base origin's perpendicular on the plane, at floor height.
  const double d = (point - Eigen::Vector3d::Zero()).dot(n);  // signed: origin is at -d along n
  Eigen::Vector3d origin = d * n;
  origin.z() = -standing_height;
  WallFrame w;
  const Eigen::Vector3d y = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d z = n;
  const Eigen::Vector3d x = y.cross(z);
  w.pose.linear().col(0) = x;
  w.pose.linear().col(1) = y;
  w.pose.linear().col(2) = z;
  w.pose.translation() = origin;
  return w;
}

Eigen::Vector3d WallFrame::point(double x, double y, double offset) const { return pose * Eigen::Vector3d(x, y, offset); }

Eigen::Vector3d WallFrame::coordinates(const Eigen::Vector3d& base_point) const { return pose.inverse() * base_point; }

double WallFrame::distance() const { return std::abs(coordinates(Eigen::Vector3d::Zero()).z()); }

std::string Rect::str() const {
  char b[128];
  std::snprintf(b, sizeof b, "[%.3f, %.3f] x [%.3f, %.3f] m", x0, x1, y0, y1);
  return b;
}

double ToolSpec::cone_half_angle() const {
  if (task != Task::kSpray || standoff <= 0.0) return 0.0;
  return std::atan(0.5 * coat_width / standoff);
}

}  // namespace concert::surface_finish
