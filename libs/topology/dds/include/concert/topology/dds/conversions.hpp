#pragma once
// The one conversion between the IDL types of the EtherCAT scan and the module tree
// (idl/ethercat.idl, idl/topology.idl) and the core types of libs/topology. Every adapter that
// reads or writes these topics uses it (discovery, modelgen, the robot's simulated bus, tools).

#include <cstdint>
#include <string>

#include "concert/topology/types.hpp"
#include "ethercat.h"
#include "topology.h"

namespace concert::topology::dds {

EscScan to_core(const msg::EscScan& scan);
msg::EscScan to_msg(const EscScan& scan, uint32_t scan_id, int64_t stamp_ns,
                    const std::string& source);

/// parent_port -1 on the wire stands for "no parent port" (the first slave).
ModuleTree to_core(const msg::ModuleTree& tree);
msg::ModuleTree to_msg(const ModuleTree& tree, uint32_t version, uint32_t scan_id,
                       int64_t stamp_ns);

}  // namespace concert::topology::dds
