#include "discovery/cli.hpp"

#include <filesystem>
#include <memory>
#include <optional>

#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/scan_io.hpp"
#include "concert/topology/reconstruction.hpp"

namespace concert::discovery {

int discover(DiscoverOptions options, std::ostream& out, std::ostream& err) {
  try {
    if (options.module_dbs.empty()) {
      const std::filesystem::path fallback = CONCERT_DEFAULT_MODULE_DB;
      if (!std::filesystem::is_directory(fallback)) {
        err << "concert discover: default module database " << fallback.string()
            << " not found; pass --module-db DIR\n";
        return 1;
      }
      options.module_dbs.push_back(fallback.string());
    }
    topology::EscCatalog catalog;
    for (const auto& db : options.module_dbs) catalog.merge(topology::EscCatalog::load(db));
    const topology::EscScan scan = topology::load_scan(options.scan);
    const topology::Discovery discovery(std::move(catalog),
                              topology::DiscoveryParams{*topology::parse_port_order(options.port_order)});
    // The tree that could be rebuilt is always printed, with its warnings and errors; errors
    // (the tree is undefined there) also go to stderr and make the exit code 1.
    const topology::ModuleTree tree = discovery.rebuild(scan);
    if (options.json) {
      out << topology::tree_to_json(tree).dump(2) << "\n";
    } else {
      out << topology::tree_to_text(tree);
    }
    if (!tree.has_errors()) return 0;
    for (const auto& issue : tree.issues) {
      if (issue.severity == topology::TreeIssue::Severity::kError) {
        err << "concert discover: " << options.scan << ": " << issue.text() << "\n";
      }
    }
    return 1;
  } catch (const std::exception& e) {
    err << "concert discover: " << e.what() << "\n";
  }
  return 1;
}

void register_verbs(cli::Cli& concert) {
  auto o = std::make_shared<DiscoverOptions>();
  CLI::App& verb =
      concert.verb(concert.app(), "discover", "rebuild the module tree from an EtherCAT scan file",
                   [&concert, o] { return discover(*o, concert.out(), concert.err()); });
  verb.add_option("--scan", o->scan, "the scan file (YAML or JSON)")->type_name("FILE")->required();
  cli::Cli::add_choice(verb, "--port-order", o->port_order, {"0312", "0123"},
                       "frame processing order of the ESC ports (real hardware: 0312)");
  verb.add_option(
          "--module-db", o->module_dbs,
          "module database folder (repeat to merge, later ones override; default: the project's)")
      ->type_name("DIR");
  verb.add_flag("--json", o->json, "the tree as JSON");
}

}  // namespace concert::discovery
