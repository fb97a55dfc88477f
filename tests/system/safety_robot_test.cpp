// Safety with the real simulated robot on one machine (loopback DDS): discovery, modelgen, the
// robot service (MuJoCo sim of deploy/demo/drill_robot.yaml) and safety. Holding still at the
// generated model must not trip the limits watchdog; a robot process killed hard (no goodbye)
// goes silent and the safety service stops, naming it. Between the two, an operator e-stop
// (concert safety verbs) makes the robot hold, and a reset releases it.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <sstream>
#include <string>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "helpers.hpp"
#include "process.hpp"
#include "safety/cli.hpp"

namespace concert::system_test {
namespace {

/// `concert safety ARGS...` in this process.
int safety_cli(std::vector<std::string> args, std::ostream& out, std::ostream& err) {
  args.insert(args.begin(), "safety");
  return cli::run("concert", {safety::register_verbs}, args, out, err);
}

using namespace std::chrono_literals;

/// Waits (bounded) for a status of the robot service whose message is `text`.
bool wait_robot_note(concert::dds::Reader<msg::ServiceStatus>& statuses, const std::string& text,
                     std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    const auto s = statuses.wait(100ms);
    if (s && s->service() == "robot" && s->message() == text) return true;
  }
  return false;
}

TEST(SafetyWithRobot, NoFalseStopEStopHoldsResetReleasesKilledRobotNamed) {
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

  // E-stop from the operator verbs -> safety STOPPED -> the robot holds and says why; released
  // and reset -> the robot is released.
  {
    concert::dds::Participant p({.name = "safety_robot_test"});
    concert::dds::Reader<msg::ServiceStatus> statuses(p, concert::dds::topics::status);
    std::ostringstream out, err;
    ASSERT_EQ(safety_cli({"estop", "--source", "front-left", "--reason", "test"}, out, err), 0)
        << err.str();
    EXPECT_TRUE(wait_robot_note(
        statuses, "safety stop: holding (estop: button front left engaged (test))", 10s))
        << logs();
    ASSERT_EQ(safety_cli({"estop", "--source", "front-left", "--release"}, out, err), 0)
        << err.str();
    ASSERT_EQ(safety_cli({"reset", "--source", "system test"}, out, err), 0)
        << out.str() << err.str();
    EXPECT_TRUE(wait_robot_note(statuses, "safety stop released", 10s)) << logs();
  }

  kill(robot.pid(), SIGKILL);
  EXPECT_TRUE(wait_for_err(safety, "safety: STOPPED: liveliness: robot@rt-pc silent for", 15s))
      << logs();
  EXPECT_EQ(safety.stop(10s), 0);
  modelgen.stop(10s);
  discovery.stop(10s);
}

}  // namespace
}  // namespace concert::system_test
