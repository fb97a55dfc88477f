#pragma once
// The default homing posture of a robot's arms: where each arm rests when it is first mounted,
// and where the simulator starts a joint whose module is new. The database's zero posture is
// kept when the drives hold it within a share of their continuous torque; otherwise (a long arm
// level after a bend, say) the arm is raised to a posture the drives hold.

#include <set>
#include <string>

#include "concert/model_generation/model.hpp"

namespace concert::model_generation {

/// Sets JointInfo::home of every arm joint not in `homed` (the customisation's homes stay)
/// to a posture whose gravity torques are within `fraction` x each joint's continuous torque
/// where one can be found, free of self collision (libs/collision), and no arm frame reaches
/// more than 5 cm below the arm's mount.
/// `model.urdf` must be written. Throws kinematics::ModelError on a URDF it cannot read.
RestingPosture choose_resting_posture(GeneratedModel& model, const std::set<std::string>& homed, double fraction);

}  // namespace concert::model_generation
