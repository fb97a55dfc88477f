// The simulated person (concert/world/person.hpp) against links whose motion the test computes:
// a robot that follows the pull (velocity = pull / b, an admittance), one that does not move, one
// pulled back. Simulated time at the robot's 1 kHz physics rate.
#include "concert/world/person.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace concert::world {
namespace {

constexpr double kDt = 0.001;

// A link that moves at pull / admittance_damping in the plane (a base in follow-me, roughly).
struct FollowingLink {
  Eigen::Vector3d p{1.0, 2.0, 0.9};
  Eigen::Vector3d v{Eigen::Vector3d::Zero()};
  double damping{100.0};  // [N s/m]
  void step(const Eigen::Vector3d& pull) {
    v = Eigen::Vector3d(pull.x(), pull.y(), 0.0) / damping;
    p += v * kDt;
  }
};

TEST(SimPerson, WalksTheRouteWithAFollowingRobotAndArrives) {
  SimPerson person;
  FollowingLink link;
  double t = 0.0;
  person.grip(t, link.p);
  EXPECT_EQ(person.phase(), PersonPhase::kHolding);
  person.walk(t, {link.p.head<2>() + Eigen::Vector2d(-3.0, 0.0)});
  EXPECT_DOUBLE_EQ(person.route_length(), 3.0);
  double walking_pull = 0.0;
  for (int i = 0; i < 60'000 && person.phase() != PersonPhase::kArrived; ++i) {
    t += kDt;
    const Eigen::Vector3d f = person.force(t, link.p, link.v);
    link.step(f);
    ASSERT_NE(person.phase(), PersonPhase::kLetGo) << person.reason();
    if (t > 3.0 && t < 5.0) walking_pull = f.head<2>().norm();
  }
  ASSERT_EQ(person.phase(), PersonPhase::kArrived);
  EXPECT_DOUBLE_EQ(person.walked(), 3.0);
  EXPECT_LT((link.p.head<2>() - Eigen::Vector2d(-2.0, 2.0)).norm(), 0.15);
  EXPECT_DOUBLE_EQ(link.p.z(), 0.9);
  // Walking steadily at 0.5 m/s, the link at 0.5 m/s: the pull is its damping x the speed.
  EXPECT_NEAR(walking_pull, 100.0 * 0.5, 1.0);
  EXPECT_NEAR(person.peak_pull(), 50.0, 2.0);
  // 1 s of ramp (half a second lost), 6 s at speed, the lag closed, 1 s at the end: about 8 s.
  EXPECT_GT(t, 7.0);
  EXPECT_LT(t, 9.5);
  EXPECT_TRUE(person.gripping());
}

TEST(SimPerson, WaitsForARobotThatLagsAndLetsGoOfOneThatFallsBehind) {
  SimPerson person;
  Eigen::Vector3d link(0.0, 0.0, 1.0);
  double t = 0.0;
  person.grip(t, link);
  person.walk(t, {{5.0, 0.0}});
  for (int i = 0; i < 10'000; ++i) person.force(t += kDt, link, Eigen::Vector3d::Zero());
  EXPECT_EQ(person.phase(), PersonPhase::kWaiting);
  EXPECT_NEAR(person.walked(), 0.6, 0.001);
  // Standing 0.6 m ahead: the spring's pull alone.
  EXPECT_NEAR(person.pull().x(), 150.0 * 0.6, 0.2);
  // The robot backs off 0.5 m: 1.1 m behind, past the person's reach.
  link.x() = -0.5;
  EXPECT_EQ(person.force(t += kDt, link, Eigen::Vector3d::Zero()), Eigen::Vector3d::Zero());
  EXPECT_EQ(person.phase(), PersonPhase::kLetGo);
  EXPECT_EQ(person.reason(), "the robot fell 1.10 m behind the hand (more than 1.00 m) after 0.60 of 5.00 m");
  EXPECT_FALSE(person.gripping());
  EXPECT_EQ(person.force(t += kDt, link, Eigen::Vector3d::Zero()), Eigen::Vector3d::Zero());
}

TEST(SimPerson, GuidesTheLinkThenHoldsIt) {
  SimPerson person;
  const Eigen::Vector3d link(0.5, 0.0, 1.0);
  double t = 10.0;
  person.grip(t, link, {0.1, 0.0, -0.1}, 2.0);
  EXPECT_EQ(person.phase(), PersonPhase::kGuiding);
  for (int i = 0; i < 1000; ++i) person.force(t += kDt, link, Eigen::Vector3d::Zero());
  // Half way: the hand 5 cm ahead and down, moving at 5 cm/s each way.
  EXPECT_NEAR(person.pull().x(), 150.0 * 0.05 + 30.0 * 0.05, 1e-6);
  EXPECT_NEAR(person.pull().z(), -(150.0 * 0.05 + 30.0 * 0.05), 1e-6);
  for (int i = 0; i < 1001; ++i) person.force(t += kDt, link, Eigen::Vector3d::Zero());
  EXPECT_EQ(person.phase(), PersonPhase::kHolding);
  EXPECT_TRUE(person.hand().isApprox(Eigen::Vector3d(0.6, 0.0, 0.9), 1e-12));
  EXPECT_NEAR(person.pull().x(), 150.0 * 0.1, 1e-9);
  person.let_go("asked");
  EXPECT_EQ(person.reason(), "asked");
  EXPECT_EQ(person.force(t += kDt, link, Eigen::Vector3d::Zero()), Eigen::Vector3d::Zero());
}

TEST(SimPerson, RefusesWhatItCannotDoNamingWhy) {
  SimPerson person;
  EXPECT_EQ(person.force(1.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()), Eigen::Vector3d::Zero());
  try {
    person.walk(0.0, {{1.0, 0.0}});
    FAIL() << "walked holding nothing";
  } catch (const std::logic_error& e) {
    EXPECT_STREQ(e.what(), "person: walk: the person holds nothing (grip first)");
  }
  person.grip(0.0, Eigen::Vector3d::Zero());
  EXPECT_THROW(person.walk(0.0, {}), std::invalid_argument);
  PersonParams p;
  p.wait_stretch = 1.2;
  try {
    SimPerson bad(p);
    FAIL() << "took a wait stretch beyond the let-go stretch";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "person: wait_stretch: expected a number in (0, let_go_stretch = 1), got 1.2");
  }
  EXPECT_STREQ(to_string(PersonPhase::kLetGo), "let go");
}

}  // namespace
}  // namespace concert::world
