#pragma once
// `concert discover` verb: scan file -> module tree on stdout.

#include <ostream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/topology/port_order.hpp"

namespace concert::discovery {

/// What `concert discover` reads.
struct DiscoverOptions {
  std::string scan;  ///< scan file (YAML or JSON)
  std::string port_order = "0312";  ///< frame processing order of the ESC ports: 0312 or 0123
  /// Module databases, merged in order (later entries override earlier ones with the same
  /// identity); empty: the project database (CONCERT_DEFAULT_MODULE_DB, <source>/data/module_db).
  std::vector<std::string> module_dbs;
  bool json = false;
};

/// Rebuilds the module tree of `options.scan` and prints it (JSON with `json`) to `out`.
/// Returns 0, or 1 with a one-line message naming what and where on `err`.
int discover(DiscoverOptions options, std::ostream& out, std::ostream& err);

/// Registers `concert discover --scan FILE [--port-order 0312|0123] [--module-db DIR ...]
/// [--json]` into `concert`.
void register_verbs(cli::Cli& concert);

}  // namespace concert::discovery
