#pragma once
// `concert finish ...` verbs (registered into the `concert` tool).

#include "concert/cli/cli.hpp"

namespace concert::surface_finish {

/// Registers:
/// * `concert finish areas [--json]`: the predetermined areas of the current model (tool,
///   working distance, each area's rectangle).
/// * `concert finish spray --area ID [--rect X0,X1,Y0,Y1] [--speed M_S] [--no-wait]`: sprays the
///   area (or a rectangle inside it) and prints the coverage report. Exit 0 when it succeeded.
/// * `concert finish sand --area ID --force N [--rect ...] [--speed M_S]`: asks for a sanding run.
/// * `concert finish status [--json]`: the latest run's status and report.
/// * `concert finish abort`: stops the running path (the arm holds where it is).
void register_verbs(cli::Cli& concert);

}  // namespace concert::surface_finish
