#pragma once
// `concert model ...` verbs (wired into the `concert` tool by its owner).

#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "concert/topology/types.hpp"

namespace concert::modelgen {

/// Runs `concert model <args>` (args[0] is the verb):
///   generate (--scan FILE | --tree FILE | --assembly FILE) --module-db DIR [--module-db DIR ...]
///            --out DIR [--port-order 0312|0123] [--home JOINT=RAD ...] [--addon EE=ADDON ...]
/// --module-db accepts either database format; several are merged in order. --assembly goes
/// through the simulated bus and discovery, as the real pipeline does. The bundle's version is
/// one more than the version already in DIR, or unchanged when the content hash is the same.
/// --addon EE=ADDON mounts an add-on on end-effector (or body) EE; with the key of a module
/// without ESC (passive gripper) it mounts that module on chain/body EE (see ModelGenerator).
/// Returns 0, or non-zero with a one-line message on `err`.
///   show [--timeout S]   prints the live model (version, modules, chains, joints,
///                        end-effectors) read from the latched GeneratedModel topic (CONCERT_DOMAIN_ID).
int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/// `concert model show` (args[0] == "show").
int show_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);


}  // namespace concert::modelgen
