#pragma once
// Reconstruction of the module tree from an EtherCAT scan (paper section 4.2 and Appendix A):
// the discovery service's algorithm, in the library so that model generation, the simulator and
// the tests use the same one without linking a service. Plain C++, no DDS.

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/port_order.hpp"
#include "concert/topology/types.hpp"

namespace concert::topology {

/// A scan that does not describe a valid module tree. what() reads "slave <position>: <message>"
/// (or just the message when the scan as a whole is wrong, position 0).
class DiscoveryError : public std::runtime_error {
 public:
  DiscoveryError(int32_t position, const std::string& message);
  /// Ring position of the slave concerned; 0 when no single slave is (e.g. an empty scan).
  int32_t position() const { return position_; }
  /// The message without the position prefix.
  const std::string& message() const { return message_; }

 private:
  int32_t position_;
  std::string message_;
};

/// Parameters of the discovery core.
struct DiscoveryParams {
  /// Frame processing order of the ESCs: real 0 -> 3 -> 1 -> 2 by default.
  PortOrder port_order = PortOrder::kReal0312;
};

/// Where one slave hangs in the network graph chi.
struct SlaveLink {
  int32_t parent_position = 0;         ///< 0 = attached to the master
  std::optional<int32_t> parent_port;  ///< physical port of the parent; empty for the first slave
  bool operator==(const SlaveLink&) const = default;
};

/// The scan sorted by position, after the per-slave checks, and what they found.
struct ScanCheck {
  EscScan scan;                   ///< sorted by position
  std::vector<TreeIssue> issues;  ///< in ring order
  /// Slaves [0, usable) can be placed in a tree: all of them, or those before the first slave
  /// with an error (0 when the positions themselves are wrong).
  std::size_t usable = 0;
};

/// Checks a scan. Errors (the tree is undefined from there on): no slave, positions not exactly
/// 1..n, an open-port register over 4 bits, port 0 (upstream) closed. Warnings (resolved): a
/// `topology` count that disagrees with the bits of `active_ports` (active_ports is used).
ScanCheck check_scan(const EscScan& scan);

/// check_scan's sorted scan; throws DiscoveryError for its first error (warnings are dropped).
EscScan checked_scan(const EscScan& scan);

/// Network graph chi of the first `count` slaves of a checked scan, and the error that stopped
/// it (a slave with no earlier free open port) or that it left (an open port with no slave on
/// it). links[i] is the slave at position i+1; on an error they stop before that slave.
struct Network {
  std::vector<SlaveLink> links;
  std::optional<TreeIssue> error;
};
Network rebuild_network(const EscScan& scan, PortOrder order,
                        std::size_t count);

/// Network graph chi in linear time: one pass over the ring with a stack of the slaves that
/// still have free open ports. `scan` must be checked_scan's output. Element i is the slave at
/// position i+1. Throws DiscoveryError when the open ports do not form a tree.
std::vector<SlaveLink> reconstruct_network(const EscScan& scan,
                                           PortOrder order);

/// The paper's Algorithms 1 and 2 (quadratic in the worst case), kept as the reference for
/// tests and benchmarks. Same contract and errors as reconstruct_network.
std::vector<SlaveLink> reconstruct_network_reference(const EscScan& scan,
                                                     PortOrder order);

/// Scan -> module tree, with a catalogue of ESC identities. Immutable after construction;
/// rebuild() and run() may be called from several threads.
class Discovery {
 public:
  /// Throws CatalogError if an entry of the catalogue has an inconsistent layout.
  explicit Discovery(EscCatalog catalog, DiscoveryParams params = {});

  /// Rebuilds slaves (graph chi) and modules in linear time, always: the tree holds every slave
  /// and module that could be placed, and `issues` says what was noticed. Warnings leave the
  /// tree complete: a module whose identity the catalogue does not know (or an all-zero
  /// identity) is in the tree as unknown (`known` false, one ESC, children with
  /// parent_connector -1); a `topology` count that disagrees with `active_ports` is resolved
  /// from active_ports; a blank ESC where a known module has its further ESC (e.g. a Mobile Base
  /// Hub's hub board with an unprogrammed EEPROM) is taken as that ESC. Errors are
  /// contradictions that leave the tree undefined (see check_scan and rebuild_network; a slave on
  /// a port its known parent module has no connector on; a secondary ESC of another identity or
  /// missing). Never throws for a bad scan.
  ModuleTree rebuild(const EscScan& scan) const;

  /// rebuild(), but throws DiscoveryError for the first error (warnings stay in the tree).
  ModuleTree run(const EscScan& scan) const;

  const DiscoveryParams& params() const { return params_; }
  const EscCatalog& catalog() const { return catalog_; }

 private:
  EscCatalog catalog_;
  DiscoveryParams params_;
  std::map<EscIdentity, ModuleLayout> layouts_;
};

/// One-shot convenience: Discovery(catalog, params).run(scan) (throws on the first error).
ModuleTree discover(const EscScan& scan, const EscCatalog& catalog,
                              const DiscoveryParams& params = {});

}  // namespace concert::topology
