#pragma once
// Robot models of assembly files, built in-process the way the running system builds them:
// assembly file -> simulated bus (simbus) -> module tree -> model generation with a module
// database -> the RobotModel every service builds from the model message. The one assembly ->
// model fixture of the tests and benchmarks (a library's or service's own helpers build on it).

#include <cstdint>
#include <filesystem>
#include <memory>

#include "concert/model/robot_model.hpp"
#include "concert/model_generation/model.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::testing {

/// The project's module database (data/module_db).
std::filesystem::path project_module_db();
/// The public CONCERT module database (../shared/data/concert_resources).
std::filesystem::path public_module_db();

/// The module database in `dir`, loaded once per process (thread-safe).
const module_db::ModuleDatabase& module_database(const std::filesystem::path& dir);
/// The ESC catalogue of the module database in `dir`, loaded once per process.
const topology::EscCatalog& esc_catalog(const std::filesystem::path& dir);

/// The model modelgen would publish for `assembly` with the database in `db_dir`, at `version`.
/// Throws what the assembly reader or the generator throws (naming file and module).
model_generation::GeneratedModel generated_model(const std::filesystem::path& assembly,
                                                 std::uint64_t version = 1,
                                                 const std::filesystem::path& db_dir = project_module_db());

/// The same model as the services hold it (model::RobotModel::build of its description).
std::shared_ptr<const model::RobotModel> robot_model(const std::filesystem::path& assembly,
                                                     std::uint64_t version = 1,
                                                     const std::filesystem::path& db_dir = project_module_db());

}  // namespace concert::testing
