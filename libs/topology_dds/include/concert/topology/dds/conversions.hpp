#pragma once
// The one IDL <-> core conversion of the EtherCAT scan and the module tree (idl/ethercat.idl,
// idl/topology.idl), for every adapter that reads or writes these topics (discovery, modelgen,
// the robot, the concert tool).

#include <cstdint>
#include <string>

#include "concert/topology/types.hpp"
#include "ethercat.h"
#include "topology.h"

namespace concert::topology::dds {

topology::EscScan to_core(const msg::EscScan& scan);
msg::EscScan to_msg(const topology::EscScan& scan, uint32_t scan_id, int64_t stamp_ns,
                    const std::string& source);

/// parent_port -1 on the wire stands for "no parent port" (the first slave).
topology::ModuleTree to_core(const msg::ModuleTree& tree);
msg::ModuleTree to_msg(const topology::ModuleTree& tree, uint32_t version, uint32_t scan_id,
                       int64_t stamp_ns);

}  // namespace concert::topology::dds
