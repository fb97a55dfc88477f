// esc_index.yaml, the catalogue of ESC identities, through both of its readers: the ESC
// catalogue discovery and the simulated bus use (libs/topology EscCatalog) and the module
// database's index (libs/module_db load_esc_index). Documented failures: CatalogError,
// ModuleDbError. Property: for a catalogue the reader accepts, the simulated bus's scan of
// seeded random assemblies of its modules is rebuilt by discovery as exactly their tree (the
// property test of libs/topology, on catalogues nobody wrote by hand).
#include <random>
#include <stdexcept>

#include "bus.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/simbus/testing.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;

void round_trips(const topology::EscCatalog& catalog, size_t seed) {
  std::mt19937 rng(static_cast<uint32_t>(seed));
  for (const auto order : {topology::PortOrder::kReal0312, topology::PortOrder::kNumeric0123}) {
    for (int trial = 0; trial < 4; ++trial) {
      simbus::Assembly assembly;
      try {
        assembly = simbus::random_assembly(catalog, rng, {.modules = 1 + trial * 4});
      } catch (const topology::CatalogError&) {
        return;  // an entry without a consistent layout: no assembly can use it
      } catch (const std::invalid_argument&) {
        return;  // no module with an output connector
      }
      try {
        (void)fuzz::simulate_and_rebuild(assembly, catalog, order);
      } catch (const simbus::AssemblyError&) {
        return;  // e.g. an entry whose layout holds only in the other frame order
      }
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = fuzz::text_of(data, size);
  try {
    (void)module_db::load_esc_index(fuzz::input_file("esc_index.yaml", text));
  } catch (const module_db::ModuleDbError&) {
  }
  topology::EscCatalog catalog;
  try {
    catalog = topology::EscCatalog::parse(text, "esc_index.yaml");
  } catch (const topology::CatalogError&) {
    return 0;
  }
  for (const topology::EscType& entry : catalog.entries()) {
    for (const auto order : {topology::PortOrder::kReal0312, topology::PortOrder::kNumeric0123}) {
      try {
        (void)catalog.layout(entry.identity, order);
      } catch (const topology::CatalogError&) {
      }
    }
  }
  round_trips(catalog, size);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add_file(source_dir() / "data/module_db/esc_index.yaml", source_dir() / "data");
  seeds.add_file(shared_data_dir() / "concert_resources/esc_index.yaml", shared_data_dir());
  seeds.add_tokens(kYamlTokens);
  seeds.add_tokens({"hub_board", "secondary", "mobile_base_ports", "module_ports", "esc_ports",
                    "esc_type", "outputs", "ports", "leads_to", "project_assigned"});
}
