// The drive budget against rigid-body mechanics worked by hand: a 40 kg base on four wheels
// (r 0.1 m, 1 kg, at (+-0.5, +-0.4) m) carrying a one-joint arm, a 5 kg point mass 0.8 m out
// along x from a vertical joint at the yaw axis.
//   * yaw acceleration alpha: the arm joint holds (m L^2) alpha = 3.2 alpha N m;
//   * leftward acceleration ay: the arm joint holds m L ay = 4 ay N m; forward: nothing;
//   * forward acceleration ax: the wheels push 49 kg, each a quarter, at 0.1 m.
#include "concert/model/drive_budget.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace concert::model {
namespace {

std::string urdf(const std::string& arm_axis) {
  std::string u = R"(<?xml version="1.0"?>
<robot name="budget">
  <link name="base_link">
    <inertial><origin xyz="0 0 0"/><mass value="40"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="2"/></inertial>
  </link>
  <link name="arm"><inertial><origin xyz="0.8 0 0"/><mass value="5"/><inertia ixx="1e-9" ixy="0" ixz="0" iyy="1e-9" iyz="0" izz="1e-9"/></inertial></link>
  <link name="tcp"/>
  <joint name="J1" type="revolute"><parent link="base_link"/><child link="arm"/><origin xyz="0 0 0.2"/><axis xyz=")" +
                  arm_axis + R"("/>
    <limit lower="-3" upper="3" effort="30" velocity="1"/></joint>
  <joint name="fixed_tcp" type="fixed"><parent link="arm"/><child link="tcp"/><origin xyz="0.8 0 0"/></joint>
)";
  const char* legs[4] = {"FL", "FR", "RL", "RR"};
  const double xy[4][2] = {{0.5, 0.4}, {0.5, -0.4}, {-0.5, 0.4}, {-0.5, -0.4}};
  for (int k = 0; k < 4; ++k) {
    const std::string n = legs[k];
    u += "  <link name=\"wheel_" + n +
         "\"><inertial><origin xyz=\"0 0 0\"/><mass value=\"1\"/><inertia ixx=\"1e-3\" ixy=\"0\" "
         "ixz=\"0\" iyy=\"1e-3\" iyz=\"0\" izz=\"1e-3\"/></inertial>"
         "<collision><origin xyz=\"0 0 0\" rpy=\"1.5707963267948966 0 0\"/><geometry><cylinder "
         "radius=\"0.1\" length=\"0.05\"/></geometry></collision></link>\n"
         "  <joint name=\"W_" + n + "\" type=\"continuous\"><parent link=\"base_link\"/><child link=\"wheel_" + n +
         "\"/><origin xyz=\"" + std::to_string(xy[k][0]) + " " + std::to_string(xy[k][1]) +
         " -0.1\"/><axis xyz=\"0 1 0\"/><limit effort=\"10\" velocity=\"20\"/></joint>\n";
  }
  return u + "</robot>";
}

ModelDescription robot(const std::string& arm_axis = "0 0 1") {
  ModelDescription d;
  d.version = 3;
  d.urdf = urdf(arm_axis);
  d.srdf = "<robot name=\"budget\"/>";
  d.joints = {{"J1", "A", -3, 3, 1, 30, 10}};
  d.chains = {{"A", ChainRole::kArm, "base_link", "tcp", {"J1"}}};
  d.end_effectors = {{"drill", "A", "tcp", "concert_drill", EndEffectorKind::kDrill}};
  for (const std::string n : {"FL", "FR", "RL", "RR"}) {
    d.joints.push_back({"W_" + n, n, -std::numeric_limits<double>::infinity(),
                        std::numeric_limits<double>::infinity(), 20, 10, 5});
    d.chains.push_back({n, ChainRole::kLeg, "base_link", "wheel_" + n, {"W_" + n}});
    d.end_effectors.push_back({"wheel_" + n, n, "wheel_" + n, "concert_wheel", EndEffectorKind::kWheel});
  }
  return d;
}

TEST(DriveBudget, ABaseTurnIsLimitedByTheArmsYawInertiaOnItsFirstJoint) {
  const DriveBudget budget(*RobotModel::build(robot()));
  ASSERT_EQ(budget.joint_names().size(), 5u);
  const Eigen::VectorXd q = budget.neutral_posture();
  // 10 N m continuous over 3.2 kg m^2 x 10 rad/s^2.
  const BaseBudget b = budget.base_motion(q, {0.0, 0.0, 10.0, 0.0}, 1.0);
  EXPECT_TRUE(b.holds_static);
  EXPECT_EQ(b.joint, "J1");
  EXPECT_NEAR(b.scale, 10.0 / 32.0, 1e-6);
  EXPECT_NEAR(b.dynamic_load, 3.2, 1e-6);
  // Half the continuous torque, half the acceleration.
  EXPECT_NEAR(budget.base_motion(q, {0.0, 0.0, 10.0, 0.0}, 0.5).scale, 5.0 / 32.0, 1e-6);
  // Within what the arm holds: the whole request. A turn's centrifugal load pulls the mass
  // through the vertical joint's axis: no torque.
  const BaseBudget gentle = budget.base_motion(q, {0.0, 0.0, 3.0, 1.0}, 1.0);
  EXPECT_DOUBLE_EQ(gentle.scale, 1.0);
  EXPECT_TRUE(gentle.joint.empty());
}

TEST(DriveBudget, SidewaysTheArmForwardTheWheels) {
  const DriveBudget budget(*RobotModel::build(robot()));
  const Eigen::VectorXd q = budget.neutral_posture();
  // Leftward 3 m/s^2: 5 kg x 0.8 m x 3 = 12 N m on J1; the wheels push 49 kg x 3 / 4 = 36.75 N
  // each at 0.1 m = 3.7 N m, within 5.
  const BaseBudget left = budget.base_motion(q, {0.0, 3.0, 0.0, 0.0}, 1.0);
  EXPECT_EQ(left.joint, "J1");
  EXPECT_NEAR(left.scale, 10.0 / 12.0, 1e-6);
  // Forward 5 m/s^2: J1 holds nothing; each wheel 49 x 5 / 4 x 0.1 = 6.125 N m of 5.
  const BaseBudget forward = budget.base_motion(q, {5.0, 0.0, 0.0, 0.0}, 1.0);
  EXPECT_EQ(forward.joint.rfind("W_", 0), 0u) << forward.joint;
  EXPECT_NEAR(forward.scale, 5.0 / 6.125, 1e-6);
  // With the arm turned to point left, the roles swap: forward loads J1 (4 N m per m/s^2).
  Eigen::VectorXd turned = q;
  const auto& names = budget.joint_names();
  turned(std::find(names.begin(), names.end(), "J1") - names.begin()) = M_PI / 2;
  const BaseBudget forward_turned = budget.base_motion(turned, {3.0, 0.0, 0.0, 0.0}, 1.0);
  EXPECT_EQ(forward_turned.joint, "J1");
  EXPECT_NEAR(forward_turned.scale, 10.0 / 12.0, 1e-6);
}

TEST(DriveBudget, APostureThatOverloadsAJointAloneAllowsNoAcceleration) {
  // J1 about y: the 5 kg at 0.8 m hangs 39.24 N m on a 10 N m drive.
  const DriveBudget budget(*RobotModel::build(robot("0 1 0")));
  const BaseBudget b = budget.base_motion(budget.neutral_posture(), {0.1, 0.0, 0.1, 0.0}, 1.0);
  EXPECT_FALSE(b.holds_static);
  EXPECT_EQ(b.scale, 0.0);
  EXPECT_EQ(b.joint, "J1");
  EXPECT_NEAR(b.static_load, 5.0 * 9.81 * 0.8 / 10.0, 1e-3);
}

TEST(DriveBudget, BadQueriesAreRefusedNamingTheModel) {
  const DriveBudget budget(*RobotModel::build(robot()));
  try {
    (void)budget.base_motion(Eigen::VectorXd::Zero(2), {}, 1.0);
    FAIL() << "a posture of 2 joints for 5 was accepted";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("model version 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2 joint positions for 5"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)budget.base_motion(budget.neutral_posture(), {}, 0.0), ModelError);
  EXPECT_THROW((void)budget.base_motion(budget.neutral_posture(), {}, 1.5), ModelError);
}

}  // namespace
}  // namespace concert::model
