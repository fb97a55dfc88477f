#include "concert/topology/scan_io.hpp"

#include <algorithm>
#include <bit>
#include <functional>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "concert/common/source_text.hpp"
#include "yaml_util.hpp"

namespace concert::topology {
namespace {

using detail::opt_int32;
using detail::req_int32;
using detail::where;

EscSlave parse_slave(const YAML::Node& node, const std::string& context,
                     std::optional<int32_t> key) {
  if (!node.IsMap()) throw ScanFormatError(context + ": expected a mapping" + where(node));
  EscSlave s;
  const auto position = opt_int32<ScanFormatError>(node, "position", context);
  const auto robot_id = opt_int32<ScanFormatError>(node, "robot_id", context);
  if (position) {
    s.position = *position;
    if (key && *key != *position && (!robot_id || *key != *robot_id)) {
      throw ScanFormatError(context + ": key " + std::to_string(*key) +
                            " is neither the slave's position " + std::to_string(*position) +
                            " nor its robot_id" + where(node));
    }
  } else if (key) {
    s.position = *key;  // a mapping keyed by position may leave `position` out
  } else {
    throw ScanFormatError(context + ": missing field 'position'" + where(node));
  }
  const int32_t mask = req_int32<ScanFormatError>(node, "active_ports", context);
  if (mask < 0 || mask > 15) {
    throw ScanFormatError(context + ".active_ports: " + std::to_string(mask) +
                          " is not a 4-bit port mask (0..15)" + where(node));
  }
  s.active_ports = static_cast<uint8_t>(mask);
  s.topology = opt_int32<ScanFormatError>(node, "topology", context)
                   .value_or(std::popcount(static_cast<unsigned>(mask)));
  s.esc_type = opt_int32<ScanFormatError>(node, "esc_type", context).value_or(0);
  s.identity.mod_type = req_int32<ScanFormatError>(node, "mod_type", context);
  s.identity.mod_id = req_int32<ScanFormatError>(node, "mod_id", context);
  s.identity.mod_size = req_int32<ScanFormatError>(node, "mod_size", context);
  s.identity.mod_rev = req_int32<ScanFormatError>(node, "mod_rev", context);
  s.robot_id = robot_id.value_or(-1);
  return s;
}

EscScan parse_scan_node(const YAML::Node& root, const std::string& source) {
  if (!root || root.IsNull()) throw ScanFormatError(source + ": empty scan file");
  YAML::Node slaves = root;
  std::string prefix = source + ": ";
  if (root.IsMap() && root["slaves"]) {
    slaves = root["slaves"];
    prefix += "slaves";
  }
  EscScan scan;
  if (slaves.IsSequence()) {
    for (std::size_t i = 0; i < slaves.size(); ++i) {
      scan.slaves.push_back(
          parse_slave(slaves[i], prefix + "[" + std::to_string(i) + "]", std::nullopt));
    }
    return scan;
  }
  if (!slaves.IsMap()) {
    throw ScanFormatError(source + ": expected a list under 'slaves:' or a mapping of slaves "
                                   "keyed by position or robot_id");
  }
  for (const auto& entry : slaves) {
    const std::string key_text = entry.first.IsScalar() ? entry.first.Scalar() : "?";
    const std::string context = prefix + "[" + key_text + "]";
    int32_t key = 0;
    try {
      key = entry.first.as<int32_t>();
    } catch (const YAML::Exception&) {
      throw ScanFormatError(context + ": key '" + key_text +
                            "' is not a slave position or robot_id" + where(entry.first));
    }
    scan.slaves.push_back(parse_slave(entry.second, context, key));
  }
  std::stable_sort(scan.slaves.begin(), scan.slaves.end(),
                   [](const EscSlave& a, const EscSlave& b) { return a.position < b.position; });
  return scan;
}

// JSON is read with nlohmann::json (strict JSON, clear messages) and converted to a YAML node,
// so both formats share one slave parser.
YAML::Node json_to_yaml(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::object: {
      YAML::Node node(YAML::NodeType::Map);
      for (const auto& [k, v] : j.items()) node[k] = json_to_yaml(v);
      return node;
    }
    case nlohmann::json::value_t::array: {
      YAML::Node node(YAML::NodeType::Sequence);
      for (const auto& v : j) node.push_back(json_to_yaml(v));
      return node;
    }
    case nlohmann::json::value_t::null: return YAML::Node(YAML::NodeType::Null);
    case nlohmann::json::value_t::string: return YAML::Node(j.get<std::string>());
    case nlohmann::json::value_t::boolean: return YAML::Node(j.get<bool>() ? "true" : "false");
    default: return YAML::Node(j.dump());  // numbers keep their JSON spelling
  }
}

nlohmann::json slave_fields(const EscSlave& s) {
  return nlohmann::json{{"position", s.position},
                        {"active_ports", s.active_ports},
                        {"topology", s.topology},
                        {"esc_type", s.esc_type},
                        {"mod_type", s.identity.mod_type},
                        {"mod_id", s.identity.mod_id},
                        {"mod_size", s.identity.mod_size},
                        {"mod_rev", s.identity.mod_rev},
                        {"robot_id", s.robot_id}};
}

}  // namespace

EscScan load_scan(const std::filesystem::path& file) {
  const std::string text = read_text<ScanFormatError>(file, "the scan file");
  if (file.extension() == ".json") return parse_scan_json(text, file.string());
  return parse_scan_yaml(text, file.string());
}

EscScan parse_scan_yaml(std::string_view text, const std::string& source) {
  return parse_scan_node(parse_yaml<ScanFormatError>(text, source), source);
}

EscScan parse_scan_json(std::string_view text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw ScanFormatError(source + ": not valid JSON: " + e.what());
  }
  return parse_scan_node(json_to_yaml(j), source);
}

std::string scan_to_yaml(const EscScan& scan) {
  std::ostringstream out;
  out << (scan.slaves.empty() ? "slaves: []\n" : "slaves:\n");  // "slaves:" alone is null
  for (const auto& s : scan.slaves) {
    out << "  - {position: " << s.position << ", active_ports: " << int{s.active_ports}
        << ", topology: " << s.topology << ", esc_type: " << s.esc_type
        << ", mod_type: " << s.identity.mod_type << ", mod_id: " << s.identity.mod_id
        << ", mod_size: " << s.identity.mod_size << ", mod_rev: " << s.identity.mod_rev
        << ", robot_id: " << s.robot_id << "}\n";
  }
  return out.str();
}

nlohmann::json scan_to_json(const EscScan& scan) {
  nlohmann::json slaves = nlohmann::json::array();
  for (const auto& s : scan.slaves) slaves.push_back(slave_fields(s));
  return nlohmann::json{{"slaves", slaves}};
}

nlohmann::json tree_to_json(const ModuleTree& tree) {
  nlohmann::json slaves = nlohmann::json::array();
  for (const auto& node : tree.slaves) {
    nlohmann::json j = slave_fields(node.slave);
    j["parent_position"] = node.parent_position;
    j["parent_port"] = node.parent_port ? nlohmann::json(*node.parent_port) : nlohmann::json();
    j["module"] = node.module_index;
    const auto index = static_cast<std::size_t>(node.module_index);
    j["module_key"] = index < tree.modules.size() ? tree.modules[index].key : std::string();
    slaves.push_back(std::move(j));
  }
  nlohmann::json modules = nlohmann::json::array();
  for (const auto& m : tree.modules) {
    modules.push_back(nlohmann::json{{"index", m.index},
                                     {"key", m.key},
                                     {"known", m.known},
                                     {"kind", to_string(m.kind)},
                                     {"mod_type", m.identity.mod_type},
                                     {"mod_id", m.identity.mod_id},
                                     {"mod_size", m.identity.mod_size},
                                     {"mod_rev", m.identity.mod_rev},
                                     {"slave_positions", m.slave_positions},
                                     {"parent_module", m.parent_module},
                                     {"parent_connector", m.parent_connector},
                                     {"robot_id", m.robot_id}});
  }
  nlohmann::json warnings = nlohmann::json::array();
  nlohmann::json errors = nlohmann::json::array();
  for (const auto& issue : tree.issues) {
    (issue.severity == TreeIssue::Severity::kError ? errors : warnings)
        .push_back(nlohmann::json{{"position", issue.position}, {"message", issue.message}});
  }
  return nlohmann::json{
      {"slaves", slaves}, {"modules", modules}, {"warnings", warnings}, {"errors", errors}};
}

std::string tree_to_text(const ModuleTree& tree) {
  std::vector<std::vector<std::size_t>> children(tree.modules.size());
  std::vector<std::size_t> roots;
  for (std::size_t i = 0; i < tree.modules.size(); ++i) {
    const int32_t parent = tree.modules[i].parent_module;
    if (parent >= 0 && static_cast<std::size_t>(parent) < tree.modules.size()) {
      children[static_cast<std::size_t>(parent)].push_back(i);
    } else {
      roots.push_back(i);
    }
  }
  std::ostringstream out;
  out << tree.modules.size() << " modules, " << tree.slaves.size() << " slaves\n";
  std::function<void(std::size_t, const std::string&, bool, bool)> print =
      [&](std::size_t i, const std::string& indent, bool last, bool root) {
        const ModuleNode& m = tree.modules[i];
        out << indent;
        if (!root) {
          out << (last ? "`-- " : "|-- ") << "[";
          if (m.parent_connector >= 0) {
            out << m.parent_connector;
          } else {
            out << "?";  // below an unknown module, or on a port that is no connector
          }
          out << "] ";
        }
        out << "#" << m.index << " ";
        if (m.known) {
          out << m.key;
        } else {
          out << "UNKNOWN " << to_string(m.identity);
        }
        out << " (" << to_string(m.kind) << ") slave";
        if (m.slave_positions.size() > 1) out << "s";
        for (std::size_t k = 0; k < m.slave_positions.size(); ++k) {
          out << (k == 0 ? " " : ",") << m.slave_positions[k];
        }
        if (m.robot_id >= 0) out << " robot_id " << m.robot_id;
        out << "\n";
        const std::string next = root ? indent : indent + (last ? "    " : "|   ");
        for (std::size_t c = 0; c < children[i].size(); ++c) {
          print(children[i][c], next, c + 1 == children[i].size(), false);
        }
      };
  for (std::size_t r : roots) print(r, "", true, true);
  for (const auto& issue : tree.issues) {
    out << (issue.severity == TreeIssue::Severity::kError ? "error: " : "warning: ") << issue.text()
        << "\n";
  }
  return out.str();
}

}  // namespace concert::topology
