#pragma once
// The one conversion between the RobotModel message (idl/model.idl) and the model description.
// Every service's DDS adapter uses it; no service converts the message itself.

#include <cstdint>

#include "concert/model/description.hpp"
#include "model.h"

namespace concert::model::dds {

/// RobotModel sample -> description. Limits of +-1e300 or beyond (how infinite limits travel)
/// become +-infinity. Throws ModelError naming the field of an unknown chain role,
/// end-effector kind or sensor kind (e.g. "RobotModel v3 chains[1].role: unknown chain role").
ModelDescription to_description(const msg::RobotModel& message);

/// Description -> RobotModel sample stamped `stamp_ns` [ns since the Unix epoch]. Infinite
/// limits travel as +-1e300 (CDR doubles may be infinite, but JSON tools choke on them).
msg::RobotModel to_msg(const ModelDescription& description, int64_t stamp_ns);

}  // namespace concert::model::dds
