#include "conversions.hpp"

#include <cmath>
#include <stdexcept>

namespace concert::modelgen::dds {

namespace {

topology::ModuleKind kind_of(msg::ModuleKind k) {
  switch (k) {
    case msg::ModuleKind::MODULE_JOINT: return topology::ModuleKind::kJoint;
    case msg::ModuleKind::MODULE_HUB: return topology::ModuleKind::kHub;
    case msg::ModuleKind::MODULE_END_EFFECTOR: return topology::ModuleKind::kEndEffector;
    case msg::ModuleKind::MODULE_LINK: return topology::ModuleKind::kLink;
    case msg::ModuleKind::MODULE_WHEEL: return topology::ModuleKind::kWheel;
    case msg::ModuleKind::MODULE_BASE_LINK: return topology::ModuleKind::kBaseLink;
  }
  return topology::ModuleKind::kLink;
}

}  // namespace

topology::ModuleTree to_core(const msg::ModuleTree& tree) {
  topology::ModuleTree out;
  for (const msg::SlaveNode& s : tree.slaves()) {
    topology::SlaveNode n;
    n.slave.position = s.slave().position();
    n.slave.active_ports = s.slave().active_ports();
    n.slave.topology = s.slave().topology();
    n.slave.esc_type = s.slave().esc_type();
    n.slave.identity = {s.slave().mod_type(), s.slave().mod_id(), s.slave().mod_size(), s.slave().mod_rev()};
    n.slave.robot_id = s.slave().robot_id();
    n.parent_position = s.parent_position();
    if (s.parent_port() >= 0) n.parent_port = s.parent_port();
    n.module_index = s.module_index();
    out.slaves.push_back(n);
  }
  for (const msg::ModuleNode& m : tree.modules()) {
    topology::ModuleNode n;
    n.index = m.index();
    n.key = m.key();
    n.kind = kind_of(m.kind());
    n.identity = {m.mod_type(), m.mod_id(), m.mod_size(), m.mod_rev()};
    n.slave_positions = m.slave_positions();
    n.parent_module = m.parent_module();
    n.parent_connector = m.parent_connector();
    n.robot_id = m.robot_id();
    out.modules.push_back(std::move(n));
  }
  return out;
}

CustomisationRequest to_core(const msg::ModelCustomisation& request) {
  CustomisationRequest out;
  out.request_id = request.request_id();
  out.base_version = request.base_version();
  if (request.homing_joints().size() != request.homing_positions().size()) {
    throw std::invalid_argument("customisation request " + std::to_string(request.request_id()) + ": " +
                                std::to_string(request.homing_joints().size()) + " homing joints but " +
                                std::to_string(request.homing_positions().size()) + " positions");
  }
  for (size_t i = 0; i < request.homing_joints().size(); ++i) {
    if (!out.customisation.home.emplace(request.homing_joints()[i], request.homing_positions()[i]).second) {
      throw std::invalid_argument("customisation request " + std::to_string(request.request_id()) + ": joint '" +
                                  request.homing_joints()[i] + "' listed twice");
    }
  }
  for (const msg::AddonChoice& a : request.addons()) out.customisation.addons.push_back({a.module_name(), a.addon()});
  return out;
}

}  // namespace concert::modelgen::dds
