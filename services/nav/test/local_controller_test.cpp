#include "nav/local_controller.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "planning_fixtures.hpp"

namespace concert::nav {
namespace {

using ::testing::HasSubstr;
using testing::test_robot;

constexpr double kDeg = M_PI / 180.0;

TEST(IntegrateTwist, StraightAndArc) {
  const Eigen::Vector3d p = integrate_twist({1.0, 2.0, M_PI / 2}, {0.5, 0.0, 0.0}, 2.0);
  EXPECT_NEAR(p.x(), 1.0, 1e-12);
  EXPECT_NEAR(p.y(), 3.0, 1e-12);
  // A quarter circle of radius 1 m.
  const Eigen::Vector3d q = integrate_twist({0.0, 0.0, 0.0}, {M_PI / 2, 0.0, M_PI / 2}, 1.0);
  EXPECT_NEAR(q.x(), 1.0, 1e-12);
  EXPECT_NEAR(q.y(), 1.0, 1e-12);
  EXPECT_NEAR(q.z(), M_PI / 2, 1e-12);
  // Sideways for an omni base.
  const Eigen::Vector3d s = integrate_twist({0.0, 0.0, 0.0}, {0.0, 0.2, 0.0}, 1.0);
  EXPECT_NEAR(s.y(), 0.2, 1e-12);
}

TEST(LocalController, RefusesBadParametersAndEmptyPaths) {
  ControllerParams p;
  p.limits.max_ax = 0.0;
  EXPECT_THAT([&] { LocalController c(p); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("limits.max_ax")));
  LocalController c;
  EXPECT_THAT([&] { c.set_path({}); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("empty")));
  const testing::Building b = testing::two_rooms();
  const Costmap map(b.map, test_robot(), {});
  EXPECT_EQ(c.compute(map, {2.0, 2.0, 0.0}, 0.0).status, ControlStatus::kIdle);
}

TEST(LocalController, RespectsLimitsAndFailsOffThePath) {
  const testing::Building b = testing::two_rooms();
  const Costmap map(b.map, test_robot(), {});
  GlobalPlanner planner;
  const PlanResult plan = planner.plan(map, {1.5, 2.0, 0.0}, {4.0, 2.0, 0.0});
  ASSERT_TRUE(plan.ok()) << plan.message;
  ControllerParams p;
  LocalController c(p);
  c.set_path(plan.path);
  ControlOutput out = c.compute(map, {1.5, 2.0, 0.0}, 0.0);
  EXPECT_EQ(out.status, ControlStatus::kFollowing);
  // From rest: one period of acceleration at most.
  EXPECT_LE(std::abs(out.cmd.vx), p.limits.max_ax * p.control_period + 1e-12);
  EXPECT_GT(out.cmd.vx, 0.0);
  out = c.compute(map, {1.5, 3.2, 0.0}, 0.05);
  EXPECT_EQ(out.status, ControlStatus::kFailed);
  EXPECT_THAT(out.reason, HasSubstr("from the path"));
  EXPECT_EQ(out.cmd.vx, 0.0);
}

struct LoopCase {
  ControllerParams::Drive drive;
  const char* name;
};

class ClosedLoop : public ::testing::TestWithParam<LoopCase> {};

TEST_P(ClosedLoop, ThroughTheDoorToTheGoal) {
  const testing::Building b = testing::two_rooms();
  testing::SimConfig config;
  config.controller.drive = GetParam().drive;
  config.seed = 42;
  const Eigen::Vector3d start(1.5, 1.0, 0.3);
  const Eigen::Vector3d goal(8.2, 3.0, -2.0);
  const testing::RunResult r = testing::run_mission(b.map, b.map, start, goal, config);
  ASSERT_TRUE(r.reached) << GetParam().name << ": " << r.failure;
  EXPECT_FALSE(r.collided);
  EXPECT_LE(r.position_error, 0.05);
  EXPECT_LE(r.heading_error, 2.0 * kDeg);
  EXPECT_EQ(r.replans, 0);
  // It went through the door (x = 5 crossed within it).
  bool through_door = false;
  for (std::size_t i = 1; i < r.trajectory.size(); ++i) {
    if (r.trajectory[i - 1].x() < 5.0 && r.trajectory[i].x() >= 5.0) {
      through_door = std::abs(r.trajectory[i].y() - 2.0) < 0.25;
    }
  }
  EXPECT_TRUE(through_door);
}

TEST_P(ClosedLoop, StopsBeforeAnUnmappedObstacleThenGoesAroundAfterReplanning) {
  const testing::Building b = testing::two_rooms();
  bim::OccupancyGrid truth = b.map;
  // A pallet in the middle of the left room, on the straight path from start to the door.
  const Eigen::Vector2d pallet(3.0, 2.0);
  testing::add_box(truth, pallet, {0.3, 0.3});
  testing::SimConfig config;
  config.controller.drive = GetParam().drive;
  config.seed = 7;
  const Eigen::Vector3d start(1.0, 2.0, 0.0);
  const Eigen::Vector3d goal(7.5, 2.0, 0.0);
  const testing::RunResult r = testing::run_mission(b.map, truth, start, goal, config);
  ASSERT_TRUE(r.reached) << GetParam().name << ": " << r.failure;
  EXPECT_FALSE(r.collided);
  EXPECT_TRUE(r.was_blocked) << "the controller must stop and report blocked before replanning";
  EXPECT_GE(r.replans, 1);
  EXPECT_LE(r.position_error, 0.05);
  EXPECT_LE(r.heading_error, 2.0 * kDeg);
  // It went around: some pose beside the pallet, clear of its 0.6 m square.
  bool beside = false;
  for (const auto& p : r.trajectory) {
    if (std::abs(p.x() - pallet.x()) < 0.1) beside = std::abs(p.y() - pallet.y()) > 0.55;
  }
  EXPECT_TRUE(beside);
}

INSTANTIATE_TEST_SUITE_P(Drives, ClosedLoop,
                         ::testing::Values(LoopCase{ControllerParams::Drive::kOmni, "omni"},
                                           LoopCase{ControllerParams::Drive::kDifferential,
                                                    "differential"}),
                         [](const auto& test_info) { return std::string(test_info.param.name); });

TEST(ClosedLoop, SeededPairsWithUnmappedObstacles) {
  const testing::Building b = testing::make_building(3, 2, 5.0, 0.15, 1.0, 0.05, 21);
  const Costmap map(b.map, test_robot(), {});
  GlobalPlanner planner;
  std::mt19937 rng(2024);
  int successes = 0;
  int collisions = 0;
  int with_obstacles = 0;
  const auto pairs = testing::random_pairs(map, 20, 4.0, rng);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto& [start, goal] = pairs[k];
    const PlanResult plan = planner.plan(map, start, goal);
    ASSERT_TRUE(plan.ok()) << plan.message;
    bim::OccupancyGrid truth = b.map;
    std::uniform_int_distribution<int> count(1, 2);
    with_obstacles +=
        testing::add_obstacles_on_path(truth, plan.path, b.doors, count(rng), 1.3, rng).empty() ? 0
                                                                                                : 1;
    testing::SimConfig config;
    config.seed = static_cast<std::uint32_t>(100 + k);
    const testing::RunResult r = testing::run_mission(b.map, truth, start, goal, config);
    successes += r.reached && r.position_error <= 0.05 && r.heading_error <= 2.0 * kDeg ? 1 : 0;
    collisions += r.collided ? 1 : 0;
    std::cout << "pair " << k << ": " << (r.reached ? "reached" : "FAILED") << " in " << r.time
              << " s, error " << r.position_error << " m / " << r.heading_error / kDeg << " deg, "
              << r.replans << " replans" << (r.failure.empty() ? "" : ", ") << r.failure << "\n";
  }
  RecordProperty("successes", successes);
  EXPECT_GE(with_obstacles, 15) << "most runs must meet an unmapped obstacle";
  EXPECT_GE(successes, 18);
  EXPECT_EQ(collisions, 0);
}

}  // namespace
}  // namespace concert::nav
