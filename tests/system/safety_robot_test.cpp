// Safety with the real simulated robot on one machine (loopback DDS): discovery, modelgen, the
// robot service (MuJoCo sim of deploy/demo/drill_robot.yaml) and safety. Holding still at the
// generated model must not trip the limits watchdog; a robot process killed hard (no goodbye)
// goes silent and the safety service stops, naming it.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <string>
#include <thread>

#include "helpers.hpp"
#include "process.hpp"

namespace concert::system_test {
namespace {

using namespace std::chrono_literals;

TEST(SafetyWithRobot, NoFalseStopWhileHoldingThenKilledRobotIsNamed) {
  const std::vector<std::string> env = {"CONCERT_HOST=rt-pc"};
  testing::Process safety(dies_with_test({SAFETY_BINARY}), env);
  testing::Process discovery(dies_with_test({DISCOVERY_BINARY}), env);
  testing::Process modelgen(dies_with_test({MODELGEN_BINARY}), env);
  testing::Process robot(
      dies_with_test({ROBOT_BINARY, "--assembly",
                      std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml"}),
      env);
  const auto logs = [&] {
    return "\n--- safety:\n" + safety.err() + "--- robot:\n" + robot.err() + robot.out() +
           "--- modelgen:\n" + modelgen.err() + "--- discovery:\n" + discovery.err();
  };

  // The robot's scan -> tree -> model v1 -> the safety service enforces its joint limits.
  ASSERT_TRUE(wait_for_err(safety, "safety: limits of model v1 (14 joints)", 60s)) << logs();
  // The robot holds at the new model for a while: its joint states stay within the limits
  // and its heartbeats keep coming (bounded observation, no timing assertion).
  for (int i = 0; i < 30; ++i) {
    std::this_thread::sleep_for(100ms);
    ASSERT_TRUE(robot.running()) << logs();
  }
  EXPECT_EQ(safety.err().find("STOPPED"), std::string::npos) << logs();

  kill(robot.pid(), SIGKILL);
  EXPECT_TRUE(wait_for_err(safety, "safety: STOPPED: liveliness: robot@rt-pc silent for", 15s))
      << logs();
  EXPECT_EQ(safety.stop(10s), 0);
  modelgen.stop(10s);
  discovery.stop(10s);
}

}  // namespace
}  // namespace concert::system_test
