#pragma once
// `concert plan ...` verbs (registered into the `concert` tool).

#include "concert/cli/cli.hpp"

namespace concert::planner {

/// Registers `concert plan drill --at X Y Z [--at X Y Z ...] [--normal NX NY NZ] [--execute]
/// [--end-effector NAME] [--request-id N] [--timeout S] [--domain N] [--json]`: sends one
/// PlanRequest (goals in the order given: drilling-area centres [m] in the world frame on a
/// surface with outward normal N, default -1 0 0) for the live model version (read from the
/// latched RobotModel topic) and follows the PlanResult updates until the request succeeds or
/// fails (or S seconds pass, default 30). Prints one line per update (a JSON object with
/// --json). Exit code 0 on success; 1 when planning/execution fails or times out (the reason
/// is printed); 2 for bad arguments.
void register_verbs(cli::Cli& concert);

}  // namespace concert::planner
