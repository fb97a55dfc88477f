// Property: for thousands of seeded random assemblies, simulated bus -> scan -> discovery
// gives back exactly the tree the assembly describes, and the linear reconstruction agrees
// with the paper's algorithms.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <random>

#include "concert/simbus/assembly.hpp"
#include "concert/simbus/testing.hpp"
#include "concert/topology/scan_io.hpp"
#include "concert/topology/reconstruction.hpp"

namespace concert::topology {
namespace {


void check_round_trips(const EscCatalog& catalog, uint32_t seed, int trials, int max_modules,
                       double chain_bias) {
  std::mt19937 rng(seed);
  const Discovery real(catalog, DiscoveryParams{PortOrder::kReal0312});
  const Discovery numeric(catalog, DiscoveryParams{PortOrder::kNumeric0123});
  for (int trial = 0; trial < trials; ++trial) {
    simbus::RandomAssemblyParams params;
    params.modules = 1 + static_cast<int32_t>(rng() % static_cast<uint32_t>(max_modules));
    params.chain_bias = chain_bias;
    params.hub_bias = 0.1 + 0.3 * static_cast<double>(rng() % 4) / 3.0;
    const simbus::Assembly assembly = simbus::random_assembly(catalog, rng, params);
    for (const Discovery* d : {&real, &numeric}) {
      const PortOrder order = d->params().port_order;
      const auto scan = simbus::simulate_scan(assembly, catalog, order);
      const auto expected = simbus::tree_from_assembly(assembly, catalog, order);
      ModuleTree got;
      try {
        got = d->run(scan);
      } catch (const DiscoveryError& e) {
        FAIL() << "seed " << seed << " trial " << trial << " order " << to_string(order) << ": "
               << e.what() << "\n" << simbus::assembly_to_yaml(assembly);
      }
      ASSERT_EQ(got, expected) << "seed " << seed << " trial " << trial << " order "
                               << to_string(order) << "\n" << simbus::assembly_to_yaml(assembly)
                               << tree_to_text(got);
      const auto checked = checked_scan(scan);
      ASSERT_EQ(reconstruct_network(checked, order), reconstruct_network_reference(checked, order))
          << "seed " << seed << " trial " << trial;
    }
  }
}

TEST(Property, SyntheticCatalogueSmallAndBushyTrees) {
  check_round_trips(simbus::synthetic_catalog(), 1, 2000, 40, 0.3);
}

TEST(Property, SyntheticCatalogueLongChains) {
  check_round_trips(simbus::synthetic_catalog(), 2, 300, 400, 0.95);
}

TEST(Property, PublicCatalogue) {
  check_round_trips(EscCatalog::load(std::string(CONCERT_SHARED_DATA) + "/concert_resources"), 3,
                    1000, 30, 0.6);
}

TEST(Property, CatalogueBuiltEntryByEntry) {
  // No YAML at all: a joint, a cross-point hub and a tool, added in code.
  EscCatalog catalog;
  const auto add = [&](EscIdentity id, const char* key, ModuleKind kind) {
    EscType t;
    t.identity = id;
    t.key = key;
    t.kind = kind;
    catalog.add(t);
  };
  add({1, 10, 0, 0}, "j", ModuleKind::kJoint);
  add({2, 10, 0, 0}, "h", ModuleKind::kHub);
  add({3, 10, 0, 0}, "t", ModuleKind::kEndEffector);
  check_round_trips(catalog, 6, 500, 60, 0.5);
}

TEST(Property, VeryLongChain) {
  // 5000 modules, almost a single chain: no recursion in bus, tree or discovery.
  const EscCatalog catalog = simbus::synthetic_catalog();
  std::mt19937 rng(4);
  const auto assembly = simbus::random_assembly(catalog, rng, {5000, 0.99, 0.01, true});
  const auto scan = simbus::simulate_scan(assembly, catalog);
  EXPECT_EQ(discover(scan, catalog), simbus::tree_from_assembly(assembly, catalog));
}

TEST(Property, ScanFilesRoundTripThroughDiscovery) {
  // Random scans written as YAML and JSON read back to the same tree.
  const EscCatalog catalog = simbus::synthetic_catalog();
  std::mt19937 rng(5);
  for (int trial = 0; trial < 100; ++trial) {
    const auto assembly = simbus::random_assembly(catalog, rng, {30, 0.5, 0.2, true});
    const auto scan = simbus::simulate_scan(assembly, catalog);
    const auto expected = simbus::tree_from_assembly(assembly, catalog);
    EXPECT_EQ(discover(parse_scan_yaml(scan_to_yaml(scan), "y"), catalog),
              expected);
    EXPECT_EQ(
        discover(parse_scan_json(scan_to_json(scan).dump(), "j"), catalog),
        expected);
  }
}

}  // namespace
}  // namespace concert::topology

namespace concert::topology {
namespace {

/// Depth of the deepest chain of hub modules, each mounted below the previous one.
int hub_depth(const ModuleTree& tree) {
  std::vector<int> depth(tree.modules.size(), 0);
  int best = 0;
  for (const auto& m : tree.modules) {
    const int above = m.parent_module >= 0 ? depth[static_cast<std::size_t>(m.parent_module)] : 0;
    depth[static_cast<std::size_t>(m.index)] =
        above + (m.kind == ModuleKind::kHub ? 1 : 0);
    best = std::max(best, depth[static_cast<std::size_t>(m.index)]);
  }
  return best;
}

TEST(Property, SeveralHubsChainedOrSideBySideWithTwoAndFourPortBoards) {
  // Hub-heavy random robots: hub trees of any depth, several hubs per robot, two-port boards
  // (joints, links, tools, wheels) mixed with four-port hub boards and multi-ESC hubs.
  const EscCatalog catalog = simbus::synthetic_catalog();
  std::mt19937 rng(7);
  int with_three_hubs = 0;
  int chained_three_deep = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const auto assembly = simbus::random_assembly(catalog, rng, {40, 0.5, 0.45, true});
    const auto scan = simbus::simulate_scan(assembly, catalog);
    const auto expected = simbus::tree_from_assembly(assembly, catalog);
    const auto got = Discovery(catalog).rebuild(scan);
    ASSERT_TRUE(got.issues.empty()) << "trial " << trial << ": " << tree_to_text(got);
    ASSERT_EQ(got, expected) << "trial " << trial << "\n" << simbus::assembly_to_yaml(assembly);
    int hubs = 0;
    for (const auto& m : got.modules) hubs += m.kind == ModuleKind::kHub ? 1 : 0;
    with_three_hubs += hubs >= 3 ? 1 : 0;
    chained_three_deep += hub_depth(got) >= 3 ? 1 : 0;
    for (const auto& node : got.slaves) {
      const auto& module = got.modules[static_cast<std::size_t>(node.module_index)];
      if (module.kind != ModuleKind::kHub) {
        ASSERT_EQ(node.slave.active_ports & 0b1100, 0)
            << "trial " << trial << ": a two-port board opened port 2 or 3, slave "
            << node.slave.position;
      }
    }
  }
  // The generator really covers what the test claims.
  EXPECT_GT(with_three_hubs, 500);
  EXPECT_GT(chained_three_deep, 200);
}

TEST(Property, BlankIdentitiesAndTopologyDisagreementsGiveTheSameNetworkPlusWarnings) {
  const EscCatalog catalog =
      EscCatalog::load(std::string(CONCERT_SHARED_DATA) + "/concert_resources");
  std::mt19937 rng(11);
  for (int trial = 0; trial < 500; ++trial) {
    auto assembly = simbus::random_assembly(catalog, rng, {25, 0.6, 0.3, true});
    const auto clean = Discovery(catalog).rebuild(simbus::simulate_scan(assembly, catalog));
    ASSERT_TRUE(clean.issues.empty());
    std::size_t blank_modules = 0;
    std::size_t warnings = 0;
    std::vector<bool> touched(assembly.modules.size(), false);
    for (int k = 0; k < 3; ++k) {
      const std::size_t m = rng() % assembly.modules.size();
      if (touched[m]) continue;
      touched[m] = true;
      const auto layout = catalog.layout(catalog.find_key(assembly.modules[m].key)->identity);
      simbus::Fault fault;
      fault.module = assembly.modules[m].name;
      fault.esc = static_cast<int32_t>(rng() % layout.escs.size());
      if (rng() % 2 == 0) {
        fault.type = simbus::FaultType::kUnknownIdentity;  // all zero
        blank_modules += fault.esc == 0 ? 1 : 0;
      } else {
        fault.type = simbus::FaultType::kWrongTopology;
        fault.topology = 4;  // never true of a two-port board, rarely of a hub
      }
      assembly.faults.push_back(fault);
    }
    const auto scan = simbus::simulate_scan(assembly, catalog);
    for (const auto& s : scan.slaves) {
      warnings += std::popcount(static_cast<unsigned>(s.active_ports)) != s.topology ? 1 : 0;
    }
    const auto tree = Discovery(catalog).rebuild(scan);
    ASSERT_FALSE(tree.has_errors()) << "trial " << trial << ": " << tree_to_text(tree);
    ASSERT_EQ(tree.slaves.size(), clean.slaves.size());
    for (std::size_t i = 0; i < tree.slaves.size(); ++i) {
      ASSERT_EQ(tree.slaves[i].parent_position, clean.slaves[i].parent_position) << trial;
      ASSERT_EQ(tree.slaves[i].parent_port, clean.slaves[i].parent_port) << trial;
    }
    EXPECT_EQ(tree.unknown_modules().size(), blank_modules) << "trial " << trial;
    std::size_t topology_warnings = 0;
    for (const auto& issue : tree.issues) {
      topology_warnings += issue.message.rfind("topology says", 0) == 0 ? 1 : 0;
    }
    EXPECT_EQ(topology_warnings, warnings) << "trial " << trial;
  }
}

}  // namespace
}  // namespace concert::topology
