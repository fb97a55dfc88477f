#pragma once
// `concert safety ...` verbs (operator side of the safety service), for the concert tool:
//   safety status            prints the live safety state: RUNNING, or STOPPED with its causes
//   safety estop [--source SOURCE] [--release] [--reason TEXT]
//                            engages (or releases) an e-stop input; SOURCE: front-left,
//                            front-right, rear-left, rear-right, wireless, software (default)
//   safety reset [--source NAME] [--reason TEXT]
//                            asks the safety service to reset a latched stop; prints the result
// Each takes --domain N, --timeout S (default 5) and --json. Uses DDS: not a core library.

#include "concert/cli/cli.hpp"

namespace concert::safety {

/// Registers `concert safety status|estop|reset` into `concert`. The verbs return 0 on
/// success; 1 when the work failed (no safety service answered, reset refused: the reason is
/// printed), 2 for a bad command line.
void register_verbs(cli::Cli& concert);

}  // namespace concert::safety
