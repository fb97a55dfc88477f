#include "dds/conversions.hpp"

namespace concert::safety::dds {

std::optional<EStopSource> to_core(msg::EStopSource source) {
  switch (source) {
    case msg::ESTOP_BUTTON_FRONT_LEFT:
      return EStopSource::kButtonFrontLeft;
    case msg::ESTOP_BUTTON_FRONT_RIGHT:
      return EStopSource::kButtonFrontRight;
    case msg::ESTOP_BUTTON_REAR_LEFT:
      return EStopSource::kButtonRearLeft;
    case msg::ESTOP_BUTTON_REAR_RIGHT:
      return EStopSource::kButtonRearRight;
    case msg::ESTOP_WIRELESS:
      return EStopSource::kWireless;
    case msg::ESTOP_SOFTWARE:
      return EStopSource::kSoftware;
  }
  return std::nullopt;
}

msg::EStopSource to_msg(EStopSource source) {
  switch (source) {
    case EStopSource::kButtonFrontLeft:
      return msg::ESTOP_BUTTON_FRONT_LEFT;
    case EStopSource::kButtonFrontRight:
      return msg::ESTOP_BUTTON_FRONT_RIGHT;
    case EStopSource::kButtonRearLeft:
      return msg::ESTOP_BUTTON_REAR_LEFT;
    case EStopSource::kButtonRearRight:
      return msg::ESTOP_BUTTON_REAR_RIGHT;
    case EStopSource::kWireless:
      return msg::ESTOP_WIRELESS;
    case EStopSource::kSoftware:
      return msg::ESTOP_SOFTWARE;
  }
  return msg::ESTOP_SOFTWARE;
}

JointSample to_core(const msg::JointState& state) {
  return {state.model_version(), state.name(), state.position(), state.velocity(), state.effort()};
}

msg::SafetyState to_msg(const SafetyStatus& status, int64_t stamp_ns) {
  msg::SafetyState out;
  out.mode(status.mode == Mode::kStopped ? msg::SAFETY_STOPPED : msg::SAFETY_RUNNING);
  out.reset_required(status.reset_required);
  out.stamp_ns(stamp_ns);
  out.causes(status.causes);
  return out;
}

}  // namespace concert::safety::dds
