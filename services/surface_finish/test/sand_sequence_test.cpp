// SandSequence: what a sanding run through the robot service commands when, its stops and its
// statistics, on a hand-made plan (no robot model needed).
#include "surface_finish/sand_sequence.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace concert::surface_finish {
namespace {

// A plan like plan_serpentine's for a disc (standoff 0, approach 5 cm): a joint move from
// 0.3 m off to 5 cm off (samples 0..3), the approach to the wall (1 s), one 2 s stroke up
// (x = 0, y 1.0 -> 1.2 at 0.1 m/s), the retreat back to 5 cm (1 s). The wall is the base
// frame's plane x = 1 facing the robot; the TCP's z points into it (+x).
SerpentinePlan test_plan() {
  SerpentinePlan plan;
  plan.rect = Rect{-0.1, 0.1, 1.0, 1.2};
  plan.tool = ToolSpec{Task::kSand, 0.0, 0.23, 0.1};
  plan.params.speed = 0.1;
  plan.params.approach = 0.05;
  plan.strokes.push_back(Stroke{0.0, 1.0, 1.2});
  Eigen::Matrix3d rot;
  rot << 0, 0, 1,  //
      -1, 0, 0,    //
      0, 1, 0;     // columns: x_tcp = -y_base... z_tcp = +x_base (into the wall)
  auto add = [&](double t, double off, double y, int stroke, bool on) {
    PathSample s;
    s.t = t;
    s.wall = Eigen::Vector3d(0.0, y, off);
    s.tcp.linear() = rot;
    s.tcp.translation() = Eigen::Vector3d(1.0 - off, 0.0, y);
    s.stroke = stroke;
    s.tool_on = on;
    plan.samples.push_back(s);
  };
  add(0.0, 0.3, 1.0, -1, false);
  add(1.0, 0.2, 1.0, -1, false);
  add(2.0, 0.1, 1.0, -1, false);
  add(3.0, 0.05, 1.0, -1, false);  // the approach pose
  add(3.5, 0.025, 1.0, -1, false);
  add(4.0, 0.0, 1.0, -1, false);  // on the wall
  for (int i = 1; i <= 20; ++i) add(4.0 + 0.1 * i, 0.0, 1.0 + 0.01 * i, 0, true);
  add(6.5, 0.025, 1.2, -1, false);
  add(7.0, 0.05, 1.2, -1, false);
  return plan;
}

TEST(SandSequence, RefusesANonPositiveForceNamingIt) {
  SandParams p;
  p.force = 0.0;
  try {
    SandSequence s(test_plan(), p);
    FAIL() << "a zero force was taken";
  } catch (const FinishError& e) {
    EXPECT_NE(std::string(e.what()).find("force setpoint must be positive (got 0 N)"),
              std::string::npos)
        << e.what();
  }
  p.force = -5.0;
  EXPECT_THROW(SandSequence(test_plan(), p), FinishError);
  SerpentinePlan no_stroke = test_plan();
  for (auto& s : no_stroke.samples) s.stroke = -1;
  EXPECT_THROW(SandSequence(no_stroke, SandParams{}), FinishError);
  SandParams wide;
  wide.contact_gap = 0.05;  // the plan's whole approach: the tool would never come nearer
  try {
    SandSequence(test_plan(), wide);
    ADD_FAILURE() << "a contact gap as long as the approach was accepted";
  } catch (const FinishError& e) {
    EXPECT_NE(std::string(e.what()).find("contact gap 0.050 m must be less than the plan's approach 0.050 m"),
              std::string::npos)
        << e.what();
  }
}

TEST(SandSequence, CommandsThePhasesInTurn) {
  SandParams p;  // 30 N, ramp 2 s, delay 1 s, unload 1 s
  SandSequence s(test_plan(), p);
  EXPECT_EQ(s.approach_index(), 3u);
  EXPECT_TRUE(s.normal().isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_EQ(s.phase(), SandPhase::kMove);
  s.set_move_progress(0.5);
  EXPECT_NEAR(s.progress(), 0.5 * 3.0 / 7.0, 1e-9);
  // Robot time starts at 100 s.
  s.start(100.0);
  SandCommand c = s.update(100.5);
  EXPECT_EQ(s.phase(), SandPhase::kApproach);
  EXPECT_FALSE(c.admittance);
  // Half-way to the contact gap (2 cm) in front of the wall: 1.5 cm of its 3 cm in 0.5 s.
  EXPECT_NEAR(c.target.translation().x(), 1.0 - 0.05 + 0.015, 1e-9);
  EXPECT_NEAR(c.velocity.x(), 0.03, 1e-9);
  EXPECT_DOUBLE_EQ(c.stiffness[0], 1500.0);
  EXPECT_NEAR(c.damping[0], 2.0 * std::sqrt(15000.0), 1e-9);
  c = s.update(102.0);  // 1 s in contact: half the ramp
  EXPECT_EQ(s.phase(), SandPhase::kContact);
  EXPECT_TRUE(c.admittance);
  EXPECT_NEAR(c.force_setpoint, 15.0, 1e-9);
  // The target stays the gap in front of the nominal surface: the admittance meets the wall.
  EXPECT_NEAR(c.target.translation().x(), 1.0 - 0.02, 1e-9);
  EXPECT_DOUBLE_EQ(c.admittance_gain, 0.01);
  c = s.update(103.5);  // ramped, held
  EXPECT_EQ(s.phase(), SandPhase::kContact);
  EXPECT_NEAR(c.force_setpoint, 30.0, 1e-9);
  c = s.update(105.0);  // 1 s into the stroke
  EXPECT_EQ(s.phase(), SandPhase::kStrokes);
  EXPECT_NEAR(c.force_setpoint, 30.0, 1e-9);
  EXPECT_NEAR(c.target.translation().z(), 1.1, 1e-9);
  EXPECT_NEAR(c.target.translation().x(), 1.0 - 0.02, 1e-9);
  EXPECT_NEAR(c.velocity.z(), 0.1, 1e-9);
  EXPECT_NEAR(c.velocity.x(), 0.0, 1e-9);
  c = s.update(106.5);  // 0.5 s into the unload
  EXPECT_EQ(s.phase(), SandPhase::kUnload);
  EXPECT_NEAR(c.force_setpoint, 15.0, 1e-9);
  EXPECT_NEAR(c.target.translation().z(), 1.2, 1e-9);
  c = s.update(107.5);  // 0.5 s into the retreat
  EXPECT_EQ(s.phase(), SandPhase::kRetreat);
  EXPECT_FALSE(c.admittance);
  // The admittance off, the target is still the gap in front of the wall: nothing pushes.
  EXPECT_NEAR(c.target.translation().x(), 1.0 - 0.025 - 0.02, 1e-9);
  const double before = s.progress();
  (void)s.update(109.0);
  EXPECT_EQ(s.phase(), SandPhase::kDone);
  EXPECT_TRUE(s.finished());
  EXPECT_GT(1.0, before);
  EXPECT_DOUBLE_EQ(s.progress(), 1.0);
}

TEST(SandSequence, AStalledTickDoesNotStretchAPhase) {
  SandSequence s(test_plan(), SandParams{});
  s.start(0.0);
  // One late tick: 1 s approach + 3 s contact + 0.5 s of the stroke.
  const SandCommand c = s.update(4.5);
  EXPECT_EQ(s.phase(), SandPhase::kStrokes);
  EXPECT_NEAR(c.target.translation().z(), 1.05, 1e-9);
}

// Feeds the estimate every 10 ms from t0 to t1 with f(t).
template <class F>
void feed(SandSequence& s, double t0, double t1, F f) {
  for (double t = t0; t < t1 - 1e-9; t += 0.01) {
    (void)s.update(t);
    s.add_force(t, f(t));
  }
}

TEST(SandSequence, StatisticsCountTheStrokeTimeOnly) {
  SandSequence s(test_plan(), SandParams{});
  s.start(0.0);
  // Approach and contact: far off the setpoint (not counted); strokes (4 s .. 6 s): 31 N but
  // 35 N during 0.4 s; unload and retreat: 0 N (not counted).
  feed(s, 0.0, 4.0, [](double t) { return 10.0 * t; });
  feed(s, 4.0, 6.0, [](double t) { return t >= 5.0 && t < 5.4 ? 35.0 : 31.0; });
  feed(s, 6.0, 9.0, [](double) { return 0.0; });
  ASSERT_EQ(s.phase(), SandPhase::kDone) << s.reason();
  const ForceStats st = s.stats();
  EXPECT_NEAR(st.duration, 2.0, 0.02);
  EXPECT_NEAR(st.within_fraction, 0.8, 0.02);
  EXPECT_NEAR(st.time_outside, 0.4, 0.02);
  EXPECT_NEAR(st.min, 31.0, 1e-9);
  EXPECT_NEAR(st.max, 35.0, 1e-9);
  EXPECT_NEAR(st.mean, 31.8, 0.05);
  const auto j = nlohmann::json::parse(s.report_json());
  EXPECT_EQ(j["state"], "done");
  EXPECT_NEAR(j["within_tolerance_percent"].get<double>(), 80.0, 2.0);
  EXPECT_NEAR(j["mean_n"].get<double>(), 31.8, 0.05);
}

TEST(SandSequence, AForceFarAboveTheBandLeavesTheWall) {
  SandSequence s(test_plan(), SandParams{});  // stop above 2 x 30 + 20 = 80 N for 50 ms
  s.start(0.0);
  feed(s, 0.0, 4.5, [](double) { return 30.0; });
  feed(s, 4.5, 4.54, [](double) { return 90.0; });  // 40 ms: not yet
  EXPECT_EQ(s.phase(), SandPhase::kStrokes);
  feed(s, 4.54, 4.58, [](double) { return 30.0; });
  feed(s, 4.58, 4.65, [](double) { return 90.0; });
  ASSERT_EQ(s.phase(), SandPhase::kLeaving);
  EXPECT_NE(s.reason().find("above 80.0 N"), std::string::npos) << s.reason();
  const double x0 = s.update(4.65).target.translation().x();
  const SandCommand c = s.update(5.15);  // half the leave time: 2.5 cm further off the wall
  EXPECT_FALSE(c.admittance);
  EXPECT_NEAR(c.target.translation().x(), x0 - 0.025, 1e-3);
  (void)s.update(5.7);
  EXPECT_EQ(s.phase(), SandPhase::kAborted);
  EXPECT_TRUE(s.finished());
}

TEST(SandSequence, LostContactWhileStrokingStops) {
  SandSequence s(test_plan(), SandParams{});
  s.start(0.0);
  feed(s, 0.0, 4.2, [](double) { return 30.0; });
  feed(s, 4.2, 5.3, [](double) { return 2.0; });
  ASSERT_EQ(s.phase(), SandPhase::kLeaving);
  EXPECT_NE(s.reason().find("contact lost"), std::string::npos) << s.reason();
}

// A user's abort in contact leaves the wall along the normal first, from where the TCP is
// measured (here 4 mm in front of the target the admittance pushed into the plaster), then
// ends aborted; during the joint move it stops at once.
TEST(SandSequence, AnAbortInContactLeavesTheWallAlongTheNormalFirst) {
  SandSequence s(test_plan(), SandParams{});
  s.start(0.0);
  feed(s, 0.0, 4.5, [](double) { return 30.0; });
  ASSERT_EQ(s.phase(), SandPhase::kStrokes);
  Eigen::Isometry3d tcp = s.update(4.5).target;
  tcp.translation().x() -= 0.004;
  s.set_tcp(tcp);
  EXPECT_TRUE(s.abort("aborted by the test"));
  ASSERT_EQ(s.phase(), SandPhase::kLeaving);
  const SandCommand first = s.update(4.5);
  EXPECT_FALSE(first.admittance);
  EXPECT_NEAR(first.target.translation().x(), tcp.translation().x(), 1e-9);  // not pushed back in
  EXPECT_NEAR(s.update(5.0).target.translation().x(), tcp.translation().x() - 0.025, 1e-9);
  EXPECT_FALSE(s.finished());
  (void)s.update(5.6);
  EXPECT_EQ(s.phase(), SandPhase::kAborted);
  EXPECT_EQ(s.reason(), "aborted by the test");

  SandSequence moving(test_plan(), SandParams{});
  EXPECT_FALSE(moving.abort("aborted during the move"));
  EXPECT_EQ(moving.phase(), SandPhase::kAborted);
}

TEST(SandSequence, AStopEndsAtOnce) {
  SandSequence s(test_plan(), SandParams{});
  s.start(0.0);
  feed(s, 0.0, 4.5, [](double) { return 30.0; });
  s.stop("safety stop (estop: wireless)");
  EXPECT_EQ(s.phase(), SandPhase::kAborted);
  EXPECT_EQ(s.reason(), "safety stop (estop: wireless)");
  EXPECT_GT(s.stats().duration, 0.4);
}

}  // namespace
// The run's supervision, cycle by cycle, as the service drives it (supervise()).
SandCycle answered(MoveReport move, double progress = 1.0) {
  SandCycle c;
  c.move = move;
  c.move_progress = progress;
  return c;
}

TEST(SandSupervise, TheRobotsAnswerToTheMoveStartsOrFailsTheRun) {
  SandSequence s(test_plan(), SandParams{});
  SandCycle c = answered(MoveReport::kRunning, 0.4);
  SandStep step = supervise(s, c, SandWatch{});
  EXPECT_EQ(step.end, SandEnd::kNone);
  EXPECT_FALSE(step.command);
  EXPECT_NEAR(s.progress(), 0.4 * 3.0 / 7.0, 1e-9);
  // Succeeded, but no estimate yet: the Cartesian phases wait for the robot's time.
  step = supervise(s, answered(MoveReport::kSucceeded), SandWatch{});
  EXPECT_EQ(s.phase(), SandPhase::kMove);
  EXPECT_FALSE(step.command);
  c = answered(MoveReport::kSucceeded);
  c.forces = {{100.0, Eigen::Vector3d::Zero()}};
  step = supervise(s, c, SandWatch{});
  EXPECT_EQ(s.phase(), SandPhase::kApproach);
  ASSERT_TRUE(step.command);
  EXPECT_NEAR(step.command->target.translation().x(), 1.0 - 0.05, 1e-9);  // at the approach pose

  SandSequence refused(test_plan(), SandParams{});
  c = answered(MoveReport::kStopped);
  c.move_reason = "J2_E beyond its limit";
  step = supervise(refused, c, SandWatch{});
  EXPECT_EQ(step.end, SandEnd::kFailed);
  EXPECT_EQ(step.reason, "the robot stopped the move to the approach pose: J2_E beyond its limit");

  SandSequence silent(test_plan(), SandParams{});
  c = SandCycle{};
  c.since_sent = 9.0;
  EXPECT_EQ(supervise(silent, c, SandWatch{}).end, SandEnd::kNone);
  c.since_sent = 10.5;
  step = supervise(silent, c, SandWatch{});
  EXPECT_EQ(step.end, SandEnd::kFailed);
  EXPECT_EQ(step.reason, "the robot service did not answer the move's trajectory within 10 s");
}

TEST(SandSupervise, ASafetyStopOrASilentForceEstimateAbortsTheRun) {
  SandSequence s(test_plan(), SandParams{});
  SandCycle c = answered(MoveReport::kRunning, 0.2);
  c.safety_stop = "e-stop: software";
  SandStep step = supervise(s, c, SandWatch{});
  EXPECT_EQ(step.end, SandEnd::kAborted);
  EXPECT_EQ(step.reason, "safety stop (e-stop: software)");
  EXPECT_EQ(s.phase(), SandPhase::kAborted);

  SandSequence quiet(test_plan(), SandParams{});
  c = answered(MoveReport::kSucceeded);
  c.forces = {{100.0, Eigen::Vector3d::Zero()}};
  supervise(quiet, c, SandWatch{});
  c = answered(MoveReport::kSucceeded);
  c.silence = 1.5;  // within the watch's 2 s
  EXPECT_EQ(supervise(quiet, c, SandWatch{}).end, SandEnd::kNone);
  c.silence = 2.5;
  step = supervise(quiet, c, SandWatch{});
  EXPECT_EQ(step.end, SandEnd::kAborted);
  EXPECT_EQ(step.reason, "no force estimate from the robot (concert/robot/ee_wrench) for 2.0 s");
}

// A safety stop in contact: nothing is commanded while it lasts (the robot holds the disc where
// it is), and once it is reset the run leaves the wall along the normal, then ends aborted,
// saying both.
TEST(SandSupervise, ASafetyStopInContactHoldsThenLeavesTheWallAfterTheReset) {
  SandSequence s(test_plan(), SandParams{});
  SandCycle c = answered(MoveReport::kSucceeded);
  c.forces = {{100.0, Eigen::Vector3d::Zero()}};
  supervise(s, c, SandWatch{});
  double t = 100.0;
  const auto cycle = [&](bool stopped) {
    SandCycle k = answered(MoveReport::kSucceeded);
    for (int i = 0; i < 2; ++i) {
      t += 0.01;
      k.forces.push_back({t, Eigen::Vector3d(-30.0, 0.0, 0.0)});
    }
    if (stopped) k.safety_stop = "e-stop: software";
    return supervise(s, k, SandWatch{});
  };
  while (s.phase() != SandPhase::kStrokes && t < 110.0) (void)cycle(false);
  ASSERT_EQ(s.phase(), SandPhase::kStrokes);
  for (int i = 0; i < 100; ++i) {  // 2 s of the robot's time stopped
    const SandStep held = cycle(true);
    EXPECT_FALSE(held.command);
    EXPECT_EQ(held.end, SandEnd::kNone);
  }
  EXPECT_EQ(s.phase(), SandPhase::kHeld);
  SandStep step = cycle(false);
  EXPECT_EQ(s.phase(), SandPhase::kLeaving);
  ASSERT_TRUE(step.command);
  EXPECT_FALSE(step.command->admittance);
  const double x0 = step.command->target.translation().x();
  for (int i = 0; i < 100 && step.end == SandEnd::kNone; ++i) {
    step = cycle(false);
    if (step.command) {
      EXPECT_LE(step.command->target.translation().x(), x0 + 1e-9);  // off the wall only
    }
  }
  EXPECT_EQ(step.end, SandEnd::kAborted);
  EXPECT_EQ(step.reason, "safety stop (e-stop: software); the tool left the wall after the reset");
}

TEST(SandSupervise, EstimatesAreFedAsThePushAlongTheToolsAxisUntilDone) {
  SandSequence s(test_plan(), SandParams{});
  SandCycle c = answered(MoveReport::kSucceeded);
  c.forces = {{100.0, Eigen::Vector3d::Zero()}};
  supervise(s, c, SandWatch{});
  // 50 Hz estimates: the wall pushes back along -x (the TCP's z is +x), 30 N once in contact.
  SandStep step;
  double t = 100.0;
  for (int cycle = 0; cycle < 600 && step.end == SandEnd::kNone; ++cycle) {
    c = answered(MoveReport::kSucceeded);
    for (int k = 0; k < 2; ++k) {
      t += 0.01;
      c.forces.push_back({t, Eigen::Vector3d(-30.0, 0.0, 0.0)});
    }
    step = supervise(s, c, SandWatch{});
  }
  EXPECT_EQ(step.end, SandEnd::kSucceeded) << step.reason;
  ASSERT_FALSE(s.trace().empty());
  EXPECT_NEAR(s.trace().back().estimated, 30.0, 1e-9);  // the push, not the wall's reaction
}

}  // namespace concert::surface_finish
