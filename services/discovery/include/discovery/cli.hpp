#pragma once
// `concert discover` verb: scan file -> module tree on stdout.

#include <ostream>
#include <string>
#include <vector>

namespace concert::discovery {

/// Runs `concert discover <args>`: `--scan FILE [--port-order 0312|0123] [--module-db DIR ...]
/// [--json]`. Without --module-db the project database (CONCERT_DEFAULT_MODULE_DB, i.e.
/// <source>/data/module_db) is used; several --module-db are merged, later ones overriding
/// earlier entries with the same identity. Prints the tree (JSON with --json) to `out`;
/// returns 0, or non-zero with a one-line message naming what and where on `err`.
int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace concert::discovery
