#pragma once
// Plain C++ types of the EtherCAT network and the module tree (graph chi of paper section 4.2).
// Shared by discovery (which builds them), the simulated bus (which produces scans) and
// modelgen (which reads the module tree). No DDS here: the DDS adapters convert.

#include <compare>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace concert::topology {

/// The four numbers an ESC reports about the module that hosts it.
struct EscIdentity {
  int32_t mod_type = 0;  ///< 1 joint, 2 hub, 3 end-effector, 4 passive link, 5 wheel, 6 passive base link
  int32_t mod_id = 0;
  int32_t mod_size = 0;
  int32_t mod_rev = 0;
  auto operator<=>(const EscIdentity&) const = default;
};

/// Kind of module, as the network can tell it from mod_type.
enum class ModuleKind { kJoint, kHub, kEndEffector, kLink, kWheel, kBaseLink };

/// Kind for an ESC's mod_type register (1 joint, 2 hub, 3 end-effector, 4 link, 5 wheel,
/// 6 base link); empty for any other value.
std::optional<ModuleKind> module_kind_from_mod_type(int32_t mod_type);

/// Lower-case name of a kind: "joint", "hub", "end_effector", "link", "wheel", "base_link".
std::string to_string(ModuleKind kind);

/// "(mod_type 1, mod_id 6, mod_size 4, mod_rev 0)", for messages.
std::string to_string(const EscIdentity& identity);

/// One slave as reported by the EtherCAT master after a scan.
struct EscSlave {
  int32_t position = 0;      ///< position in the ring, 1..n
  uint8_t active_ports = 0;  ///< bit i set = physical port i open
  int32_t topology = 0;      ///< number of open ports reported by the master
  int32_t esc_type = 0;      ///< ESC chip type register
  EscIdentity identity;
  int32_t robot_id = -1;     ///< per-unit id; -1 for passive slaves
  bool operator==(const EscSlave&) const = default;
};

/// A complete scan: slaves in ring order.
struct EscScan {
  std::vector<EscSlave> slaves;
  bool operator==(const EscScan&) const = default;
};

/// A slave placed in the network tree.
struct SlaveNode {
  EscSlave slave;
  int32_t parent_position = 0;         ///< 0 = attached to the master
  std::optional<int32_t> parent_port;  ///< physical port of the parent; empty for the first slave
  int32_t module_index = -1;           ///< index into ModuleTree::modules
  bool operator==(const SlaveNode&) const = default;
};

/// A module (one or more ESCs) placed in the module tree.
struct ModuleNode {
  int32_t index = 0;            ///< 0-based, in ring order of the module's first ESC
  std::string key;              ///< module-database key of the module description
  ModuleKind kind = ModuleKind::kLink;
  EscIdentity identity;         ///< identity of the module's upstream ESC
  std::vector<int32_t> slave_positions;  ///< ESCs of this module, upstream first
  int32_t parent_module = -1;   ///< -1 for the root module
  int32_t parent_connector = -1;  ///< output connector number on the parent module (1-based); -1 for root
  int32_t robot_id = -1;
  bool operator==(const ModuleNode&) const = default;
};

/// Network topology (slaves, graph chi) and the modules they form.
struct ModuleTree {
  std::vector<SlaveNode> slaves;    ///< index i = ring position i+1
  std::vector<ModuleNode> modules;  ///< parents come before their children
  bool operator==(const ModuleTree&) const = default;
};

}  // namespace concert::topology
