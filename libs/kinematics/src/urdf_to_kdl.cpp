#include "urdf_to_kdl.hpp"

#include <kdl/joint.hpp>
#include <kdl/segment.hpp>

#include <string>

namespace concert::kinematics::detail {
namespace {

KDL::Vector to_kdl_vector(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

KDL::Rotation to_kdl_rotation(const urdf::Rotation& r) { return KDL::Rotation::Quaternion(r.x, r.y, r.z, r.w); }

JointLimits limits_of(const urdf::Joint& joint) {
  JointLimits limits;
  if (joint.limits) {
    limits.velocity = joint.limits->velocity;
    limits.effort = joint.limits->effort;
    if (joint.type != urdf::Joint::CONTINUOUS) {
      limits.has_position_limits = joint.limits->upper > joint.limits->lower;
      limits.lower = joint.limits->lower;
      limits.upper = joint.limits->upper;
    }
  }
  return limits;
}

struct Converter {
  const ModelOptions& options;
  KdlConversion out;

  void add_joint_info(const std::string& name, JointType type, const JointLimits& limits,
                      const std::string& parent, const std::string& child, const Eigen::Vector3d& axis) {
    out.joint_names.push_back(name);
    out.joint_types.push_back(type);
    out.joint_limits.push_back(limits);
    out.joint_parent_links.push_back(parent);
    out.joint_child_links.push_back(child);
    out.joint_axes.push_back(axis);
  }

  KDL::RigidBodyInertia inertia_of(const urdf::Link& link) {
    if (!link.inertial) {
      return KDL::RigidBodyInertia::Zero();
    }
    if (link.inertial->mass < 0.0) {
      throw ModelError("URDF link '" + link.name + "': negative mass " + std::to_string(link.inertial->mass));
    }
    out.total_mass += link.inertial->mass;
    return to_kdl(*link.inertial);
  }

  KDL::Joint joint_of(const urdf::Joint& joint) {
    const KDL::Frame parent_to_joint = to_kdl(joint.parent_to_joint_origin_transform);
    if (joint.mimic) {
      throw ModelError("URDF joint '" + joint.name + "': mimic joints are not supported");
    }
    switch (joint.type) {
      case urdf::Joint::FIXED:
        return KDL::Joint(joint.name, KDL::Joint::None);
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::CONTINUOUS:
      case urdf::Joint::PRISMATIC: {
        KDL::Vector axis = to_kdl_vector(joint.axis);
        if (axis.Norm() < 1e-9) {
          throw ModelError("URDF joint '" + joint.name + "': zero axis");
        }
        axis.Normalize();
        const auto type = joint.type == urdf::Joint::PRISMATIC ? KDL::Joint::TransAxis : KDL::Joint::RotAxis;
        return KDL::Joint(joint.name, parent_to_joint.p, parent_to_joint.M * axis, type);
      }
      case urdf::Joint::FLOATING:
      case urdf::Joint::PLANAR:
      case urdf::Joint::UNKNOWN:
      default:
        throw ModelError("URDF joint '" + joint.name +
                         "': floating/planar/unknown joints are not supported (use ModelOptions::planar_base "
                         "for a mobile base)");
    }
  }

  void add_children(const urdf::Link& link) {
    for (const auto& child : link.child_links) {
      const urdf::Joint& joint = *child->parent_joint;
      const KDL::Segment segment(child->name, joint_of(joint), to_kdl(joint.parent_to_joint_origin_transform),
                                 inertia_of(*child));
      if (!out.tree.addSegment(segment, link.name)) {
        throw ModelError("URDF link '" + child->name + "': could not be added below '" + link.name + "'");
      }
      out.frame_names.push_back(child->name);
      if (joint.type != urdf::Joint::FIXED) {
        const JointType type = joint.type == urdf::Joint::PRISMATIC  ? JointType::kPrismatic
                               : joint.type == urdf::Joint::REVOLUTE ? JointType::kRevolute
                                                                     : JointType::kContinuous;
        Eigen::Vector3d axis(joint.axis.x, joint.axis.y, joint.axis.z);
        add_joint_info(joint.name, type, limits_of(joint), link.name, child->name, axis.normalized());
      }
      add_children(*child);
    }
  }
};

}  // namespace

KDL::Frame to_kdl(const urdf::Pose& pose) { return {to_kdl_rotation(pose.rotation), to_kdl_vector(pose.position)}; }

KDL::RigidBodyInertia to_kdl(const urdf::Inertial& inertial) {
  const KDL::Frame origin = to_kdl(inertial.origin);
  // URDF gives the inertia about the COM in the inertial frame; KDL wants it about the COM in
  // the link frame. RotationalInertia has no rotation operator, so rotate a zero-mass
  // RigidBodyInertia with COM at the origin (as kdl_parser does).
  const KDL::RotationalInertia urdf_inertia(inertial.ixx, inertial.iyy, inertial.izz, inertial.ixy, inertial.ixz,
                                            inertial.iyz);
  const KDL::RigidBodyInertia rotated = origin.M * KDL::RigidBodyInertia(0.0, KDL::Vector::Zero(), urdf_inertia);
  return KDL::RigidBodyInertia(inertial.mass, origin.p, rotated.getRotationalInertia());
}

KdlConversion urdf_to_kdl(const urdf::ModelInterface& urdf_model, const ModelOptions& options) {
  Converter conv{options, {}};
  const auto root = urdf_model.getRoot();
  if (!root) {
    throw ModelError("URDF '" + urdf_model.getName() + "' has no root link");
  }
  conv.out.frame_names.push_back("world");
  std::string hook = "world";
  if (root->name == "world") {
    if (options.planar_base) {
      throw ModelError("URDF root link is 'world': a planar base needs the mobile base link as root");
    }
    if (root->inertial && root->inertial->mass > 0.0) {
      throw ModelError("URDF link 'world' must not have mass");
    }
    conv.add_children(*root);
    return std::move(conv.out);
  }
  KDL::Joint root_joint("world_fixed", KDL::Joint::None);
  if (options.planar_base) {
    const KDL::RigidBodyInertia none = KDL::RigidBodyInertia::Zero();
    const std::string x_link = "__" + options.virtual_x_joint + "_link";
    const std::string y_link = "__" + options.virtual_y_joint + "_link";
    conv.out.tree.addSegment(
        KDL::Segment(x_link, KDL::Joint(options.virtual_x_joint, KDL::Joint::TransX), KDL::Frame::Identity(), none),
        hook);
    conv.out.tree.addSegment(
        KDL::Segment(y_link, KDL::Joint(options.virtual_y_joint, KDL::Joint::TransY), KDL::Frame::Identity(), none),
        x_link);
    hook = y_link;
    root_joint = KDL::Joint(options.virtual_yaw_joint, KDL::Joint::RotZ);
    conv.add_joint_info(options.virtual_x_joint, JointType::kPrismatic, {}, "world", x_link, Eigen::Vector3d::UnitX());
    conv.add_joint_info(options.virtual_y_joint, JointType::kPrismatic, {}, x_link, y_link, Eigen::Vector3d::UnitY());
    conv.add_joint_info(options.virtual_yaw_joint, JointType::kContinuous, {}, y_link, root->name,
                        Eigen::Vector3d::UnitZ());
    conv.out.num_virtual_joints = 3;
  }
  conv.out.tree.addSegment(KDL::Segment(root->name, root_joint, KDL::Frame::Identity(), conv.inertia_of(*root)),
                           hook);
  conv.out.frame_names.push_back(root->name);
  conv.add_children(*root);
  return std::move(conv.out);
}

}  // namespace concert::kinematics::detail
