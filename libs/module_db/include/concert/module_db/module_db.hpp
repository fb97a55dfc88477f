#pragma once
// The module database (paper section 4.3.1): one loader interface over two formats.
//   (a) the project's own YAML database: <dir>/modules/**/*.yaml, <dir>/addons/**/*.yaml
//       (schema: data/module_db/README.md);
//   (b) the public CoBRA/Timor JSON database (concert_resources): <dir>/json/**/*.json and
//       optionally <dir>/module_addons/json/**/*.json.
// Both may carry <dir>/esc_index.yaml, mapping ESC identities to module files.
//
// Connector numbering contract (shared with discovery and the simulated bus): output connector
// n (1-based) of a module is the n-th connector with role kOutput in file order; for the Mobile
// Base Hub, 1..4 are the legs (front-left, front-right, rear-left, rear-right) and 5 the arm, and
// esc_index.yaml says which physical ESC port leads to which connector number.

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "concert/module_db/module_description.hpp"

namespace concert::module_db {

/// Where one physical ESC port of a multi-connector module leads (esc_index.yaml
/// `mobile_base_ports:` / `module_ports:` rows and per-module `ports:`).
struct PortRoute {
  int32_t mod_type = 0;
  int32_t mod_id = 0;
  int32_t port = 0;               ///< physical ESC port 0..3
  std::string leads_to;           ///< output connector number ("1".."5") or another board ("hub_board")
};

/// One row of esc_index.yaml `modules:`.
struct EscIndexEntry {
  topology::EscIdentity identity;
  std::string file;               ///< relative to the database folder
  std::string key;                ///< module key (`key:` or the file stem)
  bool project_assigned = false;  ///< identity assigned by this project, not by the hardware maker
  std::optional<int> outputs;     ///< number of output connectors, if stated
};

/// Loaded esc_index.yaml.
struct EscIndex {
  std::vector<EscIndexEntry> modules;
  std::vector<PortRoute> ports;
};

/// Reads an esc_index.yaml (public format plus the project extensions `key:`, `outputs:`,
/// `ports:` per row, `module_ports:` = `mobile_base_ports:`). Throws ModuleDbError naming file
/// and field.
EscIndex load_esc_index(const std::filesystem::path& file);

/// A set of module and add-on descriptions, searchable by key and by ESC identity.
class ModuleDatabase {
 public:
  /// Adds a module; throws ModuleDbError if the key exists already (naming both files).
  void add_module(ModuleDescription module);
  /// Adds an add-on; throws ModuleDbError on a duplicate key.
  void add_addon(AddonDescription addon);
  /// Maps an identity to a module key; a later mapping of the same identity replaces the earlier.
  void map_identity(const topology::EscIdentity& identity, const std::string& key);
  /// Adds port routes (from an ESC index).
  void add_port_routes(const std::vector<PortRoute>& routes);
  /// Adds everything of `other`; module/add-on keys must be new, identity mappings of `other` win.
  void merge(const ModuleDatabase& other);

  const ModuleDescription* find(std::string_view key) const;
  /// Throws ModuleDbError("unknown module key '...'") if absent.
  const ModuleDescription& at(std::string_view key) const;
  const ModuleDescription* find_by_identity(const topology::EscIdentity& identity) const;
  const AddonDescription* find_addon(std::string_view key) const;
  const std::vector<PortRoute>& port_routes() const { return port_routes_; }

  std::vector<std::string> module_keys() const;  ///< sorted
  std::vector<std::string> addon_keys() const;   ///< sorted
  size_t size() const { return modules_.size(); }

 private:
  std::map<std::string, ModuleDescription, std::less<>> modules_;
  std::map<std::string, AddonDescription, std::less<>> addons_;
  std::map<topology::EscIdentity, std::string> by_identity_;
  std::vector<PortRoute> port_routes_;
};

/// Reads one module file of the public JSON database. Throws ModuleDbError naming the file and
/// field, e.g. `module_joint_elbow_A_concert.json: joints[0].limits.velocity: missing`.
ModuleDescription load_json_module(const std::filesystem::path& file);
/// Reads one add-on file of the public JSON database (module_addons/json/...).
AddonDescription load_json_addon(const std::filesystem::path& file);
/// Reads one module file of the project's YAML database.
ModuleDescription load_yaml_module(const std::filesystem::path& file);
/// Reads one add-on file of the project's YAML database.
AddonDescription load_yaml_addon(const std::filesystem::path& file);

/// Which format a database folder holds.
enum class DatabaseFormat { kProjectYaml, kPublicJson };
/// Detects the format from the folder layout (modules/ or json/); throws ModuleDbError if neither.
DatabaseFormat detect_format(const std::filesystem::path& dir);

/// Loads a whole database folder of either format, including esc_index.yaml when present (its
/// identities are attached to the modules; mod_type 6 marks a passive base link). Files are read
/// in sorted path order, so the result does not depend on directory iteration order.
ModuleDatabase load_module_database(const std::filesystem::path& dir);
/// Loads several folders and merges them in order (see ModuleDatabase::merge).
ModuleDatabase load_module_databases(const std::vector<std::filesystem::path>& dirs);

}  // namespace concert::module_db
