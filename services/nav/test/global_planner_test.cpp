#include "nav/global_planner.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "nav/local_controller.hpp"
#include "planning_fixtures.hpp"

namespace concert::nav {
namespace {

using ::testing::HasSubstr;
using testing::test_robot;

double max_spacing(const Path& path) {
  double m = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i)
    m = std::max(m, (path[i] - path[i - 1]).head<2>().norm());
  return m;
}

void expect_collision_free_centres(const Costmap& map, const Path& path) {
  for (const Eigen::Vector3d& p : path) {
    EXPECT_LT(map.cost_at(p.head<2>()), Costmap::kInscribed) << "path pose " << p.transpose();
  }
}

TEST(GlobalPlanner, StraightLineInFreeSpace) {
  const bim::OccupancyGrid free = bim::OccupancyGrid::filled(200, 200, 0.05, {0.0, 0.0});
  const Costmap map(free, test_robot(), {});
  GlobalPlanner planner;
  const Eigen::Vector3d start(2.0, 3.0, 0.0);
  const Eigen::Vector3d goal(8.0, 6.5, 1.0);
  const PlanResult r = planner.plan(map, start, goal);
  ASSERT_TRUE(r.ok()) << r.message;
  const double straight = (goal - start).head<2>().norm();
  EXPECT_NEAR(r.length, straight, 0.01 * straight);
  EXPECT_LE(max_spacing(r.path), 0.05 + 1e-9);
  EXPECT_NEAR((r.path.front() - start).head<2>().norm(), 0.0, 1e-9);
  EXPECT_NEAR((r.path.back() - goal).norm(), 0.0, 1e-9) << "ends at the goal with its heading";
  // Orientation along the direction of travel.
  const double travel = std::atan2(goal.y() - start.y(), goal.x() - start.x());
  EXPECT_NEAR(r.path[r.path.size() / 2].z(), travel, 0.02);
  EXPECT_GT(r.expansions, 0);
}

TEST(GlobalPlanner, GoesThroughTheDoor) {
  const testing::Building b = testing::two_rooms();
  const Costmap map(b.map, test_robot(), {});
  GlobalPlanner planner;
  const PlanResult r = planner.plan(map, {1.5, 0.9, 0.0}, {8.5, 3.0, M_PI});
  ASSERT_TRUE(r.ok()) << r.message;
  expect_collision_free_centres(map, r.path);
  // Crosses x = 5 within the door, near its middle (the cost keeps it away from the posts).
  bool crossed = false;
  for (std::size_t i = 1; i < r.path.size(); ++i) {
    if (r.path[i - 1].x() < 5.0 && r.path[i].x() >= 5.0) {
      crossed = true;
      EXPECT_NEAR(r.path[i].y(), 2.0, 0.15);
      EXPECT_FALSE(map.in_collision(r.path[i])) << "the footprint along the path fits the door";
    }
  }
  EXPECT_TRUE(crossed);
  EXPECT_LE(max_spacing(r.path), 0.05 + 1e-9);
  // Longer than the straight line, but not by much.
  const double straight = (Eigen::Vector2d(8.5, 3.0) - Eigen::Vector2d(1.5, 0.9)).norm();
  EXPECT_GT(r.length, straight);
  EXPECT_LT(r.length, 1.2 * straight);
}

TEST(GlobalPlanner, RefusesStartAndGoalInWallsWithReasons) {
  const testing::Building b = testing::two_rooms();
  const Costmap map(b.map, test_robot(), {});
  GlobalPlanner planner;
  PlanResult r = planner.plan(map, {5.0, 0.8, 0.0}, {8.0, 2.0, 0.0});
  EXPECT_EQ(r.status, PlanStatus::kStartInCollision);
  EXPECT_THAT(r.message, HasSubstr("start (5.000, 0.800"));
  EXPECT_STREQ(to_string(r.status), "start_in_collision");
  r = planner.plan(map, {2.0, 2.0, 0.0}, {9.9, 2.0, 0.0});
  EXPECT_EQ(r.status, PlanStatus::kGoalInCollision);
  EXPECT_THAT(r.message, HasSubstr("goal (9.900, 2.000"));
  r = planner.plan(map, {2.0, 2.0, 0.0}, {12.0, 2.0, 0.0});
  EXPECT_EQ(r.status, PlanStatus::kGoalOutsideMap);
  r = planner.plan(map, {-1.0, 2.0, 0.0}, {8.0, 2.0, 0.0});
  EXPECT_EQ(r.status, PlanStatus::kStartOutsideMap);
  EXPECT_TRUE(r.path.empty());
}

// A task left the base with its footprint over a wall (the drill's whole-body placement stands
// nearer a wall than the footprint, the hull of the steering sweep, allows): the path starts with
// a short straight move off it, heading kept, touching no cell the start does not touch; the
// controller follows it out and on to the goal without failing. Without the escape (0 m) the
// start is refused naming why.
TEST(GlobalPlanner, LeavesAStartWhoseFootprintCoversAWall) {
  bim::OccupancyGrid grid = bim::OccupancyGrid::filled(200, 200, 0.05, {0.0, 0.0});
  testing::add_box(grid, {5.1, 5.0}, {0.1, 3.0});  // a wall x 5.0 .. 5.2
  const Costmap map(grid, test_robot(), {});
  const Eigen::Vector3d start(4.68, 5.0, 0.0);  // the footprint's front edge at 5.03 m
  const Eigen::Vector3d goal(2.0, 2.0, M_PI / 2);
  // The wall's first cells (centres at x = 5.025 m) lie 5 mm inside the footprint's front edge.
  const double deep = map.lethal_depth(start);
  EXPECT_NEAR(deep, 0.005, 1e-9);
  EXPECT_DOUBLE_EQ(map.lethal_depth({3.0, 5.0, 0.0}), 0.0);
  ASSERT_TRUE(map.in_collision(start));
  GlobalPlanner planner;
  const PlanResult r = planner.plan(map, start, goal);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR((r.path.front() - start).norm(), 0.0, 1e-12);
  std::size_t free_from = 0;
  while (free_from < r.path.size() && map.in_collision(r.path[free_from])) {
    EXPECT_NEAR(r.path[free_from].z(), start.z(), 1e-12) << "the heading is kept while escaping";
    EXPECT_LE(map.lethal_depth(r.path[free_from]), deep + map.resolution()) << "pose " << free_from << " goes deeper";
    ++free_from;
  }
  EXPECT_GE(free_from, 1u);
  EXPECT_LE((r.path[free_from] - start).head<2>().norm(), planner.params().escape_distance + 1e-9);
  for (std::size_t i = free_from; i < r.path.size(); ++i) EXPECT_FALSE(map.in_collision(r.path[i])) << i;
  EXPECT_NEAR((r.path.back() - goal).norm(), 0.0, 1e-9);

  // Followed closed loop (exact tracking): never failed, never a new cell touched, at the goal.
  LocalController controller;
  controller.set_path(r.path);
  Eigen::Vector3d pose = start;
  bool reached = false;
  for (int step = 0; step < 4000 && !reached; ++step) {
    const ControlOutput out = controller.compute(map, pose, 0.05 * step);
    ASSERT_NE(out.status, ControlStatus::kFailed) << out.reason;
    ASSERT_NE(out.status, ControlStatus::kBlocked) << out.reason << " at " << pose.transpose();
    reached = out.status == ControlStatus::kReached;
    pose = integrate_twist(pose, out.cmd, 0.05);
    ASSERT_LE(map.lethal_depth(pose), deep + map.resolution()) << "step " << step << " at " << pose.transpose();
  }
  EXPECT_TRUE(reached);

  // Along a path (not at its start) a pose over the wall is blocked, not failed: the navigator
  // plans again from there, and the plan leaves it.
  const PlanResult along = planner.plan(map, {3.0, 5.0, 0.0}, goal);
  ASSERT_TRUE(along.ok()) << along.message;
  LocalController following;
  following.set_path(along.path);
  ASSERT_EQ(following.compute(map, {3.0, 5.0, 0.0}, 0.0).status, ControlStatus::kFollowing);
  const ControlOutput over = following.compute(map, start, 0.05);
  EXPECT_EQ(over.status, ControlStatus::kBlocked);
  EXPECT_THAT(over.reason, HasSubstr("covers an obstacle"));

  PlannerParams stay;
  stay.escape_distance = 0.0;
  GlobalPlanner refusing(stay);
  const PlanResult refused = refusing.plan(map, start, goal);
  EXPECT_EQ(refused.status, PlanStatus::kStartInCollision);
  EXPECT_THAT(refused.message, HasSubstr("no straight move of up to 0.00 m frees it"));
}

TEST(GlobalPlanner, GoalInUnknownSpace) {
  testing::Building b = testing::two_rooms();
  for (int r = 30; r < 50; ++r) {
    for (int c = 150; c < 170; ++c) b.map.at(c, r) = bim::OccupancyGrid::kUnknown;
  }
  CostmapParams keep;
  keep.unknown_is_lethal = false;
  const Costmap map(b.map, test_robot(), keep);
  GlobalPlanner planner;
  const PlanResult r = planner.plan(map, {2.0, 2.0, 0.0}, {8.0, 2.0, 0.0});
  EXPECT_EQ(r.status, PlanStatus::kGoalUnknown);
  EXPECT_THAT(r.message, HasSubstr("unknown"));
  PlannerParams allow;
  allow.allow_unknown = true;
  GlobalPlanner explorer(allow);
  EXPECT_TRUE(explorer.plan(map, {2.0, 2.0, 0.0}, {8.0, 2.0, 0.0}).ok());
}

TEST(GlobalPlanner, NoPathWhenTheDoorIsClosed) {
  const testing::Building b = testing::two_rooms(false);
  const Costmap map(b.map, test_robot(), {});
  GlobalPlanner planner;
  const PlanResult r = planner.plan(map, {2.0, 2.0, 0.0}, {8.0, 2.0, 0.0});
  EXPECT_EQ(r.status, PlanStatus::kNoPath);
  EXPECT_THAT(r.message, HasSubstr("not connected"));
  // The search covered the whole left room and stopped.
  EXPECT_GT(r.expansions, 1000);
}

TEST(GlobalPlanner, DoorNarrowerThanTheRobot) {
  testing::Building b = testing::two_rooms();
  // Narrow the door to 0.45 m: the 0.5 m wide robot cannot pass.
  for (int r = 0; r < b.map.height; ++r) {
    const double y = b.map.center_of(0, r).y();
    if ((y > 1.5 && y < 1.775) || (y > 2.225 && y < 2.5)) {
      for (int c = 98; c <= 101; ++c) b.map.at(c, r) = bim::OccupancyGrid::kOccupied;
    }
  }
  const Costmap map(b.map, test_robot(), {});
  GlobalPlanner planner;
  EXPECT_EQ(planner.plan(map, {2.0, 2.0, 0.0}, {8.0, 2.0, 0.0}).status, PlanStatus::kNoPath);
}

TEST(GlobalPlanner, ExpansionBudget) {
  const testing::Building b = testing::two_rooms();
  const Costmap map(b.map, test_robot(), {});
  PlannerParams p;
  p.max_expansions = 50;
  GlobalPlanner planner(p);
  const PlanResult r = planner.plan(map, {1.5, 0.9, 0.0}, {8.5, 3.0, 0.0});
  EXPECT_EQ(r.status, PlanStatus::kExpansionLimit);
  EXPECT_THAT(r.message, HasSubstr("50 expansions"));
  EXPECT_EQ(r.expansions, 50);
}

TEST(GlobalPlanner, CostPenaltyKeepsAwayFromWalls) {
  // A 3 m wide corridor: with the cost penalty the path runs near its middle, without it the
  // straight line along a wall is as short.
  bim::OccupancyGrid g = bim::OccupancyGrid::filled(200, 60, 0.05, {0.0, 0.0});
  for (int c = 0; c < 200; ++c) {
    for (int r : {0, 1, 2, 57, 58, 59}) g.at(c, r) = bim::OccupancyGrid::kOccupied;
  }
  const Costmap map(g, test_robot(), {});
  GlobalPlanner planner;
  const PlanResult r = planner.plan(map, {1.0, 0.6, 0.0}, {9.0, 0.6, 0.0});
  ASSERT_TRUE(r.ok()) << r.message;
  double max_y = 0.0;
  for (const auto& p : r.path) max_y = std::max(max_y, p.y());
  EXPECT_GT(max_y, 0.9) << "the path should move away from the wall where it can";
  expect_collision_free_centres(map, r.path);
}

TEST(GlobalPlanner, RandomPairsOnABuildingSucceedAndStayFree) {
  const testing::Building b = testing::make_building(4, 3, 5.0, 0.15, 1.0, 0.05, 11);
  const Costmap map(b.map, test_robot(), {});
  GlobalPlanner planner;
  std::mt19937 rng(5);
  int ok = 0;
  for (const auto& [s, g] : testing::random_pairs(map, 20, 4.0, rng)) {
    const PlanResult r = planner.plan(map, s, g);
    ASSERT_TRUE(r.ok()) << r.message;
    expect_collision_free_centres(map, r.path);
    EXPECT_GE(r.length, (g - s).head<2>().norm() - 1e-6);
    ++ok;
  }
  EXPECT_EQ(ok, 20);
}

}  // namespace
}  // namespace concert::nav
