#include "concert/sim/sim_hardware.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <fstream>
#include <sstream>

namespace concert::sim {
namespace {

using hardware::DriveCommand;
using hardware::DriveMode;
using hardware::HardwareError;
using hardware::HardwareState;
using world::load_world_file;
using world::WorldShape;

std::string fixture_path(const std::string& name) { return std::string(ROBOT_FIXTURES) + "/" + name; }

std::string read_fixture(const std::string& name) {
  std::ifstream in(fixture_path(name));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::size_t index_of(const std::vector<std::string>& names, const std::string& n) {
  return static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
}

TEST(SimHardware, MjcfHasActuatorLimitsFrictionWorldAndFreeBase) {
  World world = load_world_file(std::string(WORLD_FIXTURES) + "/world_wall.yaml");
  const std::string mjcf = urdf_to_mjcf(read_fixture("mobile_drill.urdf"), world, {});
  EXPECT_NE(mjcf.find("<freejoint"), std::string::npos);
  EXPECT_NE(mjcf.find("name=\"floor\""), std::string::npos);
  EXPECT_NE(mjcf.find("name=\"wall_front\""), std::string::npos);
  EXPECT_NE(mjcf.find("name=\"pillar\" type=\"cylinder\""), std::string::npos);
  EXPECT_NE(mjcf.find("joint=\"J1_A\" gaintype=\"fixed\""), std::string::npos);
  EXPECT_NE(mjcf.find("forcerange=\"-150 150\""), std::string::npos);
  EXPECT_NE(mjcf.find("frictionloss=\"0.1\""), std::string::npos);
  // A fixed-base arm has no free joint.
  EXPECT_EQ(urdf_to_mjcf(read_fixture("arm_drill.urdf"), world, {}).find("<freejoint"), std::string::npos);
}

// A link's own friction (a running sanding disc) decides its contacts: priority over the wall's.
TEST(SimHardware, LinkFrictionOverridesTheLinksGeomsWithPriority) {
  SimParams p;
  p.link_friction["drill"] = 0.02;
  const std::string mjcf = urdf_to_mjcf(read_fixture("arm_drill.urdf"), World{}, p);
  const auto drill = mjcf.find("name=\"drill_collision_0\"");
  ASSERT_NE(drill, std::string::npos);
  const std::string geom = mjcf.substr(drill, mjcf.find("/>", drill) - drill);
  EXPECT_NE(geom.find("friction=\"0.02 0.005 0.0001\" priority=\"1\""), std::string::npos) << geom;
  const auto link6 = mjcf.find("name=\"arm_link_6_collision_0\"");
  ASSERT_NE(link6, std::string::npos);
  const std::string other = mjcf.substr(link6, mjcf.find("/>", link6) - link6);
  EXPECT_NE(other.find("friction=\"0.5 0.005 0.0001\""), std::string::npos) << other;
  EXPECT_EQ(other.find("priority"), std::string::npos) << other;
  p.link_friction = {{"no_such_link", 0.1}};
  try {
    (void)urdf_to_mjcf(read_fixture("arm_drill.urdf"), World{}, p);
    ADD_FAILURE() << "an unknown link was accepted";
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_link"), std::string::npos) << e.what();
  }
  p.link_friction = {{"drill", -1.0}};
  EXPECT_THROW((void)urdf_to_mjcf(read_fixture("arm_drill.urdf"), World{}, p), HardwareError);
}

TEST(SimHardware, MobileBaseRestsOnTheFloorOnItsWheels) {
  SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, {});
  EXPECT_TRUE(sim.floating_base());
  EXPECT_EQ(sim.joint_names().size(), 14u);
  HardwareState s;
  for (int i = 0; i < 1000; ++i) {
    sim.step(0.001);
  }
  sim.read(s);
  EXPECT_NEAR(s.time, 1.0, 1e-9);
  // Wheel centre 0.3 m below the base frame, wheel radius 0.16 m.
  EXPECT_NEAR(sim.base_pose().translation().z(), 0.46, 0.01);
  EXPECT_NEAR(sim.base_pose().translation().x(), 0.0, 0.01);
  const Eigen::Vector3d support = sim.contact_force_on({"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"});
  const double weight = 9.81 * (80.0 + 4 * 7.0 + 2.0 + 3.6 + 3.0 + 2.5 + 1.5 + 1.2 + 0.8 + 2.0);
  EXPECT_NEAR(support.z(), weight, 0.02 * weight);
  // Arm holds its position under gravity (position-mode drives).
  const auto j2 = index_of(sim.joint_names(), "J2_A");
  EXPECT_NEAR(s.position[j2], 0.0, 0.01);
}

// An external force (a person's hand in services/collab's transport scenario) reaches the
// ground through the wheels, until cleared; an unknown link or a NaN is refused by name.
TEST(SimHardware, ExternalForceIsAppliedUntilCleared) {
  SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, {});
  const auto settle = [&sim] {
    for (int i = 0; i < 500; ++i) sim.step(0.001);
    return sim.contact_force_on({"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"}).z();
  };
  const double weight = settle();
  const Eigen::Isometry3d base = sim.base_pose();
  sim.set_external_force("mobile_base", Eigen::Vector3d(0, 0, -200.0), base.translation());
  EXPECT_NEAR(settle() - weight, 200.0, 4.0);
  sim.clear_external_force();
  EXPECT_NEAR(settle(), weight, 2.0);
  EXPECT_THROW(sim.set_external_force("no_such_link", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()),
               HardwareError);
  EXPECT_THROW(sim.set_external_force("mobile_base", Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Vector3d::Zero()),
               HardwareError);
}

// The simulated person: orders checked at once against the mounted robot, taken at the next
// step; its pull acts on the link held; a new world keeps the grip, a new robot makes it let go.
TEST(SimHardware, APersonPullsTheLinkItHoldsAndLetsGoWhenTheRobotIsSwapped) {
  SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, {});
  for (int i = 0; i < 200; ++i) sim.step(0.001);
  world::PersonOrder grip;
  try {
    sim.person(grip);
    FAIL() << "gripped a robot without a gripper";
  } catch (const HardwareError& e) {
    EXPECT_STREQ(e.what(), "sim: person: the mounted robot has no gripper to hold; name a link");
  }
  grip.link = "no_such_link";
  EXPECT_THROW(sim.person(grip), HardwareError);
  world::PersonOrder walk;
  walk.action = world::PersonOrder::Action::kWalk;
  walk.route = {{0.5, 0.0}};
  try {
    sim.person(walk);
    FAIL() << "walked holding nothing";
  } catch (const HardwareError& e) {
    EXPECT_STREQ(e.what(), "sim: person: walk: the person holds nothing (grip first)");
  }

  // Holding the base standing on its held wheels: the person walks 0.5 m off and pulls 150 N/m x
  // 0.5 m; the base stays (far below its friction), so the person has not arrived.
  grip.link = "mobile_base";
  EXPECT_EQ(sim.person(grip), "person: gripping mobile_base");
  EXPECT_EQ(sim.person(walk), "person: walking 0.50 m through 1 point");
  const Eigen::Vector3d start = sim.base_pose().translation();
  for (int i = 0; i < 3000; ++i) sim.step(0.001);
  world::PersonReport r = sim.person_report();
  EXPECT_EQ(r.orders, 2u);
  EXPECT_EQ(r.link, "mobile_base");
  EXPECT_EQ(r.phase, world::PersonPhase::kWalking) << world::to_string(r.phase) << " " << r.reason;
  EXPECT_NEAR(r.walked, 0.5, 1e-9);
  EXPECT_NEAR(r.pull.x(), 150.0 * 0.5, 2.0);
  EXPECT_NEAR(r.time, sim.time(), 1e-9);
  EXPECT_LT((sim.base_pose().translation() - start).head<2>().norm(), 0.005);

  // A new world: still held.
  World world;
  world.obstacles.push_back({.name = "crate", .size = {0.5, 0.5, 0.5}, .position = {3.0, 0.0, 0.25}});
  sim.set_world(world);
  ASSERT_TRUE(sim.switch_prepared());
  for (int i = 0; i < 10; ++i) sim.step(0.001);
  EXPECT_NEAR(sim.person_report().pull.x(), 150.0 * 0.5, 2.0);
  // Another robot: the person lets go, and its pull is gone.
  ASSERT_TRUE(sim.swap_model(read_fixture("mobile_sander.urdf")));
  ASSERT_TRUE(sim.switch_prepared());
  for (int i = 0; i < 10; ++i) sim.step(0.001);
  r = sim.person_report();
  EXPECT_EQ(r.phase, world::PersonPhase::kLetGo);
  EXPECT_EQ(r.reason, "hot swap: the robot changed");
  EXPECT_EQ(r.pull, Eigen::Vector3d::Zero());
}

// After the person let go, its report still says where the link it held is: a lift or a placing
// that follows is measured there.
TEST(SimHardware, APersonsReportFollowsTheLinkItLetGo) {
  SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, {});
  for (int i = 0; i < 200; ++i) sim.step(0.001);
  world::PersonOrder grip;
  grip.link = "arm_link_6";
  EXPECT_EQ(sim.person(grip), "person: gripping arm_link_6");
  for (int i = 0; i < 10; ++i) sim.step(0.001);
  world::PersonOrder release;
  release.action = world::PersonOrder::Action::kRelease;
  sim.person(release);
  for (int i = 0; i < 10; ++i) sim.step(0.001);
  const Eigen::Vector3d let_go_at = sim.person_report().tcp;
  EXPECT_LT((let_go_at - sim.link_pose("arm_link_6").translation()).norm(), 1e-9);
  // The arm bends 0.4 rad at its second joint.
  HardwareState s;
  sim.read(s);
  std::vector<DriveCommand> turn(sim.joint_names().size());
  for (std::size_t i = 0; i < turn.size(); ++i) {
    turn[i].mode = DriveMode::kPosition;
    turn[i].position = s.position[i] + (sim.joint_names()[i] == "J2_A" ? 0.4 : 0.0);
  }
  sim.write(turn);
  for (int i = 0; i < 1500; ++i) sim.step(0.001);
  const world::PersonReport r = sim.person_report();
  EXPECT_EQ(r.phase, world::PersonPhase::kLetGo);
  EXPECT_GT((r.tcp - let_go_at).norm(), 0.05) << "the arm did not move: the test proves nothing";
  EXPECT_LT((r.tcp - sim.link_pose("arm_link_6").translation()).norm(), 1e-9);
}

// Coulomb friction: a base standing on its held wheels stays where it is under a push well
// below mu N, and slides under one above it. At MuJoCo's soft friction it crept (0.9 mm/s under
// 150 N, 2.6 mm/s under 400 N, 1230 N of friction available), unseen by wheel odometry.
TEST(SimHardware, HeldWheelsStandUnderAPushBelowFrictionAndSlideAboveIt) {
  const double weight = 9.81 * (80.0 + 4 * 7.0 + 2.0 + 3.6 + 3.0 + 2.5 + 1.5 + 1.2 + 0.8 + 2.0);
  const auto pushed = [&](const Eigen::Vector3d& push) {
    SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, {});
    for (int i = 0; i < 500; ++i) sim.step(0.001);
    HardwareState s;
    sim.read(s);
    std::vector<DriveCommand> hold(sim.joint_names().size());
    for (std::size_t i = 0; i < hold.size(); ++i) {
      hold[i].mode = DriveMode::kPosition;
      hold[i].position = s.position[i];
    }
    sim.write(hold);
    // At the floor's height: the push slides the base rather than tipping it over its wheels.
    Eigen::Vector3d at = sim.base_pose().translation();
    at.z() = 0.0;
    sim.set_external_force("mobile_base", push, at);
    for (int i = 0; i < 1000; ++i) sim.step(0.001);  // the wheels' drives and contacts take the load
    const Eigen::Vector3d loaded = sim.base_pose().translation();
    for (int i = 0; i < 2000; ++i) sim.step(0.001);
    return std::pair{loaded, sim.base_pose().translation()};
  };
  const Eigen::Vector3d start = [] {
    SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, {});
    for (int i = 0; i < 500; ++i) sim.step(0.001);
    return sim.base_pose().translation();
  }();
  for (const Eigen::Vector3d& push : {Eigen::Vector3d(0.0, 400.0, 0.0), Eigen::Vector3d(400.0, 0.0, 0.0),
                                      Eigen::Vector3d(-250.0, 250.0, 0.0)}) {
    const auto [loaded, later] = pushed(push);
    EXPECT_LT((later - loaded).norm(), 0.1e-3) << "a push of " << push.transpose() << " N made the base creep";
    // The wheels' drives give a little under the load, no more (3000 N m/rad at 0.16 m: 1 mm).
    EXPECT_LT((loaded - start).head<2>().norm(), 2e-3) << push.transpose();
  }
  const auto [loaded, later] = pushed(Eigen::Vector3d(0.0, 1.5 * weight, 0.0));
  EXPECT_GT(later.y() - loaded.y(), 0.5) << "a push above mu N (mu 1.0) did not slide the base";
}

TEST(SimHardware, TorqueSaturatesAtTheUrdfEffortLimit) {
  SimHardware sim(read_fixture("arm_drill.urdf"), World{}, {});
  const auto j1 = index_of(sim.joint_names(), "J1_A");
  std::vector<DriveCommand> cmd(sim.joint_names().size());
  HardwareState s;
  sim.read(s);
  for (std::size_t i = 0; i < cmd.size(); ++i) {
    cmd[i].position = s.position[i];
  }
  cmd[j1].mode = DriveMode::kEffort;
  cmd[j1].effort = 1000.0;  // limit is 150 Nm
  sim.write(cmd);
  sim.step(0.001);
  sim.step(0.001);
  sim.read(s);
  EXPECT_NEAR(s.effort[j1], 150.0, 1e-9);
  EXPECT_GT(s.velocity[j1], 0.0);
  cmd.pop_back();
  EXPECT_THROW(sim.write(cmd), HardwareError);
}

TEST(SimHardware, HotSwapKeepsStateAndBumpsGeneration) {
  SimParams params;
  params.initial_positions = {{"J2_A", 0.2}};
  SimHardware sim(read_fixture("mobile_drill.urdf"), World{}, params);
  for (int i = 0; i < 200; ++i) {
    sim.step(0.001);
  }
  const auto gen = sim.generation();
  EXPECT_FALSE(sim.swap_model(read_fixture("mobile_drill.urdf")));  // the same robot again: no change
  EXPECT_FALSE(sim.switch_prepared());
  EXPECT_EQ(sim.generation(), gen);
  const double z = sim.base_pose().translation().z();
  EXPECT_TRUE(sim.swap_model(read_fixture("mobile_sander.urdf")));
  // Prepared off the control thread: announced at once, switched at the next cycle boundary.
  EXPECT_EQ(sim.mounted().generation, gen + 1);
  EXPECT_EQ(sim.generation(), gen);
  EXPECT_TRUE(sim.switch_prepared());
  EXPECT_EQ(sim.generation(), gen + 1);
  EXPECT_NEAR(sim.time(), 0.2, 1e-9);
  HardwareState s;
  sim.read(s);
  EXPECT_NEAR(s.position[index_of(sim.joint_names(), "J2_A")], 0.2, 0.01);
  EXPECT_NEAR(sim.base_pose().translation().z(), z, 1e-6);
  EXPECT_NO_THROW((void)sim.link_pose("sander"));
  EXPECT_THROW((void)sim.link_pose("drill"), HardwareError);
  sim.swap_model(read_fixture("mobile_three_legs.urdf"));
  EXPECT_EQ(sim.mounted().joint_names.size(), 12u);
  sim.switch_prepared();
  EXPECT_EQ(sim.joint_names().size(), 12u);
  EXPECT_EQ(index_of(sim.joint_names(), "J_wheel_rr"), sim.joint_names().size());
}

TEST(SimHardware, WorldChangeKeepsTheRobot) {
  SimHardware sim(read_fixture("arm_drill.urdf"), World{}, {});
  const auto gen = sim.generation();
  World world;
  world.obstacles.push_back(
      {.name = "crate", .size = {0.5, 0.5, 0.5}, .position = {2.0, 0.0, 0.25}});
  sim.set_world(world);
  EXPECT_TRUE(sim.switch_prepared());
  EXPECT_EQ(sim.generation(), gen);
  EXPECT_NE(sim.mjcf().find("name=\"crate\""), std::string::npos);
}

TEST(SimHardware, BadUrdfIsAClearError) {
  EXPECT_THROW(SimHardware("<robot name='x'>", World{}, {}), std::exception);
}

}  // namespace
}  // namespace concert::sim
