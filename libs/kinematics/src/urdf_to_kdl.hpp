#pragma once

// urdfdom -> KDL::Tree conversion. Debian 12 packages orocos-kdl and urdfdom but not
// kdl_parser (a ROS package), so this small converter follows kdl_parser's conventions:
// one KDL segment per URDF link, the segment's joint is the link's parent joint, the
// segment's inertia is the link's inertia expressed in the link frame.

#include <kdl/tree.hpp>
#include <urdf_model/model.h>

#include <Eigen/Core>

#include <string>
#include <vector>

#include "concert/kinematics/model.hpp"

namespace concert::kinematics::detail {

/// Result of converting a URDF: the KDL tree (root segment "world") and joint metadata in
/// KDL's q_nr order.
struct KdlConversion {
  KDL::Tree tree{"world"};
  std::vector<std::string> joint_names;
  std::vector<JointType> joint_types;
  std::vector<JointLimits> joint_limits;
  std::vector<std::string> joint_parent_links;
  std::vector<std::string> joint_child_links;
  std::vector<Eigen::Vector3d> joint_axes;
  std::vector<std::string> frame_names;  ///< "world" + every URDF link
  int num_virtual_joints{0};
  double total_mass{0.0};
};

KDL::Frame to_kdl(const urdf::Pose& pose);
KDL::RigidBodyInertia to_kdl(const urdf::Inertial& inertial);

/// Converts a parsed URDF. Throws ModelError for unsupported joints (floating, planar, mimic).
KdlConversion urdf_to_kdl(const urdf::ModelInterface& urdf_model, const ModelOptions& options);

}  // namespace concert::kinematics::detail
