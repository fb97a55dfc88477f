#include "nav/costmap.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "planning_fixtures.hpp"

namespace concert::nav {
namespace {

using testing::test_robot;

// A 4 x 4 m free grid at 5 cm with one occupied cell at (40, 40).
bim::OccupancyGrid single_obstacle() {
  bim::OccupancyGrid g = bim::OccupancyGrid::filled(80, 80, 0.05, {0.0, 0.0});
  g.at(40, 40) = bim::OccupancyGrid::kOccupied;
  return g;
}

TEST(RobotShape, RadiiOfARectangle) {
  const RobotShape s = RobotShape::rectangle(0.7, 0.5);
  EXPECT_DOUBLE_EQ(s.inscribed_radius, 0.25);
  EXPECT_NEAR(s.circumscribed_radius, std::hypot(0.35, 0.25), 1e-12);
}

TEST(RobotShape, RefusesBadPolygons) {
  EXPECT_THAT(
      [] {
        RobotShape::from_footprint({{1, 0}, {0, 1}});
      },
      ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("at least 3")));
  EXPECT_THAT(
      [] {
        RobotShape::from_footprint({{1, 1}, {-1, 1}, {0, 0.2}, {-1, -1}, {1, -1}});
      },
      ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("not convex")));
  EXPECT_THAT(
      [] {
        RobotShape::from_footprint({{1, 1}, {2, 1}, {2, 2}, {1, 2}});
      },
      ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("not strictly inside")));
}

TEST(Costmap, InflationFollowsNav2Semantics) {
  CostmapParams p;
  p.inflation_radius = 0.8;
  p.cost_scaling_factor = 4.0;
  const Costmap map(single_obstacle(), test_robot(), p);
  EXPECT_EQ(map.cost(40, 40), Costmap::kLethal);
  // Within the inscribed radius (0.25 m = 5 cells): inscribed.
  EXPECT_EQ(map.cost(45, 40), Costmap::kInscribed);
  EXPECT_EQ(map.cost(43, 43), Costmap::kInscribed);  // 0.212 m
  // Beyond: 252 * exp(-4 (d - 0.25)), truncated.
  for (int dx : {6, 8, 10, 15}) {
    const double d = 0.05 * dx;
    EXPECT_EQ(map.cost(40 + dx, 40), static_cast<std::uint8_t>(252.0 * std::exp(-4.0 * (d - 0.25))))
        << "at " << d << " m";
  }
  // Decreasing with distance, 0 past the inflation radius (0.8 m = 16 cells).
  for (int dx = 6; dx < 16; ++dx) EXPECT_GT(map.cost(40 + dx, 40), map.cost(41 + dx, 40));
  EXPECT_EQ(map.cost(57, 40), Costmap::kFree);
  EXPECT_EQ(map.cost(40, 40 + 17), Costmap::kFree);
  // The inverse of the cost function.
  EXPECT_NEAR(map.distance_from_cost(map.inflation_cost(0.5)), 0.5, 0.01);
  // Possibly colliding from the circumscribed radius in.
  EXPECT_EQ(map.possibly_colliding_cost(), map.inflation_cost(test_robot().circumscribed_radius));
}

TEST(Costmap, UnknownCellsLethalOrKept) {
  bim::OccupancyGrid g = bim::OccupancyGrid::filled(40, 40, 0.05, {0.0, 0.0});
  g.at(20, 20) = bim::OccupancyGrid::kUnknown;
  const Costmap lethal(g, test_robot(), {});
  EXPECT_EQ(lethal.cost(20, 20), Costmap::kLethal);
  EXPECT_EQ(lethal.cost(22, 20), Costmap::kInscribed);
  CostmapParams keep;
  keep.unknown_is_lethal = false;
  const Costmap kept(g, test_robot(), keep);
  EXPECT_EQ(kept.cost(20, 20), Costmap::kNoInformation);
  EXPECT_EQ(kept.cost(22, 20), Costmap::kFree);
  EXPECT_TRUE(kept.unknown(20, 20));
}

TEST(Costmap, RefusesBadParameters) {
  CostmapParams p;
  p.cost_scaling_factor = 0.0;
  EXPECT_THAT(
      [&] { Costmap(single_obstacle(), test_robot(), p); },
      ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("cost_scaling_factor")));
  bim::OccupancyGrid bad = single_obstacle();
  bad.cells.pop_back();
  EXPECT_THAT([&] { Costmap(bad, test_robot(), {}); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  ::testing::HasSubstr("do not match its size")));
}

TEST(Costmap, ScanMarksAndRayTracingClears) {
  const bim::OccupancyGrid free = bim::OccupancyGrid::filled(100, 100, 0.05, {0.0, 0.0});
  Costmap map(free, test_robot(), {});
  const Eigen::Vector2d sensor(1.0, 2.5);
  const Eigen::Vector2d hit(3.025, 2.525);  // cell (60, 50)
  CostmapUpdate up = map.update_obstacles(sensor, std::vector<Eigen::Vector2d>{hit});
  EXPECT_EQ(up.marked, 1);
  EXPECT_TRUE(map.obstacle(60, 50));
  EXPECT_EQ(map.cost(60, 50), Costmap::kLethal);
  EXPECT_EQ(map.cost(64, 50), Costmap::kInscribed);
  // Only a window around the change was re-inflated.
  EXPECT_LE(up.window[2] - up.window[0], 2 * 17 + 2);
  EXPECT_GE(up.window[0], 60 - 18);

  // The obstacle moved away: a beam through its cell to a farther hit clears it.
  up = map.update_obstacles(sensor, std::vector<Beam>{{{4.025, 2.525}, true}});
  EXPECT_EQ(up.cleared, 1);
  EXPECT_EQ(up.marked, 1);
  EXPECT_FALSE(map.obstacle(60, 50));
  EXPECT_TRUE(map.obstacle(80, 50));
  EXPECT_EQ(map.cost(60, 50), Costmap::kFree) << "inflation of the old mark must be gone";
  EXPECT_EQ(map.cost(80, 50), Costmap::kLethal);

  // A no-return beam clears without marking; hits beyond obstacle_max_range do not mark.
  up = map.update_obstacles(sensor, std::vector<Beam>{{{4.5, 2.525}, false}});
  EXPECT_EQ(up.marked, 0);
  EXPECT_FALSE(map.obstacle(80, 50));
  CostmapParams near;
  near.obstacle_max_range = 1.0;
  Costmap short_range(free, test_robot(), near);
  EXPECT_EQ(short_range.update_obstacles(sensor, std::vector<Eigen::Vector2d>{hit}).marked, 0);
}

TEST(Costmap, IncrementalUpdateEqualsRebuild) {
  const testing::Building b = testing::two_rooms();
  Costmap live(b.map, test_robot(), {});
  bim::OccupancyGrid with_box = b.map;
  testing::add_box(with_box, {2.5, 2.0}, {0.2, 0.2});
  const Eigen::Vector2d sensor(1.0, 1.0);
  live.update_obstacles(sensor, testing::cast_scan(with_box, sensor, 720, 8.0));
  // The box moves; a second scan from elsewhere clears part of the old marks, marks the new.
  bim::OccupancyGrid moved = b.map;
  testing::add_box(moved, {3.0, 1.0}, {0.25, 0.15});
  const Eigen::Vector2d sensor2(3.5, 3.0);
  const CostmapUpdate up =
      live.update_obstacles(sensor2, testing::cast_scan(moved, sensor2, 720, 8.0));
  EXPECT_GT(up.cleared, 0);
  EXPECT_GT(up.marked, 0);
  // What the scan saw of the box, put into the static map, gives the same costs from scratch.
  bim::OccupancyGrid seen = b.map;
  for (int r = 0; r < seen.height; ++r) {
    for (int c = 0; c < seen.width; ++c) {
      if (live.obstacle(c, r)) seen.at(c, r) = bim::OccupancyGrid::kOccupied;
    }
  }
  const Costmap rebuilt(seen, test_robot(), {});
  int marked_box = 0;
  for (int r = 0; r < seen.height; ++r) {
    for (int c = 0; c < seen.width; ++c) {
      ASSERT_EQ(live.cost(c, r), rebuilt.cost(c, r)) << "cell " << c << ", " << r;
      if (live.obstacle(c, r) && b.map.at(c, r) != bim::OccupancyGrid::kOccupied) ++marked_box;
    }
  }
  EXPECT_GT(marked_box, 5) << "the scan must have marked the box's visible faces";
  // Clearing everything restores the static costs.
  live.clear_obstacles();
  const Costmap fresh(b.map, test_robot(), {});
  EXPECT_EQ(live.costs(), fresh.costs());
}

TEST(Costmap, FootprintCollision) {
  const testing::Building b = testing::two_rooms();
  const Costmap map(b.map, test_robot(), {});
  // Centre of the left room: free.
  EXPECT_FALSE(map.in_collision({2.5, 2.0, 0.3}));
  EXPECT_EQ(map.footprint_cost({2.5, 2.0, 0.3}), Costmap::kFree);
  // Straddling the middle wall outside the door: collision.
  EXPECT_TRUE(map.in_collision({5.0, 0.8, 0.0}));
  // In the 1 m door, long axis along the passage: free; across it (0.7 m > 0.5 m... still
  // fits: 0.7 < 1.0) free as well; a pose 0.3 m down the door post collides.
  EXPECT_FALSE(map.in_collision({5.0, 2.0, 0.0}));
  EXPECT_FALSE(map.in_collision({5.0, 2.0, M_PI / 2}));
  EXPECT_TRUE(map.in_collision({5.0, 1.6, M_PI / 2}));
  // The footprint's orientation matters near a wall: 0.3 m from the bottom wall's face (y = 0.2),
  // lengthwise along it is free, across it the 0.35 m half length reaches into it.
  EXPECT_FALSE(map.in_collision({2.5, 0.5, 0.0}));
  EXPECT_TRUE(map.in_collision({2.5, 0.5, M_PI / 2}));
  // Leaving the map is a collision.
  EXPECT_TRUE(map.in_collision({0.1, 2.0, 0.0}));
  EXPECT_TRUE(map.in_collision({-3.0, 2.0, 0.0}));
}

TEST(Costmap, FastPathAgreesWithTheFullCheck) {
  const testing::Building b = testing::make_building(3, 2, 4.0, 0.15, 1.0, 0.05, 7);
  const Costmap fast(b.map, test_robot(), {});
  CostmapParams no_inflation;
  no_inflation.inflation_radius = 0.0;
  const Costmap exact(b.map, test_robot(), no_inflation);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0.0, 12.15), uy(0.0, 8.15), ut(-M_PI, M_PI);
  int collisions = 0;
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector3d pose(ux(rng), uy(rng), ut(rng));
    ASSERT_EQ(fast.in_collision(pose), exact.in_collision(pose)) << pose.transpose();
    collisions += exact.in_collision(pose) ? 1 : 0;
  }
  EXPECT_GT(collisions, 100);
  EXPECT_LT(collisions, 4900);
}

// "Free at any heading" (where an escape from a wall ends, and where a path may turn) must mean
// what it says: no heading of the footprint covers a lethal cell there. With the inflation cost
// as the test, the footprint touching a cell whose centre lies up to a cell's diagonal beyond
// the circumscribed radius was missed, and an inflation radius hardly larger than that radius
// (the demo base: 0.8 m against 0.794) left no cost to test at all: the controller then ended
// an escape at once and reported the robot blocked (bench_shift, after a drilling mission).
TEST(Costmap, FreeAtAnyHeadingMeansNoHeadingCollides) {
  const testing::Building b = testing::make_building(3, 2, 4.0, 0.15, 1.0, 0.05, 7);
  const RobotShape robot = test_robot();
  CostmapParams tight;
  tight.inflation_radius = robot.circumscribed_radius + 0.006;
  for (const CostmapParams& params : {CostmapParams{}, tight}) {
    const Costmap map(b.map, robot, params);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> ux(0.0, 12.15), uy(0.0, 8.15);
    int free = 0, near_walls = 0, wrong = 0;
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Vector2d p(ux(rng), uy(rng));
      if (!map.free_at_any_heading(p)) continue;
      ++free;
      bool near = false;
      for (int k = 0; k < 72; ++k) {
        const Eigen::Vector3d pose(p.x(), p.y(), -M_PI + k * M_PI / 36.0);
        if (map.in_collision(pose)) ++wrong;
        near = near || map.footprint_cost(pose) > Costmap::kFree;
      }
      near_walls += near ? 1 : 0;
    }
    EXPECT_EQ(wrong, 0) << "inflation radius " << params.inflation_radius;
    EXPECT_GT(free, 5000);
    EXPECT_GT(near_walls, 100) << "no free position near a wall was tried";
  }
  // Outside the map nothing is free.
  const Costmap map(b.map, robot, {});
  EXPECT_FALSE(map.free_at_any_heading({-1.0, 2.0}));
}

}  // namespace
}  // namespace concert::nav
