#pragma once
#include "concert/cli/cli.hpp"

namespace concert::tool {

/// Registers `concert bim import` (IFC file -> per storey map.yaml + map.pgm + geometry.json)
/// and `concert bim goal` (area frame on a wall face and the base pose in front of it).
void register_bim_verbs(cli::Cli& concert);

}  // namespace concert::tool
