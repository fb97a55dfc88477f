// Hot swaps between 30 seeded random robots of the project database (simbus::random_robot:
// arms of 3-7 joints, links, bends, risers, every tool with an ESC), in one process: the
// simulator swaps the mounted robot as the bus would, the robot core takes each generated model
// (read by role), and the safety service's own watchdog (its core, fed every 10th joint sample
// on the robot's clock) watches it all with the shipped safety.yaml. No swap may trip it, and
// every robot must arrive ready. Simulated time only (3 s per robot, as fast as the machine).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/simbus/random_robot.hpp"
#include "planner/environment.hpp"
#include "planner/fixtures.hpp"
#include "planner/planner.hpp"
#include "robot/robot_core.hpp"
#include "safety/params.hpp"
#include "safety/safety_monitor.hpp"

namespace concert::system_test {
namespace {

namespace fs = std::filesystem;

struct Robot {
  unsigned seed = 0;
  std::string yaml;  // the assembly, for the message of a failure
  sim::SimulatedRobot mounted;
  std::shared_ptr<const model::RobotModel> model;
};

std::vector<Robot> random_robots(unsigned count) {
  const fs::path db = fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db";
  const sim::AssemblyBuilder builder({db});
  const module_db::ModuleDatabase modules = module_db::load_module_database(db);
  std::vector<Robot> robots;
  for (unsigned seed = 1; seed <= count; ++seed) {
    std::mt19937 rng(seed);
    Robot r;
    r.seed = seed;
    r.yaml = simbus::assembly_to_yaml(simbus::random_robot(rng));
    r.mounted = builder.build_from_text(r.yaml, "random_robot_" + std::to_string(seed) + ".yaml");
    model_generation::GeneratedModel m = model_generation::ModelGenerator(modules).generate(r.mounted.tree);
    m.version = seed;
    r.model = model::RobotModel::build(m.description());
    robots.push_back(std::move(r));
  }
  return robots;
}

std::string causes_of(const safety::SafetyStatus& s) {
  std::string out;
  for (const std::string& c : s.causes) out += (out.empty() ? "" : "; ") + c;
  return out;
}

// Feeds `watchdog` the core's joint state on the robot's clock.
void watch(safety::SafetyMonitor& watchdog, safety::TimePoint t0, const robot::RobotState& s) {
  safety::JointSample sample;
  sample.model_version = static_cast<std::uint32_t>(s.model_version);
  sample.name = s.joint_names;
  sample.position = s.position;
  sample.velocity = s.velocity;
  sample.effort = s.effort;
  sample.stamp_ns = std::llround(s.time * 1e9);
  (void)watchdog.on_joint_state(
      sample, t0 + std::chrono::duration_cast<safety::Clock::duration>(std::chrono::duration<double>(s.time)));
}

TEST(RandomSwaps, ThirtyRandomRobotsEachArriveReadyAndNoneTripsTheSafetyLayer) {
  const std::vector<Robot> robots = random_robots(30);
  const safety::Params params =
      safety::load_params(std::string(CONCERT_SOURCE_DIR) + "/services/safety/config/safety.yaml");
  sim::SimHardware hardware(robots.front().mounted, world::World{}, sim::SimParams{});
  robot::RobotCore core(hardware);
  const safety::TimePoint t0 = safety::Clock::now();
  safety::SafetyMonitor watchdog(params, t0);
  for (const Robot& r : robots) {
    SCOPED_TRACE("random robot " + std::to_string(r.seed) + ":\n" + r.yaml);
    if (r.seed > 1) (void)hardware.swap_model(r.mounted);  // false: the same robot again
    for (int c = 0; c < 10; ++c) core.cycle();  // the loop switches to what is mounted
    ASSERT_NO_THROW(core.set_model(r.model));
    watchdog.set_model(r.seed, r.model->limits());
    for (int c = 0; c < 3000; ++c) {
      core.cycle();
      if (c % 10 != 0) continue;
      watch(watchdog, t0, core.state());
    }
    ASSERT_EQ(watchdog.status().mode, safety::Mode::kRunning) << causes_of(watchdog.status());
    const robot::RobotState s = core.state();
    ASSERT_TRUE(s.ready) << s.message;
    EXPECT_EQ(s.model_version, r.seed);
  }
}

// A drilling approach on each random robot that carries a drill: a wall 2.2 m ahead, an area
// 1.5 m high on it, the planner's core with generous budgets. Either the planner refuses it
// with a reason (nothing is sent), or the robot executes the plan to the end under the safety
// service's watchdog without a stop.
TEST(RandomSwaps, ADrillingApproachOnEachRandomRobotWithADrillExecutesOrIsRefusedWithAReason) {
  const std::vector<Robot> robots = random_robots(30);
  const safety::Params params =
      safety::load_params(std::string(CONCERT_SOURCE_DIR) + "/services/safety/config/safety.yaml");
  int planned = 0, refused = 0;
  for (const Robot& r : robots) {
    if (r.model->end_effectors(model::EndEffectorKind::kDrill).empty()) continue;
    SCOPED_TRACE("random robot " + std::to_string(r.seed) + ":\n" + r.yaml);
    sim::SimHardware hardware(r.mounted, world::World{}, sim::SimParams{});
    robot::RobotCore core(hardware);
    ASSERT_NO_THROW(core.set_model(r.model));
    for (int c = 0; c < 1000; ++c) core.cycle();  // standing on its wheels
    const safety::TimePoint t0 = safety::Clock::now();
    safety::SafetyMonitor watchdog(params, t0);
    watchdog.set_model(r.seed, r.model->limits());

    const planner::Params plan_params = planner::fixtures::generous(r.seed);
    planner::Planner planner(plan_params);
    planner.set_model(r.model->description());
    planner::Environment environment(plan_params.octomap_resolution);
    planner::World site;
    site.boxes.push_back(planner::fixtures::wall_at(2.2));
    environment.add_world(site);
    planner.set_environment(std::move(environment));
    const auto& k = planner.model()->kinematics();
    Eigen::VectorXd start = Eigen::VectorXd::Zero(planner.model()->full_dof());
    const robot::RobotState now = core.state();
    for (std::size_t j = 0; j < now.joint_names.size(); ++j) {
      if (const auto i = k.joint_index(now.joint_names[j])) start[*i] = now.position[j];
    }
    start[0] = now.odometry.x;
    start[1] = now.odometry.y;
    start[2] = now.odometry.yaw;
    planner::PlanRequest request;
    request.request_id = 1;
    request.model_version = r.seed;
    request.goals.push_back({planner::fixtures::drilling_area(2.2, 0.0, 1.5)});
    const planner::PlanResult plan = planner.plan(request, start);
    if (plan.status != planner::Status::kSucceeded) {
      EXPECT_FALSE(plan.reason.empty()) << "refused without a reason";
      std::cout << "random robot " << r.seed << ": refused: " << plan.reason << "\n";
      ++refused;
      continue;
    }
    ++planned;
    std::cout << "random robot " << r.seed << ": planned (" << plan.goals.at(0).drives << ")\n";
    const planner::Trajectory& t = plan.goals.at(0).trajectory;
    robot::JointTrajectory command;
    command.request_id = 7;
    command.model_version = r.seed;
    command.source = "random_swaps_test";
    command.joints = t.joint_names;
    for (const planner::TrajectoryPoint& p : t.points) {
      command.samples.push_back({p.time, std::vector<double>(p.q.data(), p.q.data() + p.q.size()),
                                 std::vector<double>(p.qd.data(), p.qd.data() + p.qd.size())});
    }
    ASSERT_NO_THROW(core.command_trajectory(command));
    // Bounded: the trajectory's duration and 10 s of simulated time to settle.
    const int cycles = static_cast<int>((t.points.back().time + 10.0) / 0.001);
    robot::TrajectoryState state = robot::TrajectoryState::kExecuting;
    for (int c = 0; c < cycles; ++c) {
      core.cycle();
      if (c % 10 == 0) watch(watchdog, t0, core.state());
      state = core.state().trajectory.state;
      if (c > 100 && state != robot::TrajectoryState::kExecuting) break;
    }
    EXPECT_EQ(state, robot::TrajectoryState::kSucceeded);
    ASSERT_EQ(watchdog.status().mode, safety::Mode::kRunning) << causes_of(watchdog.status());
  }
  std::cout << "random robots with a drill: " << planned << " approaches executed, " << refused
            << " refused with a reason\n";
  EXPECT_GT(planned + refused, 0) << "no random robot carries a drill";
}

}  // namespace
}  // namespace concert::system_test
