#pragma once
// IDL <-> core conversions of the modelgen adapter (idl/topology.idl, idl/model.idl).

#include <cstdint>
#include <string>

#include "concert/topology/types.hpp"
#include "model.h"
#include "modelgen/model.hpp"
#include "modelgen/service.hpp"
#include "topology.h"

namespace concert::modelgen::dds {

/// Customisation sample -> request. Throws std::invalid_argument when homing_joints and
/// homing_positions differ in length or a joint is listed twice.
CustomisationRequest to_core(const msg::ModelCustomisation& request);

/// Core model -> RobotModel sample. Infinite limits (continuous joints) travel as +-1e300.
msg::RobotModel to_msg(const RobotModel& model, int64_t stamp_ns);

}  // namespace concert::modelgen::dds
