#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "concert/simbus/assembly.hpp"
#include "concert/simbus/testing.hpp"
#include "concert/topology/reconstruction.hpp"
#include "scan_builder.hpp"

namespace concert::topology {
namespace {

using ::testing::HasSubstr;

using test::discovery_error;
using test::make_scan;

/// (parent_position, parent_port or -1) per slave, from both algorithms (which must agree).
std::vector<std::pair<int32_t, int32_t>> links_of(const EscScan& scan, PortOrder order) {
  const EscScan checked = checked_scan(scan);
  const auto linear = reconstruct_network(checked, order);
  const auto reference = reconstruct_network_reference(checked, order);
  EXPECT_EQ(linear, reference);
  std::vector<std::pair<int32_t, int32_t>> out;
  for (const auto& l : linear) out.emplace_back(l.parent_position, l.parent_port.value_or(-1));
  return out;
}

using Links = std::vector<std::pair<int32_t, int32_t>>;

TEST(Network, AppendixAExampleOne) {
  // Slave B on port 2 of slave A.
  const EscScan scan = make_scan({{0b0101}, {0b0001}});
  EXPECT_EQ(links_of(scan, PortOrder::kNumeric0123), (Links{{0, -1}, {1, 2}}));
  EXPECT_EQ(links_of(scan, PortOrder::kReal0312), (Links{{0, -1}, {1, 2}}));
}

TEST(Network, Line) {
  EXPECT_EQ(links_of(make_scan({{0b1001}, {0b1001}, {0b1001}, {0b0001}}), PortOrder::kReal0312),
            (Links{{0, -1}, {1, 3}, {2, 3}, {3, 3}}));
  EXPECT_EQ(links_of(make_scan({{0b0011}, {0b0011}, {0b0001}}), PortOrder::kNumeric0123),
            (Links{{0, -1}, {1, 1}, {2, 1}}));
}

TEST(Network, SplitPointThreeOpenPorts) {
  // Ports 0, 1, 3 open: the first child in ring order is on port 3 (real) or port 1 (paper).
  const EscScan scan = make_scan({{0b1011}, {0b1001}, {0b0001}, {0b0001}});
  EXPECT_EQ(links_of(scan, PortOrder::kReal0312), (Links{{0, -1}, {1, 3}, {2, 3}, {1, 1}}));
  EXPECT_EQ(links_of(scan, PortOrder::kNumeric0123), (Links{{0, -1}, {1, 1}, {2, 3}, {1, 3}}));
}

TEST(Network, CrossPointFourOpenPorts) {
  const EscScan scan = make_scan({{0b1111}, {0b0001}, {0b0001}, {0b0001}});
  EXPECT_EQ(links_of(scan, PortOrder::kReal0312), (Links{{0, -1}, {1, 3}, {1, 1}, {1, 2}}));
  EXPECT_EQ(links_of(scan, PortOrder::kNumeric0123), (Links{{0, -1}, {1, 1}, {1, 2}, {1, 3}}));
}

TEST(Network, HubTreeOfDepthThree) {
  // 1: cross point; 2: split under 1; 3, 4 leaves of 2; 5: cross under 1 with 6 (line to 7),
  // 8, 9; 10: leaf under 1.
  const EscScan scan = make_scan({{0b1111}, {0b0111}, {0b0001}, {0b0001}, {0b1111}, {0b1001},
                                  {0b0001}, {0b0001}, {0b0001}, {0b0001}});
  EXPECT_EQ(links_of(scan, PortOrder::kReal0312),
            (Links{{0, -1}, {1, 3}, {2, 1}, {2, 2}, {1, 1}, {5, 3}, {6, 3}, {5, 1}, {5, 2}, {1, 2}}));
  EXPECT_EQ(links_of(scan, PortOrder::kNumeric0123),
            (Links{{0, -1}, {1, 1}, {2, 1}, {2, 2}, {1, 2}, {5, 1}, {6, 3}, {5, 2}, {5, 3}, {1, 3}}));
}

TEST(Network, SingleSlave) {
  EXPECT_EQ(links_of(make_scan({{0b0001}}), PortOrder::kReal0312), (Links{{0, -1}}));
}

TEST(Network, CheckedScanSortsByPosition) {
  EscScan scan = make_scan({{0b1001}, {0b0001}});
  std::swap(scan.slaves[0], scan.slaves[1]);
  const EscScan sorted = checked_scan(scan);
  EXPECT_EQ(sorted.slaves[0].position, 1);
  EXPECT_EQ(sorted.slaves[0].active_ports, 0b1001);
}

TEST(Network, ErrorsNameThePositionAndTheProblem) {
  EXPECT_EQ(discovery_error([] { (void)checked_scan(EscScan{}); }), "the scan has no slaves");
  EscScan dup = make_scan({{0b1001}, {0b1001}, {0b0001}});
  dup.slaves[2].position = 2;
  EXPECT_EQ(discovery_error([&] { (void)checked_scan(dup); }),
            "slave 2: position 2 appears twice in the scan");
  EscScan missing = make_scan({{0b1001}, {0b0001}});
  missing.slaves[0].position = 2;
  missing.slaves[1].position = 2;
  EXPECT_EQ(discovery_error([&] { (void)checked_scan(missing); }),
            "slave 1: position 1 is missing from the scan (2 slaves)");
  EscScan hole = make_scan({{0b1001}, {0b1001}});
  hole.slaves[1].position = 3;
  EXPECT_EQ(discovery_error([&] { (void)checked_scan(hole); }),
            "slave 3: position 3 is outside 1..2 (the scan has 2 slaves)");
  EscScan shifted = make_scan({{0b1001}, {0b0001}});
  shifted.slaves[0].position = 0;
  EXPECT_NE(discovery_error([&] { (void)checked_scan(shifted); }).find("position 0 is outside"),
            std::string::npos);
  EXPECT_NE(discovery_error([] { (void)checked_scan(make_scan({{0b1001}, {0b1000}})); })
                .find("slave 2: port 0 (upstream) is closed"),
            std::string::npos);
}

TEST(Network, TopologyDisagreeingWithActivePortsIsAWarningResolvedFromActivePorts) {
  // Real masters report it (../shared/data/README.md): the open-port register decides.
  EscScan lying = make_scan({{0b0011}, {0b0001}});
  lying.slaves[1].topology = 2;
  const ScanCheck check = check_scan(lying);
  ASSERT_EQ(check.issues.size(), 1u);
  EXPECT_EQ(check.issues[0].severity, TreeIssue::Severity::kWarning);
  EXPECT_EQ(
      check.issues[0].text(),
      "slave 2: topology says 2 open ports but active_ports 0b0001 has 1; using active_ports");
  EXPECT_EQ(check.usable, 2u);
  EXPECT_EQ(checked_scan(lying).slaves.size(), 2u);  // no error
}

TEST(Network, ErrorsKeepWhatCameBefore) {
  // Port 0 closed on slave 3: slaves 1 and 2 are still placed.
  const EscScan scan = make_scan({{0b0011}, {0b0011}, {0b0010}});
  const ScanCheck check = check_scan(scan);
  EXPECT_EQ(check.usable, 2u);
  const Network network = rebuild_network(check.scan, PortOrder::kReal0312, check.usable);
  EXPECT_EQ(network.links.size(), 2u);
  EXPECT_FALSE(network.error);  // the scan stopped early: the open port 1 of slave 2 is not blamed
  // A slave with no free port: the earlier ones are placed, the error names it.
  const EscScan extra = make_scan({{0b0011}, {0b0001}, {0b0001}, {0b0001}});
  const Network cut = rebuild_network(extra, PortOrder::kReal0312, extra.slaves.size());
  EXPECT_EQ(cut.links.size(), 2u);
  ASSERT_TRUE(cut.error);
  EXPECT_EQ(cut.error->position, 3);
}

TEST(Network, MoreChildrenThanOpenPorts) {
  // Slave 1 has one free port but two slaves follow it in the ring as its subtree.
  const EscScan scan = make_scan({{0b1001}, {0b0001}, {0b0001}});
  for (auto f : {&reconstruct_network, &reconstruct_network_reference}) {
    const std::string error = discovery_error([&] { (void)f(scan, PortOrder::kReal0312); });
    EXPECT_THAT(error, HasSubstr("slave 3: no earlier slave has a free open port"));
  }
}

TEST(Network, OpenPortWithNothingBehindIt) {
  const EscScan scan = make_scan({{0b1011}, {0b0001}});
  for (auto f : {&reconstruct_network, &reconstruct_network_reference}) {
    EXPECT_EQ(discovery_error([&] { (void)f(scan, PortOrder::kReal0312); }),
              "slave 1: port 1 is open but no slave hangs on it (broken link?)");
  }
}

/// Random ESC trees (any node 0..3 children on random distinct ports), written as the ring
/// the master would see, with the expected links, for both orders.
TEST(Network, LinearEqualsPaperReferenceOnRandomTrees) {
  std::mt19937 rng(2024);
  for (int trial = 0; trial < 400; ++trial) {
    for (PortOrder order : {PortOrder::kReal0312, PortOrder::kNumeric0123}) {
      const auto frame = frame_order(order);
      const int n_target = 1 + static_cast<int>(rng() % 150);
      // Build the tree: node -> children (port, child).
      std::vector<std::vector<std::pair<int32_t, int>>> children(1);
      std::vector<int> open_nodes{0};
      while (static_cast<int>(children.size()) < n_target && !open_nodes.empty()) {
        const int pick = static_cast<int>(rng() % open_nodes.size());
        const int parent = open_nodes[static_cast<std::size_t>(pick)];
        auto& list = children[static_cast<std::size_t>(parent)];
        std::vector<int32_t> free_ports;
        for (int32_t p = 1; p <= 3; ++p) {
          bool used = false;
          for (const auto& c : list) used = used || c.first == p;
          if (!used) free_ports.push_back(p);
        }
        const int32_t port = free_ports[rng() % free_ports.size()];
        const int child = static_cast<int>(children.size());
        list.emplace_back(port, child);
        const bool full = list.size() == 3;
        children.emplace_back();  // invalidates `list`
        if (full) open_nodes.erase(open_nodes.begin() + pick);
        open_nodes.push_back(child);
      }
      // Pre-order with children in frame order.
      EscScan scan;
      Links expected;
      std::vector<std::tuple<int, int32_t, int32_t>> todo{{0, 0, -1}};
      while (!todo.empty()) {
        const auto [node, parent_pos, port] = todo.back();
        todo.pop_back();
        EscSlave s;
        s.position = static_cast<int32_t>(scan.slaves.size()) + 1;
        s.active_ports = 1;
        for (const auto& c : children[static_cast<std::size_t>(node)]) {
          s.active_ports = static_cast<uint8_t>(s.active_ports | (1U << c.first));
        }
        s.topology = __builtin_popcount(s.active_ports);
        scan.slaves.push_back(s);
        expected.emplace_back(parent_pos, port);
        for (int k = 3; k >= 1; --k) {
          for (const auto& c : children[static_cast<std::size_t>(node)]) {
            if (c.first == frame[static_cast<std::size_t>(k)]) todo.emplace_back(c.second, s.position, c.first);
          }
        }
      }
      ASSERT_EQ(links_of(scan, order), expected) << "trial " << trial;
    }
  }
}

/// On arbitrary open-port masks the linear pass and the paper's algorithms agree exactly:
/// same links, or the same error for the same slave.
TEST(Network, LinearAndReferenceAgreeOnArbitraryMasks) {
  std::mt19937 rng(99);
  int valid = 0;
  for (int trial = 0; trial < 8000; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 12);
    EscScan scan;
    for (int i = 0; i < n; ++i) {
      EscSlave s;
      s.position = i + 1;
      // Leaves are more likely, so that some random scans are valid trees.
      s.active_ports = static_cast<uint8_t>(rng() % 3 == 0 ? (1U | (rng() % 16)) : 1U);
      s.topology = __builtin_popcount(s.active_ports);
      scan.slaves.push_back(s);
    }
    for (PortOrder order : {PortOrder::kReal0312, PortOrder::kNumeric0123}) {
      std::string linear_error, reference_error;
      std::vector<SlaveLink> linear, reference;
      try {
        linear = reconstruct_network(scan, order);
      } catch (const DiscoveryError& e) {
        linear_error = e.what();
      }
      try {
        reference = reconstruct_network_reference(scan, order);
      } catch (const DiscoveryError& e) {
        reference_error = e.what();
      }
      ASSERT_EQ(linear_error, reference_error) << "trial " << trial;
      ASSERT_EQ(linear, reference) << "trial " << trial;
      valid += linear_error.empty() ? 1 : 0;
    }
  }
  EXPECT_GT(valid, 400);  // both outcomes are exercised
  EXPECT_LT(valid, 15000);
}

}  // namespace
}  // namespace concert::topology
