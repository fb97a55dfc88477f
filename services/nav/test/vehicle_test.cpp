// Automatic vehicle kinematics on real models: the paper's robot and wrong assemblies through the
// simulated bus + model generation with the project's module database, and a hand-written
// differential robot (two wheels and a ball caster).
#include "nav/vehicle.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::nav {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kDbDir = fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db";

std::shared_ptr<const model::RobotModel> model_from_assembly(const simbus::Assembly& assembly,
                                                             std::uint64_t version = 1) {
  static const module_db::ModuleDatabase db = module_db::load_module_database(kDbDir);
  static const topology::EscCatalog catalog = topology::EscCatalog::load(kDbDir);
  model_generation::GeneratedModel m =
      model_generation::ModelGenerator(db).generate(simbus::tree_from_assembly(assembly, catalog));
  m.version = version;
  return model::RobotModel::build(m.description());
}

std::shared_ptr<const model::RobotModel> model_from_yaml(const std::string& yaml) {
  return model_from_assembly(simbus::parse_assembly(yaml, "test assembly"));
}

// Winding number test of a convex CCW polygon.
bool contains(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d a = polygon[i];
    const Eigen::Vector2d e = polygon[(i + 1) % polygon.size()] - a;
    if (e.x() * (p - a).y() - e.y() * (p - a).x() < -1e-9) return false;
  }
  return true;
}

// Assembly YAML: the Mobile Base Hub with its first `legs` steering + wheel legs (FL, FR, RL, RR).
std::string base_with_legs(int legs) {
  const char* sides[4][2] = {{"fl", "concert_steering_fl_rr"},
                             {"fr", "concert_steering_fr_rl"},
                             {"rl", "concert_steering_fr_rl"},
                             {"rr", "concert_steering_fl_rr"}};
  std::string yaml = "modules:\n  - {name: base, key: concert_mobile_base_hub}\n";
  for (int i = 0; i < legs; ++i) {
    const std::string side = sides[i][0];
    yaml += "  - {name: steer_" + side + ", key: " + sides[i][1] +
            ", parent: base, connector: " + std::to_string(i + 1) + "}\n  - {name: wheel_" + side +
            ", key: concert_wheel, parent: steer_" + side + ", connector: 1}\n";
  }
  return yaml;
}

// recognise_vehicle(model) throws a VehicleError whose message holds every one of `parts`.
void expect_refused(const model::RobotModel& model, std::initializer_list<std::string> parts) {
  try {
    recognise_vehicle(model);
    ADD_FAILURE() << model.where() << " was given a vehicle";
  } catch (const VehicleError& e) {
    for (const std::string& part : parts) EXPECT_THAT(e.what(), HasSubstr(part));
  }
}

const SensorPose* find_sensor(const std::vector<SensorPose>& list, const std::string& name) {
  const auto it = std::find_if(list.begin(), list.end(),
                               [&](const SensorPose& s) { return s.name.find(name) == 0; });
  return it == list.end() ? nullptr : &*it;
}

TEST(Vehicle, PaperMobileBaseIsOmniSteeringWithFourLegsAndItsSensors) {
  const auto model = model_from_assembly(
      simbus::load_assembly(fs::path(CONCERT_SOURCE_DIR) / "deploy" / "demo" / "drill_robot.yaml"),
      7);
  const VehicleConfig v = recognise_vehicle(*model);
  EXPECT_EQ(v.model_version, 7u);
  EXPECT_EQ(v.drive, DriveType::kOmniSteering);
  ASSERT_EQ(v.wheels.size(), 4u);
  ASSERT_EQ(v.steering_legs.size(), 4u);
  // The Mobile Base Hub's leg connectors: FL, FR, RL, RR at (+-0.45, +-0.3).
  const Eigen::Vector2d expected[4] = {{0.45, 0.3}, {0.45, -0.3}, {-0.45, 0.3}, {-0.45, -0.3}};
  for (const Eigen::Vector2d& e : expected) {
    const auto it = std::find_if(v.wheels.begin(), v.wheels.end(), [&](const WheelConfig& w) {
      return (w.position - e).norm() < 1e-6;
    });
    ASSERT_NE(it, v.wheels.end()) << "no leg at " << e.transpose();
    EXPECT_NEAR(it->radius, 0.2, 1e-9);
    EXPECT_FALSE(it->steering_joint.empty());
    EXPECT_NEAR(it->max_wheel_speed, 13.7, 1e-9);   // Small B actuator
    EXPECT_NEAR(it->max_steering_rate, 8.1, 1e-9);  // Medium actuator
  }
  // Wheels allow 13.7 rad/s x 0.2 m = 2.74 m/s: the cap applies.
  EXPECT_DOUBLE_EQ(v.limits.linear, VehicleParams{}.max_linear_speed);
  EXPECT_DOUBLE_EQ(v.limits.lateral, v.limits.linear);
  EXPECT_NEAR(v.limits.steering_rate, 8.1, 1e-9);
  EXPECT_GT(v.limits.angular, 0.0);

  // Perception: two VLP-16s, eight sonars, one IMU, at the hub's mounts.
  EXPECT_TRUE(v.perception.planar_lidars.empty());
  ASSERT_EQ(v.perception.lidars_3d.size(), 2u);
  EXPECT_EQ(v.perception.sonars.size(), 8u);
  ASSERT_EQ(v.perception.imus.size(), 1u);
  const SensorPose* front = find_sensor(v.perception.lidars_3d, "lidar_front");
  ASSERT_NE(front, nullptr);
  EXPECT_TRUE(
      front->base_T_sensor.translation().isApprox(Eigen::Vector3d(0.62, 0.315, -0.1657), 1e-6));
  EXPECT_TRUE(
      v.perception.imus[0].base_T_sensor.translation().isApprox(Eigen::Vector3d(0, 0, -0.2), 1e-6));

  // Footprint: the arm in the SRDF home posture, the hub's chassis and the swept legs inside.
  EXPECT_EQ(v.footprint.posture, "SRDF home");
  EXPECT_TRUE(v.footprint.steering_swept);
  for (double x : {-0.6, 0.6}) {
    for (double y : {-0.4, 0.4})
      EXPECT_TRUE(contains(v.footprint.polygon, {x, y})) << x << " " << y;
  }
  for (const Eigen::Vector2d& e : expected) {
    // The wheel (radius 0.2) swings about the steering axis: its rim is always inside.
    for (double a = 0.0; a < 6.28; a += 0.5) {
      EXPECT_TRUE(
          contains(v.footprint.polygon, e + 0.2 * Eigen::Vector2d(std::cos(a), std::sin(a))));
    }
  }
  EXPECT_GE(v.footprint.inscribed_radius, 0.4);
  EXPECT_GE(v.footprint.circumscribed_radius, std::hypot(0.45, 0.3) + 0.2);
  EXPECT_LT(v.footprint.circumscribed_radius, 1.5);
  for (const Eigen::Vector2d& p : v.footprint.polygon) {
    EXPECT_LE(p.norm(), v.footprint.circumscribed_radius + 1e-12);
  }
  // The omni-steering legs feed the base kinematics directly.
  EXPECT_NO_THROW(mobile_base::BaseKinematics{v.steering_legs});
}

// A differential robot: base box, two wheels on a common axis along y, a ball caster, a lidar.
constexpr const char* kDifferentialUrdf = R"(<?xml version="1.0"?>
<robot name="diff">
  <link name="base_link">
    <inertial><mass value="20"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><box size="0.6 0.4 0.2"/></geometry></collision>
  </link>
  <link name="wheel_left">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><cylinder radius="0.1" length="0.05"/></geometry></collision>
  </link>
  <link name="wheel_right">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><cylinder radius="0.1" length="0.05"/></geometry></collision>
  </link>
  <link name="caster">
    <inertial><mass value="0.2"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <link name="lidar"/>
  <joint name="wheel_left_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_left"/>
    <origin xyz="0 0.25 0" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit effort="5" velocity="5"/>
  </joint>
  <joint name="wheel_right_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_right"/>
    <origin xyz="0 -0.25 0" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit effort="5" velocity="5"/>
  </joint>
  <joint name="caster_joint" type="fixed">
    <parent link="base_link"/><child link="caster"/><origin xyz="-0.25 0 -0.05"/>
  </joint>
  <joint name="lidar_joint" type="fixed">
    <parent link="base_link"/><child link="lidar"/><origin xyz="0.25 0 0.3"/>
  </joint>
</robot>
)";

model::ModelDescription differential_description() {
  model::ModelDescription d;
  d.version = 3;
  d.urdf = kDifferentialUrdf;
  for (const char* tag : {"A", "B"}) {
    const std::string side = std::string(tag) == "A" ? "left" : "right";
    d.joints.push_back({.name = "wheel_" + side + "_joint",
                        .chain = tag,
                        .velocity = 5.0,
                        .peak_torque = 5.0,
                        .continuous_torque = 3.0});
    d.chains.push_back(
        {tag, model::ChainRole::kLeg, "base_link", "wheel_" + side, {"wheel_" + side + "_joint"}});
    d.end_effectors.push_back({std::string("wheel_") + tag, tag, "wheel_" + side, "diff_wheel",
                               model::EndEffectorKind::kWheel});
  }
  d.sensor_frames.push_back(
      {"lidar_2d", model::SensorKind::kLidar, "lidar", "", "", "planar_lidar"});
  return d;
}

TEST(Vehicle, TwoCoaxialWheelsAndACasterAreADifferentialDrive) {
  const auto model = model::RobotModel::build(differential_description());
  VehicleParams params;
  params.planar_lidar_modules = {"planar_lidar"};
  const VehicleConfig v = recognise_vehicle(*model, params);
  EXPECT_EQ(v.drive, DriveType::kDifferential);
  EXPECT_EQ(to_string(v.drive), "differential");
  ASSERT_EQ(v.wheels.size(), 2u);
  EXPECT_TRUE(v.steering_legs.empty());
  EXPECT_NEAR(v.track, 0.5, 1e-9);
  for (const WheelConfig& w : v.wheels) {
    EXPECT_NEAR(w.radius, 0.1, 1e-9);
    EXPECT_TRUE(w.steering_joint.empty());
    // The axes point along +y: a positive wheel speed rolls the base forward.
    EXPECT_EQ(w.rolling_sign, 1.0);
  }
  EXPECT_NEAR(v.wheels[0].position.y(), 0.25, 1e-9);
  EXPECT_NEAR(v.wheels[1].position.y(), -0.25, 1e-9);
  EXPECT_NEAR(v.limits.linear, 0.5, 1e-9);  // 5 rad/s x 0.1 m
  EXPECT_EQ(v.limits.lateral, 0.0);
  EXPECT_NEAR(v.limits.angular, VehicleParams{}.max_angular_speed, 1e-9);  // 2 x 0.5 / 0.5 = 2 rad/s, capped
  EXPECT_EQ(v.limits.steering_rate, 0.0);
  // No SRDF: q = 0; the box, the wheels and the caster.
  EXPECT_EQ(v.footprint.posture, "q = 0");
  EXPECT_FALSE(v.footprint.steering_swept);
  EXPECT_NEAR(v.footprint.circumscribed_radius, std::hypot(0.3, 0.2), 1e-9);
  EXPECT_TRUE(contains(v.footprint.polygon, {0.0, 0.27}));
  EXPECT_FALSE(contains(v.footprint.polygon, {0.0, 0.29}));
  // The box (half-width 0.2 m) is inside; its front and back edges (x = +-0.3 m) are hull edges.
  EXPECT_GT(v.footprint.inscribed_radius, 0.2);
  EXPECT_LE(v.footprint.inscribed_radius, 0.3 + 1e-9);
  ASSERT_EQ(v.perception.planar_lidars.size(), 1u);
  EXPECT_TRUE(v.perception.lidars_3d.empty());
  EXPECT_TRUE(v.perception.planar_lidars[0].base_T_sensor.translation().isApprox(
      Eigen::Vector3d(0.25, 0, 0.3)));
}

TEST(Vehicle, WheelsThatAreNotCoaxialAreRefused) {
  model::ModelDescription d = differential_description();
  const std::string from = "<origin xyz=\"0 -0.25 0\"";
  d.urdf.replace(d.urdf.find(from), from.size(), "<origin xyz=\"0.2 -0.25 0\"");
  const auto model = model::RobotModel::build(d);
  expect_refused(*model, {"model version 3", "not coaxial"});
}

TEST(Vehicle, AnArmWithoutWheelsCannotNavigate) {
  const auto model = model_from_yaml(R"(
modules:
  - {name: column, key: concert_base_link_600}
  - {name: yaw_1, key: concert_straight_a, parent: column, connector: 1}
  - {name: elbow_1, key: concert_elbow_a, parent: yaw_1, connector: 1}
  - {name: tool, key: concert_drill, parent: elbow_1, connector: 1}
)");
  expect_refused(*model, {"model version 1", "no wheels: a fixed-base arm cannot navigate"});
}

TEST(Vehicle, TwoSteeredLegsAreRefused) {
  const auto model = model_from_yaml(base_with_legs(2));
  expect_refused(*model, {"2 steered legs (chains A, B)", "at least 3"});
}

TEST(Vehicle, ThreeSteeredLegsAreEnough) {
  const auto model = model_from_yaml(base_with_legs(3));
  const VehicleConfig v = recognise_vehicle(*model);
  EXPECT_EQ(v.drive, DriveType::kOmniSteering);
  EXPECT_EQ(v.wheels.size(), 3u);
  EXPECT_EQ(v.footprint.posture, "SRDF home");
}

TEST(Vehicle, ConvexHullDropsInnerAndCollinearPoints) {
  const std::vector<Eigen::Vector2d> hull =
      convex_hull({{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 1}, {0, 1}});
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_TRUE(hull[0].isApprox(Eigen::Vector2d(0, 0)));
  EXPECT_TRUE(hull[1].isApprox(Eigen::Vector2d(2, 0)));
  EXPECT_TRUE(hull[2].isApprox(Eigen::Vector2d(2, 2)));
  EXPECT_TRUE(hull[3].isApprox(Eigen::Vector2d(0, 2)));
}

}  // namespace
}  // namespace concert::nav
