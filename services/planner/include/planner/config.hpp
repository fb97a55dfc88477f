#pragma once
// YAML input of the planner service: its parameters (config/planner.yaml). The world comes
// from libs/world (one parser, one type, the latched world topic).

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

}  // namespace concert::planner
