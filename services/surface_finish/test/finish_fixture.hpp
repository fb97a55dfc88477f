#pragma once
// The project's assembly -> model fixture (tests/support/model_fixture.hpp) under the names the
// surface-finishing tests use.

#include <filesystem>
#include <memory>

#include "model_fixture.hpp"

namespace concert::surface_finish::test {

/// The model of `assembly` with the module database in `db_dir`, at `version`.
inline std::shared_ptr<const model::RobotModel> model_of(const std::filesystem::path& assembly,
                                                         const std::filesystem::path& db_dir, uint64_t version = 1) {
  return testing::robot_model(assembly, version, db_dir);
}

inline std::filesystem::path source_dir() { return CONCERT_SOURCE_DIR; }
inline std::filesystem::path project_db() { return testing::project_module_db(); }
inline std::filesystem::path public_db() { return testing::public_module_db(); }

}  // namespace concert::surface_finish::test
