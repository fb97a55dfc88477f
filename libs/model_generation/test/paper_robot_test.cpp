// The paper's robot (mobile base, four steering + wheel legs, 6-DoF arm with a drill) through
// model generation and the parsed model, with both module databases: the project's
// (data/module_db, continuous torques from the paper's Table 1) and the public
// concert_resources (peak torques only).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <cstdio>
#include <random>
#include <filesystem>

#include "concert/collision/link_shapes.hpp"
#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/simbus/random_robot.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::model_generation {
namespace {

namespace fs = std::filesystem;
using model::ChainRole;
using model::EndEffectorKind;
using model::SensorKind;

struct Database {
  fs::path dir;
  fs::path assembly;
};

GeneratedModel generate(const Database& where) {
  static std::map<std::string, module_db::ModuleDatabase> dbs;
  auto [it, fresh] = dbs.try_emplace(where.dir.string());
  if (fresh) it->second = module_db::load_module_database(where.dir);
  const topology::EscCatalog catalog = topology::EscCatalog::load(where.dir);
  const topology::ModuleTree tree =
      simbus::tree_from_assembly(simbus::load_assembly(where.assembly), catalog);
  GeneratedModel m = ModelGenerator(it->second).generate(tree);
  m.version = 1;
  return m;
}

class PaperRobot : public ::testing::TestWithParam<Database> {};

TEST_P(PaperRobot, SelectsTheDrillAsTheToolAndTheLegsByRole) {
  const GeneratedModel generated = generate(GetParam());
  const auto m = model::RobotModel::build(generated.description());
  // The first end-effector of the list is a wheel: selection by role must not care.
  ASSERT_FALSE(m->end_effectors().empty());
  EXPECT_EQ(m->end_effectors().front().kind, EndEffectorKind::kWheel);
  EXPECT_EQ(m->tool().kind, EndEffectorKind::kDrill);
  EXPECT_EQ(m->tool().name, "drill_E");
  EXPECT_EQ(m->tool().frame, "tcp_E");
  EXPECT_EQ(&m->tool(EndEffectorKind::kDrill), &m->tool());
  EXPECT_EQ(m->end_effectors(EndEffectorKind::kWheel).size(), 4u);
  EXPECT_EQ(m->arm().name, "E");
  EXPECT_EQ(m->arm().joints.size(), 6u);
  EXPECT_EQ(m->chains(ChainRole::kLeg).size(), 4u);
  const std::vector<model::Leg> legs = m->legs();
  ASSERT_EQ(legs.size(), 4u);
  for (const model::Leg& leg : legs) {
    EXPECT_EQ(leg.steering_joint, "J1_" + leg.chain->name);
    EXPECT_EQ(leg.wheel_joint, "J2_" + leg.chain->name);
    EXPECT_EQ(leg.wheel_frame, "wheel_" + leg.chain->name);
    EXPECT_GT(leg.wheel_radius, 0.1);
    EXPECT_LT(leg.wheel_radius, 0.3);
  }
  EXPECT_EQ(m->limits().size(), 6u + 8u);
  for (const model::JointLimits& j : m->limits().rows()) {
    EXPECT_GT(j.peak_torque, 0.0) << j.name;
    EXPECT_LE(j.continuous_torque, j.peak_torque) << j.name;
  }
}

TEST(PaperRobotProjectDatabase, LimitsTableKeepsPeakAndContinuousTorqueApart) {
  const auto m = model::RobotModel::build(
      generate({fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db",
                fs::path(CONCERT_SOURCE_DIR) / "deploy/demo/drill_robot.yaml"})
          .description());
  // Elbow A (Large A actuator, paper Table 1): 460 N m peak, 160 N m continuous.
  const model::JointLimits& j2 = m->limits().at("J2_E");
  EXPECT_DOUBLE_EQ(j2.peak_torque, 460.0);
  EXPECT_DOUBLE_EQ(j2.continuous_torque, 160.0);
  for (const model::JointLimits& j : m->limits().rows())
    EXPECT_LT(j.continuous_torque, j.peak_torque) << j.name;
  // The drill's camera is a sensor frame of the tool.
  const model::SensorFrame& camera = m->sensor(m->tool(), SensorKind::kCamera);
  EXPECT_EQ(camera.frame, "camera_E");
  EXPECT_EQ(camera.module_key, "concert_drill");
  EXPECT_TRUE(m->kinematics().has_frame(camera.frame));
}

TEST(PaperRobotProjectDatabase, MobilePlatformCarriesTheRealPlatformsSensors) {
  const auto m = model::RobotModel::build(
      generate({fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db",
                fs::path(CONCERT_SOURCE_DIR) / "deploy/demo/drill_robot.yaml"})
          .description());
  // mobile_platform_sensors.yaml: two lidars, eight ultrasound sensors, front and back
  // RGB-D cameras; plus the platform's IMU and the drill's camera.
  EXPECT_EQ(m->sensor_frames(SensorKind::kLidar).size(), 2u);
  EXPECT_EQ(m->sensor_frames(SensorKind::kSonar).size(), 8u);
  EXPECT_EQ(m->sensor_frames(SensorKind::kCamera).size(), 3u);
  EXPECT_EQ(m->sensor_frames(SensorKind::kImu).size(), 1u);
  const auto& kin = m->kinematics();
  auto data = kin.make_data();
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(kin.dof());
  for (const model::SensorFrame* f : m->sensor_frames(SensorKind::kLidar)) {
    ASSERT_TRUE(kin.has_frame(f->frame)) << f->name;
    EXPECT_EQ(f->module_key, "concert_mobile_base_hub");
    EXPECT_TRUE(f->end_effector.empty());
  }
  // The sensor file's poses, kept relative to the floor: the lidars' rotation axes point down
  // (mounted upside down), the front camera's optical axis looks forward and 15 deg down,
  // every sonar looks outward and 22.5 deg down.
  for (const model::SensorFrame* f : m->sensor_frames(SensorKind::kLidar)) {
    const Eigen::Isometry3d pose = kin.frame_pose(data, q, f->frame);
    EXPECT_NEAR(pose.linear().col(2).z(), -1.0, 1e-9) << f->name;
  }
  const model::SensorFrame* front = nullptr;
  for (const model::SensorFrame* f : m->sensor_frames(SensorKind::kCamera)) {
    if (f->name.rfind("d435i_front", 0) == 0) front = f;
  }
  ASSERT_NE(front, nullptr);
  const Eigen::Isometry3d camera = kin.frame_pose(data, q, front->frame);
  EXPECT_NEAR(camera.linear().col(2).x(), std::cos(0.261799), 1e-6);
  EXPECT_NEAR(camera.linear().col(2).z(), -std::sin(0.261799), 1e-6);
  EXPECT_NEAR(camera.linear().col(0).y(), -1.0, 1e-6);  // image x to the robot's right
  for (const model::SensorFrame* f : m->sensor_frames(SensorKind::kSonar)) {
    const Eigen::Isometry3d pose = kin.frame_pose(data, q, f->frame);
    const Eigen::Vector3d axis = pose.linear().col(0);
    EXPECT_NEAR(axis.z(), -std::sin(1.963496 - 1.57), 1e-6) << f->name;
    EXPECT_GT(axis.head<2>().dot(pose.translation().head<2>()), 0.0) << f->name << " looks inward";
  }
}

TEST(PaperRobotPublicDatabase, ContinuousTorqueIsThePeakWhereTheDatabaseGivesNone) {
  const fs::path db = fs::path(CONCERT_SHARED_DATA) / "concert_resources";
  const auto m = model::RobotModel::build(
      generate({db, fs::path(SIMBUS_EXAMPLES) / "concert_paper_robot.yaml"}).description());
  for (const model::JointLimits& j : m->limits().rows())
    EXPECT_DOUBLE_EQ(j.continuous_torque, j.peak_torque) << j.name;
}

TEST(PaperRobotPublicDatabase, MobilePlatformSensorsComeFromThePublicSensorFile) {
  const fs::path db = fs::path(CONCERT_SHARED_DATA) / "concert_resources";
  const auto m = model::RobotModel::build(
      generate({db, fs::path(SIMBUS_EXAMPLES) / "concert_paper_robot.yaml"}).description());
  EXPECT_EQ(m->sensor_frames(SensorKind::kLidar).size(), 2u);
  EXPECT_EQ(m->sensor_frames(SensorKind::kSonar).size(), 8u);
  EXPECT_EQ(m->sensor_frames(SensorKind::kCamera).size(), 2u);  // front, back (the drill has none there)
  // Poses exactly as mobile_platform_sensors.yaml gives them in the platform's body frame.
  const auto& kin = m->kinematics();
  auto data = kin.make_data();
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(kin.dof());
  const std::string body = m->links().front().name;
  for (const model::SensorFrame* f : m->sensor_frames(SensorKind::kLidar)) {
    const Eigen::Isometry3d pose = kin.relative_pose(data, q, body, f->frame);
    const double side = f->name.rfind("lidar_front", 0) == 0 ? 1.0 : -1.0;
    EXPECT_NEAR((pose.translation() - Eigen::Vector3d(side * 0.5305, side * 0.315, -0.0627)).norm(), 0.0, 1e-9)
        << f->name;
    EXPECT_NEAR(pose.linear().col(2).z(), -1.0, 1e-6) << f->name;  // upside down
  }
}

// Largest gravity torque of an arm joint at posture `q` (by joint name; others at 0), as a
// fraction of that joint's continuous torque, and the joint.
std::pair<double, std::string> arm_static_load(const model::RobotModel& m, const std::map<std::string, double>& q_by_name) {
  const auto& kin = m.kinematics();
  auto data = kin.make_data();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(kin.dof());
  for (const auto& [name, value] : q_by_name) q[kin.joint_index_or_throw(name)] = value;
  const Eigen::VectorXd g = kin.gravity_torques(data, q);
  std::pair<double, std::string> worst{0.0, ""};
  for (const model::ChainInfo* arm : m.chains(ChainRole::kArm)) {
    for (const std::string& j : arm->joints) {
      const double load = std::abs(g[kin.joint_index_or_throw(j)]) / m.limits().at(j).continuous_torque;
      if (load > worst.first) worst = {load, j};
    }
  }
  return worst;
}

// Thirty seeded random robots of the project database: each one's default homing posture is
// one its drives hold with half their continuous torque to spare, with no arm frame more than
// 5 cm below the arm's mount. Where the database's zero posture already holds, it is kept.
TEST(RestingPosture, EveryRandomRobotRestsWhereItsDrivesHoldIt) {
  const fs::path dir = fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db";
  const module_db::ModuleDatabase db = module_db::load_module_database(dir);
  const topology::EscCatalog catalog = topology::EscCatalog::load(dir);
  const ModelGenerator generator(db);
  int moved = 0;
  for (unsigned seed = 1; seed <= 30; ++seed) {
    SCOPED_TRACE("random robot " + std::to_string(seed));
    std::mt19937 rng(seed);
    const topology::ModuleTree tree = simbus::tree_from_assembly(simbus::random_robot(rng), catalog);
    GeneratedModel g = generator.generate(tree);
    g.version = seed;
    const auto m = model::RobotModel::build(g.description());
    std::map<std::string, double> home, zero;
    for (const JointInfo& j : g.joints) {
      home[j.name] = j.home;
      zero[j.name] = std::clamp(0.0, j.lower, j.upper);
      EXPECT_GE(j.home, j.lower) << j.name;
      EXPECT_LE(j.home, j.upper) << j.name;
    }
    const auto [at_home, joint] = arm_static_load(*m, home);
    const auto at_zero = arm_static_load(*m, zero);
    EXPECT_LE(at_home, generator.params().home_torque_fraction) << joint;
    std::printf("random robot %2u: largest static load %3.0f %% at zero, %3.0f %% at home (%s)%s\n", seed,
                100.0 * at_zero.first, 100.0 * at_home, joint.c_str(), g.resting.moved ? ": raised" : "");
    EXPECT_NEAR(g.resting.static_load, at_home, 1e-9);
    EXPECT_EQ(g.resting.joint, joint);
    EXPECT_EQ(g.resting.moved, at_zero.first > generator.params().home_torque_fraction);
    if (!g.resting.moved) {
      EXPECT_EQ(home, zero);
      continue;
    }
    ++moved;
    // Every link the arm moves stays above its mount (less 5 cm), away from the base.
    const auto& kin = m->kinematics();
    auto data = kin.make_data();
    Eigen::VectorXd q = Eigen::VectorXd::Zero(kin.dof());
    for (const auto& [name, value] : home) q[kin.joint_index_or_throw(name)] = value;
    const int first = kin.joint_index_or_throw(m->arm().joints.front());
    const double mount = kin.frame_pose(data, q, kin.joint_parent_link(first)).translation().z();
    for (const std::string& f : kin.subtree_links(first)) {
      EXPECT_GE(kin.frame_pose(data, q, f).translation().z(), mount - 0.05 - 1e-9) << f;
    }
    // Free of self collision, as every service checks it.
    collision::LinkShapes shapes(*m, collision::rigid_groups(*m, m->arm().joints));
    std::vector<Eigen::Isometry3d> poses(m->links().size(), Eigen::Isometry3d::Identity());
    for (int l : shapes.links_with_shapes()) {
      poses[static_cast<std::size_t>(l)] = kin.frame_pose(data, q, m->links()[static_cast<std::size_t>(l)].name);
    }
    shapes.place(poses);
    EXPECT_FALSE(shapes.self_collision().has_value());
    // The SRDF's home group state and the controller configuration carry the posture.
    for (const std::string& j : m->arm().joints) {
      EXPECT_NE(g.srdf.find("<joint name=\"" + j + "\""), std::string::npos) << j;
    }
  }
  // Random robot 1 (a 7-joint arm, level after a 90 degree bend) overloads J3_E at zero.
  EXPECT_GT(moved, 0) << "no random robot needed a resting posture: the test checks nothing moved";
}

// The demo's robots rest at the database's zero posture: their drives hold it within half
// their continuous torque, so their homing posture is the one every test of them starts from.
TEST(RestingPosture, TheDemoRobotsKeepTheirZeroPosture) {
  const fs::path db = fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db";
  for (const char* robot : {"drill_robot.yaml", "sanding_robot.yaml", "spraying_robot.yaml", "transport_robot.yaml"}) {
    const GeneratedModel g = generate({db, fs::path(CONCERT_SOURCE_DIR) / "deploy/demo" / robot});
    std::printf("%s: largest static load at home %.0f %% (%s)\n", robot, 100.0 * g.resting.static_load,
                g.resting.joint.c_str());
    EXPECT_FALSE(g.resting.moved) << robot << ": " << describe(g.resting, 0.5);
    for (const JointInfo& j : g.joints) EXPECT_EQ(j.home, std::clamp(0.0, j.lower, j.upper)) << robot << " " << j.name;
  }
}

// A customised home is kept as given, even where the search would move that joint.
TEST(RestingPosture, ACustomisedHomeStaysAsGiven) {
  const fs::path dir = fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db";
  const module_db::ModuleDatabase db = module_db::load_module_database(dir);
  const topology::EscCatalog catalog = topology::EscCatalog::load(dir);
  std::mt19937 rng(1);
  const topology::ModuleTree tree = simbus::tree_from_assembly(simbus::random_robot(rng), catalog);
  const ModelGenerator generator(db);
  const GeneratedModel free = generator.generate(tree);
  ASSERT_TRUE(free.resting.moved);
  const auto moved = std::find_if(free.joints.begin(), free.joints.end(),
                                  [](const JointInfo& j) { return j.chain == "E" && j.home != 0.0; });
  ASSERT_NE(moved, free.joints.end());
  Customisation custom;
  custom.home[moved->name] = 0.0;
  const GeneratedModel pinned = generator.generate(tree, custom);
  for (const JointInfo& j : pinned.joints) {
    if (j.name == moved->name) {
      EXPECT_EQ(j.home, 0.0);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    BothDatabases, PaperRobot,
    ::testing::Values(Database{fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db",
                               fs::path(CONCERT_SOURCE_DIR) / "deploy/demo/drill_robot.yaml"},
                      Database{fs::path(CONCERT_SHARED_DATA) / "concert_resources",
                               fs::path(SIMBUS_EXAMPLES) / "concert_paper_robot.yaml"}),
    [](const ::testing::TestParamInfo<Database>& param) {
      return param.index == 0 ? std::string("Project") : std::string("Public");
    });

}  // namespace
}  // namespace concert::model_generation
