#include "bus.hpp"

#include "concert/topology/reconstruction.hpp"
#include "concert/topology/scan_io.hpp"
#include "fuzz.hpp"

namespace concert::fuzz {

const std::vector<topology::EscCatalog>& catalogues() {
  static const std::vector<topology::EscCatalog> c{
      topology::EscCatalog::load(source_dir() / "data/module_db"),
      topology::EscCatalog::load(shared_data_dir() / "concert_resources")};
  return c;
}

topology::ModuleTree simulate_and_rebuild(const simbus::Assembly& assembly,
                                          const topology::EscCatalog& catalog,
                                          topology::PortOrder order) {
  const topology::EscScan scan = simbus::simulate_scan(assembly, catalog, order);
  const topology::ModuleTree expected = simbus::tree_from_assembly(assembly, catalog, order);
  const topology::ModuleTree got =
      topology::Discovery(catalog, topology::DiscoveryParams{order}).rebuild(scan);
  if (assembly.faults.empty()) {
    CONCERT_FUZZ_CHECK(got == expected, "discovery does not rebuild the assembly's tree (" +
                                            topology::to_string(order) + "):\n" +
                                            simbus::assembly_to_yaml(assembly) + "expected:\n" +
                                            topology::tree_to_text(expected) + "got:\n" +
                                            topology::tree_to_text(got));
  }
  return got;
}

}  // namespace concert::fuzz
