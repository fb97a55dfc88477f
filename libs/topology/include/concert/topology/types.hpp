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

/// Kind of module, as the network can tell it from mod_type. kUnknown: the ESC reports a
/// mod_type that is none of these (e.g. an all-zero identity: EEPROM not programmed).
enum class ModuleKind { kJoint, kHub, kEndEffector, kLink, kWheel, kBaseLink, kUnknown };

/// Kind for an ESC's mod_type register (1 joint, 2 hub, 3 end-effector, 4 link, 5 wheel,
/// 6 base link); empty for any other value.
std::optional<ModuleKind> module_kind_from_mod_type(int32_t mod_type);

/// Lower-case name of a kind: "joint", "hub", "end_effector", "link", "wheel", "base_link",
/// "unknown".
std::string to_string(ModuleKind kind);

/// "(mod_type 1, mod_id 6, mod_size 4, mod_rev 0)", for messages.
std::string to_string(const EscIdentity& identity);

/// True for the identity a board reports when its identity EEPROM is not programmed.
inline bool is_blank(const EscIdentity& identity) { return identity == EscIdentity{}; }

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
  std::string key;              ///< module-database key of the module description; empty if unknown
  ModuleKind kind = ModuleKind::kLink;
  EscIdentity identity;         ///< identity of the module's upstream ESC
  std::vector<int32_t> slave_positions;  ///< ESCs of this module, upstream first
  int32_t parent_module = -1;   ///< -1 for the root module
  /// Output connector number on the parent module (1-based); -1 for the root and when the
  /// parent's connectors are unknown (an unknown parent module).
  int32_t parent_connector = -1;
  int32_t robot_id = -1;
  /// False: the ESC catalogue does not know the identity (or it is all zero). The module is
  /// in the tree where its ports put it, with one ESC, and no model can be built from it.
  bool known = true;
  bool operator==(const ModuleNode&) const = default;
};

/// Something discovery noticed while rebuilding a tree.
///  * kWarning: the tree is defined and complete as far as the network can tell (an unknown or
///    blank identity, a `topology` count that disagrees with `active_ports`, ...);
///  * kError: a contradiction that leaves (part of) the tree undefined (no free port for a
///    slave, an open port with nothing on it, a slave on a port its module has no connector
///    on, ...). A tree with errors is never used to build a model.
struct TreeIssue {
  enum class Severity { kWarning, kError };
  Severity severity = Severity::kWarning;
  int32_t position = 0;  ///< ring position of the slave concerned; 0 = the scan as a whole
  std::string message;   ///< what is wrong, without the position
  /// "slave 4: message" (or just the message for position 0).
  std::string text() const;
  bool operator==(const TreeIssue&) const = default;
};

/// Network topology (slaves, graph chi), the modules they form, and what discovery noticed.
struct ModuleTree {
  std::vector<SlaveNode> slaves;    ///< index i = ring position i+1
  std::vector<ModuleNode> modules;  ///< parents come before their children
  std::vector<TreeIssue> issues;    ///< warnings and errors, in ring order

  /// True if an issue is an error: the tree is (partly) undefined.
  bool has_errors() const;
  /// Number of issues of one severity.
  std::size_t count(TreeIssue::Severity severity) const;
  /// Indices of the modules whose identity the catalogue does not know.
  std::vector<int32_t> unknown_modules() const;
  bool operator==(const ModuleTree&) const = default;
};

}  // namespace concert::topology
