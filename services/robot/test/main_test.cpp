// concert_robot as a process: it publishes the simulated bus scan and the world, and
// SimCommands over DDS (what `concert sim swap/world` send) hot-swap the assembly or change
// the world, or are refused with the reason. The ethercat backend's command-line errors are named.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <tuple>
#include <utility>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/world/person_order.hpp"

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

/// Sends `command` and waits (bounded) for its reply.
std::optional<concert::msg::SimCommandReply> send(cdds::Writer<concert::msg::SimCommand>& writer,
                                                  cdds::Reader<concert::msg::SimCommandReply>& replies,
                                                  const concert::msg::SimCommand& command) {
  writer.write(command);
  for (int i = 0; i < 300; ++i) {
    if (auto r = replies.wait(100ms); r && r->request_id() == command.request_id()) {
      return r;
    }
  }
  return std::nullopt;
}

TEST(RobotMain, SimCommandsSwapTheAssemblyAndChangeTheWorld) {
  cdds::Participant client({.name = "client"});
  cdds::Reader<concert::msg::EscScan> scans(client, cdds::topics::esc_scan);
  cdds::Reader<concert::msg::ServiceStatus> status(client, cdds::topics::status);
  cdds::Reader<concert::msg::World> worlds(client, cdds::topics::world);
  cdds::Reader<concert::msg::SimCommandReply> replies(client, cdds::topics::sim_reply);
  cdds::Writer<concert::msg::SimCommand> commands(client, cdds::topics::sim_command);
  Process robot({ROBOT_BINARY, "--assembly", kPaperRobot.string(), "--module-db", kPublicDb.string(), "--standalone",
                 "--duration", "60"});
  auto first = scans.wait(20s);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->slaves().size(), 19u);
  EXPECT_EQ(first->source(), "sim");
  // The world it simulates is latched on the World topic (empty here: no --world).
  auto world = worlds.wait(10s);
  ASSERT_TRUE(world.has_value());
  EXPECT_EQ(world->version(), 1u);
  EXPECT_TRUE(world->obstacles().empty());
  ASSERT_TRUE(commands.wait_for_readers(1, 10s));

  // A bad assembly is refused with the reason; the robot keeps its modules.
  concert::msg::SimCommand bad;
  bad.request_id(1);
  bad.source("test");
  bad.kind(concert::msg::SIM_SWAP_ASSEMBLY);
  bad.name("bad.yaml");
  std::string unknown = read_text(kPaperRobot);
  unknown.replace(unknown.find("module_drill_concert"), std::string("module_drill_concert").size(), "no_such_module");
  bad.content(unknown);
  auto reply = send(commands, replies, bad);
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted());
  EXPECT_NE(reply->message().find("keeps its modules"), std::string::npos) << reply->message();
  EXPECT_NE(reply->message().find("no_such_module"), std::string::npos) << reply->message();

  // Remove the rear-right leg while the robot runs: the content travels over DDS.
  std::string edited = read_text(kPaperRobot);
  for (const std::string line : {"  - {name: steer_rr, key: module_steering_concert_fl_rr, parent: base, connector: 4, robot_id: 41}\n",
                                 "  - {name: wheel_rr, key: module_wheel_concert, parent: steer_rr, connector: 1, robot_id: 42}\n"}) {
    edited.erase(edited.find(line), line.size());
  }
  concert::msg::SimCommand swap = bad;
  swap.request_id(2);
  swap.name("three_legs.yaml");
  swap.content(edited);
  reply = send(commands, replies, swap);
  ASSERT_TRUE(reply.has_value());
  EXPECT_TRUE(reply->accepted()) << reply->message();
  std::optional<concert::msg::EscScan> second;
  for (int i = 0; i < 200 && !(second && second->scan_id() > first->scan_id()); ++i) {
    second = scans.wait(100ms);
  }
  ASSERT_TRUE(second.has_value());
  EXPECT_GT(second->scan_id(), first->scan_id());
  EXPECT_EQ(second->slaves().size(), 17u);
  // The same command again (a client resending until it hears the reply): the same answer,
  // not applied twice (that would answer "the same robot is mounted again").
  const std::string answer = reply->message();
  reply = send(commands, replies, swap);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->message(), answer);
  // Standalone: the service takes the new hardware's own model and reports ready at version 2.
  // Bounded by time (30 s), the last status shown: a loaded fresh-clone run ended the old loop
  // (200 samples or 100 ms waits) without READY v2, and nothing said what the robot reported.
  bool ready_v2 = false;
  std::string last_status = "(none)";
  for (const auto until = std::chrono::steady_clock::now() + 30s; !ready_v2 && std::chrono::steady_clock::now() < until;) {
    if (auto s = status.wait(100ms); s && s->service() == "robot") {
      ready_v2 = s->state() == concert::msg::SERVICE_READY && s->model_version() == 2u;
      last_status = "state " + std::to_string(static_cast<int>(s->state())) + " at model version " +
                    std::to_string(s->model_version()) + ": " + s->message();
    }
  }
  EXPECT_TRUE(ready_v2) << "the last robot status: " << last_status;

  // A world change: refused when malformed, else simulated and republished.
  concert::msg::SimCommand w = bad;
  w.request_id(3);
  w.kind(concert::msg::SIM_SET_WORLD);
  w.name("site.yaml");
  w.content("obstacles:\n  - {name: crate, size: [0.5, -1, 0.5], position: [3, 0, 0.25]}\n");
  reply = send(commands, replies, w);
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted());
  EXPECT_NE(reply->message().find("site.yaml"), std::string::npos) << reply->message();
  EXPECT_NE(reply->message().find("obstacles[0].size"), std::string::npos) << reply->message();
  // ... and when a mark names a dictionary OpenCV does not have (the running world stays:
  // the next accepted world is version 2).
  w.request_id(5);
  w.content("walls:\n  - {name: wall, size: [0.2, 3, 2.5], position: [1, 0, 1.25]}\n"
            "marks:\n  - {type: aruco, name: m, wall: wall, face: -x, at: [0, 1.2], size: 0.15, "
            "dictionary: DICT_3X3_9, id: 1}\n");
  reply = send(commands, replies, w);
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted());
  EXPECT_NE(reply->message().find("marks[0].dictionary"), std::string::npos) << reply->message();
  w.request_id(4);
  w.content("obstacles:\n  - {name: crate, size: [0.5, 0.5, 0.5], position: [3, 0, 0.25]}\n");
  reply = send(commands, replies, w);
  ASSERT_TRUE(reply.has_value());
  EXPECT_TRUE(reply->accepted()) << reply->message();
  for (int i = 0; i < 100 && !(world && world->version() == 2u); ++i) {
    world = worlds.wait(100ms);
  }
  ASSERT_TRUE(world.has_value());
  EXPECT_EQ(world->version(), 2u);
  ASSERT_EQ(world->obstacles().size(), 1u);
  EXPECT_EQ(world->obstacles()[0].name(), "crate");
  EXPECT_EQ(world->source(), "site.yaml");

  // The simulated person: a status query answers with its state as YAML; an order the mounted
  // robot cannot take (no gripper on the paper's drilling robot) is refused with the reason; a
  // malformed one names the key and line.
  concert::msg::SimCommand p = bad;
  p.kind(concert::msg::SIM_PERSON);
  p.request_id(6);
  p.name("concert sim person status");
  p.content("action: status\n");
  reply = send(commands, replies, p);
  ASSERT_TRUE(reply.has_value());
  EXPECT_TRUE(reply->accepted()) << reply->message();
  EXPECT_EQ(concert::world::parse_person_report(reply->message()).phase, concert::world::PersonPhase::kAbsent)
      << reply->message();
  p.request_id(7);
  p.name("grip");
  p.content("action: grip\n");
  reply = send(commands, replies, p);
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted());
  EXPECT_EQ(reply->message(), "person 'grip' refused, the simulator keeps its person as it is: sim: person: the "
                              "mounted robot has no gripper to hold; name a link");
  p.request_id(8);
  p.name("walk.yaml");
  p.content("action: walk\nroute: [1.0]\n");
  reply = send(commands, replies, p);
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted());
  EXPECT_NE(reply->message().find("walk.yaml: route: expected x, y pairs [m], at least one (got 1 numbers) (line 2)"),
            std::string::npos)
      << reply->message();
}

}  // namespace

namespace {

// The command's exit code and what it printed (stdout and stderr).
std::pair<int, std::string> run_robot(const std::string& args) {
  const std::string command = std::string(ROBOT_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, "popen failed"};
  std::string out;
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// The ethercat backend's command line: the interface required, the simulator's flags refused,
// an interface that is not there named.
TEST(RobotMain, TheEthercatBackendNamesWhatIsWrongWithItsArguments) {
  auto [code, out] = run_robot("--backend ethercat");
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("--backend ethercat needs --ifname IF"), std::string::npos) << out;
  std::tie(code, out) = run_robot("--backend ethercat --ifname lo --assembly " + kPaperRobot.string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("--assembly is the simulator's: not with --backend ethercat"), std::string::npos) << out;
  std::tie(code, out) = run_robot("--assembly " + kPaperRobot.string() + " --ifname lo");
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("--ifname and --process-data are the ethercat backend's"), std::string::npos) << out;
  std::tie(code, out) = run_robot("--backend ethercat --ifname ecnosuch0");
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("ecnosuch0"), std::string::npos) << out;
}

}  // namespace
