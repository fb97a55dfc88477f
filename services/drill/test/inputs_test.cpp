// What the drill keeps of what it measured and heard, and whether the robot may move
// (drill/inputs.hpp), without DDS.
#include "drill/inputs.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace concert::drill {
namespace {

using namespace std::chrono_literals;
using Clock = Inputs::Clock;

const Clock::time_point kT0{std::chrono::seconds(1000)};

Inputs make_inputs() { return Inputs(Params::Buffers{}, Params::Liveness{}); }

JointPositions arm(double q) { return {{"J1"}, {q}}; }

// Every service a mission uses heard at `t`, safety running.
void all_heard(Inputs& in, Clock::time_point t) {
  in.on_safety({true, {}});
  in.on_joints(1, arm(0.0), t);
  in.on_service("planner", false, t);
  in.on_service("nav", false, t);
}

TEST(DrillInputs, JointStatesAreDecimatedBoundedAndCarryTheNewestOdometry) {
  Params::Buffers buffers;
  buffers.sample_step = 5ms;
  buffers.samples = 3;
  Inputs in(buffers, Params::Liveness{});
  EXPECT_FALSE(in.latest_sample());
  in.on_odometry({1.0, 2.0, 0.5});
  in.on_joints(0, arm(0.1), kT0);
  in.on_joints(4'000'000, arm(0.2), kT0);  // within the step: dropped
  ASSERT_TRUE(in.latest_sample());
  EXPECT_DOUBLE_EQ(in.latest_sample()->joints.positions[0], 0.1);
  in.on_joints(5'000'000, arm(0.3), kT0);
  EXPECT_DOUBLE_EQ(in.latest_sample()->joints.positions[0], 0.3);
  in.on_odometry({1.5, 2.0, 0.5});
  EXPECT_DOUBLE_EQ(in.latest_sample()->odometry.x(), 1.5);  // the newest, not the sample's own
  // Without a rig no frame can be posed: none kept.
  EXPECT_FALSE(in.on_frame(5'000'000, hardware::RgbdFrame{}));
  EXPECT_EQ(in.newest_stamp(), 0);
  EXPECT_FALSE(in.newest_frame(0));
  EXPECT_FALSE(in.intrinsics());
  EXPECT_FALSE(in.averaged_view(0, 1));
}

TEST(DrillInputs, AStartingStackIsWaitedForThenEachMissingServiceIsNamed) {
  Inputs in = make_inputs();
  EXPECT_EQ(in.health(kT0, false, kT0 + 1s).progress, Progress::kRunning);
  const Outcome late = in.health(kT0, false, kT0 + 6s);
  EXPECT_EQ(late.progress, Progress::kFailed);
  EXPECT_EQ(late.reason, "no safety state from the safety service");
  in.on_safety({true, {}});
  EXPECT_EQ(in.health(kT0, false, kT0 + 6s).reason, "no joint state from the robot service (never heard)");
  in.on_joints(1, arm(0.0), kT0 + 6s);
  EXPECT_EQ(in.health(kT0, false, kT0 + 6s).reason, "the planner service is lost");
  in.on_service("planner", false, kT0 + 6s);
  EXPECT_EQ(in.health(kT0, false, kT0 + 6s).progress, Progress::kSucceeded);
}

TEST(DrillInputs, ASafetyStopALostServiceOrSilentJointsStopTheMission) {
  Inputs in = make_inputs();
  all_heard(in, kT0);
  EXPECT_EQ(in.health(kT0, true, kT0 + 500ms).progress, Progress::kSucceeded);
  // Joint states older than liveness.joints_lost (1 s), the robot's status never heard.
  EXPECT_EQ(in.health(kT0, true, kT0 + 2s).reason,
            "no joint state from the robot service (lost: none for 2.0 s, its status silent too)");
  in.on_joints(2, arm(0.0), kT0 + 2s);
  in.on_service("planner", false, kT0 + 2s);
  // Nav heard at kT0 only: lost after liveness.service_lost (5 s), but only a mission using it fails.
  in.on_joints(3, arm(0.0), kT0 + 6s);
  in.on_service("planner", false, kT0 + 6s);
  EXPECT_EQ(in.health(kT0, true, kT0 + 6s).reason, "the nav service is lost");
  EXPECT_EQ(in.health(kT0, false, kT0 + 6s).progress, Progress::kSucceeded);
  // A service that says it stops is gone at once.
  in.on_service("planner", true, kT0 + 6s);
  EXPECT_EQ(in.health(kT0, false, kT0 + 6s).reason, "the planner service is lost");
  in.on_service("planner", false, kT0 + 6s);
  in.on_safety({false, {"estop: software engaged (gui)", "limits: joint J1_E position"}});
  EXPECT_EQ(in.health(kT0, false, kT0 + 6s).reason,
            "safety stop (estop: software engaged (gui), limits: joint J1_E position)");
}

TEST(DrillInputs, LateJointStatesWhileTheRobotsStatusBeatsPauseTheMissionUntilServiceLost) {
  Inputs in = make_inputs();
  all_heard(in, kT0);
  in.on_service("robot", false, kT0);
  // 1.5 s without a joint state, the robot's status heard each second: wait, do not abort.
  in.on_service("robot", false, kT0 + 1s);
  in.on_service("planner", false, kT0 + 1s);
  EXPECT_EQ(in.health(kT0, false, kT0 + 1500ms).progress, Progress::kRunning);
  // The stream comes back: healthy again.
  in.on_joints(2, arm(0.0), kT0 + 1600ms);
  EXPECT_EQ(in.health(kT0, false, kT0 + 1600ms).progress, Progress::kSucceeded);
  // Silent beyond service_lost (5 s) though the status still beats: the stream is gone.
  for (int s = 2; s <= 7; ++s) {
    in.on_service("robot", false, kT0 + std::chrono::seconds(s));
    in.on_service("planner", false, kT0 + std::chrono::seconds(s));
  }
  EXPECT_EQ(in.health(kT0, false, kT0 + 4s).progress, Progress::kRunning);
  EXPECT_EQ(in.health(kT0, false, kT0 + 7s).reason, "no joint state from the robot service (lost: none for 5.4 s)");
  // The robot's status silent too (a service lost after service_lost): at once.
  Inputs dead = make_inputs();
  all_heard(dead, kT0);
  dead.on_service("robot", false, kT0 - 5s);
  dead.on_service("planner", false, kT0 + 1s);
  EXPECT_EQ(dead.health(kT0 - 10s, false, kT0 + 1500ms).reason,
            "no joint state from the robot service (lost: none for 1.5 s, its status silent too)");
  // A robot service of another name is watched by that name.
  Params p;
  p.liveness.robot_service = "arm_robot";
  Inputs named(p.buffers, p.liveness);
  all_heard(named, kT0);
  named.on_service("robot", false, kT0 + 1s);
  EXPECT_EQ(named.health(kT0, false, kT0 + 1500ms).progress, Progress::kFailed);
  named.on_service("arm_robot", false, kT0 + 1s);
  EXPECT_EQ(named.health(kT0, false, kT0 + 1500ms).progress, Progress::kRunning);
}

TEST(DrillInputs, RepliesAreKeptPerRequestAndPlansMerged) {
  Inputs in = make_inputs();
  EXPECT_FALSE(in.plan(3));
  PlanReply planned;
  planned.request_id = 3;
  planned.state = PlanState::kPlanned;
  planned.path = {{"base_x"}, {{0.0, {0.0}, {}}, {1.0, {0.5}, {}}}};
  in.on_plan(planned);
  PlanReply done;
  done.request_id = 3;
  done.state = PlanState::kSucceeded;
  in.on_plan(done);
  ASSERT_TRUE(in.plan(3));
  EXPECT_EQ(in.plan(3)->state, PlanState::kSucceeded);
  EXPECT_EQ(in.plan(3)->path.samples.size(), 2u);

  in.on_trajectory(7, {Progress::kFailed, "aborted", "safety stop"});
  EXPECT_FALSE(in.trajectory(8));
  EXPECT_EQ(in.trajectory(7)->failure, "aborted");
  in.on_nav(7, {Progress::kSucceeded, {}, {}});
  EXPECT_EQ(in.nav(7)->progress, Progress::kSucceeded);
  EXPECT_EQ(in.trajectory(7)->progress, Progress::kFailed);  // separate tables
}

// Each joint's heat from the efforts of every state (not only the samples kept): safety's
// thermal rule (model::ThermalLoad) over its window and the present load over a short one. A
// state without as many efforts as names feeds nothing; a new rig starts cold.
TEST(DrillInputs, TheJointsHeatFollowsTheReportedEffortsAndANewRigStartsCold) {
  Inputs in = make_inputs();
  EXPECT_TRUE(in.heat().empty());
  std::int64_t stamp = 1'000'000;
  for (int i = 0; i < 5000; ++i) in.on_joints(stamp += 1'000'000, arm(0.0), kT0, {-100.0});  // 5 s at 1 kHz
  ASSERT_EQ(in.heat().count("J1"), 1u);
  // 5 s of 100 N m from cold: RMS 100 x sqrt(1 - e^-1), present 100 x sqrt(1 - e^-10).
  EXPECT_NEAR(in.heat().at("J1").rms, 100.0 * std::sqrt(1.0 - std::exp(-1.0)), 0.05);
  EXPECT_NEAR(in.heat().at("J1").present, 100.0, 0.05);
  in.on_joints(stamp += 1'000'000, arm(0.0), kT0, {1.0, 2.0});  // efforts of another state
  EXPECT_NEAR(in.heat().at("J1").present, 100.0, 0.05);
  in.set_rig(nullptr);
  EXPECT_TRUE(in.heat().empty());
}

}  // namespace
}  // namespace concert::drill
