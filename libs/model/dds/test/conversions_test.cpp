#include "concert/model/dds/conversions.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace concert::model {
namespace {

ModelDescription sample() {
  ModelDescription d;
  d.version = 5;
  d.content_hash = "sha256:00";
  d.tree_version = 3;
  d.urdf = "<robot/>";
  d.srdf = "<robot/>";
  d.config_yaml = "robot: x\n";
  d.modules = {"concert_mobile_base_hub", "concert_drill"};
  const double inf = std::numeric_limits<double>::infinity();
  d.joints = {{"J1_A", "A", -2.6, 2.6, 8.1, 127, 34}, {"J2_A", "A", -inf, inf, 13.7, 24, 17.5}};
  d.chains = {{"A", ChainRole::kLeg, "base_link", "wheel_A", {"J1_A", "J2_A"}},
              {"E", ChainRole::kArm, "base_link", "tcp_E", {}},
              {"F", ChainRole::kTool, "base_link", "tcp_F", {}}};
  d.end_effectors = {{"wheel_A", "A", "wheel_A", "concert_wheel", EndEffectorKind::kWheel},
                     {"drill_E", "E", "tcp_E", "concert_drill", EndEffectorKind::kDrill}};
  d.sensor_frames = {
      {"camera_E", SensorKind::kCamera, "camera_E", "E", "drill_E", "concert_drill"}};
  return d;
}

TEST(ModelConversions, RoundTripKeepsEveryFieldAndInfiniteLimitsTravelAsBigNumbers) {
  const ModelDescription d = sample();
  const msg::RobotModel m = dds::to_msg(d, 42);
  EXPECT_EQ(m.stamp_ns(), 42);
  EXPECT_DOUBLE_EQ(m.joints()[1].upper(), 1e300);
  EXPECT_DOUBLE_EQ(m.joints()[0].peak_torque(), 127.0);
  EXPECT_DOUBLE_EQ(m.joints()[0].continuous_torque(), 34.0);
  EXPECT_EQ(m.chains()[2].role(), "tool");
  EXPECT_EQ(m.end_effectors()[1].kind(), "drill");
  EXPECT_EQ(m.sensor_frames()[0].kind(), "camera");
  EXPECT_EQ(dds::to_description(m), d);
}

TEST(ModelConversions, UnknownKindsAreErrorsNamingTheField) {
  msg::RobotModel m = dds::to_msg(sample(), 0);
  m.end_effectors()[1].kind("laser");
  try {
    (void)dds::to_description(m);
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_STREQ(e.what(),
                 "RobotModel v5 end_effectors[1].kind: unknown end-effector kind 'laser' (known: "
                 "drill, gripper, sanding, "
                 "spraying, camera, wheel, other)");
  }
  m = dds::to_msg(sample(), 0);
  m.chains()[0].role("wing");
  EXPECT_THROW((void)dds::to_description(m), ModelError);
}

}  // namespace
}  // namespace concert::model
