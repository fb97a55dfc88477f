// No allocation on the loop thread: this binary replaces the global operator new/delete and
// malloc/free, counts what the thread running RobotCore::cycle() allocates while it cycles,
// and drives the core through every controller, a trajectory, a model switch and a world
// switch from another thread.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <thread>

#include "allocation_counter.hpp"
#include "robot/robot_core.hpp"
#include "test_helpers.hpp"

namespace concert::robot {
namespace {

using test::read_fixture;

/// Runs `cycles` cycles on a loop thread that counts its allocations; returns the count.
std::uint64_t cycles_allocating(RobotCore& core, int cycles) {
  std::uint64_t counted = 0;
  std::thread loop([&] {
    const concert::test::CountAllocations allocations;
    for (int i = 0; i < cycles; ++i) {
      core.cycle();
    }
    counted = allocations.count();
  });
  loop.join();
  return counted;
}

TEST(NoAllocation, CountingWorks) {
  std::uint64_t counted = 0;
  std::thread t([&] {
    void* m = nullptr;
    std::vector<double>* p = nullptr;
    {
      const concert::test::CountAllocations allocations;
      p = new std::vector<double>(100);
      m = std::malloc(64);
      counted = allocations.count();
    }
    std::free(m);
    delete p;
  });
  t.join();
  EXPECT_EQ(counted, 3u);  // the vector object, its storage, malloc
}

TEST(NoAllocation, EveryControllerModeAndSwitchCyclesWithoutAllocating) {
  SimParams params;
  params.initial_positions = {{"J2_A", 0.4}, {"J3_A", 0.5}};
  SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, params);
  RobotCore core(sim);
  const std::string urdf = read_fixture("mobile_drill.urdf");
  EXPECT_EQ(cycles_allocating(core, 200), 0u) << "no model: holding the hardware";
  core.set_model(urdf, 1);
  EXPECT_EQ(cycles_allocating(core, 2000), 0u) << "hold (with the model switch)";

  core.command_joints({1,
                       {{"J1_A", DriveMode::kPosition, 0.3, 0, 0, 0, 0},
                        {"J4_B", DriveMode::kVelocity, 0, 0.5, 0, 0, 0},
                        {"J5_B", DriveMode::kEffort, 0, 0, 1.0, 0, 0},
                        {"J6_B", DriveMode::kImpedance, 0.2, 0, 0, 50, 2}}});
  EXPECT_EQ(cycles_allocating(core, 2000), 0u) << "joint position/velocity/effort/impedance";

  CartesianCommand cart;
  cart.model_version = 1;
  cart.target_pose = core.state().end_effector_pose;
  cart.target_pose.translation().z() -= 0.05;
  cart.admittance.enabled = true;
  cart.admittance.force_setpoint = 5.0;
  core.command_cartesian(cart);
  EXPECT_EQ(cycles_allocating(core, 2000), 0u) << "Cartesian impedance with admittance";

  core.command_gravity_compensation(1);
  EXPECT_EQ(cycles_allocating(core, 2000), 0u) << "gravity compensation";

  core.hold();
  core.command_base({1, 0.2, 0.0, 0.1});
  EXPECT_EQ(cycles_allocating(core, 2000), 0u) << "base velocity";

  JointTrajectory t;
  t.model_version = 1;
  t.request_id = 7;
  t.joints = {"J1_A", "J2_A", kBaseX, kBaseY, kBaseYaw};
  const RobotState now = core.state();
  const double j1 = now.position[test::hw_index(now, "J1_A")];
  const double j2 = now.position[test::hw_index(now, "J2_A")];
  for (int k = 0; k <= 20; ++k) {
    const double s = k / 20.0;
    t.samples.push_back({2.0 * s,
                         {j1 + 0.2 * s, j2, now.odometry.x + 0.1 * s, now.odometry.y, now.odometry.yaw},
                         {0.1, 0.0, 0.05, 0.0, 0.0}});
  }
  core.command_trajectory(t);
  EXPECT_EQ(cycles_allocating(core, 3000), 0u) << "joint trajectory with the base";

  core.set_model(urdf, 2);  // a new version of the same model: switched at a cycle boundary
  EXPECT_EQ(cycles_allocating(core, 500), 0u) << "model switch";
  World world;
  world.obstacles.push_back(
      {.name = "crate", .size = {0.5, 0.5, 0.5}, .position = {3.0, 0.0, 0.25}});
  // A moving obstacle: the sim moves it from simulated time on the loop thread.
  world.obstacles.push_back({.name = "cart",
                             .size = {0.4, 0.4, 0.8},
                             .position = {-3.0, 0.0, 0.4},
                             .path = concert::world::ObstaclePath{{{-3.0, 2.0}, {-2.0, 2.0}}, 0.5,
                                                                  concert::world::ObstaclePath::Mode::kLoop}});
  sim.set_world(world);
  EXPECT_EQ(cycles_allocating(core, 500), 0u) << "world switch, moving obstacle";
  EXPECT_EQ(core.state().model_version, 2u);
}

}  // namespace
}  // namespace concert::robot
