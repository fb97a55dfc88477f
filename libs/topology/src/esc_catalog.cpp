#include "concert/topology/esc_catalog.hpp"

#include <algorithm>
#include <set>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "concert/common/source_text.hpp"
#include "yaml_util.hpp"

namespace concert::topology {
namespace {

using detail::opt_int32;
using detail::req_int32;
using detail::where;

constexpr const char* kHubBoard = "hub_board";
// A module with more ESCs than this is taken as a cycle of secondary-ESC rows.
constexpr std::size_t kMaxEscsPerModule = 16;

/// A port row of a `mobile_base_ports:` / `module_ports:` section.
struct SectionRow {
  int32_t mod_type = 0;
  int32_t mod_id = 0;
  std::optional<int32_t> mod_size;
  std::optional<int32_t> mod_rev;
  int32_t port = 0;
  int32_t connector = 0;  // 0: hub board
  std::optional<EscIdentity> secondary;
  std::optional<std::pair<int32_t, int32_t>> secondary_type_id;  // given as (mod_type, mod_id)
  std::string context;
};

int32_t parse_port(const YAML::Node& row, const std::string& context) {
  const int32_t port = req_int32<CatalogError>(row, "port", context);
  if (port < 1 || port > 3) {
    throw CatalogError(context + ".port: " + std::to_string(port) +
                       " is not a downstream ESC port (1..3)" + where(row));
  }
  return port;
}

/// leads_to: a connector number >= 1, or "hub_board". Returns 0 for the hub board.
int32_t parse_leads_to(const YAML::Node& row, const std::string& context) {
  const YAML::Node node = row["leads_to"];
  if (!node) throw CatalogError(context + ": missing field 'leads_to'" + where(row));
  if (node.IsScalar() && node.Scalar() == kHubBoard) return 0;
  // A plain int with 0 for "no connector number" (an optional reset in the catch trips GCC 12's
  // -Wmaybe-uninitialized at -Os).
  int32_t connector = 0;
  try {
    connector = opt_int32<CatalogError>(row, "leads_to", context).value_or(0);
  } catch (const CatalogError&) {
    connector = 0;
  }
  if (connector < 1) {
    throw CatalogError(context + ".leads_to: expected a connector number >= 1 or '" + kHubBoard +
                       "'" + where(node));
  }
  return connector;
}

/// Optional `secondary: {mod_type, mod_id[, mod_size, mod_rev]}` of a hub-board row.
void parse_secondary(const YAML::Node& row, const std::string& context,
                     std::optional<EscIdentity>& full,
                     std::optional<std::pair<int32_t, int32_t>>& type_id) {
  const YAML::Node node = row["secondary"];
  if (!node) return;
  const std::string ctx = context + ".secondary";
  if (!node.IsMap()) throw CatalogError(ctx + ": expected a mapping" + where(node));
  const int32_t type = req_int32<CatalogError>(node, "mod_type", ctx);
  const int32_t id = req_int32<CatalogError>(node, "mod_id", ctx);
  const auto size = opt_int32<CatalogError>(node, "mod_size", ctx);
  const auto rev = opt_int32<CatalogError>(node, "mod_rev", ctx);
  if (size && rev) {
    full = EscIdentity{type, id, *size, *rev};
  } else {
    type_id = std::make_pair(type, id);
  }
}

/// The single module row with this (mod_type, mod_id); throws if none or several.
EscIdentity resolve_type_id(const std::vector<EscType>& types, int32_t type, int32_t id,
                            const std::string& context) {
  std::vector<EscIdentity> found;
  for (const auto& t : types) {
    if (t.identity.mod_type == type && t.identity.mod_id == id) found.push_back(t.identity);
  }
  if (found.empty()) {
    throw CatalogError(context + ": no module row has mod_type " + std::to_string(type) +
                       " and mod_id " + std::to_string(id));
  }
  if (found.size() > 1) {
    throw CatalogError(context + ": mod_type " + std::to_string(type) + ", mod_id " +
                       std::to_string(id) +
                       " matches several module rows; give mod_size and mod_rev");
  }
  return found.front();
}

void parse_section(const YAML::Node& root, const char* name, const std::string& source,
                   std::vector<EscType>& types) {
  const YAML::Node section = root[name];
  if (!section || section.IsNull()) return;
  const std::string section_ctx = source + ": " + name;
  if (!section.IsSequence()) throw CatalogError(section_ctx + ": expected a list" + where(section));

  std::vector<SectionRow> rows;
  for (std::size_t i = 0; i < section.size(); ++i) {
    const YAML::Node node = section[i];
    SectionRow row;
    row.context = section_ctx + "[" + std::to_string(i) + "]";
    if (!node.IsMap()) throw CatalogError(row.context + ": expected a mapping" + where(node));
    row.mod_type = req_int32<CatalogError>(node, "mod_type", row.context);
    row.mod_id = req_int32<CatalogError>(node, "mod_id", row.context);
    row.mod_size = opt_int32<CatalogError>(node, "mod_size", row.context);
    row.mod_rev = opt_int32<CatalogError>(node, "mod_rev", row.context);
    row.port = parse_port(node, row.context);
    row.connector = parse_leads_to(node, row.context);
    if (row.connector == 0) {
      parse_secondary(node, row.context, row.secondary, row.secondary_type_id);
    } else if (node["secondary"]) {
      throw CatalogError(row.context + ": 'secondary' is only allowed with leads_to: hub_board");
    }
    rows.push_back(row);
  }

  // Which ESC is the hub board of a hub-board row without `secondary:`: the one identity of
  // the section that has port rows but no hub-board row of its own.
  std::set<std::pair<int32_t, int32_t>> with_rows;
  std::set<std::pair<int32_t, int32_t>> with_hub_board;
  for (const auto& row : rows) {
    with_rows.insert({row.mod_type, row.mod_id});
    if (row.connector == 0) with_hub_board.insert({row.mod_type, row.mod_id});
  }
  for (auto& row : rows) {
    if (row.connector != 0 || row.secondary) continue;
    if (!row.secondary_type_id) {
      std::vector<std::pair<int32_t, int32_t>> candidates;
      for (const auto& c : with_rows) {
        if (!with_hub_board.count(c)) candidates.push_back(c);
      }
      if (candidates.size() != 1) {
        throw CatalogError(row.context + ": cannot tell which ESC is the hub board (" +
                           std::to_string(candidates.size()) +
                           " candidates in the section); add secondary: {mod_type, mod_id}");
      }
      row.secondary_type_id = candidates.front();
    }
    row.secondary = resolve_type_id(types, row.secondary_type_id->first,
                                    row.secondary_type_id->second, row.context);
  }

  for (const auto& row : rows) {
    bool matched = false;
    for (auto& t : types) {
      if (t.identity.mod_type != row.mod_type || t.identity.mod_id != row.mod_id) continue;
      if (row.mod_size && t.identity.mod_size != *row.mod_size) continue;
      if (row.mod_rev && t.identity.mod_rev != *row.mod_rev) continue;
      matched = true;
      t.ports.push_back(PortLead{row.port, row.connector, row.secondary});
    }
    if (!matched) {
      throw CatalogError(row.context + ": no module row has mod_type " +
                         std::to_string(row.mod_type) + " and mod_id " +
                         std::to_string(row.mod_id));
    }
  }
}

EscType parse_module_row(const YAML::Node& node, const std::string& context) {
  if (!node.IsMap()) throw CatalogError(context + ": expected a mapping" + where(node));
  EscType t;
  t.origin = context;
  t.identity.mod_type = req_int32<CatalogError>(node, "mod_type", context);
  t.identity.mod_id = req_int32<CatalogError>(node, "mod_id", context);
  t.identity.mod_size = req_int32<CatalogError>(node, "mod_size", context);
  t.identity.mod_rev = req_int32<CatalogError>(node, "mod_rev", context);
  const auto kind = module_kind_from_mod_type(t.identity.mod_type);
  if (!kind) {
    throw CatalogError(context + ".mod_type: " + std::to_string(t.identity.mod_type) +
                       " is not a module type (1 joint, 2 hub, 3 end-effector, 4 link, 5 wheel, "
                       "6 base link)" + where(node));
  }
  t.kind = *kind;
  if (const YAML::Node file = node["file"]; file && !file.IsNull()) {
    if (!file.IsScalar()) throw CatalogError(context + ".file: expected a path" + where(file));
    t.file = file.Scalar();
  }
  if (const YAML::Node key = node["key"]; key && !key.IsNull()) {
    if (!key.IsScalar() || key.Scalar().empty()) {
      throw CatalogError(context + ".key: expected a module-database key" + where(key));
    }
    t.key = key.Scalar();
  } else if (!t.file.empty()) {
    t.key = std::filesystem::path(t.file).stem().string();
  } else {
    throw CatalogError(context + ": needs 'file' or 'key'" + where(node));
  }
  t.outputs = opt_int32<CatalogError>(node, "outputs", context);
  if (t.outputs && *t.outputs < 0) {
    throw CatalogError(context + ".outputs: " + std::to_string(*t.outputs) + " is negative");
  }
  if (const auto ports = opt_int32<CatalogError>(node, "esc_ports", context)) {
    t.board = board_from_port_count(*ports);
    if (!t.board) {
      throw CatalogError(context + ".esc_ports: " + std::to_string(*ports) +
                         " is not a board's port count (2 or 4)" + where(node));
    }
  }
  t.esc_type = opt_int32<CatalogError>(node, "esc_type", context);
  if (const YAML::Node ports = node["ports"]; ports && !ports.IsNull()) {
    if (!ports.IsSequence()) throw CatalogError(context + ".ports: expected a list" + where(ports));
    for (std::size_t i = 0; i < ports.size(); ++i) {
      const std::string ctx = context + ".ports[" + std::to_string(i) + "]";
      const YAML::Node row = ports[i];
      if (!row.IsMap()) throw CatalogError(ctx + ": expected a mapping" + where(row));
      PortLead lead;
      lead.port = parse_port(row, ctx);
      lead.connector = parse_leads_to(row, ctx);
      if (lead.connector == 0) {
        std::optional<std::pair<int32_t, int32_t>> type_id;
        parse_secondary(row, ctx, lead.secondary_esc, type_id);
        if (!lead.secondary_esc) {
          throw CatalogError(ctx + ": leads_to: hub_board needs secondary: {mod_type, mod_id, "
                             "mod_size, mod_rev}");
        }
      }
      t.ports.push_back(lead);
    }
  }
  return t;
}

void add_esc(const EscCatalog& catalog, const EscType& type, int32_t parent, int32_t parent_port,
             PortOrder order, ModuleLayout& layout, const std::string& origin) {
  if (layout.escs.size() >= kMaxEscsPerModule) {
    throw CatalogError(origin + ": more than " + std::to_string(kMaxEscsPerModule) +
                       " ESCs in one module (hub_board rows form a cycle?)");
  }
  const auto index = static_cast<int32_t>(layout.escs.size());
  const EscBoard board = type.board.value_or(default_board(type.kind));
  layout.escs.push_back(EscPlacement{type.identity, board,
                                     type.esc_type.value_or(default_esc_type(type.kind, index > 0)),
                                     parent, parent_port});
  if (!type.ports.empty()) {
    std::set<int32_t> seen;
    for (const auto& lead : type.ports) {
      if (lead.port < 1 || lead.port > 3) {
        throw CatalogError(type.origin + ": port " + std::to_string(lead.port) +
                           " is not a downstream ESC port (1..3)");
      }
      if (!has_port(board, lead.port)) {
        throw CatalogError(type.origin + ": port " + std::to_string(lead.port) + " but a " +
                           to_string(type.kind) + "'s ESC board has ports 0 and 1 only (give " +
                           "esc_ports: 4 if this board has four)");
      }
      if (!seen.insert(lead.port).second) {
        throw CatalogError(type.origin + ": port " + std::to_string(lead.port) +
                           " has two port rows");
      }
      if (lead.secondary_esc) {
        const EscType* secondary = catalog.find(*lead.secondary_esc);
        if (!secondary) {
          throw CatalogError(type.origin + ": hub board ESC " + to_string(*lead.secondary_esc) +
                             " on port " + std::to_string(lead.port) + " is not in the catalogue");
        }
        add_esc(catalog, *secondary, index, lead.port, order, layout, origin);
      } else {
        layout.connectors.push_back(ConnectorPlacement{lead.connector, index, lead.port});
      }
    }
  } else if (index == 0) {
    const int32_t outputs = type.outputs.value_or(default_outputs(type.kind));
    const DownstreamPorts ports = downstream_ports(board, order);
    if (outputs > ports.count) {
      throw CatalogError(type.origin + ": outputs " + std::to_string(outputs) +
                         " needs port rows " + "(its " + std::to_string(port_count(board)) +
                         "-port ESC board has " + std::to_string(ports.count) + " port" +
                         (ports.count == 1 ? "" : "s") + " after port 0)");
    }
    for (int32_t k = 1; k <= outputs; ++k) {
      layout.connectors.push_back(
          ConnectorPlacement{k, 0, ports.ports[static_cast<std::size_t>(k - 1)]});
    }
  }
}

}  // namespace

const ConnectorPlacement* ModuleLayout::connector(int32_t number) const {
  for (const auto& c : connectors) {
    if (c.connector == number) return &c;
  }
  return nullptr;
}

std::optional<int32_t> ModuleLayout::connector_at(int32_t esc, int32_t port) const {
  for (const auto& c : connectors) {
    if (c.esc == esc && c.port == port) return c.connector;
  }
  return std::nullopt;
}

std::optional<int32_t> ModuleLayout::esc_at(int32_t esc, int32_t port) const {
  for (std::size_t i = 1; i < escs.size(); ++i) {
    if (escs[i].parent_esc == esc && escs[i].parent_port == port) return static_cast<int32_t>(i);
  }
  return std::nullopt;
}

int32_t default_outputs(ModuleKind kind) {
  switch (kind) {
    case ModuleKind::kJoint:
    case ModuleKind::kLink:
    case ModuleKind::kBaseLink: return 1;
    case ModuleKind::kEndEffector:
    case ModuleKind::kWheel:
    case ModuleKind::kUnknown:
      return 0;
    case ModuleKind::kHub: return 3;
  }
  return 0;
}

EscCatalog EscCatalog::load(const std::filesystem::path& folder) {
  if (!std::filesystem::is_directory(folder)) {
    throw CatalogError(folder.string() + ": module database folder not found");
  }
  return load_file(folder / "esc_index.yaml");
}

EscCatalog EscCatalog::load_file(const std::filesystem::path& file) {
  return parse(read_text<CatalogError>(file, "the ESC catalogue"), file.string());
}

EscCatalog EscCatalog::parse(std::string_view yaml_text, const std::string& source) {
  const YAML::Node root = parse_yaml<CatalogError>(yaml_text, source);
  if (!root.IsMap()) throw CatalogError(source + ": expected a mapping with 'modules:'");
  const YAML::Node modules = root["modules"];
  if (!modules || !modules.IsSequence() || modules.size() == 0) {
    throw CatalogError(source + ": 'modules:' must be a non-empty list");
  }
  std::vector<EscType> types;
  std::map<EscIdentity, std::string> seen;
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const std::string context = source + ": modules[" + std::to_string(i) + "]";
    EscType t = parse_module_row(modules[i], context);
    if (auto [it, inserted] = seen.emplace(t.identity, context); !inserted) {
      throw CatalogError(context + ": identity " + to_string(t.identity) + " already defined by " +
                         it->second);
    }
    types.push_back(std::move(t));
  }
  parse_section(root, "mobile_base_ports", source, types);
  parse_section(root, "module_ports", source, types);

  EscCatalog catalog;
  for (auto& t : types) {
    catalog.by_identity_[t.identity] = catalog.entries_.size();
    catalog.entries_.push_back(std::move(t));
  }
  catalog.validate();
  return catalog;
}

void EscCatalog::add(EscType type) {
  if (auto it = by_identity_.find(type.identity); it != by_identity_.end()) {
    entries_[it->second] = std::move(type);
  } else {
    by_identity_[type.identity] = entries_.size();
    entries_.push_back(std::move(type));
  }
  validate();
}

void EscCatalog::merge(const EscCatalog& other) {
  for (const auto& t : other.entries_) {
    if (auto it = by_identity_.find(t.identity); it != by_identity_.end()) {
      entries_[it->second] = t;
    } else {
      by_identity_[t.identity] = entries_.size();
      entries_.push_back(t);
    }
  }
  validate();
}

const EscType* EscCatalog::find(const EscIdentity& identity) const {
  const auto it = by_identity_.find(identity);
  return it == by_identity_.end() ? nullptr : &entries_[it->second];
}

const EscType* EscCatalog::find_key(std::string_view key) const {
  for (const auto& t : entries_) {
    if (t.key == key) return &t;
  }
  return nullptr;
}

ModuleLayout EscCatalog::layout(const EscIdentity& upstream, PortOrder order) const {
  const EscType* type = find(upstream);
  if (!type) throw CatalogError("unknown ESC identity " + to_string(upstream));
  ModuleLayout layout;
  layout.key = type->key;
  layout.kind = type->kind;
  add_esc(*this, *type, -1, -1, order, layout, type->origin);
  std::sort(layout.connectors.begin(), layout.connectors.end(),
            [](const auto& a, const auto& b) { return a.connector < b.connector; });
  for (std::size_t i = 1; i < layout.connectors.size(); ++i) {
    if (layout.connectors[i].connector == layout.connectors[i - 1].connector) {
      throw CatalogError(type->origin + ": connector " +
                         std::to_string(layout.connectors[i].connector) +
                         " is wired to two ports");
    }
  }
  if (type->outputs && !type->ports.empty() && *type->outputs != layout.outputs()) {
    throw CatalogError(type->origin + ": outputs " + std::to_string(*type->outputs) +
                       " but the port rows give " + std::to_string(layout.outputs()) +
                       " connectors");
  }
  return layout;
}

void EscCatalog::validate() const {
  for (const auto& t : entries_) {
    (void)layout(t.identity, PortOrder::kReal0312);
    (void)layout(t.identity, PortOrder::kNumeric0123);
  }
}

}  // namespace concert::topology
