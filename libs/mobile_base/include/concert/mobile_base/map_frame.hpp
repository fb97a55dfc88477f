#pragma once
// Where the odometry frame lies in the map (the building's frame), for the services that mix the
// two: the planner (its environment is in the map, the robot's start and trajectories in the
// odometry frame) and the drill service (a BIM wall area is in the map, its camera sees in the
// odometry frame). The robot's odometry starts at zero where the robot was switched on; the nav
// service localises the base in the map with the lidars and publishes the base's map pose at
// the stamp of the robot odometry sample it last used (NavLocalisation). Then
//     map_T_odom = map_T_base(stamp) * inverse(odom_T_base(stamp)),
// with the robot's own odometry at that stamp (not nav's filtered odometry, which drifts apart
// from the robot's by a few cm over a drive). Until a localisation is heard: the identity (the
// map is the odometry frame, as in a world without a building). No DDS.
#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>

namespace concert::mobile_base {

/// A planar pose (x, y, yaw) composed with another: a * b.
Eigen::Vector3d compose(const Eigen::Vector3d& a, const Eigen::Vector3d& b);
/// The inverse of a planar pose.
Eigen::Vector3d inverse(const Eigen::Vector3d& a);
/// A planar pose as a 3D transform (rotation about z).
Eigen::Isometry3d isometry(const Eigen::Vector3d& pose);

/// map_T_odom from localisations and the robot's odometry. Thread-safe.
class MapFrame {
 public:
  /// `history_ns`: how much odometry is kept to match a localisation's stamp; `max_gap_ns`: how
  /// far from a kept sample a stamp may be and still be matched (a localisation older than the
  /// history, or of a stamp never seen, is ignored).
  explicit MapFrame(std::int64_t history_ns = 3'000'000'000, std::int64_t max_gap_ns = 60'000'000);

  /// A robot odometry sample (pose in the odometry frame), in stamp order.
  void on_odometry(std::int64_t stamp_ns, const Eigen::Vector3d& odom_pose);
  /// A localisation: the base's pose in the map at an odometry stamp. Returns false, and
  /// changes nothing, when no odometry sample is within max_gap of the stamp.
  bool on_localisation(std::int64_t stamp_ns, const Eigen::Vector3d& map_pose);

  /// x, y, yaw of the odometry frame in the map (the identity until a localisation matched).
  [[nodiscard]] Eigen::Vector3d map_T_odom() const;
  /// True once a localisation matched.
  [[nodiscard]] bool localised() const;
  /// A map-frame pose in the odometry frame, and back.
  [[nodiscard]] Eigen::Isometry3d to_odom(const Eigen::Isometry3d& in_map) const;
  [[nodiscard]] Eigen::Isometry3d to_map(const Eigen::Isometry3d& in_odom) const;

 private:
  std::int64_t history_ns_, max_gap_ns_;
  mutable std::mutex mutex_;
  std::deque<std::pair<std::int64_t, Eigen::Vector3d>> odometry_;
  std::optional<Eigen::Vector3d> map_T_odom_;
};

}  // namespace concert::mobile_base
