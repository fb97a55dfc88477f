#pragma once
// `concert safety ...` verbs (operator side of the safety service), for the concert tool:
//   safety status [--timeout-ms MS]
//       prints the live safety state: RUNNING, or STOPPED with its causes
//   safety estop [--source SOURCE] [--release] [--reason TEXT] [--timeout-ms MS]
//       engages (or releases) an e-stop input; SOURCE: front-left, front-right, rear-left,
//       rear-right, wireless, software (default software)
//   safety reset [--source NAME] [--reason TEXT] [--timeout-ms MS]
//       asks the safety service to reset a latched stop; prints the resulting state
// Domain: CONCERT_DOMAIN_ID. Uses DDS: not a core library.

#include <ostream>
#include <string>
#include <vector>

namespace concert::safety {

/// Runs `concert safety <args>`. Returns 0 on success; 1 when the work failed (no safety
/// service answered, reset refused: the reason is printed), 2 for a bad command line; errors
/// are one line on `err`.
int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace concert::safety
