#pragma once
// Helpers for tests and benchmarks of the bus and of discovery: a synthetic ESC catalogue,
// seeded random assemblies and hand-written scans.

#include <cstdint>
#include <initializer_list>
#include <random>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::simbus {

/// A small catalogue built in code, independent of any database: joint, link, base_link,
/// tool (end-effector), wheel, hub3 (one ESC, 3 outputs), hub2 (one ESC, 2 outputs), base
/// (two ESCs: power board + hub board on port 3, 5 outputs, like the Mobile Base Hub) and tri
/// (three ESCs, 4 outputs), plus the secondary ESCs alone (base_hub_board, tri_b, tri_c).
topology::EscCatalog synthetic_catalog();

/// Shape of random assemblies.
struct RandomAssemblyParams {
  int32_t modules = 20;       ///< number of modules (a module may hold several ESCs)
  double chain_bias = 0.6;    ///< probability of mounting on the newest module (long chains)
  double hub_bias = 0.2;      ///< probability of picking a module with several outputs
  bool with_robot_ids = true; ///< give every ESC a distinct robot_id
};

/// A random valid assembly of catalogue keys (every key whose find_key is its own entry).
/// Deterministic for a given generator state.
Assembly random_assembly(const topology::EscCatalog& catalog, std::mt19937& rng,
                         const RandomAssemblyParams& params = {});

namespace testing {

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

}  // namespace testing

}  // namespace concert::simbus
