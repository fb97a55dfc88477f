#pragma once
// Model generation is the library libs/model_generation (concert_model_generation). modelgen's
// service code uses its types under these names; the robot's simulator still includes this
// header until it moves to libs/sim and includes the library directly.

#include "concert/model_generation/generator.hpp"

namespace concert::modelgen {

using model_generation::AddonChoice;
using model_generation::ChainInfo;
using model_generation::check_modelable;
using model_generation::Customisation;
using model_generation::EndEffectorInfo;
using model_generation::GeneratedModel;
using model_generation::JointInfo;
using model_generation::ModelError;
using model_generation::ModelGenerator;
using model_generation::Params;
using model_generation::PhysicalBody;
using model_generation::PhysicalJoint;
using model_generation::PhysicalTree;
using model_generation::sha256_hex;
using model_generation::write_config_yaml;
using model_generation::write_srdf;
using model_generation::write_urdf;

}  // namespace concert::modelgen
