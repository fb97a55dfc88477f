#pragma once
// Hand-written scans for the discovery tests.

#include <cstdint>
#include <initializer_list>
#include <string>

#include "concert/topology/types.hpp"

namespace concert::discovery::test {

/// One slave: open-port mask, identity and robot_id; position and topology are filled in.
struct SlaveSpec {
  uint8_t mask;
  topology::EscIdentity identity{1, 1, 1, 0};
  int32_t robot_id = -1;
};

/// Slaves in ring order, positions 1..n, topology = number of open ports.
inline topology::EscScan make_scan(std::initializer_list<SlaveSpec> specs) {
  topology::EscScan scan;
  int32_t position = 0;
  for (const auto& spec : specs) {
    topology::EscSlave s;
    s.position = ++position;
    s.active_ports = spec.mask;
    s.topology = __builtin_popcount(spec.mask);
    s.esc_type = 50;
    s.identity = spec.identity;
    s.robot_id = spec.robot_id;
    scan.slaves.push_back(s);
  }
  return scan;
}

// Identities of simbus::synthetic_catalog().
inline constexpr topology::EscIdentity kJoint{1, 1, 1, 0};
inline constexpr topology::EscIdentity kLink{4, 1, 1, 0};
inline constexpr topology::EscIdentity kTool{3, 1, 1, 0};
inline constexpr topology::EscIdentity kWheel{5, 1, 1, 0};
inline constexpr topology::EscIdentity kHub3{2, 1, 1, 0};
inline constexpr topology::EscIdentity kHub2{2, 2, 1, 0};
inline constexpr topology::EscIdentity kBase{2, 3, 1, 0};
inline constexpr topology::EscIdentity kBaseBoard{2, 4, 1, 0};

/// Message of the DiscoveryError `f` throws, or "" if it does not throw one.
template <class F>
std::string discovery_error(F&& f) {
  try {
    f();
  } catch (const DiscoveryError& e) {
    return e.what();
  }
  return "";
}

}  // namespace concert::discovery::test
