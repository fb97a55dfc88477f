#include "concert/model/limit_checks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace concert::model {
namespace {

// 2 rad/s, 200 N m peak, 160 N m continuous.
const JointLimits kJoint{"J1_A", "A", -1.0, 1.0, 2.0, 200.0, 160.0};

TEST(LimitChecks, VelocityBeyondTheBoundWithItsMarginEitherWay) {
  EXPECT_FALSE(velocity_violated(kJoint, 2.19, 0.1));
  EXPECT_FALSE(velocity_violated(kJoint, -2.19, 0.1));
  EXPECT_TRUE(velocity_violated(kJoint, 2.21, 0.1));
  EXPECT_TRUE(velocity_violated(kJoint, -2.21, 0.1));
  EXPECT_TRUE(velocity_violated(kJoint, 2.01, 0.0));
}

TEST(LimitChecks, TorqueBeyondThePeakNotTheContinuousTorque) {
  EXPECT_FALSE(torque_violated(kJoint, 180.0, 0.0));  // above continuous, below peak
  EXPECT_FALSE(torque_violated(kJoint, -219.0, 0.1));
  EXPECT_TRUE(torque_violated(kJoint, 221.0, 0.1));
  EXPECT_TRUE(torque_violated(kJoint, -201.0, 0.0));
}

TEST(LimitChecks, MeasurementsThatAreNotFiniteAreViolations) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(velocity_violated(kJoint, std::nan(""), 0.1));
  EXPECT_TRUE(velocity_violated(kJoint, -inf, 0.1));
  EXPECT_TRUE(torque_violated(kJoint, std::nan(""), 0.1));
  EXPECT_TRUE(torque_violated(kJoint, inf, 0.1));
}

}  // namespace
}  // namespace concert::model
