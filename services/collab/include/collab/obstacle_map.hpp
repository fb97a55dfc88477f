#pragma once
// Obstacles for the follow-me MPC (paper section 5.6, Fig. 14): a grid map around the robot from
// the two lidars' points and the eight sonars' ranges, occupied cells as spheres, and the map
// split into radial sectors around the base with only the nearest obstacle of each sector
// active. Plain C++ + Eigen; no DDS.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "collab/follow_me_mpc.hpp"

namespace concert::collab {

struct GridParams {
  double resolution{0.1};   ///< cell size [m]
  double half_size{4.0};    ///< the map covers +-half_size around the base [m]
  std::size_t sectors{8};   ///< radial sectors around the base
  double max_range{3.0};    ///< obstacles farther than this from the base are ignored [m]
  double min_range{0.0};    ///< points closer than this are ignored (the robot's own body) [m]
  int min_hits{1};          ///< a cell is occupied from this many hits on
};

/// One sonar reading: the sensor's position and axis in the world frame, the measured range.
struct SonarReading {
  Eigen::Vector2d position{Eigen::Vector2d::Zero()};  ///< [m]
  double heading{0.0};          ///< axis direction [rad]
  double range{0.0};            ///< [m]; <= 0 or >= max_range: nothing seen
  double half_angle{0.2};       ///< cone half-angle [rad]
  double max_range{2.0};        ///< [m]
};

/// A planar lidar scan from a sensor at `world_T_sensor`: beam i at angle_min + i *
/// angle_increment in the sensor's x-y plane.
struct PlanarScanReading {
  Eigen::Isometry3d world_T_sensor{Eigen::Isometry3d::Identity()};
  double angle_min{0.0}, angle_increment{0.0};  ///< [rad]
  double range_min{0.0}, range_max{0.0};        ///< [m]
  std::vector<double> ranges;                   ///< [m]
};

/// A sonar at `world_T_sonar` measuring along its x axis, as the grid takes it: a non-finite
/// range is "nothing seen".
SonarReading sonar_reading(const Eigen::Isometry3d& world_T_sonar, double range, double max_range,
                           double field_of_view);

/// A grid map centred on the base, rebuilt every cycle (the sensors see the present).
class ObstacleGrid {
 public:
  /// Throws std::invalid_argument naming the bad parameter.
  explicit ObstacleGrid(GridParams params);

  /// Empties the map and centres it at `base` (x, y).
  void reset(const Eigen::Vector2d& base);
  /// A lidar point, world frame [m]; points outside the map are ignored.
  void add_point(const Eigen::Vector2d& p);
  /// A sonar echo: cells along the arc at the measured range.
  void add_sonar(const SonarReading& s);
  /// Every finite return of `scan` within [range_min, range_max] as a point.
  void add_scan(const PlanarScanReading& scan);

  std::size_t occupied() const;
  /// Every occupied cell as a sphere (centre at the cell centre, z = 0, radius = half diagonal).
  std::vector<Sphere> cells() const;
  /// The nearest occupied cell of each radial sector around `base` within max_range (at most
  /// `sectors` spheres, nearest first).
  std::vector<Sphere> active(const Eigen::Vector2d& base) const;

  const GridParams& params() const { return params_; }

 private:
  GridParams params_;
  std::size_t side_{0};
  Eigen::Vector2d origin_{Eigen::Vector2d::Zero()};  // corner of cell (0, 0)
  std::vector<std::uint16_t> hits_;
};

/// The paper's robot spheres: two for the rectangular perimeter (lidar obstacles) and one per
/// sonar, in the base frame. `length` x `width` is the base's footprint [m].
std::vector<RobotSphere> perimeter_spheres(double length, double width);

}  // namespace concert::collab
