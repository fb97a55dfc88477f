#pragma once
// Helpers for tests and benchmarks of the bus and of discovery: a synthetic ESC catalogue and
// seeded random assemblies.

#include <cstdint>
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

}  // namespace concert::simbus
