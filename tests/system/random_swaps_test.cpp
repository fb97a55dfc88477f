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
      const robot::RobotState s = core.state();
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
    ASSERT_EQ(watchdog.status().mode, safety::Mode::kRunning) << causes_of(watchdog.status());
    const robot::RobotState s = core.state();
    ASSERT_TRUE(s.ready) << s.message;
    EXPECT_EQ(s.model_version, r.seed);
  }
}

}  // namespace
}  // namespace concert::system_test
