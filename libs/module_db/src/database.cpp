#include <algorithm>

#include <yaml-cpp/yaml.h>

#include "concert/module_db/module_db.hpp"
#include "internal.hpp"

namespace concert::module_db {

namespace fs = std::filesystem;
using detail::fail;

void ModuleDatabase::add_module(ModuleDescription module) {
  auto it = modules_.find(module.key);
  if (it != modules_.end()) {
    throw ModuleDbError(module.source + ": key '" + module.key + "' already defined by " + it->second.source);
  }
  std::string key = module.key;
  std::optional<topology::EscIdentity> esc = module.esc;
  modules_.emplace(key, std::move(module));
  if (esc) by_identity_[*esc] = key;
}

void ModuleDatabase::add_addon(AddonDescription addon) {
  auto it = addons_.find(addon.key);
  if (it != addons_.end()) {
    throw ModuleDbError(addon.source + ": add-on key '" + addon.key + "' already defined by " + it->second.source);
  }
  std::string key = addon.key;
  addons_.emplace(key, std::move(addon));
}

void ModuleDatabase::map_identity(const topology::EscIdentity& identity, const std::string& key) {
  by_identity_[identity] = key;
}

void ModuleDatabase::add_port_routes(const std::vector<PortRoute>& routes) {
  port_routes_.insert(port_routes_.end(), routes.begin(), routes.end());
}

void ModuleDatabase::merge(const ModuleDatabase& other) {
  for (const auto& [key, m] : other.modules_) {
    ModuleDescription copy = m;
    copy.esc.reset();
    add_module(std::move(copy));
    modules_.at(key).esc = m.esc;
  }
  for (const auto& [key, a] : other.addons_) add_addon(a);
  for (const auto& [id, key] : other.by_identity_) by_identity_[id] = key;
  add_port_routes(other.port_routes_);
}

const ModuleDescription* ModuleDatabase::find(std::string_view key) const {
  auto it = modules_.find(key);
  return it == modules_.end() ? nullptr : &it->second;
}

const ModuleDescription& ModuleDatabase::at(std::string_view key) const {
  const ModuleDescription* m = find(key);
  if (m == nullptr) throw ModuleDbError("unknown module key '" + std::string(key) + "'");
  return *m;
}

const ModuleDescription* ModuleDatabase::find_by_identity(const topology::EscIdentity& identity) const {
  auto it = by_identity_.find(identity);
  return it == by_identity_.end() ? nullptr : find(it->second);
}

const AddonDescription* ModuleDatabase::find_addon(std::string_view key) const {
  auto it = addons_.find(key);
  return it == addons_.end() ? nullptr : &it->second;
}

std::vector<std::string> ModuleDatabase::module_keys() const {
  std::vector<std::string> keys;
  for (const auto& [k, m] : modules_) keys.push_back(k);
  return keys;
}

std::vector<std::string> ModuleDatabase::addon_keys() const {
  std::vector<std::string> keys;
  for (const auto& [k, a] : addons_) keys.push_back(k);
  return keys;
}

namespace {

int32_t req_int(const YAML::Node& row, const std::string& key, const fs::path& file, const std::string& path) {
  if (!row.IsMap())
    fail(file, path.empty() ? key : path.substr(0, path.size() - 1), "expected a mapping");
  const YAML::Node v = row[key];
  if (!v || !v.IsScalar()) fail(file, path + key, "missing");
  try {
    return v.as<int32_t>();
  } catch (const YAML::Exception&) {
    fail(file, path + key, "not an integer");
  }
}

PortRoute route_row(const YAML::Node& row, int32_t mod_type, int32_t mod_id, const fs::path& file, const std::string& p) {
  PortRoute r;
  r.mod_type = mod_type;
  r.mod_id = mod_id;
  r.port = req_int(row, "port", file, p);
  if (r.port < 0 || r.port > 3) fail(file, p + "port", "must be 0..3");
  const YAML::Node lt = row["leads_to"];
  if (!lt || !lt.IsScalar()) fail(file, p + "leads_to", "missing");
  r.leads_to = lt.Scalar();
  return r;
}

std::vector<fs::path> sorted_files(const fs::path& dir, const std::string& ext) {
  std::vector<fs::path> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ext) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

EscIndex read_esc_index(const YAML::Node& doc, const fs::path& file) {
  if (!doc.IsMap()) fail(file, "(document)", "expected a mapping with a 'modules:' list");
  EscIndex index;
  const YAML::Node mods = doc["modules"];
  if (!mods || !mods.IsSequence()) fail(file, "modules", "missing or not a list");
  for (size_t i = 0; i < mods.size(); ++i) {
    const YAML::Node row = mods[i];
    const std::string p = "modules[" + std::to_string(i) + "].";
    EscIndexEntry e;
    e.identity.mod_type = req_int(row, "mod_type", file, p);
    e.identity.mod_id = req_int(row, "mod_id", file, p);
    e.identity.mod_size = req_int(row, "mod_size", file, p);
    e.identity.mod_rev = req_int(row, "mod_rev", file, p);
    if (!row["file"] || !row["file"].IsScalar()) fail(file, p + "file", "missing");
    e.file = row["file"].Scalar();
    e.key = row["key"] && row["key"].IsScalar() ? row["key"].Scalar() : fs::path(e.file).stem().string();
    e.project_assigned = row["project_assigned"] && row["project_assigned"].as<bool>(false);
    if (row["outputs"]) e.outputs = req_int(row, "outputs", file, p);
    if (row["ports"]) {
      const YAML::Node ports = row["ports"];
      if (!ports.IsSequence()) fail(file, p + "ports", "expected a list");
      for (size_t k = 0; k < ports.size(); ++k) {
        index.ports.push_back(route_row(ports[k], e.identity.mod_type, e.identity.mod_id, file,
                                        p + "ports[" + std::to_string(k) + "]."));
      }
    }
    for (const EscIndexEntry& other : index.modules) {
      if (other.identity == e.identity) fail(file, p.substr(0, p.size() - 1), "identity listed twice");
    }
    index.modules.push_back(std::move(e));
  }
  for (const char* section : {"mobile_base_ports", "module_ports"}) {
    const YAML::Node rows = doc[section];
    if (!rows) continue;
    if (!rows.IsSequence()) fail(file, section, "expected a list");
    for (size_t i = 0; i < rows.size(); ++i) {
      const std::string p = std::string(section) + "[" + std::to_string(i) + "].";
      index.ports.push_back(route_row(rows[i], req_int(rows[i], "mod_type", file, p), req_int(rows[i], "mod_id", file, p), file, p));
    }
  }
  return index;
}

}  // namespace

EscIndex load_esc_index(const fs::path& file) {
  YAML::Node doc;
  try {
    doc = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw ModuleDbError(file.string() + ": cannot open");
  } catch (const YAML::Exception& e) {
    fail(file, "(document)", std::string("invalid YAML: ") + e.what());
  }
  try {
    return read_esc_index(doc, file);
  } catch (const YAML::Exception& e) {
    // A node of another kind than the reader checked for: named by its line.
    fail(file, "(document)", "line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

DatabaseFormat detect_format(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw ModuleDbError(dir.string() + ": module database folder does not exist");
  if (fs::is_directory(dir / "modules")) return DatabaseFormat::kProjectYaml;
  if (fs::is_directory(dir / "json")) return DatabaseFormat::kPublicJson;
  throw ModuleDbError(dir.string() + ": not a module database (expected a modules/ folder of YAML files or a json/ folder)");
}

ModuleDatabase load_module_database(const fs::path& dir) {
  const DatabaseFormat format = detect_format(dir);
  std::vector<ModuleDescription> modules;
  ModuleDatabase db;
  if (format == DatabaseFormat::kProjectYaml) {
    for (const fs::path& f : sorted_files(dir / "modules", ".yaml")) modules.push_back(load_yaml_module(f));
    for (const fs::path& f : sorted_files(dir / "addons", ".yaml")) db.add_addon(load_yaml_addon(f));
  } else {
    for (const fs::path& f : sorted_files(dir / "json", ".json")) modules.push_back(load_json_module(f));
    for (const fs::path& f : sorted_files(dir / "module_addons" / "json", ".json")) db.add_addon(load_json_addon(f));
    if (fs::is_directory(dir / "sensors")) {
      for (const fs::path& f : sorted_files(dir / "sensors", ".yaml")) detail::attach_sensor_file(f, modules);
    }
  }
  const fs::path index_file = dir / "esc_index.yaml";
  if (fs::exists(index_file)) {
    const EscIndex index = load_esc_index(index_file);
    for (size_t i = 0; i < index.modules.size(); ++i) {
      const EscIndexEntry& e = index.modules[i];
      const fs::path target = fs::weakly_canonical(dir / e.file);
      auto it = std::find_if(modules.begin(), modules.end(),
                             [&](const ModuleDescription& m) { return fs::weakly_canonical(m.source) == target; });
      if (it == modules.end()) fail(index_file, "modules[" + std::to_string(i) + "].file", "no module file '" + e.file + "'");
      if (it->key != e.key) {
        fail(index_file, "modules[" + std::to_string(i) + "].key", "'" + e.key + "' but the file defines key '" + it->key + "'");
      }
      // The non-structural hub board shares the Mobile Base Hub's body: it stays loadable, but
      // the first identity listed for a file is the module's upstream identity.
      if (!it->esc) it->esc = e.identity;
      if (e.identity.mod_type == 6) it->type = ModuleType::kBaseLink;
    }
    for (ModuleDescription& m : modules) db.add_module(std::move(m));
    for (const EscIndexEntry& e : index.modules) db.map_identity(e.identity, e.key);
    db.add_port_routes(index.ports);
  } else {
    for (ModuleDescription& m : modules) db.add_module(std::move(m));
  }
  return db;
}

ModuleDatabase load_module_databases(const std::vector<fs::path>& dirs) {
  ModuleDatabase db;
  for (const fs::path& d : dirs) db.merge(load_module_database(d));
  return db;
}

}  // namespace concert::module_db
