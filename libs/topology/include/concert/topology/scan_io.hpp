#pragma once
// ESC scan files (YAML or JSON) and JSON / text rendering of scans and module trees.
//
// A scan file holds the slaves either as a list under `slaves:` or as a mapping keyed by
// position or by robot_id (the form the CONCERT EtherCAT master reports), at the top level or
// under `slaves:`. Fields per slave: position, active_ports, topology, esc_type, mod_type,
// mod_id, mod_size, mod_rev, robot_id. See libs/topology/README.md.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "concert/topology/types.hpp"

namespace concert::topology {

/// Unreadable scan file; what() names the file, the slave entry and the field.
class ScanFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads a scan file: JSON if the name ends in .json, YAML otherwise. Slaves are kept in file
/// order (map forms: sorted by position). Throws ScanFormatError.
EscScan load_scan(const std::filesystem::path& file);
/// Parses YAML scan text; `source` names it in messages. Throws ScanFormatError.
EscScan parse_scan_yaml(std::string_view text, const std::string& source);
/// Parses JSON scan text; `source` names it in messages. Throws ScanFormatError.
EscScan parse_scan_json(std::string_view text, const std::string& source);

/// A scan as YAML text in the list form (`slaves:` list), readable by parse_scan_yaml.
std::string scan_to_yaml(const EscScan& scan);
/// A scan as JSON: {"slaves": [{position, active_ports, ...}, ...]}.
nlohmann::json scan_to_json(const EscScan& scan);

/// A module tree as JSON (the `concert discover --json` shape): {"slaves": [{position,
/// parent_position, parent_port (null for the first), active_ports, topology, esc_type,
/// mod_type, mod_id, mod_size, mod_rev, robot_id, module, module_key}], "modules": [{index,
/// key, kind, mod_type, mod_id, mod_size, mod_rev, slave_positions, parent_module,
/// parent_connector, robot_id}]}.
nlohmann::json tree_to_json(const ModuleTree& tree);
/// Reads a module tree in the tree_to_json shape (what `concert discover --json` prints).
/// Throws std::runtime_error naming `source` and the field.
ModuleTree tree_from_json(const nlohmann::json& doc, const std::string& source);

/// A module tree as indented readable text, one module per line, children under parents.
std::string tree_to_text(const ModuleTree& tree);

}  // namespace concert::topology
