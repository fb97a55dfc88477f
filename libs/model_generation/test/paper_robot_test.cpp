// The paper's robot (mobile base, four steering + wheel legs, 6-DoF arm with a drill) through
// model generation and the parsed model, with both module databases: the project's
// (data/module_db, continuous torques from the paper's Table 1) and the public
// concert_resources (peak torques only).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
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
