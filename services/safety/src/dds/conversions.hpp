#pragma once
// IDL <-> core conversions of the safety adapter (idl/system.idl, idl/robot.idl); the robot model
// is converted by libs/model (concert_model_dds).

#include <cstdint>
#include <optional>
#include <vector>

#include "robot.h"
#include "safety/safety_monitor.hpp"
#include "system.h"

namespace concert::safety::dds {

/// The core source of a wire source; nullopt for a value outside the enum (a newer sender).
std::optional<EStopSource> to_core(msg::EStopSource source);
msg::EStopSource to_msg(EStopSource source);

JointSample to_core(const msg::JointState& state);
msg::SafetyState to_msg(const SafetyStatus& status, int64_t stamp_ns);

}  // namespace concert::safety::dds
