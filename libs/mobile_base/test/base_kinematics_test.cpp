#include "concert/mobile_base/base_kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <tuple>

#include "model_fixture.hpp"

namespace concert::mobile_base {
namespace {

std::string fixture(const std::string& name) { return std::string(ROBOT_FIXTURES) + "/" + name; }

std::vector<Leg> legs_of(const std::string& file) {
  const auto model = kinematics::Model::from_urdf_file(fixture(file));
  return detect_legs(model, collision_cylinder_radii(model.urdf()));
}

TEST(BaseKinematics, DetectsFourLegsOfTheMobileBase) {
  const auto legs = legs_of("mobile_drill.urdf");
  ASSERT_EQ(legs.size(), 4u);
  EXPECT_EQ(legs[0].steering_joint, "J_steer_fl");
  EXPECT_EQ(legs[0].wheel_joint, "J_wheel_fl");
  EXPECT_TRUE(legs[0].position.isApprox(Eigen::Vector2d(0.35, 0.3)));
  EXPECT_DOUBLE_EQ(legs[0].wheel_radius, 0.16);
  EXPECT_DOUBLE_EQ(legs[0].steering_sign, 1.0);
  EXPECT_NEAR(legs[0].heading_offset, 0.0, 1e-12);  // wheel axis +y rolls towards +x
  EXPECT_NEAR(legs[0].wheel_center_height, -0.3, 1e-12);
  EXPECT_EQ(legs_of("mobile_three_legs.urdf").size(), 3u);
  EXPECT_TRUE(legs_of("arm_drill.urdf").empty());  // arm joints are not legs
}

// Legs selected by role (the model's leg chains) measure as the geometric search finds them, on
// the project's demo robot, morphology A (the pattern test's) and the paper's morphology B built
// from the public CONCERT database;
// joints that do not make a steering leg are named.
TEST(BaseKinematics, LegsByRoleMeasureAsTheGeometricSearchFindsThem) {
  for (const auto& [assembly, db] :
       {std::make_pair(std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml",
                       testing::project_module_db()),
        std::make_pair(std::string(CONCERT_SOURCE_DIR) + "/services/planner/data/morphology_a.yaml",
                       testing::project_module_db()),
        std::make_pair(std::string(CONCERT_SOURCE_DIR) +
                           "/services/surface_finish/test/fixtures/morphology_b_spraying_public.yaml",
                       testing::public_module_db())}) {
    const auto model = testing::robot_model(assembly, 1, db);
    const std::vector<Leg> by_role = steering_legs(*model);
    const std::vector<Leg> found =
        detect_legs(model->kinematics(), collision_cylinder_radii(model->description().urdf));
    ASSERT_EQ(by_role.size(), 4u) << assembly;
    ASSERT_EQ(found.size(), by_role.size()) << assembly;
    for (std::size_t i = 0; i < found.size(); ++i) {
      EXPECT_EQ(by_role[i].steering_joint, found[i].steering_joint);
      EXPECT_EQ(by_role[i].wheel_joint, found[i].wheel_joint);
      EXPECT_TRUE(by_role[i].position.isApprox(found[i].position, 1e-12));
      EXPECT_DOUBLE_EQ(by_role[i].wheel_radius, found[i].wheel_radius);
      EXPECT_DOUBLE_EQ(by_role[i].heading_offset, found[i].heading_offset);
      EXPECT_DOUBLE_EQ(by_role[i].axle_offset, found[i].axle_offset);
      EXPECT_DOUBLE_EQ(by_role[i].wheel_center_height, found[i].wheel_center_height);
    }
    EXPECT_NEAR(standing_height(*model), standing_height(found), 1e-9) << assembly;
    EXPECT_GT(standing_height(*model), 0.1);
    try {
      (void)measure_leg(model->kinematics(), found[0].wheel_joint, found[0].steering_joint, 0.1);
      ADD_FAILURE() << "a wheel taken for a steering axis";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), "joint '" + found[0].wheel_joint +
                                           "' is not a vertical steering axis directly above the "
                                           "horizontal axis of wheel joint '" +
                                           found[0].steering_joint + "'");
    }
  }
}

TEST(BaseKinematics, StandsOnItsLargestWheelBelowTheBase) {
  auto legs = legs_of("mobile_drill.urdf");
  EXPECT_NEAR(standing_height(legs), 0.16 + 0.3, 1e-12);  // wheel centres 0.3 m below the base
  legs[2].wheel_radius = 0.25;
  EXPECT_NEAR(standing_height(legs), 0.25 + 0.3, 1e-12);
  EXPECT_DOUBLE_EQ(standing_height({}), 0.0);
}

TEST(BaseKinematics, NeedsTwoLegs) {
  auto legs = legs_of("mobile_drill.urdf");
  legs.resize(1);
  EXPECT_THROW(BaseKinematics{legs}, std::invalid_argument);
}

TEST(BaseKinematics, PureTranslationsAndRotation) {
  const BaseKinematics base(legs_of("mobile_drill.urdf"));
  const std::vector<double> zero(4, 0.0);
  // Forward: every wheel straight, speed v / r.
  auto sp = base.leg_setpoints({0.5, 0.0, 0.0}, zero);
  for (const auto& s : sp) {
    EXPECT_NEAR(s.steering_angle, 0.0, 1e-12);
    EXPECT_NEAR(s.wheel_velocity, 0.5 / 0.16, 1e-12);
  }
  // Sideways: +90 degrees.
  sp = base.leg_setpoints({0.0, 0.3, 0.0}, zero);
  for (const auto& s : sp) {
    EXPECT_NEAR(s.steering_angle, M_PI / 2, 1e-12);
    EXPECT_NEAR(s.wheel_velocity, 0.3 / 0.16, 1e-12);
  }
  // Turning in place: wheel directions tangent to the circle through the leg.
  sp = base.leg_setpoints({0.0, 0.0, 1.0}, zero);
  const auto& legs = base.legs();
  for (std::size_t i = 0; i < legs.size(); ++i) {
    const Eigen::Vector2d p = legs[i].position;
    const Eigen::Vector2d dir(std::cos(sp[i].steering_angle), std::sin(sp[i].steering_angle));
    EXPECT_NEAR(dir.dot(p), 0.0, 1e-12);
    EXPECT_NEAR(std::abs(sp[i].wheel_velocity), p.norm() / 0.16, 1e-12);
    EXPECT_LE(std::abs(sp[i].steering_angle), M_PI / 2 + 1e-12);
  }
}

TEST(BaseKinematics, SteeringFlipsInsteadOfTurningMoreThanNinetyDegrees) {
  const BaseKinematics base(legs_of("mobile_drill.urdf"));
  const std::vector<double> zero(4, 0.0);
  // Backwards from straight: keep the angle, roll backwards (no half turn).
  auto sp = base.leg_setpoints({-0.4, 0.0, 0.0}, zero);
  for (const auto& s : sp) {
    EXPECT_NEAR(s.steering_angle, 0.0, 1e-12);
    EXPECT_NEAR(s.wheel_velocity, -0.4 / 0.16, 1e-12);
  }
  // Heading 135 degrees from 0: turn to -45 degrees and roll backwards.
  sp = base.leg_setpoints({-0.3, 0.3, 0.0}, zero);
  for (const auto& s : sp) {
    EXPECT_NEAR(s.steering_angle, -M_PI / 4, 1e-12);
    EXPECT_LT(s.wheel_velocity, 0.0);
  }
}

TEST(BaseKinematics, ACrawlingTwistIsNotDriven) {
  const BaseKinematics base(legs_of("mobile_drill.urdf"));
  const std::vector<double> steering(4, 0.3);
  // 3 mm/s sideways: below the deadband, no leg turns and every wheel stops.
  auto sp = base.leg_setpoints({0.0, 0.003, 0.0}, steering);
  for (const auto& s : sp) {
    EXPECT_DOUBLE_EQ(s.steering_angle, 0.3);
    EXPECT_DOUBLE_EQ(s.wheel_velocity, 0.0);
  }
  // A slow turn whose fastest contact (0.54 m out) moves 8 mm/s: driven, every leg steered, even
  // the ones that move slower.
  sp = base.leg_setpoints({0.0, 0.0, 0.015}, steering);
  for (const auto& s : sp) {
    EXPECT_GT(std::abs(s.steering_angle - 0.3), 0.1);
    EXPECT_NE(s.wheel_velocity, 0.0);
  }
  // 1 cm/s sideways: steered.
  sp = base.leg_setpoints({0.0, 0.01, 0.0}, steering);
  for (const auto& s : sp) EXPECT_GT(std::abs(s.steering_angle - 0.3), 0.1);
}

TEST(BaseKinematics, OdometryRecoversTheCommandedTwist) {
  const BaseKinematics base(legs_of("mobile_drill.urdf"));
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d twist(u(rng), u(rng), u(rng));
    const auto sp = base.leg_setpoints(twist, std::vector<double>(4, u(rng)));
    std::vector<double> steer, wheel;
    for (const auto& s : sp) {
      steer.push_back(s.steering_angle);
      wheel.push_back(s.wheel_velocity);
    }
    EXPECT_TRUE(base.twist_from_legs(steer, wheel).isApprox(twist, 1e-9));
  }
  // Integration: a quarter circle of radius 1 m (vx = 0.5 m/s, wz = 0.5 rad/s for pi s) ends at (1, 1).
  Odometry odom;
  const auto sp = base.leg_setpoints({0.5, 0.0, 0.5}, std::vector<double>(4, 0.0));
  std::vector<double> steer, wheel;
  for (const auto& s : sp) {
    steer.push_back(s.steering_angle);
    wheel.push_back(s.wheel_velocity);
  }
  for (int i = 0; i < 3142; ++i) {
    base.integrate(odom, steer, wheel, 0.001);
  }
  EXPECT_NEAR(odom.x, 1.0, 2e-3);
  EXPECT_NEAR(odom.y, 1.0, 2e-3);
  EXPECT_NEAR(odom.yaw, M_PI / 2, 2e-3);
}


// The steering modules of the project's database (data/module_db, the demo robot) carry their
// wheel 0.1 m beside the steering axis, along the wheel's axis (+-0.1 m). Judged against the geometry itself: each wheel centre's
// velocity differentiated numerically from its pose (base pose, steering axis, offset along the
// steered axle), not from the formulas under test.
TEST(BaseKinematics, WheelsBesideTheirSteeringAxesRollAsTheBaseTurnsAndTheLegsSteer) {
  std::vector<Leg> legs;
  for (const auto& [x, y, e] : {std::tuple{0.45, 0.3, -0.1}, std::tuple{0.45, -0.3, 0.1},
                                std::tuple{-0.45, 0.3, 0.1}, std::tuple{-0.45, -0.3, -0.1}}) {
    Leg leg;
    leg.position = {x, y};
    leg.axle_offset = e;
    leg.wheel_radius = 0.2;
    leg.steering_sign = -1.0;  // the module's steering axis points down
    legs.push_back(leg);
  }
  const BaseKinematics base(legs);
  // Wheel centre of leg `l` in the world: base pose (x, y, yaw), the leg steered to `steering`.
  const auto centre = [](const Leg& l, const Eigen::Vector3d& pose, double steering) {
    const double heading = l.heading_offset + l.steering_sign * steering;
    const Eigen::Vector2d axle(-std::sin(heading), std::cos(heading));  // rolling = axle x z
    const Eigen::Vector2d in_base = l.position + l.axle_offset * axle;
    const Eigen::Rotation2Dd r(pose.z());
    return Eigen::Vector2d(pose.head<2>() + r * in_base);
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 30; ++k) {
    const Eigen::Vector3d twist(0.3 * u(rng), 0.3 * u(rng), 0.6 * u(rng));
    const auto sp = base.leg_setpoints(twist, std::vector<double>(4, 0.5 * u(rng)));
    std::vector<double> steering, rate, wheel;
    for (std::size_t i = 0; i < legs.size(); ++i) {
      steering.push_back(sp[i].steering_angle);
      rate.push_back(2.0 * u(rng));  // the legs still swinging round
      wheel.push_back(sp[i].wheel_velocity + base.steering_rolling(i, rate[i]));
    }
    // The geometry: the centres' velocities over 1 us, the base at the origin.
    constexpr double dt = 1e-6;
    const Eigen::Vector3d pose(0.0, 0.0, 0.0);
    const Eigen::Vector3d next = pose + twist * dt;  // the base frame is the world's at t = 0
    for (std::size_t i = 0; i < legs.size(); ++i) {
      const Eigen::Vector2d v =
          (centre(legs[i], next, steering[i] + rate[i] * dt) - centre(legs[i], pose, steering[i])) / dt;
      const double heading = legs[i].heading_offset + legs[i].steering_sign * steering[i];
      const Eigen::Vector2d h(std::cos(heading), std::sin(heading));
      const Eigen::Vector2d axle(-h.y(), h.x());
      // What the wheel rolls is its centre's speed along its heading; across it, nothing slides.
      EXPECT_NEAR(wheel[i] * legs[i].wheel_radius, v.dot(h), 1e-5) << "leg " << i;
      EXPECT_NEAR(v.dot(axle), 0.0, 1e-5) << "leg " << i;
    }
    // The odometry reads the twist back from those wheels and steering rates.
    EXPECT_TRUE(base.twist_from_legs(steering, wheel, rate).isApprox(twist, 1e-9))
        << base.twist_from_legs(steering, wheel, rate).transpose() << " for " << twist.transpose();
    // Read as wheels on their axes (the old model), the same legs give another twist.
    if (std::abs(twist.z()) > 0.1) {
      std::vector<Leg> on_axis = legs;
      for (Leg& l : on_axis) l.axle_offset = 0.0;
      EXPECT_GT((BaseKinematics(on_axis).twist_from_legs(steering, wheel, rate) - twist).norm(), 1e-3);
    }
  }
}

}  // namespace
}  // namespace concert::mobile_base
