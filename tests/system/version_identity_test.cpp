// Model version identity across a modelgen crash, with the whole stack up in simulation
// (`concert up`): at model version 2, modelgen is killed with SIGKILL; `concert up` restarts it;
// it comes back at the same version and hash (learned from what the services on the wire run),
// every service agrees and none refused anything; the next hot swap gets a new, higher version
// everywhere. Before, the restarted modelgen published "version 1" again and a later, different
// model reused "version 2".
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "concert/idl_schema/cdr.hpp"
#include "helpers.hpp"
#include "process.hpp"

namespace concert::system_test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using testing::Process;
namespace fs = std::filesystem;

struct Ran {
  int code;
  std::string out, err;
};

/// service -> {version, hash, refusals, state} of every service on the domain.
struct Seen {
  uint32_t version;
  std::string hash;
  uint32_t refusals;
  std::string state;
};

class VersionIdentity : public ::testing::Test {
 protected:

  Ran concert(std::vector<std::string> args, std::chrono::seconds timeout = 120s) {
    args.insert(args.begin(), CONCERT_BIN);
    Process p(dies_with_test(args), env_);
    const auto code = p.wait(timeout);
    EXPECT_TRUE(code.has_value()) << "concert did not terminate: " << args[1];
    return {code.value_or(-1), p.out(), p.err()};
  }

  std::map<std::string, Seen> statuses() {
    const Ran r = concert({"status", "--json", "--wait-ms", "2000"});
    std::map<std::string, Seen> out;
    if (r.code != 0) return out;
    for (const auto& s : idl::Json::parse(r.out)) {
      out[s.at("service").get<std::string>()] = {
          s.at("model_version").get<uint32_t>(), s.at("model_hash").get<std::string>(),
          s.at("refusals").get<uint32_t>(), s.at("state").get<std::string>()};
    }
    return out;
  }

  testing::TempDir run_dir_{"concert-version-test"};  ///< XDG_RUNTIME_DIR of this test's stack
  const std::string run_ = run_dir_.path();
  const std::vector<std::string> env_{"XDG_RUNTIME_DIR=" + run_};
};

int last_pid(const std::string& log, const std::string& service) {
  const std::regex started("started " + service + " \\(pid ([0-9]+)\\)");
  int pid = -1;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), started);
       it != std::sregex_iterator(); ++it) {
    pid = std::stoi((*it)[1]);
  }
  return pid;
}

TEST_F(VersionIdentity, KilledModelgenComesBackAtTheSameVersionAndHash) {
  Process up(dies_with_test({CONCERT_BIN, "up", "--assembly",
                             CONCERT_SOURCE_DIR "/deploy/demo/drill_robot.yaml"}),
             env_);
  const auto logs = [&] { return "\n--- concert up:\n" + up.out() + up.err(); };
  Ran r = concert({"status", "--until-version", "1", "--timeout-ms", "90000"});
  ASSERT_EQ(r.code, 0) << r.out << r.err << logs();
  r = concert({"sim", "swap", CONCERT_SOURCE_DIR "/deploy/demo/sanding_robot.yaml"});
  ASSERT_EQ(r.code, 0) << r.err << logs();
  r = concert({"status", "--until-version", "2", "--timeout-ms", "90000"});
  ASSERT_EQ(r.code, 0) << r.out << r.err << logs();

  auto before = statuses();
  ASSERT_TRUE(before.count("modelgen") && before.count("robot") && before.count("planner") &&
              before.count("safety"))
      << logs();
  const std::string hash = before["modelgen"].hash;
  ASSERT_FALSE(hash.empty());
  for (const char* service : {"modelgen", "robot", "planner", "safety"}) {
    EXPECT_EQ(before[service].version, 2u) << service;
    EXPECT_EQ(before[service].hash, hash) << service;
  }

  // kill -9 modelgen; `concert up` restarts it.
  const int pid = last_pid(up.out(), "modelgen");
  ASSERT_GT(pid, 0) << logs();
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (last_pid(up.out(), "modelgen") == pid && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_NE(last_pid(up.out(), "modelgen"), pid) << "modelgen was not restarted" << logs();

  // It comes back at version 2 with the same hash; everyone agrees; nobody refused anything.
  std::map<std::string, Seen> after;
  for (int i = 0; i < 15; ++i) {
    after = statuses();
    if (after.count("modelgen") && after["modelgen"].state == "ready" &&
        after["modelgen"].version != 0) {
      break;
    }
  }
  ASSERT_TRUE(after.count("modelgen"));
  EXPECT_EQ(after["modelgen"].state, "ready") << logs();
  EXPECT_EQ(after["modelgen"].version, 2u) << logs();
  EXPECT_EQ(after["modelgen"].hash, hash) << logs();
  for (const char* service : {"robot", "planner", "safety"}) {
    EXPECT_EQ(after[service].version, 2u) << service;
    EXPECT_EQ(after[service].hash, hash) << service;
    EXPECT_EQ(after[service].refusals, 0u) << service << logs();
  }
  r = concert({"status", "--check", "--wait-ms", "2000"});
  EXPECT_EQ(r.code, 0) << r.out << r.err;

  // The next hot swap: a new, higher version, everywhere.
  r = concert({"sim", "swap", CONCERT_SOURCE_DIR "/deploy/demo/drill_robot.yaml"});
  ASSERT_EQ(r.code, 0) << r.err << logs();
  r = concert({"status", "--until-version", "3", "--timeout-ms", "90000"});
  ASSERT_EQ(r.code, 0) << r.out << r.err << logs();
  const auto swapped = statuses();
  for (const char* service : {"modelgen", "robot", "planner", "safety"}) {
    ASSERT_TRUE(swapped.count(service)) << service;
    EXPECT_EQ(swapped.at(service).version, 3u) << service;
    EXPECT_NE(swapped.at(service).hash, hash) << service;
    EXPECT_EQ(swapped.at(service).hash, swapped.at("modelgen").hash) << service;
  }
  r = concert({"status", "--check", "--wait-ms", "2000"});
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("safety: RUNNING")) << r.out;

  // A stack whose safety layer is stopped is not ready to work: --check says so and why.
  r = concert({"safety", "estop"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  r = concert({"status", "--check", "--wait-ms", "2000"});
  EXPECT_EQ(r.code, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("safety is STOPPED: estop: software engaged")) << r.err;
  EXPECT_EQ(up.stop(30s), 0) << logs();
}

}  // namespace
}  // namespace concert::system_test
