#include "concert/topology/dds/conversions.hpp"

#include <array>
#include <utility>

#include "concert/common/enum_map.hpp"

namespace concert::topology::dds {
namespace {

EscSlave slave_to_core(const msg::EscSlave& m) {
  EscSlave s;
  s.position = m.position();
  s.active_ports = m.active_ports();
  s.topology = m.topology();
  s.esc_type = m.esc_type();
  s.identity = EscIdentity{m.mod_type(), m.mod_id(), m.mod_size(), m.mod_rev()};
  s.robot_id = m.robot_id();
  return s;
}

msg::EscSlave slave_to_msg(const EscSlave& s) {
  msg::EscSlave m;
  m.position(s.position);
  m.active_ports(s.active_ports);
  m.topology(s.topology);
  m.esc_type(s.esc_type);
  m.mod_type(s.identity.mod_type);
  m.mod_id(s.identity.mod_id);
  m.mod_size(s.identity.mod_size);
  m.mod_rev(s.identity.mod_rev);
  m.robot_id(s.robot_id);
  return m;
}

// Every core kind has its wire twin; a value outside the table (a newer peer's kind) reads as
// unknown.
constexpr EnumMap kModuleKinds{std::array{
    std::pair{ModuleKind::kJoint, msg::MODULE_JOINT},
    std::pair{ModuleKind::kHub, msg::MODULE_HUB},
    std::pair{ModuleKind::kEndEffector, msg::MODULE_END_EFFECTOR},
    std::pair{ModuleKind::kLink, msg::MODULE_LINK},
    std::pair{ModuleKind::kWheel, msg::MODULE_WHEEL},
    std::pair{ModuleKind::kBaseLink, msg::MODULE_BASE_LINK},
    std::pair{ModuleKind::kUnknown, msg::MODULE_UNKNOWN},
}};

msg::ModuleKind kind_to_msg(ModuleKind kind) {
  return kModuleKinds.to(kind).value_or(msg::MODULE_UNKNOWN);
}

ModuleKind kind_to_core(msg::ModuleKind kind) {
  return kModuleKinds.from(kind).value_or(ModuleKind::kUnknown);
}

}  // namespace

EscScan to_core(const msg::EscScan& scan) {
  EscScan out;
  out.slaves.reserve(scan.slaves().size());
  for (const auto& s : scan.slaves()) out.slaves.push_back(slave_to_core(s));
  return out;
}

msg::EscScan to_msg(const EscScan& scan, uint32_t scan_id, int64_t stamp_ns,
                    const std::string& source) {
  msg::EscScan out;
  out.scan_id(scan_id);
  out.stamp_ns(stamp_ns);
  out.source(source);
  out.slaves().reserve(scan.slaves.size());
  for (const auto& s : scan.slaves) out.slaves().push_back(slave_to_msg(s));
  return out;
}

ModuleTree to_core(const msg::ModuleTree& tree) {
  ModuleTree out;
  for (const auto& m : tree.slaves()) {
    SlaveNode node;
    node.slave = slave_to_core(m.slave());
    node.parent_position = m.parent_position();
    if (m.parent_port() >= 0) node.parent_port = m.parent_port();
    node.module_index = m.module_index();
    out.slaves.push_back(node);
  }
  for (const auto& m : tree.modules()) {
    ModuleNode node;
    node.index = m.index();
    node.key = m.key();
    node.known = m.known();
    node.kind = kind_to_core(m.kind());
    node.identity = EscIdentity{m.mod_type(), m.mod_id(), m.mod_size(), m.mod_rev()};
    node.slave_positions = m.slave_positions();
    node.parent_module = m.parent_module();
    node.parent_connector = m.parent_connector();
    node.robot_id = m.robot_id();
    out.modules.push_back(std::move(node));
  }
  for (const auto& i : tree.issues()) {
    out.issues.push_back({i.error() ? TreeIssue::Severity::kError : TreeIssue::Severity::kWarning,
                          i.position(), i.message()});
  }
  return out;
}

msg::ModuleTree to_msg(const ModuleTree& tree, uint32_t version, uint32_t scan_id,
                       int64_t stamp_ns) {
  msg::ModuleTree out;
  out.version(version);
  out.scan_id(scan_id);
  out.stamp_ns(stamp_ns);
  for (const auto& s : tree.slaves) {
    msg::SlaveNode node;
    node.slave(slave_to_msg(s.slave));
    node.parent_position(s.parent_position);
    node.parent_port(s.parent_port.value_or(-1));
    node.module_index(s.module_index);
    out.slaves().push_back(node);
  }
  for (const auto& m : tree.modules) {
    msg::ModuleNode node;
    node.index(m.index);
    node.key(m.key);
    node.known(m.known);
    node.kind(kind_to_msg(m.kind));
    node.mod_type(m.identity.mod_type);
    node.mod_id(m.identity.mod_id);
    node.mod_size(m.identity.mod_size);
    node.mod_rev(m.identity.mod_rev);
    node.slave_positions(m.slave_positions);
    node.parent_module(m.parent_module);
    node.parent_connector(m.parent_connector);
    node.robot_id(m.robot_id);
    out.modules().push_back(node);
  }
  for (const auto& i : tree.issues) {
    msg::TreeIssue issue;
    issue.error(i.severity == TreeIssue::Severity::kError);
    issue.position(i.position);
    issue.message(i.message);
    out.issues().push_back(issue);
  }
  return out;
}

}  // namespace concert::topology::dds
