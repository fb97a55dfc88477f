#include "discovery/service.hpp"

#include <gtest/gtest.h>

#include "concert/simbus/testing.hpp"
#include "scan_builder.hpp"

namespace concert::discovery {
namespace {

using Kind = ScanOutcome::Kind;

TEST(DiscoveryService, VersionsGoodTreesAndKeepsThemOnFaultyScans) {
  DiscoveryService service(Discovery(simbus::synthetic_catalog()));
  EXPECT_EQ(service.version(), 0u);

  const auto bad = test::make_scan({{0b1011, test::kJoint}, {0b0001, test::kTool}});
  ScanOutcome outcome = service.on_scan(bad, 1);
  EXPECT_EQ(outcome.kind, Kind::kRejected);
  EXPECT_EQ(outcome.version, 0u);
  EXPECT_EQ(outcome.message,
            "scan 1 rejected: slave 1: port 1 is open but no slave hangs on it (broken link?) "
            "(no tree yet)");
  EXPECT_FALSE(service.tree());

  const auto one = test::make_scan({{0b1001, test::kJoint}, {0b0001, test::kTool}});
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

  const auto two = test::make_scan({{0b1001, test::kJoint}, {0b0001, test::kWheel}});
  outcome = service.on_scan(two, 5);
  EXPECT_EQ(outcome.kind, Kind::kPublished);
  EXPECT_EQ(outcome.version, 2u);
  EXPECT_EQ(service.tree()->modules[1].key, "wheel");
  EXPECT_EQ(service.tree_scan_id(), 5u);
}

}  // namespace
}  // namespace concert::discovery
