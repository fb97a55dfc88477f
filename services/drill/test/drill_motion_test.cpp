// DrillMotion (eq. 3) against a plant: the tip follows the impedance's reference through a
// spring-damper on a 15 kg effective mass, and a wall that resists as the simulator's does
// (threshold + feed damping). The plant is not the controller's code: its thrust comes from
// the stiffness and the reference's lead alone.

#include "drill/drill_motion.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace concert::drill {
namespace {

constexpr double kDt = 0.002;

// A wall facing -x at x = 1 (hole frame: z = -x, origin on the surface at y = 0.2, z = 1.1).
Eigen::Isometry3d hole_at(double y, double z) {
  Eigen::Isometry3d h = Eigen::Isometry3d::Identity();
  h.linear() << 0, 0, -1, -1, 0, 0, 0, 1, 0;  // x = -y_w, y = z_w, z = -x_w: right-handed
  h.translation() = Eigen::Vector3d(1.0, y, z);
  return h;
}

struct Plant {
  Eigen::Isometry3d tip = Eigen::Isometry3d::Identity();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double mass = 15.0;
  double wall_threshold = 20.0;  // [N]
  double wall_damping = 6000.0;  // [N s/m]
  double hole_bottom = 0.0;      // x of the deepest point drilled [m]
  double wall_x = 1.0;           // x of the wall's face [m]
  double at_bottom = 1e-9;       // the tip this close to the hole's bottom cuts [m]

  // One step under the reference (translational impedance only; the orientation follows).
  void step(const CartesianReference& r) {
    Eigen::Vector3d f =
        r.stiffness.head<3>().cwiseProduct(r.pose.translation() - tip.translation()) +
        r.damping.head<3>().cwiseProduct(r.twist.head<3>() - velocity);
    const double x = tip.translation().x();
    const bool cutting =
        x >= wall_x && x >= hole_bottom - at_bottom && (f.x() > 0.0 || velocity.x() > 0.0);
    if (cutting) {
      // At the bottom of the hole: the wall takes up to the threshold, and its feed damping
      // is taken implicitly so the step is stable.
      const double net = f.x() - std::clamp(f.x(), 0.0, wall_threshold);
      velocity.x() = (mass * velocity.x() + net * kDt) / (mass + wall_damping * kDt);
      if (velocity.x() < 0.0 && f.x() > 0.0) velocity.x() = 0.0;
    } else {
      velocity.x() += f.x() / mass * kDt;
    }
    velocity.y() += f.y() / mass * kDt;
    velocity.z() += f.z() / mass * kDt;
    tip.translation() += velocity * kDt;
    hole_bottom = std::max(hole_bottom, tip.translation().x());
    tip.linear() = r.pose.linear();
  }
};

// Runs until the phase leaves `phase` or `seconds` pass; returns the time taken.
double run(DrillMotion& m, Plant& p, double& now, double seconds) {
  const DrillMotion::Phase start = m.phase();
  const double t0 = now;
  while (m.phase() == start && now - t0 < seconds) {
    p.step(m.update(p.tip, now));
    now += kDt;
  }
  return now - t0;
}

// Drills (the motion in its drilling phase) until it leaves it or 60 s pass; returns the
// reference's largest lead on the tip along the bit [m].
double drill_until_done(DrillMotion& m, Plant& p, double& now) {
  double largest_lead = 0.0;
  while (m.phase() == DrillMotion::Phase::kDrilling && now < 60.0) {
    const CartesianReference r = m.update(p.tip, now);
    largest_lead = std::max(largest_lead, r.pose.translation().x() - p.tip.translation().x());
    p.step(r);
    now += kDt;
  }
  return largest_lead;
}

Plant plant_in_front(double x) {
  Plant p;
  p.tip.translation() = Eigen::Vector3d(x, 0.25, 1.05);
  // The bit along +x, slightly tilted.
  p.tip.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                   Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  p.hole_bottom = 1.0;
  return p;
}

// The bit square to a wall whose face is at `wall` [m], aligned on the hole the camera put at
// x = 1 (hole_at(0.25, 1.05)).
Plant aligned(DrillMotion& m, const DrillParams& params, double& now, double wall = 1.0) {
  Plant p = plant_in_front(1.0 - params.standoff);
  p.tip.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  p.wall_x = wall;
  p.hole_bottom = wall;
  m.start_align(hole_at(0.25, 1.05), p.tip, now);
  run(m, p, now, 10.0);
  return p;
}

TEST(DrillMotion, AlignsOnTheHolesAxisAtTheStandoffWithoutJumps) {
  DrillParams params;
  DrillMotion m(params);
  Plant p = plant_in_front(0.8);
  double now = 0.0;
  m.start_align(hole_at(0.2, 1.1), p.tip, now);
  Eigen::Vector3d last_ref = p.tip.translation();
  double largest_step = 0.0;
  while (m.phase() == DrillMotion::Phase::kAligning && now < 20.0) {
    const CartesianReference r = m.update(p.tip, now);
    largest_step = std::max(largest_step, (r.pose.translation() - last_ref).norm());
    last_ref = r.pose.translation();
    p.step(r);
    now += kDt;
  }
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
  EXPECT_LE(largest_step, params.approach_speed * kDt + 1e-9);
  EXPECT_LT(m.lateral_error(p.tip), params.align_tolerance);
  EXPECT_NEAR(m.depth_of(p.tip), -params.standoff, params.align_tolerance);
  EXPECT_GT(p.tip.linear().col(2).dot(Eigen::Vector3d::UnitX()), std::cos(params.align_angle));
}

TEST(DrillMotion, DrillsToDepthWithBoundedThrust) {
  DrillParams params;
  DrillMotion m(params);
  Plant p = plant_in_front(1.0 - params.standoff);
  p.tip.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  double now = 0.0;
  m.start_align(hole_at(0.25, 1.05), p.tip, now);
  run(m, p, now, 10.0);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone);
  m.start_drill(0.05, false, p.tip, now);
  const double largest_lead = drill_until_done(m, p, now);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
  EXPECT_GE(p.hole_bottom - 1.0, 0.05);
  EXPECT_LT(p.hole_bottom - 1.0, 0.056);
  EXPECT_LE(largest_lead, params.max_lead + 1e-9);  // thrust <= 8000 N/m x 15 mm = 120 N
  m.start_retract(p.tip, now);
  run(m, p, now, 10.0);
  EXPECT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
  EXPECT_LT(p.tip.translation().x(), 1.0 - params.standoff + 2 * params.align_tolerance);
}

// The base creeps back under the thrust (a wheel's velocity loop yields to a steady force;
// odometry sees it): the hole, moved in the base frame as the base moves (move_base), is still
// cut to depth. Held in the base frame it would recede with the base, 2 mm a second here.
TEST(DrillMotion, ABaseCreepingBackUnderTheThrustIsFollowed) {
  const DrillParams params;
  DrillMotion m(params);
  double now = 0.0;
  Plant p = aligned(m, params, now);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone);
  m.start_drill(0.03, false, p.tip, now);
  constexpr double kCreep = 0.002;  // [m/s]: in the base frame the wall recedes along +x
  p.at_bottom = 2.0 * kCreep * kDt;  // the bottom recedes by this each step
  double receded = 0.0;
  while (m.phase() == DrillMotion::Phase::kDrilling && now < 60.0) {
    p.wall_x += kCreep * kDt;
    p.hole_bottom += kCreep * kDt;
    receded += kCreep * kDt;
    m.move_base(Eigen::Isometry3d(Eigen::Translation3d(kCreep * kDt, 0.0, 0.0)));
    p.step(m.update(p.tip, now));
    now += kDt;
  }
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
  EXPECT_GT(receded, 0.005);
  EXPECT_GE(p.hole_bottom - p.wall_x, 0.03 - 1e-3) << "receded " << receded;
  EXPECT_NEAR(m.hole().translation().y(), 0.25, 1e-9);  // on its axis still
}

// The light drillings (light_drilling: for holes where the arm cannot hold the full thrust;
// half the lead, and kLightestLead for morphology A's row at 0.35 m) feel the wall where it is
// and cut it to depth, their thrust about that fraction of the full bound.
TEST(DrillMotion, ALightDrillingCutsTheWallAtAFractionOfTheThrust) {
  const DrillParams full;
  for (const double lead : {0.5, kLightestLead}) {
    const DrillParams params = light_drilling(full, lead);
    EXPECT_LT(thrust_bound(params), (lead + 0.05) * thrust_bound(full)) << lead;
    // The bit still feels the wall: its lead can reach past the contact's.
    EXPECT_GE(params.max_lead, params.contact_lead + kLeadOverContact - 1e-12) << lead;
    DrillMotion m(params);
    double now = 0.0;
    Plant p = aligned(m, params, now);
    ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
    m.start_drill(0.03, false, p.tip, now);
    const double started = now;
    const double largest_lead = drill_until_done(m, p, now);
    ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << lead << ": " << m.reason();
    ASSERT_TRUE(m.contact()) << lead;
    EXPECT_LT(std::abs(m.contact_offset()), 0.002) << lead;  // the wall is where the camera put it
    EXPECT_GE(p.hole_bottom - 1.0, 0.03) << lead;
    EXPECT_LT(p.hole_bottom - 1.0, 0.036) << lead;
    EXPECT_LE(largest_lead, params.max_lead + 1e-6) << lead;
    // Slower than the feed rate: the wall resists more than the light thrust feeds at 10 mm/s.
    EXPECT_GT(now - started, 0.03 / full.feed_rate) << lead;
    std::cout << "lead " << lead << ": " << thrust_bound(params) << " N at most, 30 mm in " << now - started
              << " s" << std::endl;
  }
  // Never lighter than the contact needs, however small the fraction asked.
  EXPECT_NEAR(light_drilling(full, 0.01).max_lead, full.contact_lead + kLeadOverContact, 1e-12);
}

// The drives' thermal foldback: at half the share the lead stays between the floor and the
// tuned one; at 0, in the wall, the feed stops with no lead and the time limit waits; back at 1
// the hole is cut to depth.
TEST(DrillMotion, AFoldedBackThrustLeadsLessAndAStoppedFeedPausesTheTimeLimit) {
  DrillParams params;
  params.drill_timeout = 12.0;
  DrillMotion m(params);
  double now = 0.0;
  Plant p = aligned(m, params, now);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
  m.start_drill(0.03, false, p.tip, now);
  m.set_thrust_share(0.5);
  const double floor = params.contact_lead + kLeadOverContact;
  double largest_lead = 0.0;
  const double started = now;
  while (now - started < 6.0) {  // the wall 40 mm ahead at 10 mm/s, then 2 s in it
    const CartesianReference r = m.update(p.tip, now);
    largest_lead = std::max(largest_lead, r.pose.translation().x() - p.tip.translation().x());
    p.step(r);
    now += kDt;
  }
  ASSERT_TRUE(m.contact());
  EXPECT_LE(largest_lead, floor + 0.5 * (params.max_lead - floor) + 1e-6);
  EXPECT_GT(largest_lead, floor);
  // Stopped for most of a time limit: the bit rests (no lead), nothing fails, nothing is cut.
  m.set_thrust_share(0.0);
  const double bottom = p.hole_bottom;
  double lead_at_rest = 1.0;
  for (int i = 0; i < static_cast<int>(0.9 * params.drill_timeout / kDt); ++i) {
    const CartesianReference r = m.update(p.tip, now);
    lead_at_rest = r.pose.translation().x() - p.tip.translation().x();
    p.step(r);
    now += kDt;
  }
  EXPECT_EQ(m.phase(), DrillMotion::Phase::kDrilling) << m.reason();
  EXPECT_LT(lead_at_rest, 0.0005);
  EXPECT_LT(p.hole_bottom - bottom, 0.0005);
  EXPECT_NEAR(m.paused(), 0.9 * params.drill_timeout, 0.01);
  DrillMotion again = m;  // the same hole, its feed left standing
  Plant q = p;
  double later = now;
  m.set_thrust_share(1.0);
  drill_until_done(m, p, now);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
  EXPECT_GE(p.hole_bottom - 1.0, 0.03);
  // A drive that does not cool: after another time limit standing still, the hole fails.
  for (int i = 0; i < static_cast<int>(0.2 * params.drill_timeout / kDt) && again.phase() == DrillMotion::Phase::kDrilling; ++i) {
    q.step(again.update(q.tip, later));
    later += kDt;
  }
  ASSERT_EQ(again.phase(), DrillMotion::Phase::kFailed);
  EXPECT_EQ(again.reason().rfind("the feed stood still 12 s for the arm's drives to cool, in vain: hole ", 0), 0u)
      << again.reason();
}

// The camera's surface off along the normal (a re-measure after a base move: holes came out
// up to 20 mm short): the depth is counted from where the bit meets the wall.
TEST(DrillMotion, TheDepthIsCountedFromWhereTheBitMeetsTheWall) {
  for (const double wall : {1.015, 0.99}) {  // 15 mm behind the camera's surface, 10 mm before
    DrillParams params;
    DrillMotion m(params);
    double now = 0.0;
    Plant p = aligned(m, params, now, wall);  // the camera's surface: x = 1
    ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << wall;
    m.start_drill(0.03, false, p.tip, now);
    run(m, p, now, 30.0);
    ASSERT_EQ(m.phase(), DrillMotion::Phase::kDone) << wall << ": " << m.reason();
    EXPECT_TRUE(m.contact());
    EXPECT_NEAR(m.contact_offset(), wall - 1.0, 0.002) << wall;
    EXPECT_GE(p.hole_bottom - wall, 0.03) << wall;
    EXPECT_LT(p.hole_bottom - wall, 0.034) << wall;
    // The hole frame now starts on the wall: the retract ends the standoff in front of it.
    EXPECT_NEAR(m.hole().translation().x(), wall, 0.002);
    m.start_retract(p.tip, now);
    run(m, p, now, 10.0);
    EXPECT_EQ(m.phase(), DrillMotion::Phase::kDone) << m.reason();
    EXPECT_LT(p.tip.translation().x(), wall - params.standoff + 2 * params.align_tolerance);
  }
}

TEST(DrillMotion, NoWallWhereTheCameraSawItFailsWithTheReason) {
  DrillParams params;
  DrillMotion m(params);
  double now = 0.0;
  Plant p = aligned(m, params, now, 1.2);
  m.start_drill(0.03, false, p.tip, now);
  run(m, p, now, 30.0);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kFailed);
  EXPECT_FALSE(m.contact());
  EXPECT_NE(m.reason().find("no wall felt 60 mm behind"), std::string::npos) << m.reason();
  EXPECT_LT(p.tip.translation().x(), 1.0 + 0.06 + 0.002);  // it did not feed on
}

TEST(DrillMotion, AWallHarderThanTheArmPushesFailsWithTheReason) {
  DrillParams params;
  params.drill_timeout = 3.0;
  DrillMotion m(params);
  double now = 0.0;
  Plant p = aligned(m, params, now);
  p.wall_threshold = 1000.0;  // more than stiffness x max_lead
  m.start_drill(0.05, false, p.tip, now);
  run(m, p, now, 10.0);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kFailed);
  EXPECT_NE(m.reason().find("resists"), std::string::npos) << m.reason();
}

TEST(DrillMotion, ServoingFollowsTheBlobUntilTheBitIsInTheWall) {
  DrillMotion m;
  Plant p = plant_in_front(0.9);
  double now = 0.0;
  m.start_align(hole_at(0.25, 1.05), p.tip, now);
  EXPECT_TRUE(m.observe(hole_at(0.255, 1.05)));  // 5 mm: a better estimate
  EXPECT_FALSE(m.observe(hole_at(0.4, 1.05)));   // 15 cm: another blob, not this one
  EXPECT_NEAR(m.hole().translation().y(), 0.255, 1e-12);
  run(m, p, now, 10.0);
  m.start_drill(0.05, true, p.tip, now);
  EXPECT_TRUE(m.observe(hole_at(0.256, 1.05)));
  while (m.phase() == DrillMotion::Phase::kDrilling && m.depth_of(p.tip) < 0.005 && now < 60.0) {
    p.step(m.update(p.tip, now));
    now += kDt;
  }
  EXPECT_FALSE(m.observe(hole_at(0.257, 1.05)));  // in the wall: the hole holds the bit
  EXPECT_NEAR(m.hole().translation().y(), 0.256, 1e-12);
}

TEST(DrillMotion, NotAlignedInTimeSaysHowFarOff) {
  DrillParams params;
  params.align_timeout = 0.5;
  DrillMotion m(params);
  Plant p = plant_in_front(0.5);  // 0.46 m to go at 0.05 m/s
  double now = 0.0;
  m.start_align(hole_at(0.25, 1.05), p.tip, now);
  run(m, p, now, 5.0);
  ASSERT_EQ(m.phase(), DrillMotion::Phase::kFailed);
  EXPECT_NE(m.reason().find("not aligned after 0.5 s"), std::string::npos) << m.reason();
}

}  // namespace
}  // namespace concert::drill
