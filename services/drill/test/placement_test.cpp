// An area's base placement (include/drill/placement.hpp): the goal its postures are drawn for,
// and the choice between standing and moving as the planner's answers come in.

#include "drill/placement.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "drill/mission.hpp"

namespace concert::drill {
namespace {

using Next = PlacementChoice::Next;

// A 60 cm row of 4 holes 0.2 m apart on a wall whose outward normal is `normal`, centred at
// `centre`, as find_holes() lays a pattern (x along the row, z out of the wall).
std::vector<DrillPoint> row(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal) {
  const Eigen::Vector3d z = normal.normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(z).normalized();
  std::vector<DrillPoint> out;
  for (int i = 0; i < 4; ++i) {
    DrillPoint p;
    p.frame.linear().col(0) = x;
    p.frame.linear().col(1) = z.cross(x);
    p.frame.linear().col(2) = z;
    p.frame.translation() = centre + (-0.3 + 0.2 * i) * x;
    p.label = "aruco 0 hole " + std::to_string(i + 1);
    p.marker = 0;
    p.pattern_index = i;
    out.push_back(p);
  }
  return out;
}

TEST(PlacementGoal, IsTheRowsCentreWithItsNormalXHorizontalAndYUp) {
  // Scenario 3's row at 1.5 m on the bench wall (face -x at 2.2 m), and the same row on a wall
  // turned 20 deg about the vertical.
  for (const double turn : {0.0, 20.0 * M_PI / 180.0}) {
    const Eigen::Vector3d normal(-std::cos(turn), std::sin(turn), 0.0);
    const Eigen::Vector3d centre(2.2, -0.3, 1.5);
    const Eigen::Isometry3d goal = placement_goal(row(centre, normal));
    EXPECT_LT((goal.translation() - centre).norm(), 1e-12) << "turn " << turn;
    EXPECT_LT((goal.linear().col(2) - normal).norm(), 1e-12) << "turn " << turn;
    EXPECT_NEAR(goal.linear().col(0).z(), 0.0, 1e-12) << "x is horizontal";
    EXPECT_GT(goal.linear().col(1).z(), 0.999) << "y is up on a vertical wall";
    EXPECT_TRUE(goal.linear().isUnitary(1e-12));
    EXPECT_GT(goal.linear().determinant(), 0.0) << "a right-handed frame";
  }
}

TEST(PlacementGoal, AveragesTheNormalsOfHolesMeasuredApart) {
  // Holes re-measured one by one come with normals a few tenths of a degree apart.
  std::vector<DrillPoint> holes = row({2.2, 0.0, 1.0}, {-1.0, 0.0, 0.0});
  const Eigen::AngleAxisd tilt(0.01, Eigen::Vector3d::UnitY());
  holes[0].frame.linear() = tilt.toRotationMatrix() * holes[0].frame.linear();
  holes[3].frame.linear() = tilt.inverse().toRotationMatrix() * holes[3].frame.linear();
  const Eigen::Isometry3d goal = placement_goal(holes);
  EXPECT_NEAR(goal.linear().col(2).x(), -1.0, 1e-4);
  EXPECT_NEAR(goal.linear().col(2).z(), 0.0, 1e-12) << "the two tilts cancel";
}

TEST(PlacementGoal, MovesTowardsTheMarkAlongTheWallOnly) {
  const std::vector<DrillPoint> holes = row({2.2, -0.3, 1.5}, {-1.0, 0.0, 0.0});
  // The marker 15 cm above the row, its centre 1 mm in front of the wall (a printed mark).
  const Eigen::Vector3d marker(2.199, -0.3, 1.65);
  const Eigen::Isometry3d half = placement_goal(holes, marker, 0.5);
  EXPECT_LT((half.translation() - Eigen::Vector3d(2.2, -0.3, 1.575)).norm(), 1e-12)
      << half.translation().transpose();
  EXPECT_LT((placement_goal(holes, marker, 0.0).translation() - Eigen::Vector3d(2.2, -0.3, 1.5)).norm(), 1e-12);
  EXPECT_LT((placement_goal(holes, std::nullopt, 0.5).translation() - Eigen::Vector3d(2.2, -0.3, 1.5)).norm(),
            1e-12) << "no mark: the holes' centre";
}

TEST(PlacementGoal, RefusesNoHolesAndHolesFacingUp) {
  EXPECT_THROW(placement_goal({}), DrillError);
  EXPECT_THROW(placement_goal(row({1.0, 0.0, 0.0}, {0.0, 0.0, 1.0})), DrillError);
  try {
    placement_goal(row({1.0, 0.0, 0.0}, {0.1, 0.0, 1.0}));
    ADD_FAILURE() << "a floor's holes were placed for";
  } catch (const DrillError& e) {
    EXPECT_NE(std::string(e.what()).find("face up or down"), std::string::npos) << e.what();
  }
}

TEST(ReachedFirst, PutsTheHolesTheArmReachesFirstInTheirOrder) {
  EXPECT_EQ(reached_first({false, true, true, false}), (std::vector<std::size_t>{1, 2, 0, 3}));
  EXPECT_EQ(reached_first({true, true}), (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(reached_first({false, false, false}), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_TRUE(reached_first({}).empty());
}

TEST(PlacementChoice, StandsWhenTheArmAloneReachesEveryHoleFromWhereTheBaseStands) {
  PlacementChoice c(4, 3);
  EXPECT_EQ(c.next(), Next::kCheckStanding);
  c.standing(4);
  EXPECT_EQ(c.next(), Next::kStand);
  EXPECT_EQ(c.draws(), 0u);
}

TEST(PlacementChoice, TakesTheFirstDrawnPostureReachingEveryHoleWithALook) {
  PlacementChoice c(4, 3);
  c.standing(0);
  EXPECT_EQ(c.next(), Next::kDraw);
  c.drawn(3, true);
  EXPECT_EQ(c.next(), Next::kDraw) << "3 of 4: another draw may reach them all";
  c.drawn(4, true);
  EXPECT_EQ(c.next(), Next::kMove);
  EXPECT_EQ(c.chosen(), 1u);
  EXPECT_EQ(c.draws(), 2u) << "no third draw once one reaches every hole";
}

TEST(PlacementChoice, NeverMovesToAPostureWithoutALook) {
  PlacementChoice c(4, 2);
  c.standing(1);
  c.drawn(4, false);
  EXPECT_EQ(c.next(), Next::kDraw);
  c.drawn(4, false);
  EXPECT_EQ(c.next(), Next::kStand) << "every hole reached, but drilled where odometry puts it";
  EXPECT_NE(c.summary().find("4 of 4 without a look"), std::string::npos) << c.summary();
}

TEST(PlacementChoice, AfterEveryDrawMovesToTheBestWithALookOnlyIfItReachesMoreThanStanding) {
  {
    PlacementChoice c(4, 3);
    c.standing(1);
    c.drawn(2, true);
    c.drawn(0, false);  // no posture found
    c.drawn(3, true);
    EXPECT_EQ(c.next(), Next::kMove);
    EXPECT_EQ(c.chosen(), 2u);
  }
  {
    PlacementChoice c(4, 3);
    c.standing(2);
    c.drawn(2, true);
    c.drawn(1, true);
    c.drawn(2, true);
    EXPECT_EQ(c.next(), Next::kStand) << "no drawn posture reaches more than standing: no move";
  }
  {
    PlacementChoice c(4, 2);
    c.standing(0);
    c.drawn(3, true);
    c.drawn(3, true);
    EXPECT_EQ(c.next(), Next::kMove);
    EXPECT_EQ(c.chosen(), 0u) << "the first of equals";
  }
}

TEST(PlacementChoice, IsShortOfEveryHoleOnlyWhenItEndsStandingWithoutThemAll) {
  {
    PlacementChoice c(4, 2);
    EXPECT_FALSE(c.short_of_every_hole()) << "nothing checked yet";
    c.standing(0);
    EXPECT_FALSE(c.short_of_every_hole()) << "draws still to come";
    c.drawn(0, false);
    c.drawn(4, false);
    EXPECT_TRUE(c.short_of_every_hole()) << "standing, no hole reached from there";
  }
  {
    PlacementChoice c(4, 2);
    c.standing(4);
    EXPECT_FALSE(c.short_of_every_hole()) << "standing reaches them all";
  }
  {
    PlacementChoice c(4, 2);
    c.standing(0);
    c.drawn(2, true);
    c.drawn(1, true);
    EXPECT_EQ(c.next(), Next::kMove);
    EXPECT_FALSE(c.short_of_every_hole()) << "a move to a posture with a look is taken as it is";
  }
}

TEST(PlacementChoice, SummaryNamesEveryCheck) {
  PlacementChoice c(4, 2);
  EXPECT_NE(c.summary().find("not checked"), std::string::npos) << c.summary();
  c.standing(0);
  c.drawn(4, true);
  EXPECT_EQ(c.summary(),
            "the arm alone reaches 0 of 4 holes from where the base stands; from the whole-body "
            "postures drawn: 4 of 4 with a look at the mark");
}

TEST(PlacementChoice, CountsNoMoreThanTheAreasHoles) {
  PlacementChoice c(2, 1);
  c.standing(5);
  EXPECT_EQ(c.next(), Next::kStand);
  EXPECT_NE(c.summary().find("2 of 2"), std::string::npos) << c.summary();
}

TEST(ReachSurvey, AHoleIsReachableAtTheFirstAttemptAnsweredWithAPosture) {
  ReachSurvey s(2, 3, 2);
  EXPECT_EQ(s.next(0), 0u);
  s.not_found(0, "no posture: self collision");  // a first try: the same attempt again
  EXPECT_EQ(s.next(0), 0u);
  s.not_found(0, "no posture: self collision");  // tries spent: the next attempt
  EXPECT_EQ(s.next(0), 1u);
  s.found(0, "at 35 % of the thrust");
  EXPECT_EQ(s.next(0), std::nullopt);
  EXPECT_FALSE(s.done()) << "hole 2 has no verdict yet";
  s.found(1, "at full thrust");
  ASSERT_TRUE(s.done());
  EXPECT_EQ(s.verdicts()[0].reach, Reach::kReachable);
  EXPECT_EQ(s.verdicts()[0].why, "at 35 % of the thrust");
  EXPECT_EQ(s.summary(), "2 of 2 holes reachable");
}

TEST(ReachSurvey, AHoleIsUnreachableOnlyOnceEveryAttemptsTriesFailedWithTheLastReason) {
  ReachSurvey s(1, 2, 2);
  for (int k = 0; k < 3; ++k) {
    s.not_found(0, "why " + std::to_string(k));
    EXPECT_FALSE(s.done()) << "after " << k + 1 << " failures of 4";
  }
  s.not_found(0, "no posture: J3_E 163.9 N m over 160 continuous");
  ASSERT_TRUE(s.done());
  EXPECT_EQ(s.verdicts()[0].reach, Reach::kUnreachable);
  EXPECT_EQ(s.summary(), "0 of 1 hole reachable; unreachable: hole 1 (no posture: J3_E 163.9 N m over 160 continuous)");
  s.found(0, "late answer");  // a verdict stands
  EXPECT_EQ(s.verdicts()[0].reach, Reach::kUnreachable);
}

TEST(ReachSurvey, APlannerThatCannotJudgeLeavesTheHoleUnknown) {
  ReachSurvey s(2, 1, 1);
  s.unknown(0, "the planner refused: another model");
  s.not_found(1, "no posture");
  ASSERT_TRUE(s.done());
  EXPECT_EQ(s.verdicts()[0].reach, Reach::kUnknown);
  EXPECT_EQ(s.verdicts()[1].reach, Reach::kUnreachable);
  EXPECT_EQ(s.summary(),
            "0 of 2 holes reachable; unreachable: hole 2 (no posture); not judged: hole 1 (the planner "
            "refused: another model)");
}

TEST(ReachSurvey, NoHolesIsDoneAndNoAttemptsIsRefused) {
  EXPECT_TRUE(ReachSurvey(0, 1, 1).done());
  EXPECT_THROW(ReachSurvey(1, 0, 1), DrillError);
  EXPECT_THROW(ReachSurvey(1, 1, 0), DrillError);
}

}  // namespace
}  // namespace concert::drill
