#pragma once
// IDL -> core conversions of the modelgen adapter (idl/topology.idl, idl/model.idl); the model
// itself goes out through libs/model's one conversion (concert_model_dds).

#include <cstdint>
#include <string>

#include "concert/topology/types.hpp"
#include "model.h"
#include "modelgen/service.hpp"
#include "topology.h"

namespace concert::modelgen::dds {

/// Module tree sample -> core tree (parent_port -1 on the wire = none).
topology::ModuleTree to_core(const msg::ModuleTree& tree);

/// Customisation sample -> request. Throws std::invalid_argument when homing_joints and
/// homing_positions differ in length or a joint is listed twice.
CustomisationRequest to_core(const msg::ModelCustomisation& request);

}  // namespace concert::modelgen::dds
