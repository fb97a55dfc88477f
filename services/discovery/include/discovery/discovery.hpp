#pragma once
// Discovery core: rebuild the module tree from an EtherCAT scan (paper section 4.2 and
// Appendix A). Plain C++, no DDS.

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/port_order.hpp"
#include "concert/topology/types.hpp"

namespace concert::discovery {

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
struct Params {
  /// Frame processing order of the ESCs: real 0 -> 3 -> 1 -> 2 by default.
  topology::PortOrder port_order = topology::PortOrder::kReal0312;
};

/// Where one slave hangs in the network graph chi.
struct SlaveLink {
  int32_t parent_position = 0;         ///< 0 = attached to the master
  std::optional<int32_t> parent_port;  ///< physical port of the parent; empty for the first slave
  bool operator==(const SlaveLink&) const = default;
};

/// The scan sorted by position, after the per-slave checks: at least one slave, positions
/// exactly 1..n without duplicates, active_ports and topology agree, port 0 open.
/// Throws DiscoveryError.
topology::EscScan checked_scan(const topology::EscScan& scan);

/// Network graph chi in linear time: one pass over the ring with a stack of the slaves that
/// still have free open ports. `scan` must be checked_scan's output. Element i is the slave at
/// position i+1. Throws DiscoveryError when the open ports do not form a tree.
std::vector<SlaveLink> reconstruct_network(const topology::EscScan& scan,
                                           topology::PortOrder order);

/// The paper's Algorithms 1 and 2 (quadratic in the worst case), kept as the reference for
/// tests and benchmarks. Same contract and errors as reconstruct_network.
std::vector<SlaveLink> reconstruct_network_reference(const topology::EscScan& scan,
                                                     topology::PortOrder order);

/// Scan -> module tree, with a catalogue of ESC identities. Immutable after construction;
/// run() may be called from several threads.
class Discovery {
 public:
  /// Throws topology::CatalogError if an entry of the catalogue has an inconsistent layout.
  explicit Discovery(topology::EscCatalog catalog, Params params = {});

  /// Rebuilds slaves (graph chi) and modules in linear time. Throws DiscoveryError naming the
  /// slave position and what is wrong.
  topology::ModuleTree run(const topology::EscScan& scan) const;

  const Params& params() const { return params_; }
  const topology::EscCatalog& catalog() const { return catalog_; }

 private:
  topology::EscCatalog catalog_;
  Params params_;
  std::map<topology::EscIdentity, topology::ModuleLayout> layouts_;
};

/// One-shot convenience: Discovery(catalog, params).run(scan).
topology::ModuleTree discover(const topology::EscScan& scan, const topology::EscCatalog& catalog,
                              const Params& params = {});

}  // namespace concert::discovery
