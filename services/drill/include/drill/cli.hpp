#pragma once
// `concert drill ...` verbs (registered into the `concert` tool).

#include "concert/cli/cli.hpp"

namespace concert::drill {

/// Registers:
/// * `concert drill run --mission FILE [--resume] [--mission-id N] [--no-wait] [--timeout S]
///   [--domain N] [--json]`: sends the mission file to the drill service and follows its
///   status (the active node of the behaviour tree, each area and hole) until it ends, then
///   prints the report: holes drilled / marked, per-hole state, the time split. Exit 0 when
///   every area was drilled, 1 otherwise (the reason is printed), 2 for bad arguments.
/// * `concert drill status [--json]`: the latest mission's status or report.
/// * `concert drill abort [--reason TEXT]`: stops the running mission (every motion stops).
void register_verbs(cli::Cli& concert);

}  // namespace concert::drill
