#pragma once
// `concert bag record|info|play`: recordings of topics in MCAP files (libs/bag), each channel's
// schema the IDL text of its type, its messages the samples' CDR bytes.

#include "concert/cli/cli.hpp"

namespace concert::tool {

/// Registers the `bag` verbs into `concert`.
void register_bag_verbs(cli::Cli& concert);

}  // namespace concert::tool
