#include "discovery/cli.hpp"

#include <filesystem>
#include <optional>

#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/scan_io.hpp"
#include "discovery/discovery.hpp"

namespace concert::discovery {
namespace {

constexpr const char* kUsage =
    "usage: concert discover --scan FILE [--port-order 0312|0123] [--module-db DIR ...] [--json]";

struct Options {
  std::string scan;
  topology::PortOrder order = topology::PortOrder::kReal0312;
  std::vector<std::string> module_dbs;
  bool json = false;
  bool help = false;
};

/// Parses the arguments; returns an error message or empty.
std::string parse(const std::vector<std::string>& args, Options& options) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    const auto value = [&](std::string& into) -> std::string {
      if (i + 1 >= args.size()) return "option " + arg + " needs a value";
      into = args[++i];
      return {};
    };
    std::string text;
    if (arg == "--scan") {
      if (auto e = value(options.scan); !e.empty()) return e;
    } else if (arg == "--module-db") {
      if (auto e = value(text); !e.empty()) return e;
      options.module_dbs.push_back(text);
    } else if (arg == "--port-order") {
      if (auto e = value(text); !e.empty()) return e;
      const auto order = topology::parse_port_order(text);
      if (!order) return "--port-order '" + text + "': expected 0312 or 0123";
      options.order = *order;
    } else if (arg == "--json") {
      options.json = true;
    } else if (arg == "--help" || arg == "-h") {
      options.help = true;
    } else {
      return "unknown argument '" + arg + "'";
    }
  }
  if (!options.help && options.scan.empty()) return "missing --scan FILE";
  return {};
}

}  // namespace

int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  Options options;
  if (const std::string error = parse(args, options); !error.empty()) {
    err << "concert discover: " << error << "\n" << kUsage << "\n";
    return 2;
  }
  if (options.help) {
    out << kUsage << "\n";
    return 0;
  }
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
    const Discovery discovery(std::move(catalog), Params{options.order});
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

}  // namespace concert::discovery
