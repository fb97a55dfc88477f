// concert_planner as a real process: model in over DDS, a world file as the map, a drilling
// request through `concert plan drill` (planned around the wall), bad arguments refused, clean
// stop on SIGTERM.

#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "planner/cli.hpp"
#include "planner/fixtures.hpp"
#include "model_message.hpp"

extern char** environ;

using namespace concert;
using namespace std::chrono_literals;

namespace {

int wait_exit(pid_t pid, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::this_thread::sleep_for(20ms);
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  return -1;
}

pid_t spawn(std::vector<std::string> args, const std::filesystem::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0].c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

using planner::testing::model_message;

}  // namespace

TEST(PlannerProcess, BadArgumentsExitNonZeroWithOneLine) {
  const auto log = std::filesystem::temp_directory_path() / ("concert_planner_args_" + std::to_string(getpid()) + ".log");
  EXPECT_EQ(wait_exit(spawn({PLANNER_BINARY, "--world", "/nonexistent/site.yaml"}, log), 20s), 1);
  EXPECT_NE(read(log).find("world file '/nonexistent/site.yaml' cannot be opened"), std::string::npos) << read(log);
  EXPECT_EQ(wait_exit(spawn({PLANNER_BINARY, "--bogus"}, log), 20s), 1);
  EXPECT_NE(read(log).find("unknown argument '--bogus'"), std::string::npos) << read(log);
}

TEST(PlannerProcess, ModelInRequestPlannedCleanStop) {
  const auto dir = std::filesystem::temp_directory_path() / ("concert_planner_process_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream world(dir / "site.yaml");
    world << "walls:\n  - {name: wall, size: [0.2, 6.0, 3.2], position: [2.1, 0.0, 1.6]}\n";
  }
  const pid_t pid = spawn({PLANNER_BINARY, "--world", (dir / "site.yaml").string()}, dir / "planner.log");
  ASSERT_GT(pid, 0);
  {
    concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "planner_process_test"});
    concert::dds::Writer<msg::RobotModel> models(participant, concert::dds::topics::robot_model);
    ASSERT_TRUE(models.wait_for_readers(1, 20s)) << read(dir / "planner.log");
    models.write(model_message(planner::fixtures::data_dir() / "morphology_a.yaml", 2));
    std::ostringstream out;
    std::ostringstream err;
    // The model may still be on its way: retry (bounded) while the planner reports no model.
    int rc = 1;
    for (int attempt = 0; attempt < 10 && rc != 0; ++attempt) {
      err.str("");
      rc = planner::cli_main({"drill", "--at", "2.0", "0.2", "2.1", "--request-id", std::to_string(100 + attempt), "--timeout", "20"},
                             out, err);
      if (rc != 0 && err.str().find("no model") == std::string::npos && err.str().find("stale") == std::string::npos) break;
      std::this_thread::sleep_for(200ms);
    }
    EXPECT_EQ(rc, 0) << err.str() << "\n" << read(dir / "planner.log");
    EXPECT_NE(out.str().find("succeeded"), std::string::npos) << out.str();
  }
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  EXPECT_EQ(wait_exit(pid, 20s), 0);
  const std::string log = read(dir / "planner.log");
  EXPECT_NE(log.find("occupied cells from"), std::string::npos) << log;
  EXPECT_NE(log.find("model version 2"), std::string::npos) << log;
  std::filesystem::remove_all(dir);
}
