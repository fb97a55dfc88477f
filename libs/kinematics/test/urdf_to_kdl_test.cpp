#include "urdf_to_kdl.hpp"

#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include <cmath>

namespace concert::kinematics::detail {
namespace {

TEST(UrdfToKdl, InertiaIsRotatedIntoTheLinkFrame) {
  urdf::Inertial inertial;
  inertial.mass = 2.0;
  inertial.origin.position = urdf::Vector3(0.1, 0.2, 0.3);
  inertial.origin.rotation.setFromRPY(0.0, 0.0, M_PI / 2);
  inertial.ixx = 1.0;
  inertial.iyy = 2.0;
  inertial.izz = 3.0;
  const KDL::RigidBodyInertia kdl = to_kdl(inertial);
  EXPECT_DOUBLE_EQ(kdl.getMass(), 2.0);
  EXPECT_NEAR(kdl.getCOG().x(), 0.1, 1e-12);
  EXPECT_NEAR(kdl.getCOG().z(), 0.3, 1e-12);
  // KDL stores inertia about the link origin: rotated COM inertia (xx<->yy) + m (|c|^2 I - c c^T).
  const KDL::RotationalInertia about_origin = kdl.getRotationalInertia();
  const double c2 = 0.01 + 0.04 + 0.09;
  EXPECT_NEAR(about_origin.data[0], 2.0 + 2.0 * (c2 - 0.01), 1e-9);
  EXPECT_NEAR(about_origin.data[4], 1.0 + 2.0 * (c2 - 0.04), 1e-9);
  EXPECT_NEAR(about_origin.data[8], 3.0 + 2.0 * (c2 - 0.09), 1e-9);
}

const char* kFloating = R"(<robot name="f">
  <link name="a"/><link name="b"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="free" type="floating"><parent link="a"/><child link="b"/></joint>
</robot>)";

TEST(UrdfToKdl, RejectsFloatingJointsByName) {
  const auto parsed = urdf::parseURDF(kFloating);
  ASSERT_TRUE(parsed);
  try {
    (void)urdf_to_kdl(*parsed, {});
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("'free'"), std::string::npos);
  }
}

const char* kChain = R"(<robot name="c">
  <link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <link name="b"/><link name="c"/><link name="d"/>
  <joint name="ab" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 2"/>
    <origin xyz="1 0 0" rpy="0 0 0"/><limit lower="-1" upper="1" effort="5" velocity="2"/></joint>
  <joint name="bc" type="fixed"><parent link="b"/><child link="c"/></joint>
  <joint name="cd" type="prismatic"><parent link="c"/><child link="d"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" effort="100" velocity="0.1"/></joint>
</robot>)";

TEST(UrdfToKdl, SegmentsJointsAndFrames) {
  const auto parsed = urdf::parseURDF(kChain);
  ASSERT_TRUE(parsed);
  const KdlConversion out = urdf_to_kdl(*parsed, {});
  EXPECT_EQ(out.tree.getNrOfJoints(), 2u);
  EXPECT_EQ(out.tree.getNrOfSegments(), 4u);  // a (fixed to world), b, c, d
  EXPECT_EQ(out.joint_names, (std::vector<std::string>{"ab", "cd"}));
  EXPECT_EQ(out.joint_types[1], JointType::kPrismatic);
  EXPECT_EQ(out.frame_names, (std::vector<std::string>{"world", "a", "b", "c", "d"}));
  EXPECT_TRUE(out.joint_axes[0].isApprox(Eigen::Vector3d::UnitZ()));  // normalized
  EXPECT_DOUBLE_EQ(out.total_mass, 1.0);
  EXPECT_EQ(out.num_virtual_joints, 0);
}

}  // namespace
}  // namespace concert::kinematics::detail
