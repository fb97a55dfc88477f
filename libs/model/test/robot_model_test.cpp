// The parsed model on a small hand-written robot: a base with one steering + wheel leg and a
// two-joint arm carrying a drill with a camera.
#include "concert/model/robot_model.hpp"
#include "concert/model/same_arm.hpp"

#include <gtest/gtest.h>

namespace concert::model {
namespace {

const char* kUrdf = R"(<?xml version="1.0"?>
<robot name="mini">
  <link name="base_link">
    <inertial><origin xyz="0 0 0"/><mass value="20"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><origin xyz="0 0 0"/><geometry><box size="1 0.6 0.2"/></geometry></collision>
  </link>
  <link name="L_1_A"><inertial><origin xyz="0 0 0"/><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="L_2_A">
    <inertial><origin xyz="0 0 0"/><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision><origin xyz="0 0 0"/><geometry><mesh filename="wheel.stl"/></geometry></collision>
  </link>
  <link name="wheel_A"/>
  <link name="L_1_B"><inertial><origin xyz="0 0 0"/><mass value="3"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="L_2_B">
    <inertial><origin xyz="0 0 0.2"/><mass value="3"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
  </link>
  <link name="tcp_B"/>
  <link name="camera_B"/>
  <joint name="J1_A" type="revolute"><parent link="base_link"/><child link="L_1_A"/><origin xyz="0.4 0.3 -0.1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="30" velocity="2"/></joint>
  <joint name="J2_A" type="continuous"><parent link="L_1_A"/><child link="L_2_A"/><origin xyz="0 0 -0.2" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit effort="24" velocity="13"/></joint>
  <joint name="fixed_wheel_A" type="fixed"><parent link="L_2_A"/><child link="wheel_A"/></joint>
  <joint name="J1_B" type="revolute"><parent link="base_link"/><child link="L_1_B"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="200" velocity="1"/></joint>
  <joint name="J2_B" type="revolute"><parent link="L_1_B"/><child link="L_2_B"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="200" velocity="1"/></joint>
  <joint name="fixed_tcp_B" type="fixed"><parent link="L_2_B"/><child link="tcp_B"/><origin xyz="0 0 0.4"/></joint>
  <joint name="fixed_camera_B" type="fixed"><parent link="L_2_B"/><child link="camera_B"/><origin xyz="0.1 0 0.3"/></joint>
</robot>)";

const char* kSrdf = R"(<?xml version="1.0"?>
<robot name="mini">
  <disable_collisions link1="L_1_B" link2="L_2_B" reason="Adjacent"/>
</robot>)";

ModelDescription mini(uint64_t version = 7) {
  ModelDescription d;
  d.version = version;
  d.urdf = kUrdf;
  d.srdf = kSrdf;
  d.joints = {{"J1_A", "A", -3, 3, 2, 30, 20},
              {"J2_A", "A", -std::numeric_limits<double>::infinity(),
               std::numeric_limits<double>::infinity(), 13, 24, 17.5},
              {"J1_B", "B", -2, 2, 1, 200, 160},
              {"J2_B", "B", -2, 2, 1, 200, 160}};
  // The wheel comes first, as in the paper's robot: selection never goes by position.
  d.chains = {{"A", ChainRole::kLeg, "base_link", "wheel_A", {"J1_A", "J2_A"}},
              {"B", ChainRole::kArm, "base_link", "tcp_B", {"J1_B", "J2_B"}}};
  d.end_effectors = {{"wheel_A", "A", "wheel_A", "concert_wheel", EndEffectorKind::kWheel},
                     {"drill_B", "B", "tcp_B", "concert_drill", EndEffectorKind::kDrill}};
  d.sensor_frames = {
      {"camera_B", SensorKind::kCamera, "camera_B", "B", "drill_B", "concert_drill"}};
  return d;
}

TEST(RobotModel, SelectsByRoleAndKindNeverByPosition) {
  const auto m = RobotModel::build(mini());
  EXPECT_EQ(m->version(), 7u);
  EXPECT_EQ(m->tool().name, "drill_B");
  EXPECT_EQ(m->tool(EndEffectorKind::kDrill).frame, "tcp_B");
  EXPECT_EQ(m->arm().name, "B");
  ASSERT_EQ(m->chains(ChainRole::kLeg).size(), 1u);
  EXPECT_EQ(m->chains(ChainRole::kLeg).front()->name, "A");
  EXPECT_EQ(m->end_effectors(EndEffectorKind::kWheel).size(), 1u);
  EXPECT_EQ(m->sensor(m->tool(), SensorKind::kCamera).frame, "camera_B");
  EXPECT_EQ(m->sensor_of(m->end_effector("wheel_A"), SensorKind::kCamera), nullptr);
  EXPECT_EQ(m->sensor_frames(SensorKind::kCamera).size(), 1u);
  EXPECT_DOUBLE_EQ(m->limits().at("J2_B").continuous_torque, 160.0);
}

TEST(RobotModel, ErrorsListTheCandidates) {
  const auto m = RobotModel::build(mini());
  try {
    (void)m->tool(EndEffectorKind::kGripper);
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_STREQ(e.what(),
                 "model version 7: no gripper tool on an arm (end-effectors: wheel_A (wheel, chain "
                 "A), drill_B (drill, chain B))");
  }
  try {
    (void)m->sensor(m->end_effector("wheel_A"), SensorKind::kLidar);
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_STREQ(e.what(),
                 "model version 7: end-effector 'wheel_A' has no lidar sensor (it carries: none)");
  }
  EXPECT_THROW((void)m->chain("C"), ModelError);
  EXPECT_THROW((void)m->end_effector("gripper_B"), ModelError);

  ModelDescription no_arm = mini();
  no_arm.chains[1].role = ChainRole::kOther;
  const auto n = RobotModel::build(no_arm);
  try {
    (void)n->arm();
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_STREQ(e.what(), "model version 7: no arm (chains: A (leg), B (other))");
  }
  EXPECT_THROW((void)n->tool(), ModelError);
}

// A new version whose arm is the same (a leg changed) keeps the tool where it was at the joints
// measured now; a longer link, a turned tool or a frame the model lacks does not.
TEST(SameArm, ANewVersionKeepsTheToolWhereItWasOnlyWithTheSameArm) {
  const auto before = RobotModel::build(mini(7));
  ModelDescription leg_swapped = mini(8);
  const std::string wheel_origin = R"(<origin xyz="0 0 -0.2" rpy="1.5707963267948966 0 0"/>)";
  leg_swapped.urdf.replace(leg_swapped.urdf.find(wheel_origin), wheel_origin.size(),
                           R"(<origin xyz="0 0 -0.3" rpy="1.5707963267948966 0 0"/>)");
  const auto same = RobotModel::build(leg_swapped);
  const std::vector<std::string> names{"J1_B", "J2_B", "J1_A"};
  const std::vector<double> q{0.4, -0.7, 1.0};
  EXPECT_TRUE(same_frame_pose(*before, *same, "tcp_B", names, q));

  // The tool 6 mm further out: beyond the 5 mm tolerance, within a 1 cm one.
  ModelDescription longer = mini(8);
  const std::string tcp = R"(<child link="tcp_B"/><origin xyz="0 0 0.4"/>)";
  longer.urdf.replace(longer.urdf.find(tcp), tcp.size(), R"(<child link="tcp_B"/><origin xyz="0 0 0.406"/>)");
  EXPECT_FALSE(same_frame_pose(*before, *RobotModel::build(longer), "tcp_B", names, q));
  EXPECT_TRUE(same_frame_pose(*before, *RobotModel::build(longer), "tcp_B", names, q, 0.01));

  // The tool turned 0.02 rad about its axis, in place: beyond the 0.01 rad tolerance.
  ModelDescription turned = mini(8);
  turned.urdf.replace(turned.urdf.find(tcp), tcp.size(),
                      R"(<child link="tcp_B"/><origin xyz="0 0 0.4" rpy="0 0 0.02"/>)");
  EXPECT_FALSE(same_frame_pose(*before, *RobotModel::build(turned), "tcp_B", names, q));

  EXPECT_FALSE(same_frame_pose(*before, *same, "no_such_frame", names, q));
  EXPECT_FALSE(same_frame_pose(*before, *same, "tcp_B", names, {0.4}));  // a malformed state
}

TEST(RobotModel, LegsGiveSteeringWheelJointsAndTheWheelRadius) {
  ModelDescription d = mini();
  // The wheel link's collision: a cylinder about the wheel axis (its z), beside a mesh.
  const std::string mesh =
      R"(<collision><origin xyz="0 0 0"/><geometry><mesh filename="wheel.stl"/></geometry></collision>)";
  d.urdf.replace(
      d.urdf.find(mesh), mesh.size(),
      mesh +
          R"(<collision><origin xyz="0 0 0"/><geometry><cylinder radius="0.2" length="0.1"/></geometry></collision>)");
  const auto m = RobotModel::build(d);
  const std::vector<Leg> legs = m->legs();
  ASSERT_EQ(legs.size(), 1u);
  EXPECT_EQ(legs[0].chain->name, "A");
  EXPECT_EQ(legs[0].steering_joint, "J1_A");
  EXPECT_EQ(legs[0].wheel_joint, "J2_A");
  EXPECT_EQ(legs[0].wheel_frame, "wheel_A");
  EXPECT_DOUBLE_EQ(legs[0].wheel_radius, 0.2);
  // Without the cylinder there is no radius: an error naming the leg.
  EXPECT_THROW((void)RobotModel::build(mini())->legs(), ModelError);
}

TEST(RobotModel, GeometryChainsOfLinksAndSrdfPairs) {
  const auto m = RobotModel::build(mini());
  const int l2b = m->link_index("L_2_B");
  ASSERT_GE(l2b, 0);
  const Link& link = m->links()[static_cast<std::size_t>(l2b)];
  EXPECT_EQ(link.chain, "B");
  EXPECT_TRUE(link.moving);
  ASSERT_EQ(link.shapes.size(), 1u);
  EXPECT_EQ(link.shapes[0].type, CollisionShape::Type::kCylinder);
  EXPECT_DOUBLE_EQ(link.shapes[0].size.z(), 0.4);
  EXPECT_EQ(m->links()[static_cast<std::size_t>(m->link_index("L_2_A"))].shapes[0].type,
            CollisionShape::Type::kMesh);
  EXPECT_EQ(m->links()[static_cast<std::size_t>(m->link_index("camera_B"))].chain, "B");
  EXPECT_EQ(m->links()[0].chain, "");
  ASSERT_EQ(m->disabled_pairs().size(), 1u);
  EXPECT_EQ(m->disabled_pairs()[0], std::make_pair(m->link_index("L_1_B"), l2b));
  EXPECT_EQ(m->kinematics().dof(), 4);
  EXPECT_EQ(m->planar_kinematics().dof(), 7);
  EXPECT_EQ(m->planar_kinematics().joint_names()[0], "base_x");
}

TEST(RobotModel, TheSrdfHomeIsTheHomingPosture) {
  EXPECT_TRUE(RobotModel::build(mini())->home().empty());
  EXPECT_EQ(RobotModel::build(mini())->home("J2_B"), std::nullopt);
  ModelDescription homed = mini();
  homed.srdf = R"(<robot name="mini">
  <disable_collisions link1="L_1_B" link2="L_2_B" reason="Adjacent"/>
  <group_state name="ready" group="chains"><joint name="J2_B" value="-1.5"/></group_state>
  <group_state name="home" group="chains"><joint name="J1_B" value="0"/><joint name="J2_B" value="0.75"/></group_state>
</robot>)";
  const auto m = RobotModel::build(homed);
  EXPECT_EQ(m->home().size(), 2u);
  EXPECT_EQ(m->home("J2_B"), 0.75);  // the state called home, not the first one
  EXPECT_EQ(m->home("J1_A"), std::nullopt);
  EXPECT_EQ(m->disabled_pairs().size(), 1u);
  // As a posture: the named joints at their values, the others at 0, each within its limits
  // (J2_B's 2.5 onto its upper limit 2; the continuous J2_A's -4 onto -pi).
  const Eigen::VectorXd q = m->home_posture();
  const kinematics::Model& kin = m->kinematics();
  ASSERT_EQ(q.size(), kin.dof());
  EXPECT_EQ(q[kin.joint_index_or_throw("J2_B")], 0.75);
  EXPECT_EQ(q[kin.joint_index_or_throw("J1_A")], 0.0);
  ModelDescription beyond = mini();
  beyond.srdf = R"(<robot name="mini">
  <group_state name="home" group="chains"><joint name="J2_B" value="2.5"/><joint name="J2_A" value="-4"/><joint name="J1_B" value="-0.5"/></group_state>
</robot>)";
  const auto b = RobotModel::build(beyond);
  const Eigen::VectorXd qb = b->home_posture();
  EXPECT_EQ(qb[kin.joint_index_or_throw("J2_B")], 2.0);
  EXPECT_DOUBLE_EQ(qb[kin.joint_index_or_throw("J2_A")], -M_PI);
  EXPECT_EQ(qb[kin.joint_index_or_throw("J1_B")], -0.5);

  ModelDescription bad = mini();
  bad.srdf = R"(<robot><group_state name="home"><joint name="J2_B" value="up"/></group_state></robot>)";
  try {
    RobotModel::build(bad);
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_STREQ(e.what(), "model version 7: SRDF home: joint 'J2_B' has no numeric value");
  }
}

TEST(RobotModel, RejectsDescriptionsThatDisagreeWithTheUrdf) {
  ModelDescription ghost = mini();
  ghost.joints.push_back({"J3_B", "B", -1, 1, 1, 10, 10});
  EXPECT_THROW(RobotModel::build(ghost), ModelError);
  ModelDescription missing_row = mini();
  missing_row.joints.pop_back();
  EXPECT_THROW(RobotModel::build(missing_row), ModelError);
  ModelDescription bad_frame = mini();
  bad_frame.end_effectors[1].frame = "tcp_C";
  try {
    RobotModel::build(bad_frame);
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_STREQ(e.what(), "model version 7: end-effector drill_B: no link 'tcp_C' in the URDF");
  }
  ModelDescription bad_srdf = mini();
  bad_srdf.srdf = "<robot><disable_collisions link1=\"L_1_B\" link2=\"nowhere\"/></robot>";
  EXPECT_THROW(RobotModel::build(bad_srdf), ModelError);
  ModelDescription bad_urdf = mini();
  bad_urdf.urdf = "<robot";
  EXPECT_THROW(RobotModel::build(bad_urdf), ModelError);
}

}  // namespace
}  // namespace concert::model
