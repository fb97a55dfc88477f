// The drill's own joint-space paths (drill/paths.hpp), without DDS: the measured state a path
// starts from, the base kept where it stands, settle times, a path backwards, the way back
// through every hole's posture and back from a look.
#include "drill/paths.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace concert::drill {
namespace {

const std::vector<std::string> kNames{"base_x", "base_y", "base_yaw", "J1_E"};

PathSample sample(std::vector<double> q, double t = 0.0, double v = 0.1) {
  PathSample s;
  s.time = t;
  s.velocity.assign(q.size(), v);
  s.position = std::move(q);
  return s;
}

JointSample measured(double x, double y, double yaw, double j1) {
  JointSample s;
  s.odometry = Eigen::Vector3d(x, y, yaw);
  s.joints.names = {"J1_E", "J2_E"};
  s.joints.positions = {j1, -1.0};
  return s;
}

// A settle onto a hole's posture leaves a base that stands within a few cm of the posture's
// where it is (the legs would swing round for a move smaller than the disturbance they cause);
// one farther off, or turned farther, is driven back.
TEST(DrillPaths, ASettleKeepsTheBaseWhereItStandsWhenItIsNearThePosture) {
  const PathSample here = sample({1.512, -0.205, 0.31, 0.2});
  std::vector<PathSample> settle{here, sample({1.5, -0.2, 0.3, 0.5})};
  ASSERT_TRUE(keep_base(kNames, here, settle, 0.03));
  EXPECT_EQ(settle.back().position, (std::vector<double>{1.512, -0.205, 0.31, 0.5}));
  EXPECT_EQ(settle.back().velocity, (std::vector<double>{0.0, 0.0, 0.0, 0.1}));
  // 4 cm off: driven back.
  std::vector<PathSample> far{here, sample({1.472, -0.2, 0.3, 0.5})};
  EXPECT_FALSE(keep_base(kNames, here, far, 0.03));
  EXPECT_EQ(far.back().position, (std::vector<double>{1.472, -0.2, 0.3, 0.5}));
  // Turned 0.05 rad: driven back.
  std::vector<PathSample> turned{here, sample({1.5, -0.2, 0.36, 0.5})};
  EXPECT_FALSE(keep_base(kNames, here, turned, 0.03));
  EXPECT_DOUBLE_EQ(turned.back().position[2], 0.36);
  // A path whose base goes farther on the way, though it ends near: driven as planned.
  std::vector<PathSample> out_and_back{here, sample({1.6, -0.2, 0.3, 0.4}), sample({1.5, -0.2, 0.3, 0.5})};
  EXPECT_FALSE(keep_base(kNames, here, out_and_back, 0.03));
  EXPECT_DOUBLE_EQ(out_and_back[1].position[0], 1.6);
  // No bound: always kept (the arm-alone look).
  EXPECT_TRUE(keep_base(kNames, here, far));
  EXPECT_DOUBLE_EQ(far.back().position[0], 1.512);

  // settle_path says how far off the base was kept, and ends at rest after settle_time.
  const Path posture{kNames, {sample({1.0, 0.0, 0.0, 0.0}, 0.0), sample({1.5, -0.2, 0.3, 0.5}, 2.0)}};
  const Settle kept = settle_path(posture, here);
  ASSERT_TRUE(kept.base_kept);
  EXPECT_NEAR(kept.base_off, std::hypot(0.012, 0.005), 1e-12);
  EXPECT_NEAR(kept.base_turn, 0.01, 1e-12);
  EXPECT_NEAR(kept.samples.back().time, 3.0 * 0.3 / 0.5, 1e-12);  // J1_E 0.3 rad at a third of 0.5 rad/s
  EXPECT_EQ(kept.samples.back().velocity, std::vector<double>(4, 0.0));
}

// The measured state a drill trajectory starts from: odometry's yaw is wrapped to (-pi, pi], a
// plan's is not. A robot facing -x measured -3.14 where its posture said 3.13: the straight line
// between them turned the base a whole turn with the bit at the wall (a CI run's safety stop).
TEST(DrillPaths, TheMeasuredYawIsTakenWithinHalfATurnOfThePlannedOne) {
  JointSample s = measured(1.5, -0.2, -3.14, 0.4);
  PathSample planned = sample({1.52, -0.21, 3.13, 0.5});
  const PathSample here = sample_here(kNames, s, planned);
  ASSERT_EQ(here.position.size(), 4u);
  EXPECT_DOUBLE_EQ(here.position[0], 1.5);
  EXPECT_DOUBLE_EQ(here.position[1], -0.2);
  EXPECT_NEAR(here.position[2], 2.0 * M_PI - 3.14, 1e-12);  // 3.1432: 0.013 rad from 3.13
  EXPECT_DOUBLE_EQ(here.position[3], 0.4);
  EXPECT_EQ(here.velocity, std::vector<double>(4, 0.0));
  // A plan two turns on (the planner keeps yaw near its start's): the same yaw two turns on.
  planned.position[2] = 4.0 * M_PI + 0.1;
  s.odometry.z() = 0.12;
  EXPECT_NEAR(sample_here(kNames, s, planned).position[2], 4.0 * M_PI + 0.12, 1e-12);
  // Time to settle from there: 0.02 rad at 1/3 of 0.5 rad/s, at least a second.
  planned.position[2] = 3.13;
  s.odometry.z() = -3.14;
  EXPECT_LT(settle_time(kNames, sample_here(kNames, s, planned), planned), 1.01);
}

// The way back from the holes: from where the robot stands, through every hole's path reversed,
// last hole first, each with a settling lead-in and its velocities negated.
TEST(DrillPaths, TheWayBackRunsEveryHolesPathBackwardsLastFirst) {
  const Path first{kNames, {sample({1.5, -0.2, 0.3, 0.0}, 0.0), sample({1.5, -0.2, 0.3, 0.4}, 2.0)}};
  const Path second{kNames, {sample({1.5, -0.2, 0.3, 0.4}, 0.0), sample({1.5, -0.2, 0.3, 0.8}, 1.5)}};
  const std::vector<PathSample> back = return_path({first, second}, measured(1.51, -0.2, 0.3, 0.79));
  ASSERT_EQ(back.size(), 5u);
  EXPECT_DOUBLE_EQ(back[0].time, 0.0);
  EXPECT_DOUBLE_EQ(back[0].position[3], 0.79);  // where the arm is
  EXPECT_DOUBLE_EQ(back[1].time, 1.0);          // a settling second onto the second path's end
  EXPECT_DOUBLE_EQ(back[1].position[3], 0.8);
  EXPECT_DOUBLE_EQ(back[1].velocity[3], -0.1);
  EXPECT_DOUBLE_EQ(back[2].time, 2.5);
  EXPECT_DOUBLE_EQ(back[2].position[3], 0.4);
  EXPECT_DOUBLE_EQ(back[3].time, 3.5);          // then the first path from its end
  EXPECT_DOUBLE_EQ(back[4].time, 5.5);
  EXPECT_DOUBLE_EQ(back[4].position[3], 0.0);
  for (const PathSample& p : back) EXPECT_DOUBLE_EQ(p.position[0], 1.51);  // base kept (1 cm)

  // Back from a look: its path reversed onto the posture it started from, at rest there.
  const Path look{kNames, {sample({1.5, -0.2, 0.3, 0.8}, 0.0), sample({1.5, -0.2, 0.3, 1.1}, 1.0)}};
  const std::vector<PathSample> from_look = back_from_look(look, second, measured(1.5, -0.2, 0.3, 1.1));
  ASSERT_EQ(from_look.size(), 4u);
  EXPECT_DOUBLE_EQ(from_look[2].position[3], 0.8);
  EXPECT_DOUBLE_EQ(from_look.back().position[3], 0.8);
  EXPECT_EQ(from_look.back().velocity, std::vector<double>(4, 0.0));
  EXPECT_DOUBLE_EQ(from_look.back().time, from_look[2].time + 1.0);
}

}  // namespace
}  // namespace concert::drill
