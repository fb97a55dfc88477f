// The service as a real process: concert_discovery reads scans from DDS, publishes trees and
// its status, reports faulty scans on stderr and stops cleanly on SIGTERM.
#include "process.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>
#include <tuple>
#include <vector>

#include "concert/dds/endpoint.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "test_data.hpp"

namespace concert::discovery {
namespace {

using namespace std::chrono_literals;

using namespace concert::test_data;

TEST(DiscoveryProcess, ScansInTreesAndStatusOutCleanStop) {
  concert::testing::Process discovery({DISCOVERY_BINARY, "--module-db", kPublicDb});

  {
    const auto catalog = topology::EscCatalog::load(kPublicDb);
    const auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
    const auto scan = simbus::simulate_scan(assembly, catalog);
    auto bad = scan;
    bad.slaves.pop_back();  // slave 18 (yaw) now has an open port with nothing behind it

    concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "process_test"});
    concert::dds::Writer<msg::EscScan> scans(participant, concert::dds::topics::esc_scan);
    concert::dds::Reader<msg::ModuleTree> trees(participant, concert::dds::topics::module_tree);
    concert::dds::Reader<msg::ServiceStatus> status(participant, concert::dds::topics::status);
    ASSERT_TRUE(scans.wait_for_readers(1, 20s));
    ASSERT_TRUE(scans.write(topology::dds::to_msg(scan, 1, 0, "test")));
    const auto tree = trees.wait(20s);
    ASSERT_TRUE(tree);
    EXPECT_EQ(tree->version(), 1u);
    EXPECT_EQ(topology::dds::to_core(*tree), simbus::tree_from_assembly(assembly, catalog));

    ASSERT_TRUE(scans.write(topology::dds::to_msg(bad, 2, 0, "test")));
    bool error_seen = false;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (!error_seen && std::chrono::steady_clock::now() < deadline) {
      if (auto s = status.wait(200ms)) {
        error_seen = s->service() == "discovery" && s->state() == msg::SERVICE_ERROR &&
                     s->message().find("scan 2 rejected: slave 18") != std::string::npos;
      }
    }
    EXPECT_TRUE(error_seen);
    EXPECT_FALSE(trees.wait(300ms));
  }
  kill(discovery.pid(), SIGTERM);
  EXPECT_EQ(discovery.wait(15s), 0);
  const std::string log = discovery.err();
  EXPECT_NE(log.find("discovery: scan 1: tree version 1 (18 modules, 19 slaves)"), std::string::npos)
      << log;
  EXPECT_NE(log.find("scan 2 rejected: slave 18: port 1 is open but no slave hangs on it"),
            std::string::npos)
      << log;
}

/// Runs the binary with `args`; returns (exit status, stderr); -1 if it does not end in 15 s.
std::pair<int, std::string> run_binary(std::vector<std::string> args) {
  args.insert(args.begin(), DISCOVERY_BINARY);
  concert::testing::Process p(args);
  const std::optional<int> status = p.wait(15s);
  return {status.value_or(-1), p.err()};
}

TEST(DiscoveryProcess, BadArgumentsExitNonZeroWithOneLine) {
  // A wrong command line: 2, naming the option. A failure (bad folder, bad file): 1.
  auto [status, err] = run_binary({"--port-order", "9"});
  EXPECT_EQ(status, 2);
  EXPECT_NE(err.find("concert_discovery: --port-order: 9 not in {0312,0123}"), std::string::npos)
      << err;
  std::tie(status, err) = run_binary({"--module-db", "/nonexistent/db"});
  EXPECT_EQ(status, 1);
  EXPECT_NE(err.find("/nonexistent/db: module database folder not found"), std::string::npos)
      << err;
  const auto params = std::filesystem::temp_directory_path() /
                      ("concert_discovery_params_" + std::to_string(getpid()) + ".yaml");
  std::ofstream(params) << "port_order: [1]\n";
  std::tie(status, err) = run_binary({"--params", params.string()});
  EXPECT_EQ(status, 1);
  EXPECT_NE(
      err.find(params.string() + ": port_order: expected one of 0312, 0123, got a list (line 1)"),
      std::string::npos)
      << err;
  std::filesystem::remove(params);
  std::tie(status, err) = run_binary({"--bogus"});
  EXPECT_EQ(status, 2);
  EXPECT_NE(err.find("concert_discovery: The following argument was not expected: --bogus"),
            std::string::npos)
      << err;
  concert::testing::Process help({DISCOVERY_BINARY, "--help"});
  EXPECT_EQ(help.wait(15s), 0);
  EXPECT_NE(help.out().find("--port-order"), std::string::npos) << help.out();
}

}  // namespace
}  // namespace concert::discovery
