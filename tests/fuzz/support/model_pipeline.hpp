#pragma once
// The path a module description takes through the stack, for the module database and URDF
// targets: model generation (modelgen), the RobotModel every service builds from the message,
// and what the services ask of it first (chains, legs, tools, sensors, kinematics).

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::fuzz {

/// A module database with its ESC catalogue.
struct Database {
  module_db::ModuleDatabase db;
  topology::EscCatalog catalog;
};

/// The project's and the public module database (each alone: merged, the public catalogue's
/// entries replace the project's, which share identities). Loaded once.
const std::vector<Database>& databases();

/// The database whose catalogue knows the assembly's root module; throws std::runtime_error if
/// none does.
const Database& database_of(const simbus::Assembly& assembly);

/// Asks `model` what the services ask of a new model: selections by role and kind (their
/// documented ModelError is caught), every frame's pose, the tools' Jacobians and the gravity
/// torques at the zero posture, with a fixed and a planar base.
void exercise(const model::RobotModel& model);

/// Generates the model of `tree` (model_generation::ModelError: documented, nothing more
/// happens); a model the generator accepts must build as a RobotModel (modelgen never publishes
/// a model the services refuse), which is then exercised.
void generate_and_build(const model_generation::ModelGenerator& generator,
                        const topology::ModuleTree& tree);

/// A module database file with `content`, named `name`, through the format's add-on and module
/// readers (ModuleDbError documented); a module whose key `db` lacks goes through generate_with.
void module_file(std::string_view content, const std::string& name,
                 module_db::ModuleDescription (*load_module)(const std::filesystem::path&),
                 module_db::AddonDescription (*load_addon)(const std::filesystem::path&),
                 const module_db::ModuleDatabase& db, const std::string& parent_key,
                 const std::string& child_key);

/// Generates models with `module` (its key must be new to `db`) alone and mounted between real
/// modules of `db` (`parent_key` -> `module` on connector 1 -> `child_key` on its connector 1),
/// through generate_and_build.
void generate_with(const module_db::ModuleDatabase& db, const module_db::ModuleDescription& module,
                   const std::string& parent_key, const std::string& child_key);

}  // namespace concert::fuzz
