#include "concert/mobile_base/map_frame.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace concert::mobile_base {

namespace {
double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }
}  // namespace

Eigen::Vector3d compose(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {a.x() + c * b.x() - s * b.y(), a.y() + s * b.x() + c * b.y(), wrap(a.z() + b.z())};
}

Eigen::Vector3d inverse(const Eigen::Vector3d& a) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {-c * a.x() - s * a.y(), s * a.x() - c * a.y(), wrap(-a.z())};
}

Eigen::Isometry3d isometry(const Eigen::Vector3d& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(pose.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(pose.x(), pose.y(), 0.0);
  return t;
}

MapFrame::MapFrame(std::int64_t history_ns, std::int64_t max_gap_ns)
    : history_ns_(history_ns), max_gap_ns_(max_gap_ns) {}

void MapFrame::on_odometry(std::int64_t stamp_ns, const Eigen::Vector3d& odom_pose) {
  std::lock_guard lock(mutex_);
  if (!odometry_.empty() && stamp_ns <= odometry_.back().first) {
    if (stamp_ns < odometry_.back().first - history_ns_) odometry_.clear();  // the clock restarted
    else return;  // out of order or repeated
  }
  odometry_.emplace_back(stamp_ns, odom_pose);
  while (!odometry_.empty() && odometry_.front().first < stamp_ns - history_ns_) odometry_.pop_front();
}

bool MapFrame::on_localisation(std::int64_t stamp_ns, const Eigen::Vector3d& map_pose) {
  std::lock_guard lock(mutex_);
  const auto later = std::lower_bound(
      odometry_.begin(), odometry_.end(), stamp_ns,
      [](const auto& sample, std::int64_t t) { return sample.first < t; });
  const std::pair<std::int64_t, Eigen::Vector3d>* nearest = nullptr;
  if (later != odometry_.end()) nearest = &*later;
  if (later != odometry_.begin()) {
    const auto& before = *(later - 1);
    if (nearest == nullptr || stamp_ns - before.first < nearest->first - stamp_ns) nearest = &before;
  }
  if (nearest == nullptr || std::llabs(nearest->first - stamp_ns) > max_gap_ns_) return false;
  map_T_odom_ = compose(map_pose, inverse(nearest->second));
  return true;
}

Eigen::Vector3d MapFrame::map_T_odom() const {
  std::lock_guard lock(mutex_);
  return map_T_odom_.value_or(Eigen::Vector3d::Zero());
}

bool MapFrame::localised() const {
  std::lock_guard lock(mutex_);
  return map_T_odom_.has_value();
}

Eigen::Isometry3d MapFrame::to_odom(const Eigen::Isometry3d& in_map) const {
  return isometry(inverse(map_T_odom())) * in_map;
}

Eigen::Isometry3d MapFrame::to_map(const Eigen::Isometry3d& in_odom) const {
  return isometry(map_T_odom()) * in_odom;
}

}  // namespace concert::mobile_base
