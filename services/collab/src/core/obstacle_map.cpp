#include "collab/obstacle_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace concert::collab {

ObstacleGrid::ObstacleGrid(GridParams params) : params_(params) {
  auto bad = [](const std::string& w) { throw std::invalid_argument("obstacle grid: " + w); };
  if (!(params_.resolution > 0.0)) bad("resolution must be > 0");
  if (!(params_.half_size > params_.resolution)) bad("half_size must exceed the resolution");
  if (params_.sectors < 1 || params_.sectors > 360) bad("sectors must be 1..360");
  if (!(params_.max_range > 0.0)) bad("max_range must be > 0");
  const double cells = 2.0 * params_.half_size / params_.resolution;
  if (cells > 2000) bad("the map would have more than 2000 x 2000 cells");
  side_ = static_cast<std::size_t>(std::ceil(cells));
  hits_.assign(side_ * side_, 0);
}

void ObstacleGrid::reset(const Eigen::Vector2d& base) {
  std::fill(hits_.begin(), hits_.end(), std::uint16_t{0});
  origin_ = base - Eigen::Vector2d::Constant(params_.half_size);
}

void ObstacleGrid::add_point(const Eigen::Vector2d& p) {
  if (!p.allFinite()) return;
  const Eigen::Vector2d rel = (p - origin_) / params_.resolution;
  if (rel.x() < 0 || rel.y() < 0) return;
  const auto ix = static_cast<std::size_t>(rel.x());
  const auto iy = static_cast<std::size_t>(rel.y());
  if (ix >= side_ || iy >= side_) return;
  auto& h = hits_[iy * side_ + ix];
  if (h < std::numeric_limits<std::uint16_t>::max()) ++h;
}

void ObstacleGrid::add_sonar(const SonarReading& s) {
  if (!(s.range > 0.0) || s.range >= s.max_range || !std::isfinite(s.range)) return;
  // The echo may come from anywhere on the arc: mark it at the cell spacing.
  const double arc = 2.0 * s.half_angle * s.range;
  const int steps = std::max(1, static_cast<int>(std::ceil(arc / params_.resolution)));
  for (int i = 0; i <= steps; ++i) {
    const double a = s.heading - s.half_angle + 2.0 * s.half_angle * i / steps;
    add_point(s.position + s.range * Eigen::Vector2d(std::cos(a), std::sin(a)));
  }
}

std::size_t ObstacleGrid::occupied() const {
  return static_cast<std::size_t>(
      std::count_if(hits_.begin(), hits_.end(), [this](std::uint16_t h) { return h >= params_.min_hits; }));
}

std::vector<Sphere> ObstacleGrid::cells() const {
  std::vector<Sphere> out;
  const double r = params_.resolution * std::numbers::sqrt2 / 2.0;
  for (std::size_t iy = 0; iy < side_; ++iy)
    for (std::size_t ix = 0; ix < side_; ++ix)
      if (hits_[iy * side_ + ix] >= params_.min_hits) {
        const Eigen::Vector2d c = origin_ + params_.resolution * Eigen::Vector2d(static_cast<double>(ix) + 0.5, static_cast<double>(iy) + 0.5);
        out.push_back(Sphere{Eigen::Vector3d(c.x(), c.y(), 0.0), r});
      }
  return out;
}

std::vector<Sphere> ObstacleGrid::active(const Eigen::Vector2d& base) const {
  const std::size_t n = params_.sectors;
  std::vector<double> best(n, std::numeric_limits<double>::infinity());
  std::vector<Sphere> pick(n);
  for (const Sphere& s : cells()) {
    const Eigen::Vector2d d = s.centre.head<2>() - base;
    const double dist = d.norm();
    if (dist > params_.max_range || dist < params_.min_range) continue;
    double a = std::atan2(d.y(), d.x());
    if (a < 0) a += 2.0 * std::numbers::pi;
    const auto sector = std::min(n - 1, static_cast<std::size_t>(a / (2.0 * std::numbers::pi) * static_cast<double>(n)));
    if (dist < best[sector]) {
      best[sector] = dist;
      pick[sector] = s;
    }
  }
  std::vector<std::pair<double, Sphere>> found;
  for (std::size_t i = 0; i < n; ++i)
    if (std::isfinite(best[i])) found.emplace_back(best[i], pick[i]);
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Sphere> out;
  for (auto& f : found) out.push_back(f.second);
  return out;
}

std::vector<RobotSphere> perimeter_spheres(double length, double width) {
  if (!(length > 0.0) || !(width > 0.0)) throw std::invalid_argument("perimeter_spheres: length and width must be > 0");
  // Two spheres along the long axis, each covering half the rectangle (circumscribed).
  const double half = length / 4.0;
  const double r = std::hypot(length / 4.0, width / 2.0);
  return {RobotSphere{Eigen::Vector2d(half, 0.0), r}, RobotSphere{Eigen::Vector2d(-half, 0.0), r}};
}

SonarReading sonar_reading(const Eigen::Isometry3d& world_T_sonar, double range, double max_range,
                           double field_of_view) {
  const Eigen::Vector3d axis = world_T_sonar.linear().col(0);
  SonarReading r;
  r.position = world_T_sonar.translation().head<2>();
  r.heading = std::atan2(axis.y(), axis.x());
  r.range = std::isfinite(range) ? range : -1.0;
  r.max_range = max_range;
  r.half_angle = field_of_view / 2.0;
  return r;
}

void ObstacleGrid::add_scan(const PlanarScanReading& scan) {
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const double r = scan.ranges[i];
    if (!std::isfinite(r) || r < scan.range_min || r > scan.range_max) continue;
    const double a = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    add_point((scan.world_T_sensor * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0.0)).head<2>());
  }
}

}  // namespace concert::collab
