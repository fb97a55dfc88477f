#pragma once
// `concert plan ...` verbs (wired into the `concert` tool by its owner).

#include <ostream>
#include <string>
#include <vector>

namespace concert::planner {

/// Runs `concert plan <args>` (args[0] is the verb):
///   drill --at X Y Z [--at X Y Z ...] [--normal NX NY NZ] [--execute] [--end-effector NAME]
///         [--request-id N] [--timeout S]
/// sends one PlanRequest (goals in the order given: drilling-area centres [m] in the world
/// frame on a surface with outward normal N, default -1 0 0) for the live model version (read
/// from the latched RobotModel topic) and follows the PlanResult updates until the request
/// succeeds or fails (or S seconds pass, default 30). Prints one line per update. Returns 0
/// on success; 1 when planning/execution fails or times out (the reason is printed); 2 for
/// bad arguments. Domain: CONCERT_DOMAIN_ID.
int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace concert::planner
