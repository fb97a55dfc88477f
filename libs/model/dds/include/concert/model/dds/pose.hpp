#pragma once
// The one conversion between the Pose and Vector3 messages (idl/robot.idl) and Eigen, for every
// adapter.

#include <Eigen/Geometry>

#include "robot.h"

namespace concert::model::dds {

/// Pose sample -> rigid transform. A zero quaternion stays a zero rotation (not a rigid
/// transform), so that whoever checks the request refuses it rather than a silent identity.
Eigen::Isometry3d to_isometry(const msg::Pose& pose);
/// Rigid transform -> Pose sample.
msg::Pose to_pose_msg(const Eigen::Isometry3d& pose);
/// Vector -> Vector3 sample.
msg::Vector3 to_vector_msg(const Eigen::Vector3d& v);

}  // namespace concert::model::dds
