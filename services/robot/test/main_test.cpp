// concert_robot as a process: it publishes the simulated bus scan, and editing the assembly
// file while it runs (the hot-swap verb) gives a new scan.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "concert/dds/endpoint.hpp"

namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;
namespace cdds = concert::dds;

const fs::path kPaperRobot = fs::path(CONCERT_SOURCE_DIR) / "libs" / "simbus" / "examples" / "concert_paper_robot.yaml";
const fs::path kPublicDb = fs::path(CONCERT_SHARED_DATA) / "concert_resources";

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class Process {
 public:
  explicit Process(std::vector<std::string> args) {
    pid_ = fork();
    if (pid_ == 0) {
      std::vector<char*> argv;
      for (auto& a : args) {
        argv.push_back(a.data());
      }
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
  }
  ~Process() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      int status = 0;
      for (int i = 0; i < 100 && waitpid(pid_, &status, WNOHANG) == 0; ++i) {
        std::this_thread::sleep_for(50ms);
      }
      if (waitpid(pid_, &status, WNOHANG) == 0) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
      }
    }
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

 private:
  pid_t pid_{-1};
};

TEST(RobotMain, HotSwapByEditingTheAssemblyGivesANewScan) {
  const fs::path dir = fs::temp_directory_path() / ("robot_main_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path assembly = dir / "robot.yaml";
  const std::string paper = read_text(kPaperRobot);
  std::ofstream(assembly) << paper;

  cdds::Participant client({.name = "client"});
  cdds::Reader<concert::msg::EscScan> scans(client, cdds::topics::esc_scan);
  cdds::Reader<concert::msg::ServiceStatus> status(client, cdds::topics::status);
  Process robot({ROBOT_BINARY, "--assembly", assembly.string(), "--module-db", kPublicDb.string(), "--standalone",
                 "--duration", "60"});
  auto first = scans.wait(20s);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->slaves().size(), 19u);
  EXPECT_EQ(first->source(), "sim");

  // Remove the rear-right leg while the robot runs.
  std::string edited = paper;
  for (const std::string line : {"  - {name: steer_rr, key: module_steering_concert_fl_rr, parent: base, connector: 4, robot_id: 41}\n",
                                 "  - {name: wheel_rr, key: module_wheel_concert, parent: steer_rr, connector: 1, robot_id: 42}\n"}) {
    edited.erase(edited.find(line), line.size());
  }
  std::this_thread::sleep_for(1100ms);  // file-time granularity
  std::ofstream(assembly) << edited;
  std::optional<concert::msg::EscScan> second;
  for (int i = 0; i < 200 && !(second && second->scan_id() > first->scan_id()); ++i) {
    second = scans.wait(100ms);
  }
  ASSERT_TRUE(second.has_value());
  EXPECT_GT(second->scan_id(), first->scan_id());
  EXPECT_EQ(second->slaves().size(), 17u);
  // Standalone: the service takes the new hardware's own model and reports ready at version 2.
  bool ready_v2 = false;
  for (int i = 0; i < 200 && !ready_v2; ++i) {
    if (auto s = status.wait(100ms)) {
      ready_v2 = s->service() == "robot" && s->state() == concert::msg::SERVICE_READY && s->model_version() == 2u;
    }
  }
  EXPECT_TRUE(ready_v2);
  fs::remove_all(dir);
}

}  // namespace
