#pragma once
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::tool {

/// The ESC catalogue of the given module databases (merged in order); the project's own
/// database when none is given.
topology::EscCatalog load_catalogs(std::vector<std::string> module_dbs);

/// Registers `concert scan show|publish`.
void register_scan_verbs(cli::Cli& concert);

}  // namespace concert::tool
