#pragma once
// Every verb of the `concert` tool: its own (topic, bag, scan, camera, bim, status, up, sim, help) and those each
// service's CLI library registers (discover, model, safety, plan), for the services built.

#include "concert/cli/cli.hpp"

namespace concert::tool {

/// Registers every verb into `concert`.
void register_all(cli::Cli& concert);

/// Registers the verbs of the services that are built (generated: service_verbs.cpp.in).
void register_service_verbs(cli::Cli& concert);

}  // namespace concert::tool
