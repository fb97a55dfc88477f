#pragma once
// Test helper: a planner ModelDescription as the RobotModel message modelgen would publish.

#include "modelPubSubTypes.h"
#include "planner/types.hpp"

namespace concert::planner::testing {

inline msg::RobotModel to_msg(const ModelDescription& d) {
  msg::RobotModel m;
  m.version(static_cast<uint32_t>(d.version));
  m.urdf(d.urdf);
  m.srdf(d.srdf);
  for (const JointSpec& j : d.joints) {
    msg::JointInfo i;
    i.name(j.name);
    i.chain(j.chain);
    i.lower(j.lower);
    i.upper(j.upper);
    i.velocity(j.velocity);
    i.effort(j.effort);
    m.joints().push_back(i);
  }
  for (const ChainSpec& c : d.chains) {
    msg::ChainInfo i;
    i.name(c.name);
    i.role(c.role);
    i.joints(c.joints);
    m.chains().push_back(i);
  }
  for (const EndEffectorSpec& e : d.end_effectors) {
    msg::EndEffectorInfo i;
    i.name(e.name);
    i.chain(e.chain);
    i.frame(e.frame);
    i.module_key(e.module_key);
    m.end_effectors().push_back(i);
  }
  return m;
}

}  // namespace concert::planner::testing
