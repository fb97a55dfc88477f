// Simulated drilling (drilling.hpp): a bit on a two-axis carriage (feed along x, lateral along
// y) pushed into a wall by effort commands. Checked against the model's own physics: no
// advance under the thrust threshold, feed rate = (thrust - threshold) / feed damping above
// it, the hole's entry on the face, the tip held on the hole's axis, re-entry into the same hole.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "concert/sim/sim_hardware.hpp"

namespace concert::sim {
namespace {

using hardware::DriveCommand;
using hardware::DriveMode;

// A fixed frame carrying a 20 kg carriage (a drill and the arm's wrist) on a feed (x) and a
// lateral (y) slide; the bit's tip 0.1 m ahead of the carriage, its z axis along +x. The tip
// starts at x = 0.895 m, y = 0.2 m, z = 1.0 m, 5 mm before the wall's face at x = 0.9 m.
const char* kUrdf = R"(<?xml version="1.0"?>
<robot name="rig">
  <link name="frame"/>
  <link name="slide"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="carriage"><inertial><mass value="20"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"/>
  <joint name="lateral" type="prismatic"><parent link="frame"/><child link="slide"/>
    <origin xyz="0.795 0.2 1.0"/><axis xyz="0 1 0"/><limit lower="-0.5" upper="0.5" effort="500" velocity="1"/></joint>
  <joint name="feed" type="prismatic"><parent link="slide"/><child link="carriage"/>
    <axis xyz="1 0 0"/><limit lower="-0.5" upper="0.5" effort="500" velocity="1"/></joint>
  <joint name="fixed_tip" type="fixed"><parent link="carriage"/><child link="tip"/>
    <origin xyz="0.1 0 0" rpy="0 1.5707963267948966 0"/></joint>
</robot>)";

World wall_world() {
  World w;
  world::WorldShape wall;
  wall.name = "wall";
  wall.size = {0.2, 4.0, 3.0};
  wall.position = {1.0, 0.0, 1.5};
  w.walls.push_back(wall);
  return w;
}

class Drilling : public ::testing::Test {
 protected:
  Drilling() : sim_(kUrdf, wall_world(), params(), {}, {DrillBit{"tip", 0.012}}) {}

  static SimParams params() {
    SimParams p;
    p.floating_base = false;
    p.sensors.enabled = false;
    return p;
  }

  // Pushes with `feed` [N] along x and `lateral` [N] along y for `seconds`.
  void push(double feed, double lateral, double seconds) {
    std::vector<DriveCommand> c(2);
    const auto& names = sim_.joint_names();
    for (std::size_t i = 0; i < names.size(); ++i) {
      c[i].mode = DriveMode::kEffort;
      c[i].effort = names[i] == "feed" ? feed : lateral;
    }
    for (int k = 0; k < static_cast<int>(std::lround(seconds / 0.001)); ++k) {
      sim_.write(c);
      sim_.step(0.001);
    }
  }

  [[nodiscard]] Eigen::Vector3d tip() const { return sim_.link_pose("tip").translation(); }

  SimHardware sim_;
};

TEST_F(Drilling, NoHoleBeforeTheBitReachesTheWall) {
  push(0.0, 0.0, 0.2);
  EXPECT_TRUE(sim_.holes().empty());
  EXPECT_NEAR(tip().x(), 0.895, 1e-6);
}

TEST_F(Drilling, BelowTheThresholdTheBitRestsAtTheSurface) {
  push(10.0, 0.0, 2.0);  // half the 20 N threshold
  ASSERT_EQ(sim_.holes().size(), 1u);
  const SimHole h = sim_.holes()[0];
  EXPECT_LT(h.depth, 1.5e-3);  // the impact at ~0.07 m/s and the 10 N hold, no cutting
  EXPECT_LT(tip().x(), 0.9 + 1.5e-3);
}

TEST_F(Drilling, FeedRateFollowsTheThrustAndTheHoleStartsOnTheFace) {
  const DrillingParams model;
  push(30.0, 0.0, 0.5);  // reach the wall
  const double x0 = tip().x();
  const double thrust = 80.0;
  push(thrust, 0.0, 2.0);
  const double rate = (tip().x() - x0) / 2.0;
  const double expected = (thrust - model.thrust_threshold) / model.feed_damping;  // 10 mm/s
  EXPECT_NEAR(rate, expected, 0.1 * expected);
  ASSERT_EQ(sim_.holes().size(), 1u);
  const SimHole h = sim_.holes()[0];
  EXPECT_EQ(h.wall, "wall");
  EXPECT_EQ(h.bit, "tip");
  EXPECT_NEAR(h.entry.x(), 0.9, 1e-9);
  EXPECT_NEAR(h.entry.y(), 0.2, 1e-4);
  EXPECT_NEAR(h.entry.z(), 1.0, 1e-4);
  EXPECT_TRUE(h.axis.isApprox(Eigen::Vector3d::UnitX(), 1e-4));
  EXPECT_TRUE(h.face_normal.isApprox(-Eigen::Vector3d::UnitX(), 1e-9));
  EXPECT_NEAR(h.depth, tip().x() - 0.9, 2e-4);
  EXPECT_NEAR(h.diameter, 0.012, 1e-12);
}

TEST_F(Drilling, TheHoleHoldsTheBitOnItsAxis) {
  push(80.0, 0.0, 2.5);  // ~20 mm deep
  const double y_in = tip().y();
  push(20.0, 40.0, 1.0);  // 40 N sideways in the hole: 40 N / 2e4 N/m = 2 mm
  EXPECT_NEAR(tip().y() - y_in, 40.0 / DrillingParams{}.lateral_stiffness, 3e-4);
}

TEST_F(Drilling, APulledOutBitComesBackIntoTheSameHole) {
  push(80.0, 0.0, 2.5);
  push(-40.0, 0.0, 1.0);  // pull out
  EXPECT_LT(tip().x(), 0.9);
  push(80.0, 0.0, 1.5);                // back in
  EXPECT_EQ(sim_.holes().size(), 1u);  // the same hole
}

TEST(DrillingModel, AnUnknownBitLinkIsRefusedByName) {
  SimParams p;
  p.floating_base = false;
  p.sensors.enabled = false;
  try {
    SimHardware sim(kUrdf, wall_world(), p, {}, {DrillBit{"no_such_tcp", 0.012}});
    FAIL() << "accepted an unknown bit link";
  } catch (const hardware::HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_tcp"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace concert::sim
