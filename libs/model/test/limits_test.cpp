#include "concert/model/limits.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace concert::model {
namespace {

JointLimits joint(double continuous, double peak) {
  return {"J1_A", "A", -1.0, 1.0, 2.0, peak, continuous};
}

TEST(LimitsTable, FindsRowsAndListsJointsWhenAskedForAnUnknownOne) {
  const LimitsTable table({joint(160, 200), {"J2_A", "A", -2.0, 2.0, 1.0, 50, 40}},
                          "model version 4");
  EXPECT_EQ(table.size(), 2u);
  EXPECT_DOUBLE_EQ(table.at("J2_A").peak_torque, 50.0);
  EXPECT_EQ(table.find("J3_A"), nullptr);
  try {
    (void)table.at("J3_A");
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_STREQ(e.what(),
                 "model version 4: no joint 'J3_A' in the limits table (joints: J1_A, J2_A)");
  }
}

TEST(LimitsTable, RejectsRowsThatBreakTheRule) {
  EXPECT_THROW(LimitsTable({joint(210, 200)}, "v"), ModelError);  // continuous above peak
  EXPECT_THROW(LimitsTable({joint(0, 200)}, "v"), ModelError);
  EXPECT_THROW(LimitsTable({joint(10, 0)}, "v"), ModelError);
  EXPECT_THROW(LimitsTable({joint(160, 200), joint(160, 200)}, "v"), ModelError);
  JointLimits empty = joint(160, 200);
  empty.lower = 2.0;
  EXPECT_THROW(LimitsTable({empty}, "v"), ModelError);
  JointLimits still = joint(160, 200);
  still.velocity = 0.0;
  try {
    LimitsTable({still}, "model version 2");
    FAIL() << "no throw";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("model version 2: joint 'J1_A': velocity limit"),
              std::string::npos)
        << e.what();
  }
}

TEST(LimitsRule, EachConsumerEnforcesItsColumn) {
  const JointLimits j = joint(160, 200);
  EXPECT_DOUBLE_EQ(drive_torque_limit(j), 200.0);
  EXPECT_DOUBLE_EQ(planning_torque_limit(j), 160.0);
  EXPECT_DOUBLE_EQ(instant_torque_bound(j, 0.1), 220.0);
  EXPECT_DOUBLE_EQ(sustained_torque_bound(j, 0.1), 176.0);
  EXPECT_DOUBLE_EQ(velocity_bound(j, 0.1), 2.2);
  EXPECT_FALSE(position_violated(j, 1.01, 0.02));
  EXPECT_TRUE(position_violated(j, 1.03, 0.02));
  EXPECT_TRUE(position_violated(j, std::nan(""), 0.02));
}

TEST(ThermalLoad, ConvergesToTheRmsOfASteadyLoadWithTheWindowAsTimeConstant) {
  ThermalLoad load(5.0);
  load.add(100.0, 0.0);
  EXPECT_DOUBLE_EQ(load.rms(), 0.0);  // cold drive
  double rms = 0.0;
  for (int i = 0; i < 500; ++i) rms = load.add(100.0, 0.01);  // 5 s = one window
  EXPECT_NEAR(rms * rms, 100.0 * 100.0 * (1.0 - std::exp(-1.0)), 1.0);
  for (int i = 0; i < 5000; ++i) rms = load.add(100.0, 0.01);
  EXPECT_NEAR(rms, 100.0, 0.1);
  // Alternating sign: the RMS, not the mean.
  for (int i = 0; i < 10000; ++i) rms = load.add(i % 2 ? 50.0 : -50.0, 0.01);
  EXPECT_NEAR(rms, 50.0, 0.1);
  EXPECT_THROW(ThermalLoad(0.0), ModelError);
}

// A drive that has held a load: its RMS starts there and cools towards a lighter one with the
// window as time constant (mean square 100^2 -> 20^2 by e^-1 of the way in one window).
TEST(ThermalLoad, StartsWarmFromAHeldLoad) {
  ThermalLoad load(5.0);
  load.hold(-100.0);
  EXPECT_DOUBLE_EQ(load.rms(), 100.0);
  double rms = 0.0;
  for (int i = 0; i < 500; ++i) rms = load.add(20.0, 0.01);
  EXPECT_NEAR(rms * rms, 400.0 + (10000.0 - 400.0) * std::exp(-1.0), 1.0);
}

TEST(FoldedBackTorque, PeakWhileCoolThenDownToTheContinuousTorque) {
  // The wheel drive of the demo robot (Table 1, Small B): peak 24, continuous 17.5 N m.
  const JointLimits wheel = joint(17.5, 24.0);
  EXPECT_DOUBLE_EQ(folded_back_torque(wheel, 0.0), 24.0);
  EXPECT_DOUBLE_EQ(folded_back_torque(wheel, 0.9 * 17.5), 24.0);
  EXPECT_NEAR(folded_back_torque(wheel, 0.95 * 17.5), 20.75, 1e-9);  // half way
  EXPECT_DOUBLE_EQ(folded_back_torque(wheel, 17.5), 17.5);
  EXPECT_DOUBLE_EQ(folded_back_torque(wheel, 30.0), 17.5);
}

TEST(FoldedBackTorque, AStalledDriveNeverReachesSafetysSustainedBound) {
  // A wheel scrubbing against the others asks its peak torque for a minute; the drive
  // delivers what the foldback allows. Its RMS over the thermal window must stay within the
  // continuous torque (safety stops at 1.1 x), yet the peak is there while the drive is cool.
  const JointLimits wheel = joint(17.5, 24.0);
  ThermalLoad load;
  load.add(0.0, 0.0);
  double largest = 0.0, first_second = 0.0;
  for (int k = 1; k <= 60000; ++k) {  // 60 s at 1 kHz
    const double tau = std::min(24.0, folded_back_torque(wheel, load.rms()));
    if (k <= 1000) first_second += tau / 1000.0;
    largest = std::max(largest, load.add(tau, 0.001));
  }
  EXPECT_NEAR(first_second, 24.0, 1e-9);
  EXPECT_LE(largest, 17.5 * 1.001);
  EXPECT_GT(load.rms(), 17.5 * 0.99);  // it still delivers its continuous torque
  EXPECT_LT(largest, sustained_torque_bound(wheel, 0.1));
}

}  // namespace
}  // namespace concert::model
