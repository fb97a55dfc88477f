#include "modelgen/cli.hpp"

#include <filesystem>
#include <fstream>

#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/scan_io.hpp"
#include "discovery/discovery.hpp"
#include "modelgen/bundle.hpp"
#include "modelgen/model_generator.hpp"

namespace concert::modelgen {
namespace {

namespace fs = std::filesystem;

constexpr const char* kUsage =
    "usage: concert model generate (--scan FILE | --tree FILE | --assembly FILE) --module-db DIR [--module-db DIR ...] "
    "--out DIR [--port-order 0312|0123] [--home JOINT=RAD ...] [--addon EE=ADDON ...]";

struct Options {
  std::string scan, tree, assembly, out;
  std::vector<fs::path> module_dbs;
  topology::PortOrder order = topology::PortOrder::kReal0312;
  Customisation custom;
};

std::string parse(const std::vector<std::string>& args, Options& o) {
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& arg = args[i];
    auto value = [&](std::string& into) -> std::string {
      if (i + 1 >= args.size()) return "option " + arg + " needs a value";
      into = args[++i];
      return {};
    };
    std::string text;
    std::string e;
    if (arg == "--scan") {
      e = value(o.scan);
    } else if (arg == "--tree") {
      e = value(o.tree);
    } else if (arg == "--assembly") {
      e = value(o.assembly);
    } else if (arg == "--out") {
      e = value(o.out);
    } else if (arg == "--module-db") {
      e = value(text);
      o.module_dbs.emplace_back(text);
    } else if (arg == "--port-order") {
      e = value(text);
      const auto order = topology::parse_port_order(text);
      if (e.empty() && !order) return "--port-order '" + text + "': expected 0312 or 0123";
      if (order) o.order = *order;
    } else if (arg == "--home" || arg == "--addon") {
      e = value(text);
      const size_t eq = text.find('=');
      if (e.empty() && (eq == std::string::npos || eq == 0 || eq + 1 == text.size())) {
        return arg + " '" + text + "': expected " + (arg == "--home" ? "JOINT=RAD" : "EE=ADDON");
      }
      if (!e.empty()) return e;
      if (arg == "--home") {
        try {
          size_t pos = 0;
          const double v = std::stod(text.substr(eq + 1), &pos);
          if (pos != text.size() - eq - 1) throw std::invalid_argument("trailing characters");
          o.custom.home[text.substr(0, eq)] = v;
        } catch (const std::exception&) {
          return "--home '" + text + "': '" + text.substr(eq + 1) + "' is not a number";
        }
      } else {
        o.custom.addons.push_back({text.substr(0, eq), text.substr(eq + 1)});
      }
    } else {
      return "unknown argument '" + arg + "'";
    }
    if (!e.empty()) return e;
  }
  const int sources = (o.scan.empty() ? 0 : 1) + (o.tree.empty() ? 0 : 1) + (o.assembly.empty() ? 0 : 1);
  if (sources != 1) return "give exactly one of --scan, --tree, --assembly";
  if (o.module_dbs.empty()) return "missing --module-db DIR";
  if (o.out.empty()) return "missing --out DIR";
  return {};
}

topology::EscCatalog catalog_of(const std::vector<fs::path>& dirs) {
  topology::EscCatalog catalog;
  for (const fs::path& d : dirs) catalog.merge(topology::EscCatalog::load(d));
  return catalog;
}

int generate(const Options& o, std::ostream& out) {
  const module_db::ModuleDatabase db = module_db::load_module_databases(o.module_dbs);
  topology::ModuleTree tree;
  std::string source;
  if (!o.tree.empty()) {
    std::ifstream in(o.tree);
    if (!in) throw std::runtime_error(o.tree + ": cannot open");
    nlohmann::json doc;
    try {
      in >> doc;
    } catch (const nlohmann::json::exception& e) {
      throw std::runtime_error(o.tree + ": invalid JSON: " + e.what());
    }
    tree = topology::tree_from_json(doc, o.tree);
    source = o.tree;
  } else if (!o.scan.empty()) {
    tree = discovery::discover(topology::load_scan(o.scan), catalog_of(o.module_dbs), {o.order});
    source = o.scan;
  } else {
    const topology::EscCatalog catalog = catalog_of(o.module_dbs);
    const simbus::Assembly assembly = simbus::load_assembly(o.assembly);
    tree = discovery::discover(simbus::simulate_scan(assembly, catalog, o.order), catalog, {o.order});
    source = o.assembly;
  }
  GeneratedModel model = ModelGenerator(db).generate(tree, o.custom);
  const auto [old_version, old_hash] = read_bundle_version(o.out);
  const bool unchanged = old_version > 0 && old_hash == model.content_hash;
  model.version = unchanged ? old_version : old_version + 1;
  if (!unchanged) write_bundle(model, o.out);
  out << (unchanged ? "unchanged" : "wrote") << " model version " << model.version << " (" << model.content_hash << ") from " << source
      << " to " << o.out << "\n";
  out << "  " << model.modules.size() << " modules, " << model.tree.bodies.size() << " links, " << model.joints.size()
      << " moving joints\n";
  for (const ChainInfo& c : model.chains) {
    out << "  chain " << c.name << " (" << concert::model::to_string(c.role) << "): " << c.base_link << " -> " << c.tip_link << ", joints:";
    for (const std::string& j : c.joints) out << " " << j;
    out << "\n";
  }
  for (const EndEffectorInfo& e : model.end_effectors) out << "  end-effector " << e.name << " (" << concert::model::to_string(e.kind) << ") at " << e.frame << " (" << e.module_key << ")\n";
  return 0;
}

}  // namespace

int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    (args.empty() ? err : out) << kUsage << "\n";
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "show") return show_main(args, out, err);
  if (args[0] != "generate") {
    err << "concert model: unknown verb '" << args[0] << "' (expected generate or show)\n";
    return 2;
  }
  Options o;
  if (const std::string e = parse(args, o); !e.empty()) {
    err << "concert model generate: " << e << "\n" << kUsage << "\n";
    return 2;
  }
  try {
    return generate(o, out);
  } catch (const std::exception& e) {
    err << "concert model generate: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace concert::modelgen
