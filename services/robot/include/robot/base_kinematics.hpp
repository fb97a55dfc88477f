#pragma once
// The robot's loop drives the mobile base through libs/mobile_base.

#include "concert/mobile_base/base_kinematics.hpp"

namespace concert::robot {

using mobile_base::BaseKinematics;
using mobile_base::collision_cylinder_radii;
using mobile_base::detect_legs;
using mobile_base::Leg;
using mobile_base::LegSetpoint;
using mobile_base::Odometry;

}  // namespace concert::robot
