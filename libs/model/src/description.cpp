#include "concert/model/description.hpp"

#include <array>
#include <utility>

namespace concert::model {
namespace {

template <typename Enum, std::size_t N>
Enum from_string(const std::array<std::pair<Enum, std::string_view>, N>& names,
                 std::string_view name, const std::string& what, const char* kind) {
  std::string known;
  for (const auto& [value, text] : names) {
    if (text == name) return value;
    known += (known.empty() ? "" : ", ") + std::string(text);
  }
  throw ModelError(what + ": unknown " + kind + " '" + std::string(name) + "' (known: " + known +
                   ")");
}

template <typename Enum, std::size_t N>
std::string_view name_of(const std::array<std::pair<Enum, std::string_view>, N>& names,
                         Enum value) {
  for (const auto& [v, text] : names) {
    if (v == value) return text;
  }
  return "other";
}

constexpr std::array<std::pair<ChainRole, std::string_view>, 4> kRoles{
    {{ChainRole::kArm, "arm"},
     {ChainRole::kLeg, "leg"},
     {ChainRole::kTool, "tool"},
     {ChainRole::kOther, "other"}}};
constexpr std::array<std::pair<EndEffectorKind, std::string_view>, 7> kEndEffectorKinds{
    {{EndEffectorKind::kDrill, "drill"},
     {EndEffectorKind::kGripper, "gripper"},
     {EndEffectorKind::kSanding, "sanding"},
     {EndEffectorKind::kSpraying, "spraying"},
     {EndEffectorKind::kCamera, "camera"},
     {EndEffectorKind::kWheel, "wheel"},
     {EndEffectorKind::kOther, "other"}}};
constexpr std::array<std::pair<SensorKind, std::string_view>, 6> kSensorKinds{
    {{SensorKind::kCamera, "camera"},
     {SensorKind::kLidar, "lidar"},
     {SensorKind::kSonar, "sonar"},
     {SensorKind::kImu, "imu"},
     {SensorKind::kForceTorque, "force_torque"},
     {SensorKind::kOther, "other"}}};

}  // namespace

std::string_view to_string(ChainRole role) { return name_of(kRoles, role); }
std::string_view to_string(EndEffectorKind kind) { return name_of(kEndEffectorKinds, kind); }
std::string_view to_string(SensorKind kind) { return name_of(kSensorKinds, kind); }

ChainRole chain_role_from_string(std::string_view name, const std::string& what) {
  return from_string(kRoles, name, what, "chain role");
}
EndEffectorKind end_effector_kind_from_string(std::string_view name, const std::string& what) {
  return from_string(kEndEffectorKinds, name, what, "end-effector kind");
}
SensorKind sensor_kind_from_string(std::string_view name, const std::string& what) {
  return from_string(kSensorKinds, name, what, "sensor kind");
}

}  // namespace concert::model
