// Module tree from the network graph: group the ESCs of multi-ESC modules, name each module
// from the catalogue and find the output connector each module hangs on.
#include "concert/topology/reconstruction.hpp"

#include <algorithm>
#include <utility>

namespace concert::topology {
namespace {


std::string module_name(const ModuleNode& m) {
  return "module #" + std::to_string(m.index) + " " + m.key + " (" + to_string(m.kind) + ")";
}

std::string connectors_text(const ModuleLayout& layout) {
  if (layout.connectors.empty()) return "no output connector";
  std::string text = std::to_string(layout.outputs()) + " output connector" +
                     (layout.outputs() == 1 ? "" : "s") + " (";
  for (std::size_t i = 0; i < layout.connectors.size(); ++i) {
    const auto& c = layout.connectors[i];
    if (i > 0) text += ", ";
    text += std::to_string(c.connector) + " on port " + std::to_string(c.port);
    if (layout.escs.size() > 1) text += " of ESC " + std::to_string(c.esc + 1);
  }
  return text + ")";
}

}  // namespace

Discovery::Discovery(EscCatalog catalog, DiscoveryParams params)
    : catalog_(std::move(catalog)), params_(params) {
  for (const auto& entry : catalog_.entries()) {
    layouts_.emplace(entry.identity, catalog_.layout(entry.identity, params_.port_order));
  }
}

ModuleTree Discovery::rebuild(const EscScan& raw_scan) const {
  using Severity = TreeIssue::Severity;
  ScanCheck check = check_scan(raw_scan);
  const EscScan& scan = check.scan;
  Network network = rebuild_network(scan, params_.port_order, check.usable);
  const std::size_t n = network.links.size();
  const auto& links = network.links;

  ModuleTree tree;
  tree.issues = std::move(check.issues);
  const auto warn = [&](int32_t position, std::string message) {
    tree.issues.push_back({Severity::kWarning, position, std::move(message)});
  };
  const auto fail = [&](int32_t position, std::string message) {
    tree.issues.push_back({Severity::kError, position, std::move(message)});
  };

  std::vector<int32_t> child_count(n, 0);
  for (const auto& link : links) {
    if (link.parent_position > 0) ++child_count[static_cast<std::size_t>(link.parent_position - 1)];
  }

  tree.slaves.resize(n);
  std::vector<const ModuleLayout*> module_layouts;  // nullptr: unknown module
  std::vector<int32_t> esc_in_module(n, 0);  // index of the slave's ESC in its module layout
  std::vector<std::pair<int32_t, int32_t>> misfilled;  // (module, ESC) taken by a foreign slave

  for (std::size_t i = 0; i < n; ++i) {
    const auto& slave = scan.slaves[i];
    const SlaveLink& link = links[i];
    SlaveNode& node = tree.slaves[i];
    node.slave = slave;
    node.parent_position = link.parent_position;
    node.parent_port = link.parent_port;

    int32_t parent_module = -1;
    int32_t parent_connector = -1;
    if (link.parent_position > 0) {
      const auto p = static_cast<std::size_t>(link.parent_position - 1);
      const int32_t port = *link.parent_port;
      parent_module = tree.slaves[p].module_index;
      const ModuleLayout* layout = module_layouts[static_cast<std::size_t>(parent_module)];
      ModuleNode& owner = tree.modules[static_cast<std::size_t>(parent_module)];
      if (layout == nullptr) {
        // Below an unknown module: the ports place it, no connector can be named.
      } else if (const auto esc = layout->esc_at(esc_in_module[p], port)) {
        // Another ESC of the parent's own module (e.g. the Mobile Base Hub's hub board).
        const auto& expected = layout->escs[static_cast<std::size_t>(*esc)].identity;
        if (slave.identity == expected || is_blank(slave.identity)) {
          if (slave.identity != expected) {
            warn(slave.position,
                 "reports a blank identity (all zero: identity EEPROM not "
                 "programmed?) where " +
                     module_name(owner) + " has its ESC " + to_string(expected) +
                     "; taken as that ESC");
          }
          node.module_index = parent_module;
          esc_in_module[i] = *esc;
          owner.slave_positions.push_back(slave.position);
          continue;
        }
        misfilled.emplace_back(parent_module, *esc);
        fail(slave.position, "hangs on port " + std::to_string(port) + " of slave " +
                                 std::to_string(link.parent_position) + ", where " +
                                 module_name(owner) + " has its ESC " + to_string(expected) +
                                 ", but reports " + to_string(slave.identity));
      } else if (const auto connector = layout->connector_at(esc_in_module[p], port)) {
        parent_connector = *connector;
      } else {
        int32_t children = 0;
        for (int32_t pos : owner.slave_positions) {
          children += child_count[static_cast<std::size_t>(pos - 1)];
        }
        children -= static_cast<int32_t>(layout->escs.size()) - 1;
        if (children > layout->outputs()) {
          fail(owner.slave_positions.front(),
               module_name(owner) + " has " + std::to_string(children) + " child module" +
                   (children == 1 ? "" : "s") + " but " + owner.key + " has " +
                   connectors_text(*layout) + "; slave " + std::to_string(slave.position) +
                   " hangs on port " + std::to_string(port) + " of slave " +
                   std::to_string(link.parent_position));
        } else {
          misfilled.emplace_back(parent_module, *esc);
          fail(slave.position, "hangs on port " + std::to_string(port) + " of slave " +
                                   std::to_string(link.parent_position) +
                                   ", which is not an output connector of " + module_name(owner) +
                                   ": it has " + connectors_text(*layout));
        }
      }
    }

    ModuleNode module;
    module.index = static_cast<int32_t>(tree.modules.size());
    module.identity = slave.identity;
    module.slave_positions.push_back(slave.position);
    module.parent_module = parent_module;
    module.parent_connector = parent_connector;
    module.robot_id = slave.robot_id;
    const auto found = layouts_.find(slave.identity);
    if (found == layouts_.end()) {
      module.known = false;
      module.kind = module_kind_from_mod_type(slave.identity.mod_type)
                        .value_or(ModuleKind::kUnknown);
      warn(slave.position,
           is_blank(slave.identity)
               ? "blank module identity (all zero: identity EEPROM not programmed?): unknown "
                 "module in the tree"
               : "unknown module identity " + to_string(slave.identity) +
                     ": not in the ESC catalogue; unknown module in the tree");
      module_layouts.push_back(nullptr);
    } else {
      module.key = found->second.key;
      module.kind = found->second.kind;
      module_layouts.push_back(&found->second);
    }
    node.module_index = module.index;
    esc_in_module[i] = 0;
    tree.modules.push_back(std::move(module));
  }

  for (std::size_t m = 0; m < tree.modules.size(); ++m) {
    const ModuleLayout* layout = module_layouts[m];
    const ModuleNode& module = tree.modules[m];
    if (layout == nullptr || module.slave_positions.size() == layout->escs.size()) continue;
    // The first ESC of the layout that no slave filled (the scan may have stopped early).
    std::vector<bool> present(layout->escs.size(), false);
    for (int32_t pos : module.slave_positions) {
      present[static_cast<std::size_t>(esc_in_module[static_cast<std::size_t>(pos - 1)])] = true;
    }
    for (const auto& [owner, esc] : misfilled) {
      if (owner == module.index) present[static_cast<std::size_t>(esc)] = true;  // reported above
    }
    for (std::size_t e = 1; e < layout->escs.size(); ++e) {
      if (present[e] || n < scan.slaves.size()) continue;
      const auto& placement = layout->escs[e];
      fail(module.slave_positions.front(),
           module_name(module) + " lacks its ESC " + to_string(placement.identity) + " on port " +
               std::to_string(placement.parent_port) + " of its ESC " +
               std::to_string(placement.parent_esc + 1));
      break;
    }
  }
  if (network.error) tree.issues.push_back(std::move(*network.error));
  return tree;
}

ModuleTree Discovery::run(const EscScan& scan) const {
  ModuleTree tree = rebuild(scan);
  for (const auto& issue : tree.issues) {
    if (issue.severity == TreeIssue::Severity::kError) {
      throw DiscoveryError(issue.position, issue.message);
    }
  }
  return tree;
}

ModuleTree discover(const EscScan& scan, const EscCatalog& catalog,
                    const DiscoveryParams& params) {
  return Discovery(catalog, params).run(scan);
}

}  // namespace concert::topology
