#pragma once
#include "concert/cli/cli.hpp"

namespace concert::tool {

/// Registers `concert camera list|snapshot`: the robot's cameras (from the SensorList) and one
/// RGB-D frame of a camera written as PNG files.
void register_camera_verbs(cli::Cli& concert);

}  // namespace concert::tool
