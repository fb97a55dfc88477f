// The DDS adapter in one process: scans in, versioned latched trees and status out; a faulty
// scan keeps the last good tree.
#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <string>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "dds/discovery_node.hpp"
#include "dds/service_params.hpp"
#include "test_data.hpp"

namespace concert::discovery {
namespace {

using namespace std::chrono_literals;

using namespace concert::test_data;

TEST(DdsConversions, RoundTrip) {
  const auto catalog = topology::EscCatalog::load(kPublicDb);
  const auto assembly = simbus::load_assembly(kExamples + "/concert_torso_two_arms.yaml");
  const auto scan = simbus::simulate_scan(assembly, catalog);
  const auto msg_scan = topology::dds::to_msg(scan, 7, 123, "sim");
  EXPECT_EQ(msg_scan.scan_id(), 7u);
  EXPECT_EQ(msg_scan.source(), "sim");
  EXPECT_EQ(topology::dds::to_core(msg_scan), scan);
  const auto tree = simbus::tree_from_assembly(assembly, catalog);
  const auto msg_tree = topology::dds::to_msg(tree, 3, 7, 456);
  EXPECT_EQ(msg_tree.version(), 3u);
  EXPECT_EQ(msg_tree.slaves()[0].parent_port(), -1);
  EXPECT_EQ(msg_tree.modules()[10].kind(), msg::MODULE_HUB);
  EXPECT_EQ(topology::dds::to_core(msg_tree), tree);
  // Unknown modules and issues travel too.
  auto odd = tree;
  odd.modules[3].known = false;
  odd.modules[3].key.clear();
  odd.modules[3].kind = topology::ModuleKind::kUnknown;
  odd.issues = {{topology::TreeIssue::Severity::kWarning, 4, "blank module identity"},
                {topology::TreeIssue::Severity::kError, 0, "the scan has no slaves"}};
  const auto msg_odd = topology::dds::to_msg(odd, 4, 8, 789);
  EXPECT_FALSE(msg_odd.modules()[3].known());
  EXPECT_EQ(msg_odd.modules()[3].kind(), msg::MODULE_UNKNOWN);
  ASSERT_EQ(msg_odd.issues().size(), 2u);
  EXPECT_TRUE(msg_odd.issues()[1].error());
  EXPECT_EQ(topology::dds::to_core(msg_odd), odd);
}

/// Waits (bounded) for a status sample of the discovery service in `state`.
// The discovery service's next status in `state` whose message starts with `prefix` (an
// earlier scan's status may still be unread when the next scan is written).
std::optional<msg::ServiceStatus> wait_status(concert::dds::Reader<msg::ServiceStatus>& reader,
                                              msg::ServiceState state, const std::string& prefix = "") {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto s = reader.wait(200ms); s && s->service() == "discovery" && s->state() == state &&
                                     s->message().rfind(prefix, 0) == 0) {
      return s;
    }
  }
  return std::nullopt;
}

TEST(DiscoveryNode, PublishesVersionedTreesAndKeepsThemOnFaultyScans) {
  const auto catalog = topology::EscCatalog::load(kPublicDb);
  const auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
  const auto good = simbus::simulate_scan(assembly, catalog);
  auto bad = good;
  bad.slaves[4].active_ports = 0b0010;  // port 0 closed: undefined from slave 5 on

  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "discovery_test"});
  concert::dds::Reader<msg::ServiceStatus> status(participant, concert::dds::topics::status);
  std::ostringstream log;
  // Alone on the wire: no model to resume from (listened for 0.2 s).
  dds::DiscoveryNode node(participant, DiscoveryService(topology::Discovery(catalog)), log, 200ms);
  concert::dds::Writer<msg::EscScan> scans(participant, concert::dds::topics::esc_scan);
  concert::dds::Reader<msg::ModuleTree> trees(participant, concert::dds::topics::module_tree);
  ASSERT_TRUE(scans.wait_for_readers(1, 10s));
  ASSERT_TRUE(trees.wait_for_writers(1, 10s));

  ASSERT_TRUE(scans.write(topology::dds::to_msg(good, 1, 0, "test")));
  int handled = 0;
  for (int i = 0; i < 50 && handled == 0; ++i) handled = node.spin_once(200ms);
  ASSERT_EQ(handled, 1);
  const auto first = trees.wait(10s);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->version(), 1u);
  EXPECT_EQ(first->scan_id(), 1u);
  EXPECT_EQ(topology::dds::to_core(*first), simbus::tree_from_assembly(assembly, catalog));
  ASSERT_TRUE(wait_status(status, msg::SERVICE_READY));

  ASSERT_TRUE(scans.write(topology::dds::to_msg(bad, 2, 0, "test")));
  handled = 0;
  for (int i = 0; i < 50 && handled == 0; ++i) handled = node.spin_once(200ms);
  ASSERT_EQ(handled, 1);
  const auto error = wait_status(status, msg::SERVICE_ERROR);
  ASSERT_TRUE(error);
  EXPECT_EQ(
      error->message(),
      "scan 2 rejected: slave 5: port 0 (upstream) is closed in active_ports 0b0010: every "
      "slave is reached through port 0 (module mounted upside down?) (keeping tree version 1)");
  EXPECT_NE(log.str().find("scan 2 rejected: slave 5"), std::string::npos);
  EXPECT_FALSE(trees.wait(300ms));
  EXPECT_EQ(node.service().version(), 1u);

  // A late joiner gets the last good tree at once (transient local).
  concert::dds::Reader<msg::ModuleTree> late(participant, concert::dds::topics::module_tree);
  const auto latched = late.wait(10s);
  ASSERT_TRUE(latched);
  EXPECT_EQ(latched->version(), 1u);

  // A different robot: version 2.
  auto changed = assembly;
  changed.faults.push_back(simbus::Fault{simbus::FaultType::kBrokenLink, "drill", {}, {}});
  ASSERT_TRUE(
      scans.write(topology::dds::to_msg(simbus::simulate_scan(changed, catalog), 3, 0, "test")));
  handled = 0;
  for (int i = 0; i < 50 && handled == 0; ++i) handled = node.spin_once(200ms);
  const auto second = trees.wait(10s);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->version(), 2u);
  EXPECT_EQ(second->modules().size(), 17u);

  // A board with a blank identity: the tree is published with the unknown module flagged and
  // the warning on the wire (modelgen refuses it, naming the slave); the status stays READY.
  auto blank = simbus::simulate_scan(assembly, catalog);
  blank.slaves[11].identity = topology::EscIdentity{};
  ASSERT_TRUE(scans.write(topology::dds::to_msg(blank, 4, 0, "test")));
  handled = 0;
  for (int i = 0; i < 50 && handled == 0; ++i) handled = node.spin_once(200ms);
  const auto third = trees.wait(10s);
  ASSERT_TRUE(third);
  EXPECT_EQ(third->version(), 3u);
  const auto core = topology::dds::to_core(*third);
  EXPECT_EQ(core.unknown_modules().size(), 1u);
  ASSERT_EQ(core.issues.size(), 1u);
  EXPECT_EQ(core.issues[0].position, 12);
  const auto ready = wait_status(status, msg::SERVICE_READY, "scan 4:");
  ASSERT_TRUE(ready);
  EXPECT_NE(ready->message().find("1 unknown; 1 warning: slave 12: blank module identity"),
            std::string::npos)
      << ready->message();
}

TEST(DiscoveryNode, ARestartedNodeContinuesAfterTheTreeTheRunningModelCameFrom) {
  const auto catalog = topology::EscCatalog::load(kPublicDb);
  const auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "discovery_test"});
  // What modelgen keeps on the wire: model version 4, generated from tree version 6.
  concert::dds::Writer<msg::RobotModel> models(participant, concert::dds::topics::robot_model);
  msg::RobotModel model;
  model.version(4);
  model.tree_version(6);
  ASSERT_TRUE(models.write(model));
  std::ostringstream log;
  dds::DiscoveryNode node(participant, DiscoveryService(topology::Discovery(catalog)), log);
  concert::dds::Writer<msg::EscScan> scans(participant, concert::dds::topics::esc_scan);
  concert::dds::Reader<msg::ModuleTree> trees(participant, concert::dds::topics::module_tree);
  ASSERT_TRUE(scans.wait_for_readers(1, 10s));
  ASSERT_TRUE(scans.write(topology::dds::to_msg(simbus::simulate_scan(assembly, catalog), 1, 0, "test")));
  int handled = 0;
  for (int i = 0; i < 50 && handled == 0; ++i) handled = node.spin_once(200ms);
  ASSERT_EQ(handled, 1);
  const auto tree = trees.wait(10s);
  ASSERT_TRUE(tree);
  EXPECT_EQ(tree->version(), 7u);
  EXPECT_NE(log.str().find("model version 4 was generated from tree version 6"), std::string::npos)
      << log.str();
}

TEST(ServiceParams, ShippedConfigListsEveryParameterWithItsDefault) {
  auto doc = config::Document::load(std::string(CONCERT_SOURCE_DIR) +
                                    "/services/discovery/config/discovery.yaml");
  (void)dds::read_service_params(doc);
  EXPECT_EQ(doc.keys().size(), 2u);
  EXPECT_TRUE(doc.differences_from_defaults().empty())
      << ::testing::PrintToString(doc.differences_from_defaults());
}

TEST(ServiceParams, ValuesAndErrorsNamingFileAndKey) {
  auto doc = config::Document::parse("module_db: /db\nport_order: '0123'\n", "d.yaml");
  const auto p = dds::read_service_params(doc);
  EXPECT_EQ(p.module_dbs, std::vector<std::string>{"/db"});
  EXPECT_EQ(p.port_order, "0123");
  auto error_of = [](const std::string& yaml) {
    try {
      auto d = config::Document::parse(yaml, "d.yaml");
      (void)dds::read_service_params(d);
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error_of("port_order: '0321'"),
            "d.yaml: port_order: expected one of 0312, 0123, got '0321' (line 1)");
  EXPECT_EQ(error_of("module_dbs: [a]"),
            "d.yaml: module_dbs: unknown key (line 1); known keys: module_db, port_order");
  EXPECT_EQ(error_of("module_db: {a: 1}"),
            "d.yaml: module_db: expected a list of strings or one string, got a map (line 1)");
}

}  // namespace
}  // namespace concert::discovery
