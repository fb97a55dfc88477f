#pragma once
// The scan and module-tree conversions live in libs/topology_dds (concert_topology_dds); this
// header keeps their discovery names for the code that still includes it (the robot's adapter
// and the concert tool) until it includes "concert/topology/dds/conversions.hpp" itself.

#include "concert/topology/dds/conversions.hpp"

namespace concert::discovery::dds {

using topology::dds::to_core;
using topology::dds::to_msg;

}  // namespace concert::discovery::dds
