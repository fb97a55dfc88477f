#pragma once
// Test and benchmark helper of the localiser: a synthetic storey (two rooms joined by a door,
// a partial wall, a wall stub, pillars) as the 5 cm map and as a 1 cm "world" that may also hold
// boxes the map does not know; a seeded route through the door; the planar scan of the CONCERT
// base (two lidars at the Mobile Base Hub's mounts, 0.4 degree columns, 1.5 cm range noise,
// binned into 720 base-frame bearings as sim::derive_scan2d does) ray-cast in the world; drifting
// wheel odometry.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "concert/bim/occupancy_grid.hpp"
#include "nav/localiser.hpp"

namespace concert::nav::testing {

/// An axis-aligned rectangle [x0, x1] x [y0, y1] of the storey [m].
struct Rect {
  double x0, y0, x1, y1;
};

/// Walls and pillars of the storey (map frame, metres; the building spans [0, 16] x [0, 10]).
inline std::vector<Rect> storey_walls() {
  return {
      {0.0, 0.0, 16.0, 0.2}, {0.0, 9.8, 16.0, 10.0},  // outer walls
      {0.0, 0.0, 0.2, 10.0}, {15.8, 0.0, 16.0, 10.0},
      {9.0, 0.2, 9.2, 3.0},  {9.0, 4.0, 9.2, 9.8},    // dividing wall, door y in [3, 4]
      {9.2, 6.4, 13.0, 6.6},                          // partial wall in the right room
      {2.0, 5.0, 5.0, 5.2},                           // wall stub in the left room
      {4.0, 7.0, 4.4, 7.4},  {12.0, 1.6, 12.4, 2.0},  // pillars
  };
}

/// Boxes (pallets) standing in the world but not in the map.
inline std::vector<Rect> unmapped_boxes() {
  return {
      {5.5, 2.2, 6.0, 2.7}, {3.0, 3.0, 3.5, 3.5}, {12.5, 4.5, 13.0, 5.0}, {11.0, 7.5, 11.5, 8.0}};
}

/// The rectangles rasterised at `resolution` [m] over [-0.5, 16.5] x [-0.5, 10.5] shifted by
/// `shift` (so that wall faces need not fall on cell boundaries): a cell is occupied when its
/// centre lies in a rectangle, free inside the building, unknown outside.
inline bim::OccupancyGrid rasterise(const std::vector<Rect>& rects, double resolution,
                                    const Eigen::Vector2d& shift = Eigen::Vector2d::Zero()) {
  const int w = static_cast<int>(std::lround(17.0 / resolution));
  const int h = static_cast<int>(std::lround(11.0 / resolution));
  bim::OccupancyGrid g = bim::OccupancyGrid::filled(
      w, h, resolution, Eigen::Vector2d(-0.5, -0.5) + shift, bim::OccupancyGrid::kUnknown);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const Eigen::Vector2d c = g.center_of(col, row);
      if (c.x() > 0.0 && c.x() < 16.0 && c.y() > 0.0 && c.y() < 10.0) {
        g.at(col, row) = bim::OccupancyGrid::kFree;
      }
      for (const Rect& r : rects) {
        if (c.x() > r.x0 && c.x() < r.x1 && c.y() > r.y0 && c.y() < r.y1) {
          g.at(col, row) = bim::OccupancyGrid::kOccupied;
        }
      }
    }
  }
  return g;
}

/// True poses (x, y, yaw) every `dt` [s] along a route through the door and back (~ 41.5 m):
/// turns in place at `turn_rate` [rad/s], then straight runs at `speed` [m/s].
inline std::vector<Eigen::Vector3d> route(double speed = 0.5, double turn_rate = 0.6,
                                          double dt = 0.1) {
  const std::vector<Eigen::Vector2d> waypoints = {
      {1.5, 1.5},  {7.0, 1.5},  {7.0, 3.5},  {11.0, 3.5}, {14.5, 3.5},
      {14.5, 8.5}, {10.0, 8.5}, {14.5, 8.5}, {14.5, 3.5}, {7.0, 3.5}};
  std::vector<Eigen::Vector3d> poses;
  Eigen::Vector3d pose(waypoints[0].x(), waypoints[0].y(), 0.0);
  poses.push_back(pose);
  for (std::size_t i = 1; i < waypoints.size(); ++i) {
    const Eigen::Vector2d d = waypoints[i] - pose.head<2>();
    const double heading = std::atan2(d.y(), d.x());
    double turn = std::remainder(heading - pose.z(), 2.0 * std::numbers::pi);
    while (std::abs(turn) > 1e-9) {
      const double step = std::copysign(std::min(std::abs(turn), turn_rate * dt), turn);
      pose.z() += step;
      turn -= step;
      poses.push_back(pose);
    }
    const double length = d.norm();
    const int steps = static_cast<int>(std::ceil(length / (speed * dt)));
    const Eigen::Vector2d start = pose.head<2>();
    for (int k = 1; k <= steps; ++k) {
      pose.head<2>() = start + d * (static_cast<double>(k) / steps);
      poses.push_back(pose);
    }
  }
  return poses;
}

/// Length of a route [m].
inline double route_length(const std::vector<Eigen::Vector3d>& poses) {
  double length = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i)
    length += (poses[i] - poses[i - 1]).head<2>().norm();
  return length;
}

/// The planar scan of the base at `pose` in `world`.
inline PlanarScan simulate_scan(const bim::OccupancyGrid& world, const Eigen::Vector3d& pose,
                                std::mt19937_64& rng) {
  constexpr int kBins = 720;
  constexpr int kColumns = 900;
  constexpr double kRangeMax = 30.0;
  constexpr double kNoise = 0.015;
  const Eigen::Vector2d mounts[2] = {{0.62, 0.315}, {-0.62, -0.315}};
  std::normal_distribution<double> noise(0.0, kNoise);
  PlanarScan scan;
  scan.range_min = 0.0;
  scan.range_max = kRangeMax;
  scan.angles.resize(kBins);
  scan.ranges.assign(kBins, std::numeric_limits<double>::infinity());
  const double inc = 2.0 * std::numbers::pi / kBins;
  for (int b = 0; b < kBins; ++b)
    scan.angles[static_cast<std::size_t>(b)] = -std::numbers::pi + (b + 0.5) * inc;
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  for (const Eigen::Vector2d& m : mounts) {
    const Eigen::Vector2d origin(pose.x() + c * m.x() - s * m.y(),
                                 pose.y() + s * m.x() + c * m.y());
    for (int k = 0; k < kColumns; ++k) {
      const double a = -std::numbers::pi + 2.0 * std::numbers::pi * k / kColumns;  // base frame
      const double r = cast_ray(world, origin, pose.z() + a, kRangeMax);
      if (r >= kRangeMax || r <= 0.0) continue;
      const Eigen::Vector2d p = m + (r + noise(rng)) * Eigen::Vector2d(std::cos(a), std::sin(a));
      const double bearing = std::atan2(p.y(), p.x());
      const int bin =
          std::clamp(static_cast<int>((bearing + std::numbers::pi) / inc), 0, kBins - 1);
      double& slot = scan.ranges[static_cast<std::size_t>(bin)];
      slot = std::min(slot, p.norm());
    }
  }
  return scan;
}

/// Wheel odometry along true poses: each step's motion (in the base frame) scaled by 2 % and
/// its rotation by 3 %, plus white noise, integrated into odom_T_base from `start`.
inline std::vector<Eigen::Vector3d> drifting_odometry(
    const std::vector<Eigen::Vector3d>& truth, std::mt19937_64& rng,
    const Eigen::Vector3d& start = Eigen::Vector3d::Zero()) {
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<Eigen::Vector3d> odom{start};
  for (std::size_t i = 1; i < truth.size(); ++i) {
    const Eigen::Vector3d& a = truth[i - 1];
    const Eigen::Vector3d& b = truth[i];
    const double ca = std::cos(a.z()), sa = std::sin(a.z());
    const Eigen::Vector2d dw = (b - a).head<2>();
    Eigen::Vector3d d(ca * dw.x() + sa * dw.y(), -sa * dw.x() + ca * dw.y(),
                      std::remainder(b.z() - a.z(), 2.0 * std::numbers::pi));
    d.head<2>() *= 1.02;
    d.z() = d.z() * 1.03 + 0.002 * n01(rng) * (d.head<2>().norm() + std::abs(d.z()));
    d.head<2>() += 0.005 * d.head<2>().norm() * Eigen::Vector2d(n01(rng), n01(rng));
    const Eigen::Vector3d& o = odom.back();
    const double co = std::cos(o.z()), so = std::sin(o.z());
    odom.emplace_back(o.x() + co * d.x() - so * d.y(), o.y() + so * d.x() + co * d.y(),
                      o.z() + d.z());
  }
  return odom;
}

/// a * b for planar poses (x, y, yaw).
inline Eigen::Vector3d compose(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {a.x() + c * b.x() - s * b.y(), a.y() + s * b.x() + c * b.y(), a.z() + b.z()};
}

/// a^-1 for a planar pose.
inline Eigen::Vector3d inverse(const Eigen::Vector3d& a) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {-c * a.x() - s * a.y(), s * a.x() - c * a.y(), -a.z()};
}

/// Planar position error and absolute yaw error of an estimate.
inline Eigen::Vector2d pose_error(const Eigen::Vector3d& estimate, const Eigen::Vector3d& truth) {
  return {(estimate - truth).head<2>().norm(),
          std::abs(std::remainder(estimate.z() - truth.z(), 2.0 * std::numbers::pi))};
}

}  // namespace concert::nav::testing
