#include "concert/simbus/testing.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace concert::simbus {

topology::EscCatalog synthetic_catalog() {
  // Written in the esc_index.yaml format (with the project's extensions) so the catalogue
  // parser is exercised too.
  static const char* const kYaml = R"(
modules:
  - {mod_type: 1, mod_id: 1, mod_size: 1, mod_rev: 0, key: joint}
  - {mod_type: 4, mod_id: 1, mod_size: 1, mod_rev: 0, key: link}
  - {mod_type: 6, mod_id: 1, mod_size: 1, mod_rev: 0, key: base_link}
  - {mod_type: 3, mod_id: 1, mod_size: 1, mod_rev: 0, key: tool}
  - {mod_type: 5, mod_id: 1, mod_size: 1, mod_rev: 0, key: wheel}
  - {mod_type: 2, mod_id: 1, mod_size: 1, mod_rev: 0, key: hub3}
  - {mod_type: 2, mod_id: 2, mod_size: 1, mod_rev: 0, key: hub2, outputs: 2}
  - {mod_type: 2, mod_id: 3, mod_size: 1, mod_rev: 0, key: base}
  - {mod_type: 2, mod_id: 4, mod_size: 1, mod_rev: 0, key: base_hub_board}
  - mod_type: 2
    mod_id: 5
    mod_size: 1
    mod_rev: 0
    key: tri
    ports:
      - {port: 3, leads_to: 1}
      - {port: 1, leads_to: hub_board, secondary: {mod_type: 2, mod_id: 6, mod_size: 1, mod_rev: 0}}
      - {port: 2, leads_to: hub_board, secondary: {mod_type: 2, mod_id: 7, mod_size: 1, mod_rev: 0}}
  - {mod_type: 2, mod_id: 6, mod_size: 1, mod_rev: 0, key: tri_b, ports: [{port: 3, leads_to: 2}, {port: 2, leads_to: 3}]}
  - {mod_type: 2, mod_id: 7, mod_size: 1, mod_rev: 0, key: tri_c, ports: [{port: 1, leads_to: 4}]}
module_ports:
  - {mod_type: 2, mod_id: 3, port: 3, leads_to: hub_board}
  - {mod_type: 2, mod_id: 3, port: 1, leads_to: 4}
  - {mod_type: 2, mod_id: 3, port: 2, leads_to: 5}
  - {mod_type: 2, mod_id: 4, port: 3, leads_to: 1}
  - {mod_type: 2, mod_id: 4, port: 1, leads_to: 2}
  - {mod_type: 2, mod_id: 4, port: 2, leads_to: 3}
)";
  return topology::EscCatalog::parse(kYaml, "synthetic_catalog");
}

Assembly random_assembly(const topology::EscCatalog& catalog, std::mt19937& rng,
                         const RandomAssemblyParams& params) {
  struct Kind {
    std::string key;
    int32_t outputs;
    int32_t escs;
    std::vector<int32_t> connectors;
  };
  std::vector<Kind> leaves, singles, hubs;
  for (const auto& entry : catalog.entries()) {
    if (catalog.find_key(entry.key) != &entry) continue;
    const auto layout = catalog.layout(entry.identity);
    Kind kind{entry.key, layout.outputs(), static_cast<int32_t>(layout.escs.size()), {}};
    for (const auto& c : layout.connectors) kind.connectors.push_back(c.connector);
    if (kind.outputs == 0) {
      leaves.push_back(kind);
    } else if (kind.outputs == 1) {
      singles.push_back(kind);
    } else {
      hubs.push_back(kind);
    }
  }
  if (singles.empty() && hubs.empty()) {
    throw std::invalid_argument("random_assembly: the catalogue has no module with outputs");
  }
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto pick = [&](const std::vector<Kind>& from) -> const Kind& {
    std::uniform_int_distribution<std::size_t> index(0, from.size() - 1);
    return from[index(rng)];
  };

  Assembly assembly;
  assembly.source = "random_assembly";
  struct Slot {
    std::size_t module;
    int32_t connector;
  };
  std::vector<Slot> slots;
  int32_t next_robot_id = 1;
  const auto add = [&](const Kind& kind, const std::string& parent, int32_t connector) {
    MountedModule m;
    // Appended rather than "m" + ...: GCC 12 at -O3 flags that with a -Wrestrict false positive.
    m.name = "m";
    m.name += std::to_string(assembly.modules.size());
    m.key = kind.key;
    m.parent = parent;
    m.connector = connector;
    if (params.with_robot_ids) {
      for (int32_t e = 0; e < kind.escs; ++e) m.robot_ids.push_back(next_robot_id++);
    }
    for (auto c = kind.connectors.rbegin(); c != kind.connectors.rend(); ++c) {
      slots.push_back(Slot{assembly.modules.size(), *c});
    }
    assembly.modules.push_back(std::move(m));
  };

  add(hubs.empty() ? pick(singles) : (unit(rng) < 0.5 || singles.empty() ? pick(hubs)
                                                                         : pick(singles)),
      "", 0);
  while (static_cast<int32_t>(assembly.modules.size()) < params.modules && !slots.empty()) {
    std::size_t slot_index = slots.size() - 1;  // newest module's first free connector
    if (unit(rng) >= params.chain_bias) {
      slot_index = std::uniform_int_distribution<std::size_t>(0, slots.size() - 1)(rng);
    }
    const Slot slot = slots[slot_index];
    slots.erase(slots.begin() + static_cast<std::ptrdiff_t>(slot_index));
    const bool last_slot = slots.empty();
    const double r = unit(rng);
    const Kind* kind = nullptr;
    if (!hubs.empty() && r < params.hub_bias) {
      kind = &pick(hubs);
    } else if (!leaves.empty() && !last_slot && r > 0.85) {
      kind = &pick(leaves);
    } else {
      kind = singles.empty() ? &pick(hubs) : &pick(singles);
    }
    add(*kind, assembly.modules[slot.module].name, slot.connector);
  }
  return assembly;
}

}  // namespace concert::simbus
