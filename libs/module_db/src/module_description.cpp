#include "concert/module_db/module_description.hpp"

#include <algorithm>
#include <array>
#include <string_view>

#include "internal.hpp"

namespace concert::module_db {
namespace {

// The names of each enumeration, in the order of its values.
constexpr std::array<std::string_view, 7> kModuleTypeNames{
    "joint", "hub", "mobile_base", "link", "base_link", "end_effector", "wheel"};
constexpr std::array<std::string_view, 4> kJointTypeNames{"revolute", "continuous", "prismatic",
                                                          "fixed"};
constexpr std::array<std::string_view, 10> kFrameKindNames{
    "input", "joint", "output", "tcp", "wheel", "camera", "lidar", "sonar", "imu", "other"};
static_assert(kModuleTypeNames.size() == static_cast<std::size_t>(ModuleType::kWheel) + 1);
static_assert(kJointTypeNames.size() == static_cast<std::size_t>(JointType::kFixed) + 1);
static_assert(kFrameKindNames.size() == static_cast<std::size_t>(FrameKind::kOther) + 1);

/// The name of `value`; `fallback` for a value outside the enumeration.
template <class Enum, std::size_t N>
std::string name_of(const std::array<std::string_view, N>& names, Enum value,
                    std::string_view fallback) {
  const auto index = static_cast<std::size_t>(value);
  return std::string(index < N ? names[index] : fallback);
}

/// The value called `name`; throws std::invalid_argument "unknown <what> '<name>'".
template <class Enum, std::size_t N>
Enum value_of(const std::array<std::string_view, N>& names, const std::string& name,
              const std::string& what) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::invalid_argument("unknown " + what + " '" + name + "'");
  return static_cast<Enum>(it - names.begin());
}

}  // namespace

std::string to_string(ModuleType type) { return name_of(kModuleTypeNames, type, "unknown"); }

ModuleType module_type_from_string(const std::string& name) {
  return value_of<ModuleType>(kModuleTypeNames, name, "module type");
}

std::string to_string(JointType type) { return name_of(kJointTypeNames, type, "fixed"); }

JointType joint_type_from_string(const std::string& name) {
  return value_of<JointType>(kJointTypeNames, name, "joint type");
}

std::string to_string(FrameKind kind) { return name_of(kFrameKindNames, kind, "other"); }

FrameKind detail::frame_kind_from_string(const std::string& name) {
  return value_of<FrameKind>(kFrameKindNames, name, "frame kind");
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
