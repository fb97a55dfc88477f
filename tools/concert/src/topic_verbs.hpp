#pragma once
// `concert topic list|info|echo|hz|pub`: any topic on the domain, ours (typed through the
// schema-driven CDR <-> JSON codec) or another program's.

#include "concert/cli/cli.hpp"

namespace concert::tool {

/// Registers the `topic` verbs into `concert`.
void register_topic_verbs(cli::Cli& concert);

}  // namespace concert::tool
