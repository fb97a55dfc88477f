#include "concert/module_db/module_description.hpp"

#include <algorithm>

namespace concert::module_db {

std::string to_string(ModuleType type) {
  switch (type) {
    case ModuleType::kJoint: return "joint";
    case ModuleType::kHub: return "hub";
    case ModuleType::kMobileBase: return "mobile_base";
    case ModuleType::kLink: return "link";
    case ModuleType::kBaseLink: return "base_link";
    case ModuleType::kEndEffector: return "end_effector";
    case ModuleType::kWheel: return "wheel";
  }
  return "unknown";
}

ModuleType module_type_from_string(const std::string& name) {
  for (ModuleType t : {ModuleType::kJoint, ModuleType::kHub, ModuleType::kMobileBase, ModuleType::kLink,
                       ModuleType::kBaseLink, ModuleType::kEndEffector, ModuleType::kWheel}) {
    if (to_string(t) == name) return t;
  }
  throw std::invalid_argument("unknown module type '" + name + "'");
}

std::string to_string(FrameKind kind) {
  switch (kind) {
    case FrameKind::kInput: return "input";
    case FrameKind::kJoint: return "joint";
    case FrameKind::kOutput: return "output";
    case FrameKind::kTcp: return "tcp";
    case FrameKind::kWheel: return "wheel";
    case FrameKind::kCamera: return "camera";
    case FrameKind::kOther: return "other";
  }
  return "other";
}

int ModuleDescription::input_connector() const {
  for (size_t i = 0; i < connectors.size(); ++i) {
    if (connectors[i].role == ConnectorRole::kInput) return static_cast<int>(i);
  }
  return -1;
}

int ModuleDescription::root_body() const {
  int in = input_connector();
  if (in >= 0) return connectors[static_cast<size_t>(in)].body;
  for (const Connector& c : connectors) {
    if (c.role == ConnectorRole::kBase) return c.body;
  }
  // No input: the body that is no joint's child.
  for (size_t b = 0; b < bodies.size(); ++b) {
    bool is_child = std::any_of(joints.begin(), joints.end(),
                                [&](const JointDescription& j) { return j.child_body == static_cast<int>(b); });
    if (!is_child) return static_cast<int>(b);
  }
  return 0;
}

std::vector<int> ModuleDescription::output_connectors() const {
  std::vector<int> out;
  for (size_t i = 0; i < connectors.size(); ++i) {
    if (connectors[i].role == ConnectorRole::kOutput) out.push_back(static_cast<int>(i));
  }
  return out;
}

std::vector<int> ModuleDescription::tcp_connectors() const {
  std::vector<int> out;
  for (size_t i = 0; i < connectors.size(); ++i) {
    if (connectors[i].role == ConnectorRole::kTcp) out.push_back(static_cast<int>(i));
  }
  return out;
}

std::vector<Frame> ModuleDescription::named_frames() const {
  std::vector<Frame> out;
  auto add = [&](ConnectorRole role, FrameKind kind) {
    for (const Connector& c : connectors) {
      if (c.role == role) out.push_back({c.name, kind, c.body, c.pose});
    }
  };
  add(ConnectorRole::kInput, FrameKind::kInput);
  for (const JointDescription& j : joints) {
    if (j.actuated()) out.push_back({j.name, FrameKind::kJoint, j.parent_body, j.pose_parent});
  }
  add(ConnectorRole::kOutput, FrameKind::kOutput);
  add(ConnectorRole::kTcp, type == ModuleType::kWheel ? FrameKind::kWheel : FrameKind::kTcp);
  out.insert(out.end(), frames.begin(), frames.end());
  return out;
}

double ModuleDescription::mass() const {
  double m = 0.0;
  for (const Body& b : bodies) m += b.inertial.mass;
  return m;
}

bool ModuleDescription::actuated() const {
  return std::any_of(joints.begin(), joints.end(), [](const JointDescription& j) { return j.actuated(); });
}

}  // namespace concert::module_db
