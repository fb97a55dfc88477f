#pragma once
// Test and benchmark helpers of the nav planning code: synthetic buildings (rooms and doors),
// unmapped box obstacles, a 2D lidar ray-cast against the true world, and a seeded kinematic
// closed loop (plan -> follow -> scan -> replan when blocked) with acceleration-limited motion.

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "concert/bim/occupancy_grid.hpp"
#include "nav/costmap.hpp"
#include "nav/global_planner.hpp"
#include "nav/local_controller.hpp"

namespace concert::nav::testing {

/// A synthetic storey: the grid and the centres of its door openings (map frame [m]).
struct Building {
  bim::OccupancyGrid map;
  std::vector<Eigen::Vector2d> doors;
};

/// `rooms_x` x `rooms_y` square rooms of side `room` [m], walls `wall` thick [m] all round, one
/// door `door` wide [m] in every inner wall, at a seeded position along it; origin (0, 0).
Building make_building(int rooms_x, int rooms_y, double room, double wall, double door,
                       double resolution, std::uint32_t seed);

/// Two 5 x 4 m rooms side by side (x in [0, 10], wall at x = 5, 0.2 m thick), with a 1.0 m door
/// centred at y = 2; `door_open` false walls it up. 5 cm cells.
Building two_rooms(bool door_open = true);

/// Marks the cells of an axis-aligned box [m] occupied.
void add_box(bim::OccupancyGrid& grid, const Eigen::Vector2d& centre,
             const Eigen::Vector2d& half_size);

/// A 360 deg scan of `beams` rays from `origin` against `truth` (occupied cells block), up to
/// `max_range` [m]: a hit ends just inside the first occupied cell, a miss at max range.
std::vector<Beam> cast_scan(const bim::OccupancyGrid& truth, const Eigen::Vector2d& origin,
                            int beams, double max_range);

/// The rectangular robot of the tests: 0.7 x 0.5 m (inscribed 0.25 m, circumscribed 0.43 m).
RobotShape test_robot();

/// `count` start/goal pairs of poses whose footprints are free with room to turn (centre cost
/// below the possibly-colliding cost), at least `min_distance` apart [m]; seeded.
std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> random_pairs(const Costmap& costmap,
                                                                      int count,
                                                                      double min_distance,
                                                                      std::mt19937& rng);

/// Closed-loop simulation settings.
struct SimConfig {
  RobotShape shape = test_robot();
  CostmapParams costmap;
  PlannerParams planner;
  ControllerParams controller;
  double dt{0.05};         ///< control and integration period [s]
  double max_time{240.0};  ///< give up after [s] of simulated time
  int scan_beams{180};
  double scan_range{6.0};       ///< [m]
  int scan_every{2};            ///< scan every n control periods
  double velocity_noise{0.02};  ///< relative std-dev of the executed velocity
  int max_replans{8};
  std::uint32_t seed{1};
};

/// One simulated mission.
struct RunResult {
  bool reached{false};
  bool collided{false};        ///< the true footprint covered an occupied cell of the truth
  double time{0.0};            ///< simulated time to the goal (or to the end) [s]
  double position_error{0.0};  ///< at the end [m]
  double heading_error{0.0};   ///< at the end [rad]
  int replans{0};
  bool was_blocked{false};                  ///< the controller reported kBlocked at least once
  std::string failure;                      ///< why it did not reach the goal
  std::vector<Eigen::Vector3d> trajectory;  ///< every pose [m, rad]
};

/// Plans on `map` (before any scan), follows the path while scanning `truth` into the costmap's
/// obstacle layer and replanning on kBlocked (or kFailed), until the goal is reached, the run fails
/// or max_time passes. The plant tracks the command with the controller's acceleration limits and
/// seeded velocity noise; collisions are checked against `truth` with the exact footprint.
RunResult run_mission(const bim::OccupancyGrid& map, const bim::OccupancyGrid& truth,
                      const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                      const SimConfig& config);

/// Adds `count` unmapped boxes (half sizes 0.15..0.3 m) to `truth` on the planned `path`
/// between 1.5 m after its start and 1.5 m before its end, at least `door_clearance` [m] from
/// every door; returns their centres.
std::vector<Eigen::Vector2d> add_obstacles_on_path(bim::OccupancyGrid& truth, const Path& path,
                                                   const std::vector<Eigen::Vector2d>& doors,
                                                   int count, double door_clearance,
                                                   std::mt19937& rng);

}  // namespace concert::nav::testing
