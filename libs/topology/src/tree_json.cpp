#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include "concert/topology/scan_io.hpp"

namespace concert::topology {
namespace {

using nlohmann::json;

/// `v` as an int32; throws naming `what` for another type or a value out of range.
int32_t int32_of(const json& v, const std::string& what) {
  if (!v.is_number_integer()) throw std::runtime_error(what + ": expected an integer");
  const bool fits =
      v.is_number_unsigned()
          ? v.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<int32_t>::max())
          : v.get<int64_t>() >= std::numeric_limits<int32_t>::min() &&
                v.get<int64_t>() <= std::numeric_limits<int32_t>::max();
  if (!fits) throw std::runtime_error(what + ": " + v.dump() + " is out of range");
  return v.get<int32_t>();
}

int32_t int_field(const json& obj, const char* key, const std::string& where) {
  if (!obj.contains(key)) throw std::runtime_error(where + "." + key + ": missing");
  return int32_of(obj.at(key), where + "." + key);
}

ModuleKind kind_from(const std::string& s, const std::string& where) {
  for (auto k : {ModuleKind::kJoint, ModuleKind::kHub, ModuleKind::kEndEffector, ModuleKind::kLink,
                 ModuleKind::kWheel, ModuleKind::kBaseLink, ModuleKind::kUnknown}) {
    if (to_string(k) == s) return k;
  }
  throw std::runtime_error(where + ".kind: unknown kind '" + s + "'");
}

}  // namespace

ModuleTree tree_from_json(const json& doc, const std::string& source) {
  ModuleTree tree;
  if (!doc.is_object() || !doc.contains("modules") || !doc.at("modules").is_array()) {
    throw std::runtime_error(source + ": modules: missing or not a list");
  }
  const json& mods = doc.at("modules");
  for (size_t i = 0; i < mods.size(); ++i) {
    const json& m = mods[i];
    const std::string where = source + ": modules[" + std::to_string(i) + "]";
    if (!m.is_object()) throw std::runtime_error(where + ": expected an object");
    ModuleNode n;
    n.index = m.contains("index") ? int_field(m, "index", where) : static_cast<int32_t>(i);
    if (n.index != static_cast<int32_t>(i)) throw std::runtime_error(where + ".index: " + std::to_string(n.index) + " but it is entry " + std::to_string(i));
    if (m.contains("key") && !m.at("key").is_string())
      throw std::runtime_error(where + ".key: expected a string");
    n.key = m.value("key", std::string());
    if (m.contains("known")) {
      if (!m.at("known").is_boolean())
        throw std::runtime_error(where + ".known: expected true or false");
      n.known = m.at("known").get<bool>();
    }
    if (m.contains("kind") && m.at("kind").is_string()) n.kind = kind_from(m.at("kind").get<std::string>(), where);
    n.identity.mod_type = m.contains("mod_type") ? int_field(m, "mod_type", where) : 0;
    n.identity.mod_id = m.contains("mod_id") ? int_field(m, "mod_id", where) : 0;
    n.identity.mod_size = m.contains("mod_size") ? int_field(m, "mod_size", where) : 0;
    n.identity.mod_rev = m.contains("mod_rev") ? int_field(m, "mod_rev", where) : 0;
    if (m.contains("slave_positions")) {
      if (!m.at("slave_positions").is_array()) throw std::runtime_error(where + ".slave_positions: expected a list");
      for (const json& p : m.at("slave_positions")) {
        n.slave_positions.push_back(int32_of(p, where + ".slave_positions"));
      }
    }
    n.parent_module = int_field(m, "parent_module", where);
    if (n.parent_module >= 0 && !m.contains("parent_connector")) {
      throw std::runtime_error(where + ".parent_connector: missing (module " + std::to_string(i) + " has parent " +
                               std::to_string(n.parent_module) + ")");
    }
    n.parent_connector = m.contains("parent_connector") ? int_field(m, "parent_connector", where) : -1;
    n.robot_id = m.contains("robot_id") ? int_field(m, "robot_id", where) : -1;
    if (n.known && n.key.empty() && n.identity == EscIdentity{}) {
      throw std::runtime_error(where + ": needs a key or an identity (mod_type, mod_id, mod_size, mod_rev)");
    }
    tree.modules.push_back(std::move(n));
  }
  if (doc.contains("slaves") && doc.at("slaves").is_array()) {
    const json& slaves = doc.at("slaves");
    for (size_t i = 0; i < slaves.size(); ++i) {
      const json& s = slaves[i];
      const std::string where = source + ": slaves[" + std::to_string(i) + "]";
      SlaveNode node;
      node.slave.position = int_field(s, "position", where);
      node.slave.active_ports = static_cast<uint8_t>(s.contains("active_ports") ? int_field(s, "active_ports", where) : 0);
      node.slave.topology = s.contains("topology") ? int_field(s, "topology", where) : 0;
      node.slave.esc_type = s.contains("esc_type") ? int_field(s, "esc_type", where) : 0;
      node.slave.identity = {s.contains("mod_type") ? int_field(s, "mod_type", where) : 0, s.contains("mod_id") ? int_field(s, "mod_id", where) : 0,
                             s.contains("mod_size") ? int_field(s, "mod_size", where) : 0, s.contains("mod_rev") ? int_field(s, "mod_rev", where) : 0};
      node.slave.robot_id = s.contains("robot_id") ? int_field(s, "robot_id", where) : -1;
      node.parent_position = s.contains("parent_position") ? int_field(s, "parent_position", where) : 0;
      if (s.contains("parent_port") && !s.at("parent_port").is_null()) node.parent_port = int_field(s, "parent_port", where);
      node.module_index = s.contains("module") ? int_field(s, "module", where) : -1;
      tree.slaves.push_back(node);
    }
  }
  for (const auto& [field, severity] : {std::pair{"warnings", TreeIssue::Severity::kWarning},
                                        std::pair{"errors", TreeIssue::Severity::kError}}) {
    if (!doc.contains(field)) continue;
    const json& list = doc.at(field);
    if (!list.is_array()) throw std::runtime_error(source + ": " + field + ": expected a list");
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string where = source + ": " + field + "[" + std::to_string(i) + "]";
      if (!list[i].is_object() || !list[i].contains("message") ||
          !list[i].at("message").is_string()) {
        throw std::runtime_error(where + ": expected {position, message}");
      }
      const int32_t position =
          list[i].contains("position") ? int_field(list[i], "position", where) : 0;
      tree.issues.push_back({severity, position, list[i].at("message").get<std::string>()});
    }
  }
  std::stable_sort(tree.issues.begin(), tree.issues.end(),
                   [](const TreeIssue& a, const TreeIssue& b) { return a.position < b.position; });
  return tree;
}

}  // namespace concert::topology
