#pragma once
// `concert nav ...` verbs (registered into the `concert` tool).

#include "concert/cli/cli.hpp"

namespace concert::nav {

/// Registers:
/// * `concert nav goto X Y THETA | --wall GLOBALID --at S H [--request-id N] [--no-wait]
///   [--timeout S] [--domain N] [--json]`: sends one NavGoal for the live model version (read
///   from the latched RobotModel topic) and follows its NavStatus until it is reached, fails,
///   is refused or cancelled (or S seconds pass, default 300). Exit 0 when reached; 1 otherwise
///   (the reason is printed); 2 for bad arguments.
/// * `concert nav cancel [--request-id N]`: cancels that goal (default: whatever runs).
/// * `concert nav init X Y THETA [--std-xy M] [--std-yaw RAD]`: the robot's pose in the map
///   to (re)start localisation from.
/// * `concert nav status [--json]`: the vehicle set-up, localisation and the latest goal.
void register_verbs(cli::Cli& concert);

}  // namespace concert::nav
