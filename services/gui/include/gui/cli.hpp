#pragma once
// `concert gui` (registered into the `concert` tool), and the gateway's options, shared with
// the concert_gui executable.

#include "concert/cli/cli.hpp"
#include "gui/gateway.hpp"

namespace concert::gui {

/// --port, --bind, --app, --module-db, --stream-hz, --image-hz, --jpeg-quality.
void add_gateway_options(CLI::App& app, GatewayOptions& options);

/// Registers `concert gui [--port N] [--bind ADDR] [--module-db DIR] [--domain N] [--timeout S]
/// [--json]`: the operator GUI's gateway in this process, until Ctrl-C (or S seconds).
void register_verbs(cli::Cli& concert);

}  // namespace concert::gui
