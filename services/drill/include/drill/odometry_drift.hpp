#pragma once
// How far the wheel odometry has drifted, from the marks the drill camera sees again. No DDS.
//
// The planner's map is the world's description, in the map frame; the robot's start and its
// trajectories are in the odometry frame. Without nav's localisation the two are taken for one,
// and the wheel odometry drifts: 4-6 cm over a whole-body move near the wall, up to 64 mm over a
// pattern's four holes (system_drill_pattern_test). The drill sees it (a hole's mark found away
// from where odometry put it) and drills where the camera sees the mark, but the planner, told
// nothing, keeps the wall where odometry puts it: arm paths planned 3 cm from it then press the
// drill on it (safety stops on J1_E's and J2_E's RMS torque).
//
// So the marks are landmarks. A mark's map position is fixed when it is first seen, with the
// drift as then estimated; seen again, the drift becomes what puts it back there. A surface
// measured again (an area's wall, first measured from where the mission started) gives the drift
// along its normal. The estimate is a translation of the odometry frame in the map: the yaw
// comes from the base's gyro, within 5-10 mrad over a pattern (the same test), and a marker's
// own yaw, measured on 10 cm, is noisier than that.
//
// Not a filter: the latest sighting wins, as nav's localisation does. A sighting is a few mm
// off (the camera's noise); the drift it corrects is centimetres.
#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>

namespace concert::drill {

class OdometryDrift {
 public:
  /// Forgets every mark (a new mission: its marks are new); the drift stays, the odometry
  /// frame did not move.
  void forget_marks() { marks_.clear(); }

  /// A mark (`key`: any name unique within the mission) first seen at `in_odom` (odometry
  /// frame): its map position is fixed with the drift as now estimated. Seen before: nothing
  /// changes (use seen_again).
  void first_seen(const std::string& key, const Eigen::Vector3d& in_odom);
  /// A mark seen again at `in_odom`: the drift (x, y) becomes what puts it where it was first
  /// seen. Returns how far the estimate moved [m]; none for a mark never seen first.
  std::optional<double> seen_again(const std::string& key, const Eigen::Vector3d& in_odom);
  [[nodiscard]] bool known(const std::string& key) const { return marks_.count(key) > 0; }

  /// A surface measured at `first_in_map` (map frame) with outward `normal`, now measured through
  /// `now_in_odom`: the drift's component along the normal becomes what puts the surface back,
  /// the rest stays. A vertical surface only moves the x-y drift (the normal's horizontal part,
  /// normalised); a surface facing up (|horizontal part| < 0.3) tells nothing: none returned.
  /// Returns how far the estimate moved [m].
  std::optional<double> surface_seen(const Eigen::Vector3d& first_in_map, const Eigen::Vector3d& normal,
                                     const Eigen::Vector3d& now_in_odom);

  /// x, y [m], yaw (0) of the odometry frame in the map.
  [[nodiscard]] Eigen::Vector3d odom_in_map() const { return {drift_.x(), drift_.y(), 0.0}; }
  /// A point of the odometry frame in the map.
  [[nodiscard]] Eigen::Vector3d to_map(const Eigen::Vector3d& in_odom) const {
    return in_odom + Eigen::Vector3d(drift_.x(), drift_.y(), 0.0);
  }
  /// True once a sighting moved the estimate.
  [[nodiscard]] bool corrected() const { return corrected_; }

 private:
  Eigen::Vector2d drift_{Eigen::Vector2d::Zero()};  // map = odometry + drift
  std::map<std::string, Eigen::Vector3d> marks_;    // map positions
  bool corrected_{false};
};

}  // namespace concert::drill
