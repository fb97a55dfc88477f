#pragma once
// IDL <-> robot core conversions (idl/robot.idl). Commands that cannot be converted throw
// CommandError naming the field and the sender.

#include <cstdint>

#include "robot.h"
#include "robot/robot_core.hpp"

namespace concert::robot::dds {

JointCommandSet to_core(const msg::JointCommand& command);
CartesianCommand to_core(const msg::CartesianImpedanceCommand& command);
BaseCommand to_core(const msg::BaseVelocityCommand& command);
JointTrajectory to_core(const msg::JointTrajectoryCommand& command);

/// The trajectory state of the IDL for a core progress (kIdle has none: EXECUTING).
msg::TrajectoryState to_msg(TrajectoryState state);

msg::JointState to_joint_state(const RobotState& state);
/// `distance` [m] travelled since start grows the (x, y, yaw) variances (documented in README).
msg::Odometry to_odometry(const RobotState& state, double distance);
msg::EndEffectorWrench to_wrench(const RobotState& state);

/// Simulated or real time [s] -> stamp [ns].
int64_t to_stamp_ns(double time);

}  // namespace concert::robot::dds
