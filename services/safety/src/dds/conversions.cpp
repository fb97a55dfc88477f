#include "dds/conversions.hpp"

#include <array>
#include <utility>

#include "concert/common/enum_map.hpp"

namespace concert::safety::dds {

namespace {

// Every e-stop source and its wire twin, one row each; read both ways.
constexpr EnumMap kEStopSources{std::array{
    std::pair{EStopSource::kButtonFrontLeft, msg::ESTOP_BUTTON_FRONT_LEFT},
    std::pair{EStopSource::kButtonFrontRight, msg::ESTOP_BUTTON_FRONT_RIGHT},
    std::pair{EStopSource::kButtonRearLeft, msg::ESTOP_BUTTON_REAR_LEFT},
    std::pair{EStopSource::kButtonRearRight, msg::ESTOP_BUTTON_REAR_RIGHT},
    std::pair{EStopSource::kWireless, msg::ESTOP_WIRELESS},
    std::pair{EStopSource::kSoftware, msg::ESTOP_SOFTWARE},
}};

}  // namespace

std::optional<EStopSource> to_core(msg::EStopSource source) { return kEStopSources.from(source); }

msg::EStopSource to_msg(EStopSource source) {
  return kEStopSources.to(source).value_or(msg::ESTOP_SOFTWARE);
}

JointSample to_core(const msg::JointState& state) {
  return {state.model_version(), state.name(),     state.position(),
          state.velocity(),      state.effort(),   state.stamp_ns()};
}

msg::SafetyState to_msg(const SafetyStatus& status, int64_t stamp_ns) {
  msg::SafetyState out;
  out.mode(status.mode == Mode::kStopped ? msg::SAFETY_STOPPED : msg::SAFETY_RUNNING);
  out.reset_required(status.reset_required);
  out.stamp_ns(stamp_ns);
  out.causes(status.causes);
  for (const EStopSource e : status.engaged) out.engaged_inputs().push_back(to_msg(e));
  return out;
}

}  // namespace concert::safety::dds
