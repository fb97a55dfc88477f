#pragma once
#include <ostream>
#include <string>
#include <vector>

#include "concert/topology/esc_catalog.hpp"

namespace concert::cli {

/// The ESC catalogue of the given module databases (merged in order); the project's own
/// database when none is given.
topology::EscCatalog load_catalogs(std::vector<std::string> module_dbs);

/// `concert scan show|publish ...`; args start after "scan". Returns the exit code.
int run_scan(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace concert::cli
