#pragma once
// IDL -> core conversion of the modelgen adapter's own message (idl/model.idl customisation);
// the module tree comes in through libs/topology_dds, the model goes out through libs/model's
// one conversion (concert_model_dds).

#include <cstdint>
#include <string>

#include "model.h"
#include "modelgen/service.hpp"

namespace concert::modelgen::dds {

/// Customisation sample -> request. Throws std::invalid_argument when homing_joints and
/// homing_positions differ in length or a joint is listed twice.
CustomisationRequest to_core(const msg::ModelCustomisation& request);

}  // namespace concert::modelgen::dds
