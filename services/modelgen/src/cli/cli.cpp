#include "modelgen/cli.hpp"

#include <filesystem>
#include <fstream>
#include <memory>

#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/scan_io.hpp"
#include "concert/topology/reconstruction.hpp"
#include "modelgen/bundle.hpp"
#include "modelgen/model_generator.hpp"

namespace concert::modelgen {
namespace {

namespace fs = std::filesystem;

topology::EscCatalog catalog_of(const std::vector<fs::path>& dirs) {
  topology::EscCatalog catalog;
  for (const fs::path& d : dirs) catalog.merge(topology::EscCatalog::load(d));
  return catalog;
}

}  // namespace

int generate(const GenerateOptions& o, std::ostream& out) {
  const topology::PortOrder order = *topology::parse_port_order(o.port_order);
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
    tree = topology::discover(topology::load_scan(o.scan), catalog_of(o.module_dbs), {order});
    source = o.scan;
  } else {
    const topology::EscCatalog catalog = catalog_of(o.module_dbs);
    const simbus::Assembly assembly = simbus::load_assembly(o.assembly);
    tree = topology::discover(simbus::simulate_scan(assembly, catalog, order), catalog, {order});
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
  if (const std::string rest = describe(model.resting, Params{}.home_torque_fraction); !rest.empty()) out << "  " << rest << "\n";
  for (const EndEffectorInfo& e : model.end_effectors) out << "  end-effector " << e.name << " (" << concert::model::to_string(e.kind) << ") at " << e.frame << " (" << e.module_key << ")\n";
  return 0;
}

namespace {

/// "NAME=VALUE" split at the first '=', both parts non-empty.
std::pair<std::string, std::string> pair_of(const std::string& text) {
  const size_t eq = text.find('=');
  return {text.substr(0, eq), text.substr(eq + 1)};
}

CLI::Validator name_equals(const std::string& what, bool number) {
  return CLI::Validator(
      [what, number](std::string& text) -> std::string {
        const size_t eq = text.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == text.size()) {
          return "'" + text + "': expected " + what;
        }
        if (number) {
          const std::string value = text.substr(eq + 1);
          size_t pos = 0;
          try {
            (void)std::stod(value, &pos);
          } catch (const std::exception&) {
            pos = 0;
          }
          if (pos != value.size()) return "'" + text + "': '" + value + "' is not a number";
        }
        return "";
      },
      "", what);
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& model =
      concert.group(concert.app(), "model", "robot models: generate a bundle, show the live model");

  auto g = std::make_shared<GenerateOptions>();
  CLI::App& gen = concert.verb(
      model, "generate", "write URDF, SRDF, controller config and manifest to a bundle folder",
      [&concert, g] { return generate(*g, concert.out()); });
  CLI::Option* scan = gen.add_option("--scan", g->scan, "an EtherCAT scan file")->type_name("FILE");
  CLI::Option* tree = gen.add_option("--tree", g->tree, "a module tree (JSON)")->type_name("FILE");
  CLI::Option* assembly =
      gen.add_option("--assembly", g->assembly,
                     "an assembly file (through the simulated bus and discovery)")
          ->type_name("FILE");
  scan->excludes(tree)->excludes(assembly);
  tree->excludes(assembly);
  gen.add_option("--module-db", g->module_dbs,
                 "module database folder, either format (repeat to merge)")
      ->type_name("DIR")
      ->required();
  gen.add_option("--out", g->out, "the bundle folder")->type_name("DIR")->required();
  cli::Cli::add_choice(gen, "--port-order", g->port_order, {"0312", "0123"},
                       "frame processing order of the ESC ports");
  gen.add_option_function<std::vector<std::string>>(
         "--home",
         [g](const std::vector<std::string>& items) {
           for (const auto& item : items) {
             const auto [joint, value] = pair_of(item);
             g->custom.home[joint] = std::stod(value);
           }
         },
         "homing position of a joint (repeat)")
      ->type_name("JOINT=RAD")
      ->check(name_equals("JOINT=RAD", true));
  gen.add_option_function<std::vector<std::string>>(
         "--addon",
         [g](const std::vector<std::string>& items) {
           for (const auto& item : items) {
             const auto [ee, addon] = pair_of(item);
             g->custom.addons.push_back({ee, addon});
           }
         },
         "mount an add-on on an end-effector or body (repeat)")
      ->type_name("EE=ADDON")
      ->check(name_equals("EE=ADDON", false));
  gen.callback([scan, tree, assembly] {
    if (scan->count() + tree->count() + assembly->count() != 1) {
      throw CLI::ValidationError("give exactly one of --scan, --tree, --assembly");
    }
  });

  auto s = std::make_shared<cli::DdsOptions>();
  CLI::App& show_verb = concert.verb(
      model, "show", "the live robot model: version, modules, chains, joints, end-effectors",
      [&concert, s] { return show(*s, concert.out()); });
  concert.add_dds_options(show_verb, *s, 3.0, "how long to wait for the latched model");
}

}  // namespace concert::modelgen
