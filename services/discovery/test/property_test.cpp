// Property: for thousands of seeded random assemblies, simulated bus -> scan -> discovery
// gives back exactly the tree the assembly describes, and the linear reconstruction agrees
// with the paper's algorithms.
#include <gtest/gtest.h>

#include <random>

#include "concert/simbus/assembly.hpp"
#include "concert/simbus/testing.hpp"
#include "concert/topology/scan_io.hpp"
#include "discovery/discovery.hpp"

namespace concert::discovery {
namespace {

using topology::EscCatalog;
using topology::PortOrder;

void check_round_trips(const EscCatalog& catalog, uint32_t seed, int trials, int max_modules,
                       double chain_bias) {
  std::mt19937 rng(seed);
  const Discovery real(catalog, Params{PortOrder::kReal0312});
  const Discovery numeric(catalog, Params{PortOrder::kNumeric0123});
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
      topology::ModuleTree got;
      try {
        got = d->run(scan);
      } catch (const DiscoveryError& e) {
        FAIL() << "seed " << seed << " trial " << trial << " order " << to_string(order) << ": "
               << e.what() << "\n" << simbus::assembly_to_yaml(assembly);
      }
      ASSERT_EQ(got, expected) << "seed " << seed << " trial " << trial << " order "
                               << to_string(order) << "\n" << simbus::assembly_to_yaml(assembly)
                               << topology::tree_to_text(got);
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
  const auto add = [&](topology::EscIdentity id, const char* key, topology::ModuleKind kind) {
    topology::EscType t;
    t.identity = id;
    t.key = key;
    t.kind = kind;
    catalog.add(t);
  };
  add({1, 10, 0, 0}, "j", topology::ModuleKind::kJoint);
  add({2, 10, 0, 0}, "h", topology::ModuleKind::kHub);
  add({3, 10, 0, 0}, "t", topology::ModuleKind::kEndEffector);
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
    EXPECT_EQ(discover(topology::parse_scan_yaml(topology::scan_to_yaml(scan), "y"), catalog),
              expected);
    EXPECT_EQ(
        discover(topology::parse_scan_json(topology::scan_to_json(scan).dump(), "j"), catalog),
        expected);
  }
}

}  // namespace
}  // namespace concert::discovery
