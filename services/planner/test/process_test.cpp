// concert_planner as a real process: model in over DDS, a world file as the map, a drilling
// request through `concert plan drill` (planned around the wall), bad arguments refused, clean
// stop on SIGTERM.

#include <gtest/gtest.h>

#include <csignal>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "planner/cli.hpp"
#include "planner/fixtures.hpp"
#include "model_message.hpp"
#include "process.hpp"


using namespace concert;
using namespace std::chrono_literals;

namespace {

using planner::testing::model_message;

}  // namespace

TEST(PlannerProcess, BadArgumentsExitNonZeroWithOneLine) {
  concert::testing::Process no_world({PLANNER_BINARY, "--world", "/nonexistent/site.yaml"});
  EXPECT_EQ(no_world.wait(20s), 1);
  EXPECT_NE(no_world.err().find("cannot open world file '/nonexistent/site.yaml'"), std::string::npos) << no_world.err();
  concert::testing::Process bogus({PLANNER_BINARY, "--bogus"});
  EXPECT_EQ(bogus.wait(20s), 2);
  EXPECT_NE(bogus.err().find("concert_planner: The following argument was not expected: --bogus"),
            std::string::npos)
      << bogus.err();
  concert::testing::Process bad_params({PLANNER_BINARY, "--params", "/nonexistent/planner.yaml"});
  EXPECT_EQ(bad_params.wait(20s), 1);
  EXPECT_NE(bad_params.err().find("params file '/nonexistent/planner.yaml' cannot be opened"),
            std::string::npos)
      << bad_params.err();
}

TEST(PlannerProcess, ModelInRequestPlannedCleanStop) {
  const auto dir = std::filesystem::temp_directory_path() / ("concert_planner_process_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream world(dir / "site.yaml");
    world << "walls:\n  - {name: wall, size: [0.2, 6.0, 3.2], position: [2.1, 0.0, 1.6]}\n";
  }
  concert::testing::Process planner({PLANNER_BINARY, "--world", (dir / "site.yaml").string()});
  {
    concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "planner_process_test"});
    concert::dds::Writer<msg::RobotModel> models(participant, concert::dds::topics::robot_model);
    ASSERT_TRUE(models.wait_for_readers(1, 20s)) << planner.err();
    models.write(model_message(planner::fixtures::data_dir() / "morphology_a.yaml", 2));
    std::ostringstream out;
    std::ostringstream err;
    // The model may still be on its way: retry (bounded) while the planner reports no model.
    int rc = 1;
    for (int attempt = 0; attempt < 10 && rc != 0; ++attempt) {
      err.str("");
      rc = cli::run("concert", {planner::register_verbs},
                    {"plan", "drill", "--at", "2.0", "0.2", "2.1", "--request-id",
                     std::to_string(100 + attempt), "--timeout", "20"},
                    out, err);
      if (rc != 0 && err.str().find("no model") == std::string::npos && err.str().find("stale") == std::string::npos) break;
      std::this_thread::sleep_for(200ms);
    }
    EXPECT_EQ(rc, 0) << err.str() << "\n" << planner.err();
    EXPECT_NE(out.str().find("succeeded"), std::string::npos) << out.str();
  }
  ASSERT_EQ(kill(planner.pid(), SIGTERM), 0);
  EXPECT_EQ(planner.wait(20s), 0);
  const std::string log = planner.err();
  EXPECT_NE(log.find("occupied cells from"), std::string::npos) << log;
  EXPECT_NE(log.find("model version 2"), std::string::npos) << log;
  std::filesystem::remove_all(dir);
}
