#pragma once
// The EtherCAT side for the scan, assembly and catalogue targets: the catalogues the stack runs
// with, and the simulated bus -> discovery round trip.

#include <vector>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/types.hpp"

namespace concert::fuzz {

/// The catalogues of the project's and of the public module database (each alone: merged, the
/// public entries replace the project's, which share identities). Loaded once.
const std::vector<topology::EscCatalog>& catalogues();

/// The tree discovery rebuilds (it never throws) from the simulated bus's scan of `assembly`,
/// faults applied. Without faults it must be exactly the tree the assembly describes (checked).
/// Throws simbus::AssemblyError when the assembly does not fit the catalogue.
topology::ModuleTree simulate_and_rebuild(const simbus::Assembly& assembly,
                                          const topology::EscCatalog& catalog,
                                          topology::PortOrder order);

}  // namespace concert::fuzz
