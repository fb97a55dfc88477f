#include "concert/simbus/assembly.hpp"
#include "concert/simbus/bus.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <bit>
#include <limits>
#include <map>
#include <set>

#include "concert/common/enum_map.hpp"
#include "concert/common/source_text.hpp"

namespace concert::simbus {
namespace {

using topology::EscCatalog;
using topology::EscIdentity;
using topology::EscScan;
using topology::EscSlave;
using topology::ModuleLayout;
using topology::ModuleTree;
using topology::PortOrder;
using namespace std::string_view_literals;

std::string line_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line < 0 ? "" : " (line " + std::to_string(mark.line + 1) + ")";
}

int32_t to_int32(const YAML::Node& node, const std::string& context) {
  int64_t value = 0;
  try {
    if (!node.IsScalar()) throw YAML::Exception(node.Mark(), "not a scalar");
    value = node.as<int64_t>();
  } catch (const YAML::Exception&) {
    throw AssemblyError(context + ": expected an integer" + line_of(node));
  }
  if (value < std::numeric_limits<int32_t>::min() || value > std::numeric_limits<int32_t>::max()) {
    throw AssemblyError(context + ": " + std::to_string(value) + " is out of range" + line_of(node));
  }
  return static_cast<int32_t>(value);
}

std::string to_text(const YAML::Node& node, const std::string& context) {
  if (!node.IsScalar() || node.Scalar().empty()) {
    throw AssemblyError(context + ": expected a non-empty name" + line_of(node));
  }
  return node.Scalar();
}

/// The `type:` of each fault in assembly files.
constexpr EnumMap kFaultTypes{std::array{
    std::pair{FaultType::kUpsideDown, "upside_down"sv},
    std::pair{FaultType::kBrokenLink, "broken_link"sv},
    std::pair{FaultType::kUnknownIdentity, "unknown_identity"sv},
    std::pair{FaultType::kWrongTopology, "wrong_topology"sv},
}};

Fault parse_fault(const YAML::Node& node, const std::string& context) {
  if (!node.IsMap()) throw AssemblyError(context + ": expected a mapping" + line_of(node));
  Fault fault;
  if (!node["type"]) throw AssemblyError(context + ": missing field 'type'" + line_of(node));
  const std::string type = to_text(node["type"], context + ".type");
  const std::optional<FaultType> fault_type = kFaultTypes.from(type);
  if (!fault_type) {
    throw AssemblyError(context + ".type: '" + type +
                        "' is not upside_down, broken_link, unknown_identity or wrong_topology" +
                        line_of(node));
  }
  fault.type = *fault_type;
  if (!node["module"]) throw AssemblyError(context + ": missing field 'module'" + line_of(node));
  fault.module = to_text(node["module"], context + ".module");
  if (const YAML::Node port = node["upstream_port"]) {
    if (fault.type != FaultType::kUpsideDown) {
      throw AssemblyError(context + ": upstream_port only applies to upside_down" + line_of(port));
    }
    fault.upstream_port = to_int32(port, context + ".upstream_port");
  }
  if (const YAML::Node id = node["identity"]) {
    if (fault.type != FaultType::kUnknownIdentity || !id.IsMap()) {
      throw AssemblyError(context + ".identity: only a mapping for unknown_identity" +
                          line_of(id));
    }
    const auto field = [&](const char* name) {
      if (!id[name]) return 0;
      return to_int32(id[name], context + ".identity." + name);
    };
    fault.identity = EscIdentity{field("mod_type"), field("mod_id"), field("mod_size"),
                                 field("mod_rev")};
  }
  if (const YAML::Node esc = node["esc"]) {
    if (fault.type != FaultType::kUnknownIdentity && fault.type != FaultType::kWrongTopology) {
      throw AssemblyError(context + ": esc only applies to unknown_identity and wrong_topology" +
                          line_of(esc));
    }
    fault.esc = to_int32(esc, context + ".esc");
  }
  if (const YAML::Node topology = node["topology"]) {
    if (fault.type != FaultType::kWrongTopology) {
      throw AssemblyError(context + ": topology only applies to wrong_topology" +
                          line_of(topology));
    }
    fault.topology = to_int32(topology, context + ".topology");
  } else if (fault.type == FaultType::kWrongTopology) {
    throw AssemblyError(context +
                        ": wrong_topology needs 'topology' (the count the master "
                        "reports)" +
                        line_of(node));
  }
  return fault;
}

/// The assembly with names resolved and checked against the catalogue.
struct Resolved {
  std::vector<ModuleLayout> layouts;  // per assembly module
  std::vector<std::vector<std::pair<int32_t, std::size_t>>> children;  // (connector, child)
  std::size_t root = 0;
  std::map<std::string, std::size_t> by_name;
};

Resolved resolve(const Assembly& assembly, const EscCatalog& catalog, PortOrder order) {
  const std::string& src = assembly.source;
  if (assembly.modules.empty()) throw AssemblyError(src + ": the assembly has no modules");
  Resolved r;
  const std::size_t n = assembly.modules.size();
  r.children.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const MountedModule& m = assembly.modules[i];
    const std::string ctx = src + ": module '" + m.name + "'";
    if (m.name.empty()) throw AssemblyError(src + ": modules[" + std::to_string(i) + "] has no name");
    if (!r.by_name.emplace(m.name, i).second) throw AssemblyError(ctx + ": name used twice");
    const topology::EscType* type = catalog.find_key(m.key);
    if (!type) throw AssemblyError(ctx + ": key '" + m.key + "' is not in the ESC catalogue");
    try {
      r.layouts.push_back(catalog.layout(type->identity, order));
    } catch (const topology::CatalogError& e) {
      throw AssemblyError(ctx + ": " + e.what());
    }
    if (m.robot_ids.size() > r.layouts.back().escs.size()) {
      throw AssemblyError(ctx + ": " + std::to_string(m.robot_ids.size()) + " robot_ids for " +
                          std::to_string(r.layouts.back().escs.size()) + " ESC(s)");
    }
  }
  std::size_t roots = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const MountedModule& m = assembly.modules[i];
    const std::string ctx = src + ": module '" + m.name + "'";
    if (m.parent.empty()) {
      r.root = i;
      ++roots;
      continue;
    }
    const auto parent = r.by_name.find(m.parent);
    if (parent == r.by_name.end()) {
      throw AssemblyError(ctx + ": parent '" + m.parent + "' is not a module of the assembly");
    }
    const ModuleLayout& pl = r.layouts[parent->second];
    if (!pl.connector(m.connector)) {
      throw AssemblyError(ctx + ": parent '" + m.parent + "' (" + pl.key + ") has no output " +
                          "connector " + std::to_string(m.connector) + " (it has " +
                          std::to_string(pl.outputs()) + ")");
    }
    for (const auto& [connector, other] : r.children[parent->second]) {
      if (connector == m.connector) {
        throw AssemblyError(ctx + ": connector " + std::to_string(m.connector) + " of '" +
                            m.parent + "' is already taken by '" + assembly.modules[other].name +
                            "'");
      }
    }
    r.children[parent->second].emplace_back(m.connector, i);
  }
  if (roots != 1) {
    throw AssemblyError(src + ": " + std::to_string(roots) +
                        " modules have no parent; exactly one (the root) must have none");
  }
  // Every module must hang below the root (a parent cycle would not).
  std::vector<bool> reached(n, false);
  std::vector<std::size_t> todo{r.root};
  reached[r.root] = true;
  while (!todo.empty()) {
    const std::size_t m = todo.back();
    todo.pop_back();
    for (const auto& child : r.children[m]) {
      if (!reached[child.second]) {
        reached[child.second] = true;
        todo.push_back(child.second);
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!reached[i]) {
      throw AssemblyError(src + ": module '" + assembly.modules[i].name +
                          "' is not connected to the root (parent cycle)");
    }
  }
  for (auto& c : r.children) std::sort(c.begin(), c.end());
  for (std::size_t f = 0; f < assembly.faults.size(); ++f) {
    const Fault& fault = assembly.faults[f];
    const std::string ctx = src + ": faults[" + std::to_string(f) + "]";
    const auto it = r.by_name.find(fault.module);
    if (it == r.by_name.end()) {
      throw AssemblyError(ctx + ": module '" + fault.module + "' is not in the assembly");
    }
    if (fault.upstream_port && (*fault.upstream_port < 1 || *fault.upstream_port > 3)) {
      throw AssemblyError(ctx + ": upstream_port " + std::to_string(*fault.upstream_port) +
                          " is not 1..3");
    }
    const topology::ModuleLayout& layout = r.layouts[it->second];
    if (fault.upstream_port && !topology::has_port(layout.escs[0].board, *fault.upstream_port)) {
      throw AssemblyError(ctx + ": upstream_port " + std::to_string(*fault.upstream_port) +
                          " but the ESC board of module '" + fault.module +
                          "' has ports 0 and 1 only");
    }
    const auto escs = static_cast<int32_t>(layout.escs.size());
    if (fault.esc < 0 || fault.esc >= escs) {
      throw AssemblyError(ctx + ": esc " + std::to_string(fault.esc) + " but module '" +
                          fault.module + "' has " + std::to_string(escs) + " ESC" +
                          (escs == 1 ? "" : "s") + " (0.." + std::to_string(escs - 1) + ")");
    }
    if (fault.type == FaultType::kWrongTopology && (fault.topology < 0 || fault.topology > 4)) {
      throw AssemblyError(ctx + ": topology " + std::to_string(fault.topology) +
                          " is not a port count (0..4)");
    }
  }
  return r;
}

int32_t robot_id_of(const MountedModule& m, std::size_t esc) {
  return esc < m.robot_ids.size() ? m.robot_ids[esc] : -1;
}

}  // namespace

Assembly parse_assembly(std::string_view yaml_text, const std::string& source) {
  const YAML::Node root = parse_yaml<AssemblyError>(yaml_text, source);
  if (!root.IsMap() || !root["modules"] || !root["modules"].IsSequence()) {
    throw AssemblyError(source + ": expected a mapping with a 'modules:' list");
  }
  Assembly assembly;
  assembly.source = source;
  const YAML::Node modules = root["modules"];
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const YAML::Node node = modules[i];
    const std::string ctx = source + ": modules[" + std::to_string(i) + "]";
    if (!node.IsMap()) throw AssemblyError(ctx + ": expected a mapping" + line_of(node));
    MountedModule m;
    if (!node["name"]) throw AssemblyError(ctx + ": missing field 'name'" + line_of(node));
    if (!node["key"]) throw AssemblyError(ctx + ": missing field 'key'" + line_of(node));
    m.name = to_text(node["name"], ctx + ".name");
    m.key = to_text(node["key"], ctx + ".key");
    if (const YAML::Node parent = node["parent"]; parent && !parent.IsNull()) {
      m.parent = to_text(parent, ctx + ".parent");
      if (!node["connector"]) {
        throw AssemblyError(ctx + ": module '" + m.name + "' has a parent but no 'connector'" +
                            line_of(node));
      }
      m.connector = to_int32(node["connector"], ctx + ".connector");
    } else if (node["connector"]) {
      throw AssemblyError(ctx + ": 'connector' without 'parent'" + line_of(node));
    }
    if (const YAML::Node ids = node["robot_id"]; ids && !ids.IsNull()) {
      if (ids.IsSequence()) {
        for (std::size_t k = 0; k < ids.size(); ++k) {
          m.robot_ids.push_back(to_int32(ids[k], ctx + ".robot_id[" + std::to_string(k) + "]"));
        }
      } else {
        m.robot_ids.push_back(to_int32(ids, ctx + ".robot_id"));
      }
    }
    assembly.modules.push_back(std::move(m));
  }
  if (const YAML::Node faults = root["faults"]; faults && !faults.IsNull()) {
    if (!faults.IsSequence()) throw AssemblyError(source + ": 'faults:' must be a list");
    for (std::size_t i = 0; i < faults.size(); ++i) {
      assembly.faults.push_back(
          parse_fault(faults[i], source + ": faults[" + std::to_string(i) + "]"));
    }
  }
  return assembly;
}

Assembly load_assembly(const std::filesystem::path& file) {
  return parse_assembly(read_text<AssemblyError>(file, "the assembly file"), file.string());
}

std::string assembly_to_yaml(const Assembly& assembly) {
  // yaml-cpp's emitter quotes the names and keys that need it (a name may hold ", " or "}").
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "modules" << YAML::Value << YAML::BeginSeq;
  for (const auto& m : assembly.modules) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << m.name;
    out << YAML::Key << "key" << YAML::Value << m.key;
    if (!m.parent.empty()) {
      out << YAML::Key << "parent" << YAML::Value << m.parent;
      out << YAML::Key << "connector" << YAML::Value << m.connector;
    }
    if (m.robot_ids.size() == 1)
      out << YAML::Key << "robot_id" << YAML::Value << m.robot_ids.front();
    if (m.robot_ids.size() > 1) {
      out << YAML::Key << "robot_id" << YAML::Value << YAML::Flow << m.robot_ids;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  if (!assembly.faults.empty()) {
    out << YAML::Key << "faults" << YAML::Value << YAML::BeginSeq;
    for (const auto& f : assembly.faults) {
      out << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "type" << YAML::Value
          << std::string(kFaultTypes.to(f.type).value_or("unknown"));
      out << YAML::Key << "module" << YAML::Value << f.module;
      switch (f.type) {
        case FaultType::kUpsideDown:
          if (f.upstream_port)
            out << YAML::Key << "upstream_port" << YAML::Value << *f.upstream_port;
          break;
        case FaultType::kBrokenLink:
          break;
        case FaultType::kUnknownIdentity:
          out << YAML::Key << "esc" << YAML::Value << f.esc;
          out << YAML::Key << "identity" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
              << "mod_type" << YAML::Value << f.identity.mod_type << YAML::Key << "mod_id"
              << YAML::Value << f.identity.mod_id << YAML::Key << "mod_size" << YAML::Value
              << f.identity.mod_size << YAML::Key << "mod_rev" << YAML::Value << f.identity.mod_rev
              << YAML::EndMap;
          break;
        case FaultType::kWrongTopology:
          out << YAML::Key << "esc" << YAML::Value << f.esc;
          out << YAML::Key << "topology" << YAML::Value << f.topology;
          break;
      }
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void validate(const Assembly& assembly, const EscCatalog& catalog, PortOrder order) {
  (void)resolve(assembly, catalog, order);
}

uint8_t BusEsc::open_ports() const {
  uint8_t mask = 0;
  for (std::size_t p = 0; p < 4; ++p) {
    if (peer[p] != kNoPeer) mask = static_cast<uint8_t>(mask | (1U << p));
  }
  return mask;
}

namespace {

void connect(std::vector<BusEsc>& escs, int32_t a, int32_t port_a, int32_t b, int32_t port_b) {
  escs[static_cast<std::size_t>(a)].peer[static_cast<std::size_t>(port_a)] = b;
  escs[static_cast<std::size_t>(a)].peer_port[static_cast<std::size_t>(port_a)] = port_b;
  escs[static_cast<std::size_t>(b)].peer[static_cast<std::size_t>(port_b)] = a;
  escs[static_cast<std::size_t>(b)].peer_port[static_cast<std::size_t>(port_b)] = port_a;
}

}  // namespace

Bus wire_bus(const Assembly& assembly, const EscCatalog& catalog, PortOrder order) {
  const Resolved r = resolve(assembly, catalog, order);
  const std::size_t n = assembly.modules.size();

  // Wire every ESC: inside modules (secondary ESCs), between modules (connectors), master.
  Bus bus;
  std::vector<BusEsc>& escs = bus.escs;
  std::vector<int32_t> first_esc(n, 0);
  for (std::size_t m = 0; m < n; ++m) {
    first_esc[m] = static_cast<int32_t>(escs.size());
    const ModuleLayout& layout = r.layouts[m];
    for (std::size_t e = 0; e < layout.escs.size(); ++e) {
      BusEsc esc;
      esc.module = assembly.modules[m].name;
      esc.module_esc = static_cast<int32_t>(e);
      esc.board = layout.escs[e].board;
      esc.identity = layout.escs[e].identity;
      esc.esc_type = layout.escs[e].esc_type;
      esc.robot_id = robot_id_of(assembly.modules[m], e);
      escs.push_back(esc);
      if (e > 0) {
        connect(escs, first_esc[m] + layout.escs[e].parent_esc, layout.escs[e].parent_port,
                first_esc[m] + static_cast<int32_t>(e), 0);
      }
    }
  }
  std::vector<bool> broken(n, false);
  for (const Fault& f : assembly.faults) {
    if (f.type == FaultType::kBrokenLink) broken[r.by_name.at(f.module)] = true;
  }
  for (std::size_t m = 0; m < n; ++m) {
    for (const auto& [connector, child] : r.children[m]) {
      if (broken[child]) continue;
      const auto* placement = r.layouts[m].connector(connector);
      connect(escs, first_esc[m] + placement->esc, placement->port, first_esc[child], 0);
    }
  }
  if (broken[r.root]) return bus;
  bus.root = first_esc[r.root];
  {
    auto& root = escs[static_cast<std::size_t>(bus.root)];
    root.peer[0] = kMasterPeer;
    root.peer_port[0] = 0;
  }
  for (const Fault& f : assembly.faults) {
    const std::size_t m = r.by_name.at(f.module);
    const auto index = static_cast<std::size_t>(first_esc[m]);
    if (f.type == FaultType::kUnknownIdentity) {
      escs[index + static_cast<std::size_t>(f.esc)].identity = f.identity;
    } else if (f.type == FaultType::kWrongTopology) {
      escs[index + static_cast<std::size_t>(f.esc)].reported_topology = f.topology;
    } else if (f.type == FaultType::kUpsideDown) {
      // Mounted the wrong way round: the connector of `port` faces the parent, the input
      // connector (port 0) faces what was mounted on that connector.
      const topology::EscBoard board = r.layouts[m].escs[0].board;
      int32_t port = topology::downstream_ports(board, order).ports[0];
      if (f.upstream_port) {
        port = *f.upstream_port;
      } else if (const auto* c = r.layouts[m].connector(1); c && c->esc == 0) {
        port = c->port;
      }
      BusEsc& esc = escs[index];
      const std::array<int32_t, 2> peers{esc.peer[0], esc.peer[static_cast<std::size_t>(port)]};
      const std::array<int32_t, 2> peer_ports{esc.peer_port[0],
                                              esc.peer_port[static_cast<std::size_t>(port)]};
      const std::array<int32_t, 2> new_ports{static_cast<int32_t>(port), 0};
      esc.peer[0] = kNoPeer;
      esc.peer[static_cast<std::size_t>(port)] = kNoPeer;
      for (std::size_t k = 0; k < 2; ++k) {
        const int32_t p = new_ports[k];
        esc.peer[static_cast<std::size_t>(p)] = peers[k];
        esc.peer_port[static_cast<std::size_t>(p)] = peer_ports[k];
        if (peers[k] >= 0) {
          auto& other = escs[static_cast<std::size_t>(peers[k])];
          other.peer_port[static_cast<std::size_t>(peer_ports[k])] = p;
        }
      }
    }
  }
  return bus;
}

std::vector<FrameStep> follow_frame(const Bus& bus, PortOrder order) {
  std::vector<FrameStep> steps;
  if (bus.root < 0) return steps;
  // An ESC receiving on port L[j] forwards to L[j+1] (closed ports loop back at once); the EPU
  // sits between receiving on port 0 and forwarding to L[1].
  const auto loop = topology::frame_order(order);
  std::array<int32_t, 4> loop_index{};
  for (std::size_t k = 0; k < 4; ++k) loop_index[static_cast<std::size_t>(loop[k])] = static_cast<int32_t>(k);
  const auto& escs = bus.escs;
  int32_t entry = 0;
  for (std::size_t p = 0; p < 4; ++p) {
    if (escs[static_cast<std::size_t>(bus.root)].peer[p] == kMasterPeer) entry = static_cast<int32_t>(p);
  }
  using Kind = FrameStep::Kind;
  struct Visit {
    int32_t esc;
    int32_t entry_index;
    int32_t step;
  };
  std::vector<Visit> stack{{bus.root, loop_index[static_cast<std::size_t>(entry)], 0}};
  steps.push_back({Kind::kReceive, bus.root, entry});
  while (!stack.empty()) {
    Visit& v = stack.back();
    if (v.step == 4) {
      // Back out through the entry port, to the parent's port the frame left by.
      const int32_t port = loop[static_cast<std::size_t>(v.entry_index)];
      steps.push_back({Kind::kSend, v.esc, port});
      stack.pop_back();
      if (!stack.empty()) {
        const Visit& parent = stack.back();
        const auto at = static_cast<std::size_t>((parent.entry_index + parent.step) % 4);
        steps.push_back({Kind::kReceive, parent.esc, loop[at]});
      }
      continue;
    }
    ++v.step;
    const auto index = static_cast<std::size_t>((v.entry_index + v.step) % 4);
    const BusEsc& esc = escs[static_cast<std::size_t>(v.esc)];
    if (index == 1) steps.push_back({Kind::kProcess, v.esc, 0});
    if (v.step == 4) continue;
    const auto port = static_cast<std::size_t>(loop[index]);
    if (esc.peer[port] >= 0) {
      const int32_t next = esc.peer[port];
      const int32_t next_port = esc.peer_port[port];
      steps.push_back({Kind::kSend, v.esc, static_cast<int32_t>(port)});
      steps.push_back({Kind::kReceive, next, next_port});
      stack.push_back(Visit{next, loop_index[static_cast<std::size_t>(next_port)], 0});
    } else {
      steps.push_back({Kind::kLoopback, v.esc, static_cast<int32_t>(port)});
    }
  }
  return steps;
}

EscScan simulate_scan(const Assembly& assembly, const EscCatalog& catalog, PortOrder order) {
  const Bus bus = wire_bus(assembly, catalog, order);
  EscScan scan;
  for (const FrameStep& step : follow_frame(bus, order)) {
    if (step.kind != FrameStep::Kind::kProcess) continue;
    const BusEsc& esc = bus.escs[static_cast<std::size_t>(step.esc)];
    EscSlave s;
    s.position = static_cast<int32_t>(scan.slaves.size()) + 1;
    s.active_ports = esc.open_ports();
    s.topology =
        esc.reported_topology.value_or(std::popcount(static_cast<unsigned>(s.active_ports)));
    s.esc_type = esc.esc_type;
    s.identity = esc.identity;
    s.robot_id = esc.robot_id;
    scan.slaves.push_back(s);
  }
  return scan;
}

ModuleTree tree_from_assembly(const Assembly& assembly, const EscCatalog& catalog,
                              PortOrder order) {
  const Resolved r = resolve(assembly, catalog, order);
  const auto ports = topology::frame_order(order);
  ModuleTree tree;
  std::vector<int32_t> module_index(assembly.modules.size(), -1);
  std::vector<std::vector<int32_t>> esc_position(assembly.modules.size());

  // Pre-order over the ESCs: an ESC, then what hangs on its ports in frame order.
  struct Item {
    std::size_t module;
    int32_t esc;
    int32_t parent_position;
    int32_t parent_port;  // -1: on the master
  };
  std::vector<Item> todo{{r.root, 0, 0, -1}};
  while (!todo.empty()) {
    const Item item = todo.back();
    todo.pop_back();
    const MountedModule& mounted = assembly.modules[item.module];
    const ModuleLayout& layout = r.layouts[item.module];
    const auto position = static_cast<int32_t>(tree.slaves.size()) + 1;
    if (item.esc == 0) {
      topology::ModuleNode node;
      node.index = static_cast<int32_t>(tree.modules.size());
      node.key = layout.key;
      node.kind = layout.kind;
      node.identity = layout.escs[0].identity;
      if (!mounted.parent.empty()) {
        node.parent_module = module_index[r.by_name.at(mounted.parent)];
        node.parent_connector = mounted.connector;
      }
      node.robot_id = robot_id_of(mounted, 0);
      module_index[item.module] = node.index;
      esc_position[item.module].assign(layout.escs.size(), 0);
      tree.modules.push_back(std::move(node));
    }
    esc_position[item.module][static_cast<std::size_t>(item.esc)] = position;
    tree.modules[static_cast<std::size_t>(module_index[item.module])].slave_positions.push_back(
        position);

    topology::SlaveNode slave;
    slave.slave.position = position;
    slave.slave.esc_type = layout.escs[static_cast<std::size_t>(item.esc)].esc_type;
    slave.slave.identity = layout.escs[static_cast<std::size_t>(item.esc)].identity;
    slave.slave.robot_id = robot_id_of(mounted, static_cast<std::size_t>(item.esc));
    slave.parent_position = item.parent_position;
    if (item.parent_port >= 0) slave.parent_port = item.parent_port;
    slave.module_index = module_index[item.module];
    uint8_t mask = 1;  // port 0: towards the parent
    std::vector<Item> below;
    for (std::size_t k = 1; k < 4; ++k) {
      const int32_t port = ports[k];
      if (const auto esc = layout.esc_at(item.esc, port)) {
        below.push_back(Item{item.module, *esc, position, port});
      } else if (const auto connector = layout.connector_at(item.esc, port)) {
        for (const auto& [c, child] : r.children[item.module]) {
          if (c == *connector) below.push_back(Item{child, 0, position, port});
        }
      } else {
        continue;
      }
      if (!below.empty() && below.back().parent_port == port) {
        mask = static_cast<uint8_t>(mask | (1U << port));
      }
    }
    slave.slave.active_ports = mask;
    slave.slave.topology = std::popcount(static_cast<unsigned>(mask));
    tree.slaves.push_back(slave);
    for (auto it = below.rbegin(); it != below.rend(); ++it) todo.push_back(*it);
  }
  return tree;
}

}  // namespace concert::simbus
