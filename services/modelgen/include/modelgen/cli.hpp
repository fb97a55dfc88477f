#pragma once
// `concert model generate|show` verbs (registered into the `concert` tool).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/topology/port_order.hpp"
#include "concert/topology/types.hpp"
#include "modelgen/model_generator.hpp"

namespace concert::modelgen {

/// `concert model generate`: where the module tree comes from and where the bundle goes.
struct GenerateOptions {
  std::string scan, tree, assembly;  ///< exactly one: scan file, tree JSON, assembly file
  std::string out;                   ///< bundle folder
  std::vector<std::filesystem::path> module_dbs;  ///< either database format, merged in order
  std::string port_order = "0312";  ///< frame processing order of the ESC ports: 0312 or 0123
  Customisation custom;  ///< --home JOINT=RAD, --addon EE=ADDON
};

/// Writes the bundle (URDF, SRDF, controller config, manifest) of the model of `o`'s source.
/// --assembly goes through the simulated bus and discovery, as the real pipeline does. The
/// bundle's version is one more than the version already in the folder, or unchanged when the
/// content hash is the same. --addon EE=ADDON mounts an add-on on end-effector (or body) EE;
/// with the key of a module without ESC (passive gripper) it mounts that module on chain/body
/// EE (see ModelGenerator). Returns 0; throws with a one-line message on failure.
int generate(const GenerateOptions& o, std::ostream& out);

/// Prints the live robot model (version, modules, chains, joints, end-effectors; JSON with
/// `dds.json`) read from the latched RobotModel topic within `dds.timeout_s`. Returns 0, or
/// throws cli::Failure when none arrives.
int show(const cli::DdsOptions& dds, std::ostream& out);

/// Registers `concert model generate ...` and `concert model show ...` into `concert`.
void register_verbs(cli::Cli& concert);

}  // namespace concert::modelgen
