#pragma once
// The robot's loop drives the hardware abstraction of libs/hardware.

#include "concert/hardware/hardware.hpp"

namespace concert::robot {

using hardware::DriveCommand;
using hardware::DriveMode;
using hardware::Hardware;
using hardware::HardwareError;
using hardware::HardwareState;
using hardware::MountedHardware;

}  // namespace concert::robot
