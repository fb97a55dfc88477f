#include "conversions.hpp"

#include <cmath>
#include <stdexcept>

namespace concert::modelgen::dds {

namespace {

double finite_or_big(double v) {
  if (std::isinf(v)) return v > 0 ? 1e300 : -1e300;
  return v;
}

}  // namespace

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

msg::RobotModel to_msg(const RobotModel& model, int64_t stamp_ns) {
  msg::RobotModel m;
  m.version(static_cast<uint32_t>(model.version));
  m.content_hash(model.content_hash);
  m.tree_version(static_cast<uint32_t>(model.tree_version));
  m.stamp_ns(stamp_ns);
  m.urdf(model.urdf);
  m.srdf(model.srdf);
  m.config_yaml(model.config_yaml);
  m.modules(model.modules);
  for (const JointInfo& j : model.joints) {
    msg::JointInfo w;
    w.name(j.name);
    w.chain(j.chain);
    w.lower(finite_or_big(j.lower));
    w.upper(finite_or_big(j.upper));
    w.velocity(j.velocity);
    w.effort(j.continuous_torque);
    m.joints().push_back(w);
  }
  for (const ChainInfo& c : model.chains) {
    msg::ChainInfo w;
    w.name(c.name);
    w.role(c.role);
    w.base_link(c.base_link);
    w.tip_link(c.tip_link);
    w.joints(c.joints);
    m.chains().push_back(w);
  }
  for (const EndEffectorInfo& e : model.end_effectors) {
    msg::EndEffectorInfo w;
    w.name(e.name);
    w.chain(e.chain);
    w.frame(e.frame);
    w.module_key(e.module_key);
    m.end_effectors().push_back(w);
  }
  return m;
}

}  // namespace concert::modelgen::dds
