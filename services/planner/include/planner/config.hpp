#pragma once
// YAML input of the planner service: parameters (config/planner.yaml) and the world
// description (walls/obstacles; the robot service's world file format).

#include <filesystem>
#include <string>

#include "concert/config/config.hpp"
#include "planner/types.hpp"

namespace concert::planner {

/// Reads Params from YAML (keys as in Params, all optional; unknown keys are errors). Throws
/// PlannerError naming the file, the key and the line.
Params load_params(const std::filesystem::path& file);
Params parse_params(const std::string& yaml, const std::string& source);
/// Reads the parameters of `doc`, starting from the defaults (throws config::ConfigError).
Params read_params(config::Document& doc);

/// Reads walls (boxes) and obstacles (boxes or vertical cylinders) of a world file; `floor`
/// and `friction` keys are accepted and ignored. Throws PlannerError naming file and field.
World load_world(const std::filesystem::path& file);
World parse_world(const std::string& yaml, const std::string& source);

}  // namespace concert::planner
