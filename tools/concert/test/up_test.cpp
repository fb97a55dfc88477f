// `concert up`, `concert status` and `concert sim` with the real services: the whole stack
// on this machine, a hot swap, a bad file refused without disturbing it, a killed service
// restarted, a clean stop.
#include <gtest/gtest.h>

#include <signal.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>

#include "concert/idl_schema/cdr.hpp"
#include "process.hpp"

namespace concert {
namespace {

using namespace std::chrono_literals;
using testing::Process;
namespace fs = std::filesystem;

class UpTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/concert-up-test-XXXXXX";
    run_ = mkdtemp(tmpl);
    env_ = {"XDG_RUNTIME_DIR=" + run_};
  }
  void TearDown() override { fs::remove_all(run_); }

  testing::Outcome concert(std::vector<std::string> args, std::chrono::seconds timeout = 90s) {
    args.insert(args.begin(), CONCERT_BIN);
    const auto r = testing::run(args, timeout, env_);
    EXPECT_NE(r.code, -1) << "concert did not terminate: " << args[1];
    return r;
  }

  std::string run_;
  std::vector<std::string> env_;
};

TEST_F(UpTest, BadInputIsRefusedBeforeAnythingStarts) {
  const std::string bad = run_ + "/bad.yaml";
  std::ofstream(bad) << "modules:\n  - {name: base, key: concert_mobile_base_hub}\n"
                        "  - {name: x, key: no_such_module, parent: base, connector: 5}\n";
  auto r = concert({"up", "--assembly", bad, "--duration", "5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no_such_module"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
  r = concert({"up", "--world", run_ + "/missing.yaml", "--duration", "5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("missing.yaml"), std::string::npos) << r.err;
  r = concert({"up", "--backend", "ethercat"});
  EXPECT_EQ(r.code, 2);
  r = concert({"up", "--domain", "300"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("'300' is not a DDS domain id"), std::string::npos) << r.err;
  r = concert({"sim", "swap", CONCERT_SOURCE_DIR "/deploy/demo/sanding_robot.yaml"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("concert up"), std::string::npos) << r.err;
}

TEST_F(UpTest, WholeStackSwapRestartAndStop) {
  Process up({CONCERT_BIN, "up", "--assembly", CONCERT_SOURCE_DIR "/deploy/demo/drill_robot.yaml", "--duration", "150"},
             env_);
  auto r = concert({"status", "--until-version", "1", "--timeout", "60"});
  ASSERT_EQ(r.code, 0) << r.out << r.err << up.out();
  EXPECT_NE(r.out.find("robot@"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("modelgen@"), std::string::npos) << r.out;

  r = concert({"status", "--json", "--timeout", "1.5"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::map<std::string, idl::Json> by_service;
  for (const auto& s : idl::Json::parse(r.out)) by_service[s.at("service").get<std::string>()] = s;
  for (const char* service : {"discovery", "modelgen", "robot"}) {
    ASSERT_TRUE(by_service.count(service)) << service << " missing: " << r.out;
    EXPECT_EQ(by_service[service].at("state"), "ready") << r.out;
    EXPECT_TRUE(by_service[service].contains("host"));
  }
  EXPECT_EQ(by_service["robot"].at("model_version"), 1);

  // A malformed assembly is refused and the running stack keeps its model.
  const std::string bad = run_ + "/bad.yaml";
  std::ofstream(bad) << "modules: [ {name: base, key: concert_mobile_base_hub}, {name: t, key: concert_drill, parent: base, connector: 9} ]\n";
  r = concert({"sim", "swap", bad});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("nothing changed"), std::string::npos) << r.err;

  r = concert({"sim", "swap", CONCERT_SOURCE_DIR "/deploy/demo/sanding_robot.yaml"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = concert({"status", "--until-version", "2", "--timeout", "60"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;

  // A service that dies is restarted (with back-off) and the stack is whole again.
  std::smatch m;
  const std::string log = up.out();
  ASSERT_TRUE(std::regex_search(log, m, std::regex("started discovery \\(pid ([0-9]+)\\)"))) << log;
  ASSERT_EQ(kill(std::stoi(m[1]), SIGKILL), 0);
  ASSERT_TRUE(up.wait_for_output("discovery was killed by signal 9; restarting in", 10s)) << up.out();
  ASSERT_TRUE(up.wait_for_output("(restart 1", 1s));
  const std::regex started("started discovery");
  for (int i = 0; i < 100; ++i) {
    const std::string out = up.out();
    if (std::distance(std::sregex_iterator(out.begin(), out.end(), started), std::sregex_iterator()) >= 2) break;
    std::this_thread::sleep_for(100ms);
  }
  r = concert({"status", "--json", "--timeout", "2.5"});
  bool discovery_back = false;
  for (const auto& s : idl::Json::parse(r.out)) {
    if (s.at("service") == "discovery" && s.at("state") == "ready") discovery_back = true;
  }
  EXPECT_TRUE(discovery_back) << r.out << up.out();

  EXPECT_EQ(up.stop(20s), 0);
  EXPECT_NE(up.out().find("stopped robot"), std::string::npos) << up.out();
}

}  // namespace
}  // namespace concert
