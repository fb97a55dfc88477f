// `concert up`, `concert status`, `concert sim` and `concert plan` with the real services: the
// whole stack on this machine, a hot swap, a bad file refused without disturbing it, a killed
// service restarted, a clean stop; the planner planning against the world the simulator
// publishes, `concert sim world` (over DDS) changing the plan, and `concert plan --execute`
// running through the robot's joint-trajectory command; a collaborative transport with the
// simulated person (`concert plan posture`, `concert sim person`, `concert collab mode`).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <signal.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include <Eigen/Core>

#include "concert/dds/endpoint.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "process.hpp"

namespace concert {
namespace {

using ::testing::HasSubstr;

using namespace std::chrono_literals;
using testing::Process;
namespace fs = std::filesystem;

class UpTest : public ::testing::Test {
 protected:

  testing::Outcome concert(std::vector<std::string> args, std::chrono::seconds timeout = 90s) {
    args.insert(args.begin(), CONCERT_BIN);
    const auto r = testing::run(args, timeout, env_);
    EXPECT_NE(r.code, -1) << "concert did not terminate: " << args[1];
    return r;
  }

  std::string write_file(const std::string& name, const std::string& text) {
    const std::string path = run_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }

  testing::TempDir run_dir_{"concert-up-test"};  ///< XDG_RUNTIME_DIR of this test's stack
  const std::string run_ = run_dir_.path();
  const std::vector<std::string> env_{"XDG_RUNTIME_DIR=" + run_};
};

constexpr const char* kWall =
    "walls:\n"
    "  - {name: wall, size: [0.2, 6.0, 2.5], position: [2.1, 0.0, 1.25]}\n";

TEST_F(UpTest, BadInputIsRefusedBeforeAnythingStarts) {
  const std::string bad = run_ + "/bad.yaml";
  std::ofstream(bad) << "modules:\n  - {name: base, key: concert_mobile_base_hub}\n"
                        "  - {name: x, key: no_such_module, parent: base, connector: 5}\n";
  auto r = concert({"up", "--assembly", bad, "--duration", "5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("no_such_module"));
  EXPECT_THAT(r.err, HasSubstr(bad));
  r = concert({"up", "--world", run_ + "/missing.yaml", "--duration", "5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("missing.yaml"));
  r = concert({"up", "--backend", "ethercat"});
  EXPECT_EQ(r.code, 2);
  r = concert({"up", "--domain", "300"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("'300' is not a DDS domain id"));
  // A world with an unknown ArUco dictionary is refused before anything is sent.
  r = concert({"sim", "world", CONCERT_SOURCE_DIR "/libs/world/test/fixtures/marks_bad_dictionary.yaml"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("world rejected, nothing changed"));
  EXPECT_THAT(r.err, HasSubstr("marks[0].dictionary: unknown ArUco dictionary 'DICT_3X3_9'"));
  r = concert({"sim", "swap", CONCERT_SOURCE_DIR "/deploy/demo/sanding_robot.yaml"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("concert up"));
}

TEST_F(UpTest, WholeStackSwapRestartAndStop) {
  Process up({CONCERT_BIN, "up", "--assembly", CONCERT_SOURCE_DIR "/deploy/demo/drill_robot.yaml", "--duration", "150"},
             env_);
  auto r = concert({"status", "--until-version", "1", "--timeout", "60"});
  ASSERT_EQ(r.code, 0) << r.out << r.err << up.out();
  EXPECT_THAT(r.out, HasSubstr("robot@"));
  EXPECT_THAT(r.out, HasSubstr("modelgen@"));

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
  EXPECT_THAT(r.err, HasSubstr("nothing changed"));

  r = concert({"sim", "swap", CONCERT_SOURCE_DIR "/deploy/demo/sanding_robot.yaml"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = concert({"status", "--until-version", "2", "--timeout", "60"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  // The simulator keeps what it mounted for a restart (the robot service's --keep-swaps over
  // the run folder's copy): the modules stay bolted on when the software dies.
  const char* domain = std::getenv("CONCERT_DOMAIN_ID");
  const fs::path kept = fs::path(run_) / (std::string("concert-d") + (domain ? domain : "0")) / "assembly.yaml";
  std::ifstream kept_in(kept), sanding_in(CONCERT_SOURCE_DIR "/deploy/demo/sanding_robot.yaml");
  std::stringstream kept_text, sanding_text;
  kept_text << kept_in.rdbuf();
  sanding_text << sanding_in.rdbuf();
  EXPECT_EQ(kept_text.str(), sanding_text.str()) << kept;

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
  EXPECT_THAT(up.out(), HasSubstr("stopped robot"));
}

TEST_F(UpTest, WorldFromTheSimulatorChangesThePlanAndExecutionRunsInTheRobot) {
  dds::Participant p({.name = "stack_test"});
  std::mutex m;
  std::map<uint32_t, msg::PlanResult> final_plans;
  std::map<uint32_t, msg::TrajectoryStatus> trajectories;
  dds::Reader<msg::PlanResult> plans(p, dds::topics::plan_result, [&](const msg::PlanResult& r, const auto&) {
    if (r.state() != msg::PLAN_SUCCEEDED && r.state() != msg::PLAN_FAILED) return;
    std::lock_guard lock(m);
    final_plans[r.request_id()] = r;
  });
  dds::Reader<msg::TrajectoryStatus> robot(p, dds::topics::trajectory_status,
                                           [&](const msg::TrajectoryStatus& s, const auto&) {
                                             std::lock_guard lock(m);
                                             trajectories[s.request_id()] = s;
                                           });
  auto final_plan = [&](uint32_t id) {
    std::lock_guard lock(m);
    const auto it = final_plans.find(id);
    return it == final_plans.end() ? std::nullopt : std::optional<msg::PlanResult>(it->second);
  };
  auto plan_until = [&](uint32_t id) {
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (!final_plan(id) && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(20ms);
    return final_plan(id);
  };

  Process up({CONCERT_BIN, "up", "--assembly", CONCERT_SOURCE_DIR "/deploy/demo/drill_robot.yaml", "--world",
              write_file("wall.yaml", kWall), "--duration", "240"},
             env_);
  auto r = concert({"status", "--until-version", "1", "--timeout-ms", "90000"});
  ASSERT_EQ(r.code, 0) << r.out << r.err << up.out();

  // Planned against the wall the simulator published; the drilling area is 1.6 m to the side,
  // so the base drives there.
  r = concert({"plan", "drill", "--at", "2.0", "1.6", "1.2", "--request-id", "101", "--timeout", "60"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto open = plan_until(101);
  ASSERT_TRUE(open.has_value());
  ASSERT_EQ(open->state(), msg::PLAN_SUCCEEDED) << open->reason();
  ASSERT_GT(open->trajectory().size(), 1u);
  const double x = open->trajectory().back().position()[0];
  const double y = open->trajectory().back().position()[1];

  // A crate where the base stood: sent to the simulator, which republishes the world.
  const std::string crate = write_file("crate.yaml", std::string(kWall) + "obstacles:\n  - {name: crate, size: [0.8, 0.8, 0.6], position: [" +
                                                    std::to_string(x) + ", " + std::to_string(y) + ", 0.3]}\n");
  r = concert({"sim", "world", crate});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("world version 2: 1 walls, 1 obstacles"));
  // The planner takes the world from the topic; plan again until its answer reflects it
  // (bounded: a few requests at most, the world arrives within milliseconds). The same request
  // succeeded before the crate; now the base stands elsewhere, or the posture search names the
  // map as what kept every posture off the task. Which of the two depends on where the first
  // plan left the base: from some of those spots no posture the search draws within its budget
  // stands clear of the crate (CI, and a fresh clone here: 5 requests, each rejecting 96-114 of
  // about 140 postures for the map). Finding one is base placement as a search (issue #51).
  bool reflected = false;
  std::string last;
  for (uint32_t id = 102; id < 107 && !reflected; ++id) {
    r = concert({"plan", "drill", "--at", "2.0", "1.6", "1.2", "--request-id", std::to_string(id), "--timeout", "60"});
    const auto blocked = plan_until(id);
    ASSERT_TRUE(blocked.has_value()) << r.out << r.err;
    if (blocked->state() != msg::PLAN_SUCCEEDED || blocked->trajectory().empty()) {
      last += "\n  request " + std::to_string(id) + ": failed: " + blocked->reason();
      reflected = blocked->reason().find("first: environment collision: obstacles") != std::string::npos;
      continue;
    }
    const auto& end = blocked->trajectory().back().position();
    reflected = std::abs(end[0] - x) > 0.4 || std::abs(end[1] - y) > 0.4;
    last += "\n  request " + std::to_string(id) + ": the base ends at (" + std::to_string(end[0]) + ", " +
            std::to_string(end[1]) + ")";
  }
  std::cout << "after the crate at (" << x << ", " << y << "):" << last << std::endl;
  EXPECT_TRUE(reflected) << "no answer reflects the crate at (" << x << ", " << y << "):" << last << "\n" << up.out();

  // Executed: the planner hands the trajectory to the robot, whose loop tracks it, and the
  // plan's result is the robot's. On this stack the safety service may stop the robot on the
  // way (its torque limit is the joints' continuous rating, the robot's the peak one: issue
  // #14, branch model); then the robot aborts the trajectory and the plan fails with the
  // robot's reason. Either way the outcome must come from the robot's trajectory status.
  r = concert({"plan", "drill", "--at", "2.0", "0.0", "1.8", "--execute", "--request-id", "110", "--timeout", "90"}, 150s);
  const auto executed = plan_until(110);
  ASSERT_TRUE(executed.has_value()) << r.out << r.err;
  std::optional<msg::TrajectoryStatus> by_robot;
  for (int i = 0; i < 100 && !by_robot; ++i) {
    {
      std::lock_guard lock(m);
      for (const auto& [id, s] : trajectories) {
        if (s.source() == "planner" && s.state() != msg::TRAJECTORY_EXECUTING) by_robot = s;
      }
    }
    if (!by_robot) std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(by_robot.has_value()) << "the robot reported no result for the planner's trajectory: " << r.out << r.err;
  if (by_robot->state() == msg::TRAJECTORY_SUCCEEDED) {
    EXPECT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_EQ(executed->state(), msg::PLAN_SUCCEEDED) << executed->reason();
  } else {
    EXPECT_EQ(by_robot->state(), msg::TRAJECTORY_ABORTED) << by_robot->reason();
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(executed->state(), msg::PLAN_FAILED);
    EXPECT_EQ(executed->failure(), msg::PLAN_EXECUTION_ABORTED);
    EXPECT_THAT(executed->reason(), HasSubstr("aborted by the robot: " + by_robot->reason()))
        << executed->reason() << " / " << by_robot->reason();
  }
  EXPECT_EQ(up.stop(20s), 0);
}

// The collaborative transport through the command line a crew uses, on the whole stack: the arm
// from home to its carrying posture (concert plan posture), the simulated person in the robot's
// simulator guiding the gravity-compensated gripper (concert sim person), collab's modes
// (concert collab mode). Judged against the simulator's truth of the gripper (the person's
// report) and the services' status: nothing refused, safety RUNNING.
TEST_F(UpTest, ATransportWithTheSimulatedPersonThroughTheCommandLine) {
  Process up({CONCERT_BIN, "up", "--assembly", CONCERT_SOURCE_DIR "/deploy/demo/transport_robot.yaml", "--duration", "300"},
             env_);
  auto r = concert({"status", "--until-version", "1", "--timeout", "90"});
  ASSERT_EQ(r.code, 0) << r.out << r.err << up.out();
  const auto json_of = [](const testing::Outcome& o) {
    const auto brace = o.out.rfind("\n{");
    const std::string line = brace == std::string::npos ? o.out : o.out.substr(brace + 1);
    try {
      return idl::Json::parse(line);
    } catch (const std::exception&) {
      return idl::Json::object();
    }
  };
  const auto person = [&](std::vector<std::string> args, std::chrono::seconds timeout = 30s) {
    args.insert(args.begin(), {"sim", "person"});
    args.insert(args.end(), {"--json", "--timeout", std::to_string(timeout.count())});
    const auto o = concert(args, timeout + 30s);
    EXPECT_EQ(o.code, 0) << args[2] << ": " << o.out << o.err;
    return json_of(o).value("person", idl::Json::object());
  };
  const auto tcp = [&]() {
    const idl::Json p = person({"status"});
    return p.contains("tcp") ? Eigen::Vector3d(p["tcp"][0].get<double>(), p["tcp"][1].get<double>(),
                                               p["tcp"][2].get<double>())
                             : Eigen::Vector3d::Constant(std::nan(""));
  };
  // The gripper settles near `z` (a lift or a placing): polled through the simulator's report, at
  // most 40 times (a status answer takes a few hundred milliseconds).
  const auto settled_near = [&](double z) {
    Eigen::Vector3d at = tcp();
    for (int i = 0; i < 40 && !(std::abs(at.z() - z) < 0.01); ++i) at = tcp();
    return at;
  };
  const auto collab = [&](const std::string& mode, const std::string& state) {
    const auto o = concert({"collab", "mode", mode, "--json", "--timeout", "10"});
    EXPECT_EQ(o.code, 0) << mode << ": " << o.out << o.err;
    EXPECT_EQ(json_of(o).value("state", ""), state) << mode << ": " << o.out;
  };

  // After the swap-in the arm stands at home, straight up; the transport starts elbow down.
  r = concert({"plan", "posture", "J2_E=0.65", "J4_E=1.05", "J6_E=1.40", "--timeout", "60"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("goal 1/1 succeeded"));
  r = concert({"plan", "posture", "J9_Z=0.1", "--plan-only", "--timeout", "30"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("'J9_Z' is not an arm joint of model version 1 (its arm joints: J1_E"));

  // Teaching: the hand guides the gravity-compensated gripper 10 cm ahead and 10 cm down.
  collab("teaching", "teaching/general");
  const Eigen::Vector3d taught_from = tcp();
  idl::Json p = person({"grip", "--guide", "0.1", "0", "-0.1", "--guide-time", "2", "--wait"}, 60s);
  const Eigen::Vector3d guided = tcp();
  EXPECT_GT((guided - taught_from).norm(), 0.1) << "the arm did not follow the hand: " << p.dump();
  EXPECT_LT(p.value("pull", 1e9), 10.0) << p.dump();
  collab("close", "teaching/close");

  // Lift: 0.15 m up, the person lets go.
  collab("lift", "autonomous/lift");
  person({"release"});
  const Eigen::Vector3d lifted = settled_near(guided.z() + 0.15);
  EXPECT_NEAR(lifted.z() - guided.z(), 0.15, 0.03);

  // Follow me: the person grips again and walks 3 m west; the robot follows.
  collab("follow-me", "follow-me");
  person({"grip"});
  p = person({"walk", "-3.0", "0", "--wait"}, 180s);
  EXPECT_EQ(p.value("phase", ""), "arrived") << p.dump();
  person({"release"});
  const Eigen::Vector3d walked = tcp();
  EXPECT_NEAR(walked.x() - lifted.x(), -3.0, 0.3);
  EXPECT_NEAR(walked.y() - lifted.y(), 0.0, 0.3);

  // Place: 0.15 m down; open; stop.
  collab("place", "autonomous/place");
  const Eigen::Vector3d placed = settled_near(walked.z() - 0.15);
  EXPECT_NEAR(walked.z() - placed.z(), 0.15, 0.03);
  collab("teaching", "teaching/general");
  collab("open", "teaching/open");
  collab("stop", "stop");

  // Nothing refused on the way, safety running.
  r = concert({"status", "--json", "--timeout", "1.5"});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const auto& s : idl::Json::parse(r.out)) {
    EXPECT_EQ(s.value("refusals", 0), 0) << s.dump();
    if (s.at("service") == "safety") {
      EXPECT_EQ(s.value("message", ""), "RUNNING") << s.dump();
    }
  }
  EXPECT_EQ(up.stop(20s), 0);
}

}  // namespace
}  // namespace concert
