#include "model_fixture.hpp"

#include <map>
#include <mutex>
#include <string>

#include "concert/model_generation/generator.hpp"
#include "concert/simbus/assembly.hpp"

namespace concert::testing {

namespace fs = std::filesystem;

fs::path project_module_db() { return fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db"; }
fs::path public_module_db() { return fs::path(CONCERT_SHARED_DATA) / "concert_resources"; }

namespace {
// Loaded once per folder: a database takes 0.1-0.5 s to read and the tests build many models.
template <typename T, typename Load>
const T& cached(const fs::path& dir, Load load) {
  static std::mutex mutex;
  static std::map<std::string, T> loaded;  // node-based: references stay valid
  std::lock_guard lock(mutex);
  const std::string key = fs::weakly_canonical(dir).string();
  auto it = loaded.find(key);
  if (it == loaded.end()) it = loaded.emplace(key, load(dir)).first;
  return it->second;
}
}  // namespace

const module_db::ModuleDatabase& module_database(const fs::path& dir) {
  return cached<module_db::ModuleDatabase>(dir, [](const fs::path& d) { return module_db::load_module_database(d); });
}

const topology::EscCatalog& esc_catalog(const fs::path& dir) {
  return cached<topology::EscCatalog>(dir, [](const fs::path& d) { return topology::EscCatalog::load(d); });
}

model_generation::GeneratedModel generated_model(const fs::path& assembly, std::uint64_t version,
                                                 const fs::path& db_dir) {
  const topology::ModuleTree tree =
      simbus::tree_from_assembly(simbus::load_assembly(assembly), esc_catalog(db_dir));
  model_generation::GeneratedModel m = model_generation::ModelGenerator(module_database(db_dir)).generate(tree);
  m.version = version;
  return m;
}

std::shared_ptr<const model::RobotModel> robot_model(const fs::path& assembly, std::uint64_t version,
                                                     const fs::path& db_dir) {
  return model::RobotModel::build(generated_model(assembly, version, db_dir).description());
}

}  // namespace concert::testing
