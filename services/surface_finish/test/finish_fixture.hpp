#pragma once
// Robot models of assembly files through the simulated bus and model generation, as modelgen
// builds them (tests and the benchmark; the planner has the same helper, and a service may not
// include another).

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::surface_finish::test {

/// The model of `assembly` with the module database in `db_dir` (project: data/module_db;
/// public: ../shared/data/concert_resources), at `version`.
inline std::shared_ptr<const model::RobotModel> model_of(const std::filesystem::path& assembly,
                                                         const std::filesystem::path& db_dir, uint64_t version = 1) {
  static std::map<std::string, module_db::ModuleDatabase> dbs;
  auto [it, fresh] = dbs.try_emplace(db_dir.string());
  if (fresh) it->second = module_db::load_module_database(db_dir);
  const topology::EscCatalog catalog = topology::EscCatalog::load(db_dir);
  const topology::ModuleTree tree = simbus::tree_from_assembly(simbus::load_assembly(assembly), catalog);
  model_generation::GeneratedModel m = model_generation::ModelGenerator(it->second).generate(tree);
  m.version = version;
  return model::RobotModel::build(m.description());
}

inline std::filesystem::path source_dir() { return CONCERT_SOURCE_DIR; }
inline std::filesystem::path project_db() { return source_dir() / "data" / "module_db"; }
inline std::filesystem::path public_db() { return std::filesystem::path(CONCERT_SHARED_DATA) / "concert_resources"; }

}  // namespace concert::surface_finish::test
