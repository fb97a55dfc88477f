// The stack across three "onboard PCs": three network namespaces on a bridge, created here and
// always removed after (no address outside the namespaces, no default route: traffic only
// between them). RT control PC: discovery, modelgen, safety and the simulated EtherCAT master
// (concert scan publish). Navigation PC: a nav stand-in; manipulation PC: planner stand-in,
// later a drill stand-in (tests/system/probe.cpp). Checks: the model published on the RT host
// reaches the other two; a service started late on the manipulation host gets the current
// model; cutting the manipulation host's link stops the robot, naming the silent service.
//
// DDS runs UDP only with the three namespace addresses as unicast peers (a generated Fast DDS
// profile, CONCERT_DDS_PROFILES): no shared memory, which would bypass the cut link, since all
// namespaces share /dev/shm.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "helpers.hpp"
#include "process.hpp"

namespace concert::system_test {
namespace {

using ::testing::HasSubstr;

using namespace std::chrono_literals;
namespace fs = std::filesystem;

constexpr std::array<const char*, 3> kHosts = {"rt-pc", "nav-pc", "manip-pc"};
constexpr std::array<const char*, 3> kRoles = {"rt", "nav", "man"};

/// Runs a shell command; returns (exit code, combined output).
std::pair<int, std::string> shell(const std::string& command) {
  std::string output;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return {-1, "popen failed"};
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), pipe) != nullptr) output += buf.data();
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

std::string ip_binary() { return tool("ip", "iproute2"); }

/// Three namespaces "concert-sys-<pid>-{rt,nav,man}" with veth links to one bridge.
class ThreeHosts {
 public:
  ThreeHosts() : tag_(std::to_string(getpid())) {
    remove_leftovers();
    try {
      run("ip link add " + bridge() + " type bridge");
      run("ip link set " + bridge() + " up");
      for (std::size_t i = 0; i < kRoles.size(); ++i) {
        run("ip netns add " + ns(i));
        run("ip link add " + outer(i) + " type veth peer name eth0 netns " + ns(i));
        run("ip link set " + outer(i) + " master " + bridge() + " up");
        run("ip -n " + ns(i) + " addr add " + address(i) + "/24 dev eth0");
        run("ip -n " + ns(i) + " link set eth0 up");
        run("ip -n " + ns(i) + " link set lo up");
      }
    } catch (...) {
      remove();
      throw;
    }
  }
  ~ThreeHosts() { remove(); }
  ThreeHosts(const ThreeHosts&) = delete;
  ThreeHosts& operator=(const ThreeHosts&) = delete;

  std::string ns(std::size_t i) const { return "concert-sys-" + tag_ + "-" + kRoles[i]; }
  static std::string address(std::size_t i) { return "10.77.0." + std::to_string(i + 1); }
  /// Cuts host i off the bridge (its end of the cable is unplugged).
  void cut(std::size_t i) const { run("ip link set " + outer(i) + " down"); }

 private:
  std::string bridge() const { return "cbr" + tag_; }
  std::string outer(std::size_t i) const { return "cv" + tag_ + kRoles[i]; }

  static void run(const std::string& command) {
    const auto [code, output] = shell(command);
    if (code != 0)
      throw std::runtime_error("'" + command + "' failed (" + std::to_string(code) +
                               "): " + output);
  }

  void remove() const {
    for (std::size_t i = 0; i < kRoles.size(); ++i) shell("ip netns del " + ns(i));
    for (std::size_t i = 0; i < kRoles.size(); ++i) shell("ip link del " + outer(i));
    shell("ip link del " + bridge());
  }

  /// Namespaces and bridges of earlier runs of this test whose process is gone (killed by a
  /// timeout before its destructor ran).
  static void remove_leftovers() {
    const auto [code, list] = shell("ip netns list");
    if (code != 0) return;
    const std::regex name("concert-sys-([0-9]+)-(rt|nav|man)");
    std::smatch m;
    std::string rest = list;
    while (std::regex_search(rest, m, name)) {
      if (!fs::exists("/proc/" + m[1].str())) {
        shell("ip netns pids " + m[0].str() + " | xargs -r kill -KILL");
        shell("ip netns del " + m[0].str());
        shell("ip link del cbr" + m[1].str());
      }
      rest = m.suffix();
    }
  }

  std::string tag_;
};

/// Fast DDS profile of host i: UDP only, bound to the host's address, the three hosts as peers.
fs::path write_profile(const fs::path& dir, std::size_t i) {
  const auto path = dir / ("fastdds_" + std::string(kRoles[i]) + ".xml");
  std::ofstream out(path);
  out << R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <profiles>
    <transport_descriptors>
      <transport_descriptor>
        <transport_id>udp</transport_id>
        <type>UDPv4</type>
        <interfaceWhiteList><address>)"
      << ThreeHosts::address(i) << R"(</address></interfaceWhiteList>
        <maxInitialPeersRange>16</maxInitialPeersRange>
      </transport_descriptor>
    </transport_descriptors>
    <participant profile_name="concert_participant" is_default_profile="true">
      <rtps>
        <userTransports><transport_id>udp</transport_id></userTransports>
        <useBuiltinTransports>false</useBuiltinTransports>
        <builtin>
          <initialPeersList>
)";
  for (std::size_t j = 0; j < kHosts.size(); ++j) {
    out << "            <locator><udpv4><address>" << ThreeHosts::address(j)
        << "</address></udpv4></locator>\n";
  }
  out << R"(          </initialPeersList>
        </builtin>
      </rtps>
    </participant>
  </profiles>
</dds>
)";
  return path;
}

class Stack {
 public:
  Stack(const ThreeHosts& hosts, fs::path dir)
      : hosts_(hosts), dir_(std::move(dir)), ip_(ip_binary()) {
    for (std::size_t i = 0; i < kHosts.size(); ++i) profiles_[i] = write_profile(dir_, i);
  }
  ~Stack() {
    for (auto it = processes_.rbegin(); it != processes_.rend(); ++it) (*it)->stop(10s);
  }

  /// Starts `argv` on host i (in its namespace, with its DDS profile and host name). The
  /// process gets SIGKILL if the test dies first (setpriv --pdeathsig).
  testing::Process& start(std::size_t i, std::vector<std::string> argv) {
    argv.insert(argv.begin(), {ip_, "netns", "exec", hosts_.ns(i)});
    processes_.push_back(std::make_unique<testing::Process>(
        dies_with_test(argv),
        std::vector<std::string>{"CONCERT_DDS_PROFILES=" + profiles_[i].string(),
                                 "CONCERT_HOST=" + std::string(kHosts[i])}));
    return *processes_.back();
  }

 private:
  const ThreeHosts& hosts_;
  fs::path dir_;
  std::string ip_;
  std::array<fs::path, 3> profiles_;
  std::vector<std::unique_ptr<testing::Process>> processes_;
};

/// The "model <version> <hash> <joints>" line of a probe for `version`, or "".
std::string model_line(const std::string& out, int version) {
  for (const auto& line : testing::lines(out)) {
    if (line.rfind("model " + std::to_string(version) + " ", 0) == 0) return line;
  }
  return "";
}

std::string dump(const char* name, const testing::Process& p) {
  return std::string("\n--- ") + name + " stdout:\n" + p.out() + "--- " + name + " stderr:\n" +
         p.err();
}

TEST(ThreeHostSystem, ModelReachesEveryHostLateJoinerGetsItCutLinkStopsTheRobot) {
  ASSERT_EQ(geteuid(), 0u)
      << "this test creates network namespaces and a bridge and must run as root "
         "(CI runs as root); run it with sudo";
  std::unique_ptr<ThreeHosts> hosts;
  try {
    hosts = std::make_unique<ThreeHosts>();
  } catch (const std::exception& e) {
    FAIL() << "cannot create the three hosts: " << e.what();
  }
  for (std::size_t i = 0; i < kRoles.size(); ++i) {  // isolated: no way out of the bridge
    EXPECT_EQ(shell("ip -n " + hosts->ns(i) + " route show default").second, "") << hosts->ns(i);
  }

  const auto dir = fs::temp_directory_path() / ("concert_three_hosts_" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "safety.yaml")
      << "liveliness_timeout: 1.0\ntask_services: [nav, planner, drill]\n";
  {
    Stack stack(*hosts, dir);
    auto& discovery = stack.start(0, {DISCOVERY_BINARY});
    auto& modelgen = stack.start(0, {MODELGEN_BINARY});
    auto& safety = stack.start(0, {SAFETY_BINARY, "--params", (dir / "safety.yaml").string()});
    auto& nav = stack.start(1, {PROBE_BINARY, "--service", "nav"});
    auto& planner = stack.start(2, {PROBE_BINARY, "--service", "planner"});
    auto& bus = stack.start(0, {CONCERT_BIN, "scan", "publish", "--assembly",
                                std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml",
                                "--source", "three-host-test"});
    const auto all = [&] {
      return dump("discovery", discovery) + dump("modelgen", modelgen) + dump("safety", safety) +
             dump("bus", bus) + dump("nav", nav) + dump("planner", planner);
    };

    // 1. The model made on the RT host reaches the navigation and manipulation hosts.
    ASSERT_TRUE(nav.wait_for_output("model 1 ", 30s)) << all();
    ASSERT_TRUE(planner.wait_for_output("model 1 ", 30s)) << all();
    const auto line = model_line(nav.out(), 1);
    EXPECT_EQ(model_line(planner.out(), 1), line);
    EXPECT_TRUE(std::regex_match(line, std::regex("model 1 sha256:[0-9a-f]{64} [1-9][0-9]*")))
        << line;
    EXPECT_TRUE(wait_for_err(safety, "safety: limits of model v1 (", 10s)) << all();

    // 2. A service started late on the manipulation host gets the current model at once.
    auto& drill = stack.start(2, {PROBE_BINARY, "--service", "drill"});
    ASSERT_TRUE(drill.wait_for_output("model 1 ", 20s)) << all() << dump("drill", drill);
    EXPECT_EQ(model_line(drill.out(), 1), line);

    // Every watched service is beating: the safety state seen on the navigation host is RUNNING.
    ASSERT_TRUE(nav.wait_for_output("safety RUNNING", 20s)) << all();
    EXPECT_EQ(nav.out().find("safety STOPPED"), std::string::npos) << all();

    // 3. The manipulation host's link is cut: its services go silent -> safe stop naming them.
    hosts->cut(2);
    ASSERT_TRUE(nav.wait_for_output("safety STOPPED: liveliness: ", 15s)) << all();
    std::string stopped;
    for (const auto& l : testing::lines(nav.out())) {
      if (l.rfind("safety STOPPED", 0) == 0) stopped = l;
    }
    // Which of the cut host's services the safety layer names first is a race between their
    // liveliness deadlines; any of them is right, a service of another host is not.
    EXPECT_TRUE(std::regex_search(stopped, std::regex("(planner|drill)@manip-pc silent for")))
        << stopped;
    EXPECT_EQ(stopped.find("nav@nav-pc"), std::string::npos) << stopped;  // still connected
    EXPECT_TRUE(wait_for_err(safety, "safety: STOPPED: liveliness: ", 5s)) << all();
    EXPECT_TRUE(safety.running()) << all();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace concert::system_test
