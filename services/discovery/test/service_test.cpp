#include "discovery/service.hpp"

#include <gtest/gtest.h>

#include "concert/simbus/testing.hpp"

namespace concert::discovery {
namespace {

using Kind = ScanOutcome::Kind;

TEST(DiscoveryService, ARestartedServiceNumbersItsTreesAfterTheVersionOnTheWire) {
  DiscoveryService service(topology::Discovery(simbus::synthetic_catalog()));
  service.continue_after(7);
  EXPECT_EQ(service.version(), 0u);  // no tree yet
  const auto one = simbus::testing::make_scan({{0b0011, simbus::testing::kJoint}, {0b0001, simbus::testing::kTool}});
  ScanOutcome outcome = service.on_scan(one, 1);
  EXPECT_EQ(outcome.kind, Kind::kPublished);
  EXPECT_EQ(outcome.version, 8u);
  EXPECT_EQ(service.on_scan(one, 2).kind, Kind::kUnchanged);
  // Learning an older version later changes nothing.
  service.continue_after(3);
  const auto two = simbus::testing::make_scan({{0b0011, simbus::testing::kJoint}, {0b0001, simbus::testing::kWheel}});
  EXPECT_EQ(service.on_scan(two, 3).version, 9u);
}

TEST(DiscoveryService, VersionsGoodTreesAndKeepsThemOnFaultyScans) {
  DiscoveryService service(topology::Discovery(simbus::synthetic_catalog()));
  EXPECT_EQ(service.version(), 0u);

  // Port 2 of a hub is open with nothing on it.
  const auto bad = simbus::testing::make_scan({{0b0111, simbus::testing::kHub3}, {0b0001, simbus::testing::kTool}});
  ScanOutcome outcome = service.on_scan(bad, 1);
  EXPECT_EQ(outcome.kind, Kind::kRejected);
  EXPECT_EQ(outcome.version, 0u);
  EXPECT_EQ(outcome.message,
            "scan 1 rejected: slave 1: port 2 is open but no slave hangs on it (broken link?) "
            "(no tree yet)");
  EXPECT_FALSE(service.tree());

  const auto one = simbus::testing::make_scan({{0b0011, simbus::testing::kJoint}, {0b0001, simbus::testing::kTool}});
  outcome = service.on_scan(one, 2);
  EXPECT_EQ(outcome.kind, Kind::kPublished);
  EXPECT_EQ(outcome.version, 1u);
  EXPECT_EQ(outcome.message, "scan 2: tree version 1 (2 modules, 2 slaves)");
  ASSERT_TRUE(service.tree());
  EXPECT_EQ(service.tree()->modules[1].key, "tool");

  outcome = service.on_scan(one, 3);
  EXPECT_EQ(outcome.kind, Kind::kUnchanged);
  EXPECT_EQ(outcome.version, 1u);

  outcome = service.on_scan(bad, 4);
  EXPECT_EQ(outcome.kind, Kind::kRejected);
  EXPECT_NE(outcome.message.find("(keeping tree version 1)"), std::string::npos);
  EXPECT_EQ(service.version(), 1u);
  EXPECT_EQ(service.tree_scan_id(), 2u);
  EXPECT_EQ(service.tree()->modules[1].key, "tool");

  const auto two = simbus::testing::make_scan({{0b0011, simbus::testing::kJoint}, {0b0001, simbus::testing::kWheel}});
  outcome = service.on_scan(two, 5);
  EXPECT_EQ(outcome.kind, Kind::kPublished);
  EXPECT_EQ(outcome.version, 2u);
  EXPECT_EQ(service.tree()->modules[1].key, "wheel");
  EXPECT_EQ(service.tree_scan_id(), 5u);

  // Unknown modules and topology disagreements are warnings: the tree is published with them.
  auto odd = simbus::testing::make_scan({{0b0011, simbus::testing::kJoint}, {0b0001, topology::EscIdentity{}}});
  odd.slaves[0].topology = 3;
  outcome = service.on_scan(odd, 6);
  EXPECT_EQ(outcome.kind, Kind::kPublished);
  EXPECT_EQ(outcome.version, 3u);
  EXPECT_EQ(outcome.message,
            "scan 6: tree version 3 (2 modules, 2 slaves, 1 unknown; 2 warnings: slave 1: "
            "topology says 3 open ports but active_ports 0b0011 has 2; using active_ports (and 1 "
            "more))");
  EXPECT_EQ(service.tree()->unknown_modules(), (std::vector<int32_t>{1}));
}

}  // namespace
}  // namespace concert::discovery
