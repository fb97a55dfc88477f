#pragma once
// Simulated EtherCAT bus: an assembly (which module is mounted on which output connector of
// which parent) -> the scan real hardware would report. Format: libs/simbus/README.md.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/port_order.hpp"
#include "concert/topology/types.hpp"

namespace concert::simbus {

/// Unreadable or inconsistent assembly; what() names the file, the module and the field.
class AssemblyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One module bolted onto the robot.
struct MountedModule {
  std::string name;     ///< unique name within the assembly
  std::string key;      ///< module-database key (EscType::key in the catalogue)
  std::string parent;   ///< name of the parent module; empty for the root (on the master)
  int32_t connector = 0;  ///< output connector of the parent it is mounted on (1-based)
  std::vector<int32_t> robot_ids;  ///< per ESC, upstream first; missing entries are -1
  bool operator==(const MountedModule&) const = default;
};

/// Faults the bus can simulate.
enum class FaultType {
  kUpsideDown,       ///< the module's ESC is entered through `upstream_port`, not port 0
  kBrokenLink,       ///< the link from the module to its parent is cut: it and its subtree vanish
  kUnknownIdentity,  ///< ESC `esc` of the module reports `identity` instead of its own
  kWrongTopology,    ///< the master reports `topology` open ports for ESC `esc` of the module
};

/// One fault, applied by simulate_scan (never by tree_from_assembly).
struct Fault {
  FaultType type = FaultType::kBrokenLink;
  std::string module;  ///< name of the module concerned
  /// kUpsideDown: the ESC port facing the parent; empty = the port of the module's connector 1
  /// (for a module without connectors, the board's first downstream port: 1 on a two-port
  /// board, 3 on a four-port board). Its port 0 and this port swap roles.
  std::optional<int32_t> upstream_port;
  /// kUnknownIdentity: what the ESC reports (default all zero: EEPROM not programmed).
  topology::EscIdentity identity{0, 0, 0, 0};
  /// kUnknownIdentity, kWrongTopology: which ESC of the module (0 = upstream, as in the
  /// catalogue's layout, e.g. 1 = the Mobile Base Hub's hub board).
  int32_t esc = 0;
  /// kWrongTopology: the count the master reports, whatever the open-port register says.
  int32_t topology = 0;
  bool operator==(const Fault&) const = default;
};

/// A robot as assembled by the user.
struct Assembly {
  std::vector<MountedModule> modules;  ///< any order; exactly one root
  std::vector<Fault> faults;
  std::string source = "<assembly>";   ///< file name, for messages
};

/// Reads an assembly YAML file. Throws AssemblyError.
Assembly load_assembly(const std::filesystem::path& file);
/// Parses assembly YAML text; `source` names it in messages. Throws AssemblyError.
Assembly parse_assembly(std::string_view yaml_text, const std::string& source);
/// Writes an assembly as YAML text readable by parse_assembly.
std::string assembly_to_yaml(const Assembly& assembly);

/// Checks the assembly against the catalogue: unique names, one root, known parents and keys,
/// existing free connectors, every module reachable from the root, valid faults.
/// Throws AssemblyError.
void validate(const Assembly& assembly, const topology::EscCatalog& catalog,
              topology::PortOrder order = topology::PortOrder::kReal0312);

/// The scan the EtherCAT master would report for the assembly, faults applied: the frame is
/// followed port by port (`order`) through every ESC, positions are given in the order the
/// EPUs are met, open-port registers reflect the links. Throws AssemblyError.
topology::EscScan simulate_scan(const Assembly& assembly, const topology::EscCatalog& catalog,
                                topology::PortOrder order = topology::PortOrder::kReal0312);

/// The tree the assembly describes (faults ignored), built from the assembly's structure
/// without any scan: what discovery must rebuild from simulate_scan. Throws AssemblyError.
topology::ModuleTree tree_from_assembly(const Assembly& assembly,
                                        const topology::EscCatalog& catalog,
                                        topology::PortOrder order = topology::PortOrder::kReal0312);

}  // namespace concert::simbus
