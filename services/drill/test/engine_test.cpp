// The drill's mission engine (drill/engine.hpp) without DDS: a fake sink records what it would
// send, Inputs gets what the planner and the robot would answer, the test ticks the clock.
#include "drill/engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "model_fixture.hpp"

namespace concert::drill {
namespace {

// Records every command and log line the engine sends.
struct FakeSink final : DrillSink {
  std::vector<PlanAsk> plans;
  std::vector<std::uint32_t> trajectories;
  int cancels = 0;
  std::vector<JointPositions> holds;
  std::vector<MissionStatus> statuses;
  std::vector<std::string> refusals;
  std::vector<std::string> cartesian_frames;
  std::vector<CartesianReference> cartesian_refs;
  std::string log_text;

  void plan(const PlanAsk& ask) override { plans.push_back(ask); }
  void trajectory(std::uint32_t id, std::uint32_t, const std::vector<std::string>&,
                  const std::vector<PathSample>&) override {
    trajectories.push_back(id);
  }
  std::vector<std::pair<std::uint32_t, BasePose>> goals;
  void navigate(std::uint32_t id, std::uint32_t, const BasePose& goal) override { goals.emplace_back(id, goal); }
  void cancel_navigation() override { ++cancels; }
  void hold(std::uint32_t, const JointPositions& arm) override { holds.push_back(arm); }
  void cartesian(std::uint32_t, const std::string& frame, const CartesianReference& reference) override {
    cartesian_frames.push_back(frame);
    cartesian_refs.push_back(reference);
  }
  void mission_status(std::uint32_t, const MissionStatus& status, const MissionReport&) override {
    statuses.push_back(status);
  }
  void refused(const std::string& why) override { refusals.push_back(why); }
  void log(const std::string& line) override { log_text += line + "\n"; }

  [[nodiscard]] std::size_t logged(const std::string& what) const {
    std::size_t n = 0;
    for (auto at = log_text.find(what); at != std::string::npos; at = log_text.find(what, at + 1)) ++n;
    return n;
  }
};

struct EngineTest : ::testing::Test {
  FakeSink sink;
  Params tuning;
  Inputs inputs{tuning.buffers, tuning.liveness};
  mobile_base::MapFrame map_frame;
  DrillEngine engine{EngineParams{{}, {}, tuning}, inputs, map_frame, sink};

  PlanReply reply(std::uint32_t id, PlanState state) const {
    PlanReply r;
    r.request_id = id;
    r.state = state;
    return r;
  }
};

// A plan request written before the planner's reader matched is lost: it is sent again, same id,
// every plan_requests.ack_bound (2 s) until the planner acknowledges it, and no more after that.
TEST_F(EngineTest, APlanRequestIsSentAgainUntilThePlannerAcknowledgesIt) {
  engine.tick(0.0);
  engine.plan(0, Eigen::Isometry3d::Identity(), std::nullopt);
  ASSERT_EQ(sink.plans.size(), 1u);
  const std::uint32_t id = sink.plans[0].request_id;
  engine.tick(1.9);
  EXPECT_EQ(sink.plans.size(), 1u);
  engine.tick(2.1);
  ASSERT_EQ(sink.plans.size(), 2u);
  EXPECT_EQ(sink.plans[1].request_id, id);
  EXPECT_EQ(sink.logged("plan request " + std::to_string(id) +
                        " not acknowledged by the planner within 2 s; sent again (1 of 5)"),
            1u)
      << sink.log_text;
  inputs.on_plan(reply(id, PlanState::kPlanning));
  for (double t = 2.2; t < 20.0; t += 0.5) engine.tick(t);
  EXPECT_EQ(sink.plans.size(), 2u) << sink.log_text;
  EXPECT_EQ(engine.planning(0).progress, Progress::kRunning);
}

// Never acknowledged: sent plan_requests.resends more times, then the answer is waited for.
TEST_F(EngineTest, AnUnacknowledgedRequestIsSentAgainABoundedNumberOfTimes) {
  engine.tick(0.0);
  engine.plan(0, Eigen::Isometry3d::Identity(), std::nullopt);
  for (double t = 0.5; t < 60.0; t += 0.5) engine.tick(t);
  EXPECT_EQ(sink.plans.size(), static_cast<std::size_t>(1 + tuning.plan_requests.resends));
  EXPECT_EQ(sink.logged("not acknowledged by the planner after 6 sends; waiting for its answer"), 1u)
      << sink.log_text;
}

// A planner's acknowledgement that comes after its answer is not news: the plan, made, stays made.
TEST_F(EngineTest, AnAcknowledgementAfterThePlanDoesNotUndoIt) {
  engine.tick(0.0);
  engine.plan(0, Eigen::Isometry3d::Identity(), std::nullopt);
  const std::uint32_t id = sink.plans.at(0).request_id;
  PlanReply planned = reply(id, PlanState::kSucceeded);
  planned.path = {{"base_x", "base_y", "base_yaw"}, {{0.0, {0.1, 0.0, 0.0}, {}}}};
  inputs.on_plan(planned);
  inputs.on_plan(reply(id, PlanState::kPlanning));
  EXPECT_EQ(engine.planning(0).progress, Progress::kSucceeded) << engine.planning(0).reason;
}

// A plan that failed for want of a path is asked again (approach.attempts), then fails the area
// with the planner's reason.
TEST_F(EngineTest, AnApproachWithoutAPathIsAskedAgainThenFailsWithThePlannersReason) {
  engine.tick(0.0);
  engine.plan(0, Eigen::Isometry3d::Identity(), std::nullopt);
  for (int attempt = 1; attempt <= tuning.approach.attempts; ++attempt) {
    ASSERT_EQ(sink.plans.size(), static_cast<std::size_t>(attempt)) << sink.log_text;
    PlanReply failed = reply(sink.plans.back().request_id, PlanState::kFailed);
    failed.failure = PlanFailure::kNoPath;
    failed.reason = "no collision-free path";
    inputs.on_plan(failed);
    const Outcome o = engine.planning(0);
    if (attempt < tuning.approach.attempts) {
      EXPECT_EQ(o.progress, Progress::kRunning);
    } else {
      EXPECT_EQ(o.progress, Progress::kFailed);
      EXPECT_EQ(o.reason, "planner: no collision-free path");
    }
  }
}

// Nav drives with the arm in its transport posture: a navigation first asks the planner to take
// the arm home (executed), and only then sends the goal; a homing the planner refuses fails the
// navigation with its reason, and no goal is sent.
TEST_F(EngineTest, ANavigationTakesTheArmHomeFirst) {
  engine.tick(0.0);
  engine.navigate(BasePose{1.0, 2.0, 0.5});
  ASSERT_EQ(sink.plans.size(), 1u);
  const PlanAsk home = sink.plans[0];
  EXPECT_TRUE(home.home);
  EXPECT_TRUE(home.execute);
  EXPECT_TRUE(home.goals.empty());
  EXPECT_TRUE(sink.goals.empty());
  inputs.on_plan(reply(home.request_id, PlanState::kExecuting));
  EXPECT_EQ(engine.navigation().progress, Progress::kRunning);
  EXPECT_TRUE(sink.goals.empty()) << "the goal went to nav with the arm still moving";
  inputs.on_plan(reply(home.request_id, PlanState::kSucceeded));
  EXPECT_EQ(engine.navigation().progress, Progress::kRunning);
  ASSERT_EQ(sink.goals.size(), 1u);
  EXPECT_EQ(sink.goals[0].second.x, 1.0);
  EXPECT_EQ(sink.goals[0].second.theta, 0.5);
  inputs.on_nav(sink.goals[0].first, {Progress::kSucceeded, {}, {}});
  EXPECT_EQ(engine.navigation().progress, Progress::kSucceeded);

  engine.navigate(BasePose{3.0, 2.0, 0.0});
  ASSERT_EQ(sink.plans.size(), 2u);
  PlanReply refused = reply(sink.plans[1].request_id, PlanState::kFailed);
  refused.failure = PlanFailure::kUnreachable;
  refused.reason = "home: the homing posture is rejected where the robot stands by environment collision: L_4_E";
  inputs.on_plan(refused);
  const Outcome o = engine.navigation();
  EXPECT_EQ(o.progress, Progress::kFailed);
  EXPECT_EQ(o.reason, "the arm home before driving: " + refused.reason);
  EXPECT_EQ(sink.goals.size(), 1u);
}

// The mission's end: the arm home, the base standing; nothing goes to nav. The planner's refusal
// is the outcome's reason.
TEST_F(EngineTest, StowingTakesTheArmHomeAndSaysWhyNot) {
  engine.tick(0.0);
  engine.stow();
  ASSERT_EQ(sink.plans.size(), 1u);
  EXPECT_TRUE(sink.plans[0].home);
  EXPECT_TRUE(sink.plans[0].execute);
  EXPECT_EQ(engine.stowing().progress, Progress::kRunning);
  inputs.on_plan(reply(sink.plans[0].request_id, PlanState::kSucceeded));
  EXPECT_EQ(engine.stowing().progress, Progress::kSucceeded);
  EXPECT_TRUE(sink.goals.empty());

  engine.stow();
  ASSERT_EQ(sink.plans.size(), 2u);
  PlanReply refused = reply(sink.plans[1].request_id, PlanState::kFailed);
  refused.reason = "home: no collision-free path";
  inputs.on_plan(refused);
  const Outcome o = engine.stowing();
  EXPECT_EQ(o.progress, Progress::kFailed);
  EXPECT_EQ(o.reason, "home: no collision-free path");
}

// Stopped (an abort, a failure), nothing is sent again: a planner taking the request then would
// still move the robot.
TEST_F(EngineTest, AfterAStopNoPlanRequestIsSentAgain) {
  engine.tick(0.0);
  engine.plan(0, Eigen::Isometry3d::Identity(), std::nullopt);
  engine.stop();
  for (double t = 0.5; t < 10.0; t += 0.5) engine.tick(t);
  EXPECT_EQ(sink.plans.size(), 1u);
  EXPECT_EQ(sink.logged("sent again"), 0u) << sink.log_text;
}

// Without a model that can drill, a mission is refused with the reason, and said so.
TEST_F(EngineTest, AMissionWithoutADrillingModelIsRefusedOnce) {
  const MissionOrder m{7, 100, "m", "areas:\n  - {name: a, marks: blobs, point: [1, 0, 1]}\n", "", false};
  engine.start_mission(m);
  engine.start_mission(m);  // written again by a sender that had not heard the answer
  ASSERT_EQ(sink.refusals.size(), 1u);
  EXPECT_EQ(sink.refusals[0], "mission 7: no robot model yet");
  ASSERT_EQ(sink.statuses.size(), 1u);
  EXPECT_EQ(sink.statuses[0].state, MissionState::kFailed);
  EXPECT_FALSE(engine.mission_active());
  EXPECT_EQ(engine.apply_model(2, nullptr, "model version 2 cannot drill: no drill"),
            "model version 2 cannot drill: no drill");
  engine.start_mission({8, 101, "m", m.yaml, "", false});
  ASSERT_EQ(sink.refusals.size(), 2u);
  EXPECT_EQ(sink.refusals[1], "mission 8: model version 2 cannot drill: no drill");
  EXPECT_EQ(engine.health().reason, "model version 2 cannot drill: no drill");
}


// --- A hole's motion on the demo's drill robot (deploy/demo/drill_robot.yaml) -----------------
// The ports the mission tree calls (align), driven by hand; step_motion() runs the motion as a
// control period does. The robot stands at its zero posture; the camera sees a synthetic flat
// view (grey, constant depth) with one blue blob drawn where the test puts it.

struct RigEngineTest : EngineTest {
  std::shared_ptr<const DrillRig> rig;
  JointPositions joints;
  std::int64_t stamp_ns = 1'000'000'000;
  double now = 0.0;

  void SetUp() override {
    rig = std::make_shared<const DrillRig>(
        testing::robot_model(std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml", 2));
    engine.apply_model(2, rig, "");
    for (const std::string& name : rig->model().kinematics().joint_names()) {
      joints.names.push_back(name);
      joints.positions.push_back(0.0);
    }
    inputs.on_odometry(Eigen::Vector3d::Zero());
    sample();
  }

  // A joint sample at the next stamp (5 ms on).
  void sample() {
    stamp_ns += 5'000'000;
    inputs.on_joints(stamp_ns, joints, Inputs::Clock::now());
  }

  [[nodiscard]] Eigen::Isometry3d world_T_optical() const {
    return rig->base_in_world(Eigen::Vector3d::Zero()) * rig->camera_in_base(rig->q(joints));
  }

  // A blob hole 0.5 m in front of the camera, on a wall facing it.
  [[nodiscard]] DrillPoint hole_ahead() const {
    DrillPoint p;
    p.label = "blob 1";
    p.frame = world_T_optical() * Eigen::Translation3d(0.0, 0.0, 0.5) *
              Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY());  // z out of the wall, to the camera
    return p;
  }

  // `count` frames of the wall 0.5 m ahead with a 2 cm blue blob at `blob` (world), each after a
  // new joint sample.
  void camera_sees_blob_at(const Eigen::Vector3d& blob, int count) {
    const Eigen::Vector3d in_optical = world_T_optical().inverse() * blob;
    for (int i = 0; i < count; ++i) {
      sample();
      hardware::RgbdFrame f;
      f.sensor = rig->camera();
      f.intrinsics = {640, 480, 615.0, 615.0, 319.5, 239.5};
      f.rgb.assign(640u * 480u * 3u, 128);
      f.depth.assign(640u * 480u, static_cast<std::uint16_t>(std::lround(in_optical.z() * 1e3)));
      const double u = 615.0 * in_optical.x() / in_optical.z() + 319.5;
      const double v = 615.0 * in_optical.y() / in_optical.z() + 239.5;
      const double r = 615.0 * 0.01 / in_optical.z();
      for (int y = 0; y < 480; ++y) {
        for (int x = 0; x < 640; ++x) {
          if (std::hypot(x - u, y - v) > r) continue;
          std::uint8_t* px = &f.rgb[(static_cast<std::size_t>(y) * 640 + static_cast<std::size_t>(x)) * 3];
          px[0] = 20;
          px[1] = 30;
          px[2] = 220;
        }
      }
      ASSERT_TRUE(inputs.on_frame(stamp_ns + 1, std::move(f)));
    }
  }

  // Answers the newest plan request with `state` (and `failure`, `reason`); a success carries a
  // one-sample path of the base and the arm at the zero posture.
  std::uint32_t answer(PlanState state, PlanFailure failure = PlanFailure::kOk, const std::string& reason = "") {
    PlanReply r = reply(sink.plans.back().request_id, state);
    r.failure = failure;
    r.reason = reason;
    if (state == PlanState::kSucceeded) {
      r.path.names = {"base_x", "base_y", "base_yaw"};
      r.path.samples = {{0.0, {0.0, 0.0, 0.0}, {}}};
      const model::ChainInfo& arm = rig->model().arm();
      for (const std::string& j : arm.joints) {
        r.path.names.push_back(j);
        r.path.samples[0].position.push_back(0.0);
      }
    }
    inputs.on_plan(r);
    return r.request_id;
  }

  void step(int periods = 1) {
    for (int i = 0; i < periods; ++i) engine.step_motion(now += 0.005);
  }

  // Fails the arm-alone postures until the first whole-body one (Params::hole.attempts) is
  // asked, and returns its request.
  PlanAsk fail_until_whole_body() {
    while (sink.plans.back().fixed_base) {
      answer(PlanState::kFailed, PlanFailure::kUnreachable, "no posture reaches the hole");
      step();
    }
    return sink.plans.back();
  }
};

// The hole's posture is asked of the planner for the drill's tool, the bit on the hole's axis,
// the arm alone first; each posture the planner cannot find moves on to the next attempt.
TEST_F(RigEngineTest, TheHolesPostureIsAskedArmAloneFirstThenTheNextAttempts) {
  const DrillPoint hole = hole_ahead();
  engine.align(hole);
  ASSERT_EQ(sink.plans.size(), 1u);
  const PlanAsk first = sink.plans.back();
  EXPECT_EQ(first.end_effector, rig->tool());
  EXPECT_EQ(first.model_version, 2u);
  ASSERT_EQ(first.goals.size(), 1u);
  EXPECT_TRUE(first.goals[0].isApprox(hole.frame, 1e-9));
  EXPECT_TRUE(first.fixed_base);
  EXPECT_TRUE(first.execute);  // a blob hole: planned and executed at once
  EXPECT_NEAR(first.tip_distance, tuning.motion.standoff + tuning.hole.align_margin, 1e-9);

  const PlanAsk body = fail_until_whole_body();
  EXPECT_FALSE(body.fixed_base);
  EXPECT_NE(body.request_id, first.request_id);
  EXPECT_EQ(sink.logged("blob 1: no drilling posture for the arm alone"), 3u) << sink.log_text;
  EXPECT_EQ(engine.alignment().progress, Progress::kRunning);
}

// A safety stop while the robot moves onto the hole's posture: the planner reports the
// execution aborted, and the hole fails with its reason; nothing else is asked or aligned.
TEST_F(RigEngineTest, ASafetyStopOnTheWayToTheHolesPostureFailsTheHole) {
  engine.align(hole_ahead());
  answer(PlanState::kFailed, PlanFailure::kExecutionAborted,
         "execution aborted: safety stop (limits: joint J2_E effort)");
  step(10);
  const Outcome o = engine.alignment();
  EXPECT_EQ(o.progress, Progress::kFailed);
  EXPECT_EQ(o.reason, "planner: the hole's drilling posture: execution aborted: safety stop "
                      "(limits: joint J2_E effort)");
  EXPECT_EQ(sink.plans.size(), 1u) << sink.log_text;
  EXPECT_TRUE(sink.cartesian_frames.empty());
  // The tree stops the engine then: the arm is held where it stands, every arm joint.
  engine.stop();
  ASSERT_EQ(sink.holds.size(), 1u);
  EXPECT_EQ(sink.holds[0].names, rig->model().arm().joints);
}

// The posture reached, the hole is measured again in the camera's frames (the blob where it was
// predicted) and the bit aligned onto it by the Cartesian reference of the drill's TCP.
TEST_F(RigEngineTest, APostureReachedIsMeasuredAgainThenTheBitAligned) {
  const DrillPoint hole = hole_ahead();
  engine.align(hole);
  answer(PlanState::kSucceeded);
  step();
  EXPECT_TRUE(sink.cartesian_frames.empty()) << "aligned before the hole was measured again";
  camera_sees_blob_at(hole.frame.translation(), tuning.camera.reanchor_frames);
  step();
  EXPECT_EQ(sink.logged("blob 1 measured again from its drilling posture: 0.0 mm"), 1u) << sink.log_text;
  step();  // the alignment's first reference
  ASSERT_FALSE(sink.cartesian_frames.empty()) << sink.log_text;
  EXPECT_EQ(sink.cartesian_frames.back(), rig->tcp_frame());
  EXPECT_EQ(sink.plans.size(), 1u) << "planned again though the hole was where predicted";
  EXPECT_EQ(engine.alignment().progress, Progress::kRunning);
}

// The survey asks the planner, plan only, for each hole's whole-body posture from the full thrust
// on; a posture not found is asked again (survey.tries) before the next attempt, and a hole none
// reaches is unreachable with the planner's reason; a refused request leaves it unjudged.
TEST_F(RigEngineTest, TheSurveyAsksWholeBodyPosturesAndJudgesEachHole) {
  const DrillPoint hole = hole_ahead();
  engine.classify(0, {hole, hole});
  ASSERT_EQ(sink.plans.size(), 2u);
  for (const PlanAsk& r : sink.plans) {
    EXPECT_FALSE(r.execute);
    EXPECT_FALSE(r.fixed_base);
    EXPECT_EQ(r.base_travel, 0.0);
  }
  std::vector<HoleReach> reach;
  EXPECT_EQ(engine.classification(reach).progress, Progress::kRunning);
  const std::uint32_t first = sink.plans[0].request_id, second = sink.plans[1].request_id;
  PlanReply refused = reply(second, PlanState::kFailed);
  refused.failure = PlanFailure::kStaleModel;
  refused.reason = "another model";
  inputs.on_plan(refused);
  // Hole 1: every attempt fails, each survey.tries times.
  std::uint32_t id = first;
  const std::size_t asks = tuning.survey.attempts.size() * static_cast<std::size_t>(tuning.survey.tries);
  for (std::size_t k = 0; k < asks; ++k) {
    PlanReply none = reply(id, PlanState::kFailed);
    none.failure = PlanFailure::kUnreachable;
    none.reason = "torque limit x120";
    inputs.on_plan(none);
    const Outcome o = engine.classification(reach);
    if (k + 1 < asks) {
      ASSERT_EQ(o.progress, Progress::kRunning) << k;
      id = sink.plans.back().request_id;
      EXPECT_NE(id, first);
    } else {
      ASSERT_EQ(o.progress, Progress::kSucceeded) << sink.log_text;
    }
  }
  EXPECT_EQ(sink.plans.size(), 2u + asks - 1);
  ASSERT_EQ(reach.size(), 2u);
  EXPECT_EQ(reach[0].reach, Reach::kUnreachable);
  EXPECT_EQ(reach[0].why.rfind("no posture found, even a whole-body posture", 0), 0u) << reach[0].why;
  EXPECT_NE(reach[0].why.find("torque limit x120"), std::string::npos) << reach[0].why;
  EXPECT_EQ(reach[1].reach, Reach::kUnknown);
  EXPECT_EQ(reach[1].why, "the planner could not judge: another model");
  EXPECT_EQ(sink.logged("0 of 2 holes reachable"), 1u) << sink.log_text;

  // Found at once: reachable at full thrust.
  engine.classify(1, {hole});
  answer(PlanState::kSucceeded);
  ASSERT_EQ(engine.classification(reach).progress, Progress::kSucceeded);
  ASSERT_EQ(reach.size(), 1u);
  EXPECT_EQ(reach[0].reach, Reach::kReachable);
  EXPECT_EQ(reach[0].why, "a whole-body posture at full thrust");
}

// The mission's end after a hole: the arm goes back along the holes' paths to the area's approach
// posture first (the planner's way home from a hole's posture does not keep the bit, which has no
// collision shape, off the wall), then the planner takes it home; the way back failing fails the
// stow with its reason.
TEST_F(RigEngineTest, StowingAfterAHoleGoesBackAlongItsPathsBeforeTheHoming) {
  engine.align(hole_ahead());
  answer(PlanState::kSucceeded);
  step();
  const std::size_t plans = sink.plans.size();
  engine.stow();
  ASSERT_EQ(sink.trajectories.size(), 1u) << sink.log_text;
  EXPECT_EQ(sink.plans.size(), plans) << "home asked before the way back ended";
  EXPECT_EQ(engine.stowing().progress, Progress::kRunning);
  inputs.on_trajectory(sink.trajectories.back(), {Progress::kSucceeded, "", ""});
  EXPECT_EQ(engine.stowing().progress, Progress::kRunning);
  ASSERT_EQ(sink.plans.size(), plans + 1);
  EXPECT_TRUE(sink.plans.back().home);
  inputs.on_plan(reply(sink.plans.back().request_id, PlanState::kSucceeded));
  EXPECT_EQ(engine.stowing().progress, Progress::kSucceeded);
  // Nothing to go back along now: straight home.
  engine.stow();
  EXPECT_EQ(sink.trajectories.size(), 1u);
  EXPECT_TRUE(sink.plans.back().home);
}

TEST_F(RigEngineTest, AStowWhoseWayBackFailsSaysWhy) {
  engine.align(hole_ahead());
  answer(PlanState::kSucceeded);
  step();
  engine.stow();
  ASSERT_EQ(sink.trajectories.size(), 1u);
  inputs.on_trajectory(sink.trajectories.back(), {Progress::kFailed, "aborted", "safety stop"});
  const Outcome o = engine.stowing();
  EXPECT_EQ(o.progress, Progress::kFailed);
  EXPECT_EQ(o.reason, "robot: the way back from the holes aborted: safety stop");
}

// --- Where the arm waits (Params::Rest) ---------------------------------------------------------
// The robot reports each drive's torque; the drill keeps safety's thermal rule on it. An arm whose
// drives run hot goes home before a hole's posture is asked and waits there, cooling, while the
// planner's request is held back; a cool arm asks at once.

struct RestTest : RigEngineTest {
  std::string hot_joint;
  double continuous = 0.0;

  void SetUp() override {
    RigEngineTest::SetUp();
    for (const std::string& j : rig->model().arm().joints) {
      const model::JointLimits& l = rig->model().limits().at(j);
      if (l.continuous_torque > continuous) {
        continuous = l.continuous_torque;
        hot_joint = j;
      }
    }
    ASSERT_GT(continuous, 0.0);
  }

  // Joint samples over `seconds` of robot time, `hot_joint` carrying `share` of its continuous
  // torque, the other joints 1 N m.
  void load(double share, double seconds) {
    std::vector<double> efforts(joints.names.size(), 1.0);
    const auto at = std::find(joints.names.begin(), joints.names.end(), hot_joint);
    ASSERT_NE(at, joints.names.end());
    efforts[static_cast<std::size_t>(at - joints.names.begin())] = share * continuous;
    for (int i = 0; i < static_cast<int>(std::lround(seconds / 0.005)); ++i) {
      stamp_ns += 5'000'000;
      inputs.on_joints(stamp_ns, joints, Inputs::Clock::now(), efforts);
    }
  }
  [[nodiscard]] double robot_seconds() const { return 1e-9 * static_cast<double>(stamp_ns); }
};

// A hot arm at a hole's posture goes back along the holes' paths to the area's approach posture
// before the planner takes it home: the planner's way home from in front of the wall does not
// keep the bit off it. A way back that fails sends the held request from where the arm stands.
TEST_F(RestTest, AHotArmAtAHolesPostureGoesBackAlongItsPathsBeforeResting) {
  engine.align(hole_ahead());
  answer(PlanState::kSucceeded);  // the hole's posture reached: its path joins the area's chain
  step();
  const std::size_t plans = sink.plans.size();
  load(0.95, 30.0);
  engine.align(hole_ahead());  // the next hole's posture request, held back
  ASSERT_EQ(sink.trajectories.size(), 1u) << sink.log_text;
  EXPECT_EQ(sink.plans.size(), plans) << "home or the hole asked before the way back ended";
  step();
  inputs.on_trajectory(sink.trajectories.back(), {Progress::kSucceeded, "", ""});
  step();
  ASSERT_EQ(sink.plans.size(), plans + 1);
  EXPECT_TRUE(sink.plans.back().home);

  // Another hole, the arm hot again at its posture; the way back fails.
  answer(PlanState::kSucceeded);  // home reached (a one-sample path: nothing joins the chain)
  load(0.1, 30.0);
  step();  // rested: the held request goes out
  ASSERT_FALSE(sink.plans.back().home);
  answer(PlanState::kSucceeded);
  step();
  load(0.95, 30.0);
  engine.align(hole_ahead());
  ASSERT_EQ(sink.trajectories.size(), 2u) << sink.log_text;
  inputs.on_trajectory(sink.trajectories.back(), {Progress::kFailed, "aborted", "tracking error"});
  const std::size_t before = sink.plans.size();
  step();
  ASSERT_EQ(sink.plans.size(), before + 1);
  EXPECT_FALSE(sink.plans.back().home);
  EXPECT_EQ(sink.logged("the arm could not go back from the holes to rest (aborted: tracking error)"), 1u)
      << sink.log_text;
}

TEST_F(RestTest, ACoolArmAsksForTheHolesPostureAtOnce) {
  load(0.8, 30.0);  // the RMS settles at 0.8 of continuous, below rest.above (0.85)
  engine.align(hole_ahead());
  ASSERT_EQ(sink.plans.size(), 1u);
  EXPECT_FALSE(sink.plans[0].home);
  EXPECT_EQ(sink.logged("rests at home"), 0u) << sink.log_text;
}

TEST_F(RestTest, AHotArmRestsAtHomeUntilItsDrivesCooledThenAsks) {
  load(0.95, 30.0);  // the RMS over the 5 s window settles at 0.95 of continuous
  const DrillPoint hole = hole_ahead();
  engine.align(hole);
  ASSERT_EQ(sink.plans.size(), 1u);
  const PlanAsk home = sink.plans[0];
  EXPECT_TRUE(home.home);
  EXPECT_TRUE(home.execute);
  EXPECT_EQ(sink.logged("drill: the arm rests at home before the planner's next answer (" + hot_joint + ": RMS "), 1u)
      << sink.log_text;
  EXPECT_EQ(sink.logged("0.95 of its continuous torque)"), 1u) << sink.log_text;
  EXPECT_EQ(engine.alignment().progress, Progress::kRunning);

  // At home, the drive carries little; the hole's request waits until the RMS is below
  // rest.until (0.7): from 0.95 at 0.1 of continuous, 5 s x ln((0.95^2 - 0.1^2) / (0.7^2 - 0.1^2))
  // = 3.1 s of robot time.
  answer(PlanState::kSucceeded);
  const double home_at = robot_seconds();
  double asked_at = -1.0;
  for (int i = 0; i < 2000 && asked_at < 0.0; ++i) {
    load(0.1, 0.005);
    step();
    if (sink.plans.size() > 1) asked_at = robot_seconds();
  }
  ASSERT_GT(asked_at, 0.0) << sink.log_text;
  EXPECT_NEAR(asked_at - home_at, 5.0 * std::log((0.95 * 0.95 - 0.01) / (0.49 - 0.01)), 0.05);
  ASSERT_EQ(sink.plans.size(), 2u);
  const PlanAsk asked = sink.plans[1];
  EXPECT_FALSE(asked.home);
  EXPECT_TRUE(asked.fixed_base);
  ASSERT_EQ(asked.goals.size(), 1u);
  EXPECT_TRUE(asked.goals[0].isApprox(hole.frame, 1e-9));
  EXPECT_EQ(sink.logged("at home, its drives at 0.70 of continuous; 1 plan request sent"), 1u) << sink.log_text;

  // The hole goes on as without the rest: its posture found, reached, the hole measured again.
  answer(PlanState::kSucceeded);
  step();
  camera_sees_blob_at(hole.frame.translation(), tuning.camera.reanchor_frames);
  step(2);
  EXPECT_EQ(sink.logged("blob 1 measured again from its drilling posture"), 1u) << sink.log_text;
  EXPECT_EQ(engine.alignment().progress, Progress::kRunning);
}

// A posture that loads a drive beyond its continuous torque is left before the wait, before
// the RMS has risen: held through the planner's search it would pass safety's bound.
TEST_F(RestTest, APostureHeldBeyondTheContinuousTorqueIsLeftBeforeTheWait) {
  load(1.05, 3.0);  // the RMS from cold: 1.05 x sqrt(1 - e^-0.6) = 0.74 of continuous
  engine.align(hole_ahead());
  ASSERT_EQ(sink.plans.size(), 1u);
  EXPECT_TRUE(sink.plans[0].home);
  EXPECT_EQ(sink.logged("(" + hot_joint + ": holds "), 1u) << sink.log_text;
}

// A rest is bounded: drives still hot after rest.timeout of robot time (20 s) at home, the
// request goes anyway, said so; a homing the planner refuses sends it at once from where the arm is.
TEST_F(RestTest, ARestEndsAfterItsTimeoutOrWhenTheArmCannotGoHome) {
  load(0.95, 30.0);
  engine.align(hole_ahead());
  ASSERT_TRUE(sink.plans.at(0).home);
  answer(PlanState::kSucceeded);
  const double home_at = robot_seconds();
  for (int i = 0; i < 100 && sink.plans.size() == 1; ++i) {
    load(0.95, 0.5);
    step();
  }
  ASSERT_EQ(sink.plans.size(), 2u) << sink.log_text;
  EXPECT_NEAR(robot_seconds() - home_at, tuning.rest.timeout, 0.5 + 1e-9);
  EXPECT_EQ(sink.logged("at home, its drives still at 0.95 of continuous; 1 plan request sent"), 1u) << sink.log_text;

  // The hole's next attempt, still hot: the planner cannot take the arm home.
  answer(PlanState::kFailed, PlanFailure::kUnreachable, "no posture reaches the hole");
  step();
  ASSERT_EQ(sink.plans.size(), 3u) << sink.log_text;
  EXPECT_TRUE(sink.plans[2].home);
  answer(PlanState::kFailed, PlanFailure::kUnreachable, "home: no collision-free path");
  step();
  ASSERT_EQ(sink.plans.size(), 4u) << sink.log_text;
  EXPECT_FALSE(sink.plans[3].home);
  EXPECT_EQ(sink.logged("the arm could not go home to rest (home: no collision-free path); asked from where it "
                        "stands; 1 plan request sent"),
            1u)
      << sink.log_text;
}

// A stop drops the requests a rest held back: none is sent after it.
TEST_F(RestTest, AStopDropsTheRequestsARestHeldBack) {
  load(0.95, 30.0);
  engine.align(hole_ahead());
  ASSERT_TRUE(sink.plans.at(0).home);
  engine.stop();
  answer(PlanState::kSucceeded);
  load(0.0, 30.0);
  step(10);
  EXPECT_EQ(sink.plans.size(), 1u) << sink.log_text;
}

// A loaded machine slows the simulated robot: the alignment's time limit counts the robot's time
// (the joint samples' stamps), so a wall clock running ten times faster fails nothing; the arm
// not aligned after align_timeout of its own time fails the hole, saying so.
TEST_F(RigEngineTest, TheAlignmentsTimeLimitCountsTheRobotsTimeNotTheWalls) {
  const DrillPoint hole = hole_ahead();
  engine.align(hole);
  answer(PlanState::kSucceeded);
  step();
  camera_sees_blob_at(hole.frame.translation(), tuning.camera.reanchor_frames);
  step(2);
  ASSERT_EQ(engine.alignment().progress, Progress::kRunning) << sink.log_text;
  const double limit = tuning.motion.align_timeout;
  // Wall time 2 x the limit, robot time a tenth of it: a new joint sample every tenth period.
  const int periods = static_cast<int>(2.0 * limit / 0.005);
  for (int i = 0; i < periods; ++i) {
    if (i % 10 == 0) sample();
    step();
  }
  EXPECT_EQ(engine.alignment().progress, Progress::kRunning) << engine.alignment().reason;
  // Robot time past the limit, the tip never moved onto the hole: the hole fails.
  for (int i = 0; i < static_cast<int>(limit / 0.005); ++i) {
    sample();
    step();
  }
  ASSERT_EQ(engine.alignment().progress, Progress::kFailed);
  EXPECT_EQ(engine.alignment().reason.rfind("not aligned after 15 s", 0), 0u) << engine.alignment().reason;
}

// Leaving contact is part of every stop at a hole: the bit (put by the arm's joints 10 mm into
// the hole the alignment aimed at) is pulled back along the hole's axis before the arm holds; a
// safety stop holds the robot, and the bit leaves once the stop is reset.
struct LeaveTest : RigEngineTest {
  DrillPoint hole;

  void SetUp() override {
    RigEngineTest::SetUp();
    inputs.on_safety({true, {}});
    // The arm bent (shoulder, elbow and wrist pitch: the demo arm's 2nd, 3rd and 5th joints), off
    // its stretched zero posture where the tip cannot move on along the bit.
    const std::vector<std::string>& arm = rig->model().arm().joints;
    const std::pair<std::size_t, double> bends[] = {{1, 0.3}, {2, 0.8}, {4, 0.5}};
    for (const auto& [index, angle] : bends) {
      const auto at = std::find(joints.names.begin(), joints.names.end(), arm.at(index));
      joints.positions[static_cast<std::size_t>(at - joints.names.begin())] = angle;
    }
    sample();
    // The hole 15 cm ahead of the bit on its axis: the arm reaches into it moving straight on.
    const Eigen::Isometry3d world_T_tip =
        rig->base_in_world(Eigen::Vector3d::Zero()) * rig->tip_in_base(rig->q(joints));
    hole.label = "blob 1";
    hole.frame = world_T_tip * Eigen::Translation3d(0.0, 0.0, 0.15) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY());
    engine.align(hole);
    answer(PlanState::kSucceeded);
    step();
    camera_sees_blob_at(hole.frame.translation(), tuning.camera.reanchor_frames);
    step(2);
    ASSERT_FALSE(sink.cartesian_frames.empty()) << "the alignment did not start" << sink.log_text;
  }

  // The arm's joints that put the tip `depth` [m] behind the hole's surface on its axis, the bit
  // along it (inverse kinematics of the rig's model), as the next joint sample.
  void tip_at_depth(double depth) {
    const Eigen::Isometry3d world_T_tip = hole.frame * Eigen::Translation3d(0.0, 0.0, -depth) *
                                          Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY());
    const Eigen::Isometry3d target = rig->base_in_world(Eigen::Vector3d::Zero()).inverse() * world_T_tip;
    const auto& k = rig->model().kinematics();
    kinematics::Data data = k.make_data();
    kinematics::IkOptions options;
    options.max_iterations = 5000;
    options.position_tolerance = 1e-5;
    options.orientation_tolerance = 1e-4;
    options.joints.clear();
    for (const std::string& j : rig->model().arm().joints) options.joints.push_back(k.joint_index_or_throw(j));
    const kinematics::IkResult ik = k.inverse_kinematics(data, rig->tcp_frame(), target, rig->q(joints), options);
    ASSERT_TRUE(ik.converged) << "no arm posture puts the tip " << depth << " m into the hole ("
                              << ik.position_error << " m, " << ik.orientation_error << " rad off after "
                              << ik.iterations << " iterations)";
    for (std::size_t i = 0; i < joints.positions.size(); ++i) joints.positions[i] = ik.q(static_cast<Eigen::Index>(i));
    sample();
  }
};

TEST_F(LeaveTest, AStopWithTheBitInTheWallPullsItOutAlongTheHolesAxisThenHolds) {
  tip_at_depth(0.01);
  step();
  const Eigen::Isometry3d tip = rig->tip_in_base(rig->q(joints));
  const std::size_t before = sink.cartesian_refs.size();
  engine.stop();
  EXPECT_TRUE(engine.leaving_wall());
  EXPECT_TRUE(sink.holds.empty()) << "held with the bit in the wall";
  // About 10 mm: the engine's hole is where the camera measured it again.
  EXPECT_EQ(sink.logged("leaving the wall: the bit "), 1u) << sink.log_text;
  EXPECT_EQ(sink.logged(" mm behind the surface, pulled back along the hole's axis to 40.0 mm in front of it"), 1u)
      << sink.log_text;
  // A new mission waits for the bit to be out.
  engine.start_mission({9, 101, "m", "name: m\ndepth: 0.03\nareas: []\n", "", false});
  ASSERT_FALSE(sink.refusals.empty());
  EXPECT_NE(sink.refusals.back().find("leaving the wall"), std::string::npos) << sink.refusals.back();
  // 1.2 s of the robot's time: the reference backs out along the hole's axis at the approach
  // speed, from about 9 mm in to the 40 mm standoff, and stays there. The hole's axis is the wall's
  // normal as the camera measured it (the synthetic view's wall faces the camera, 20 deg off the
  // bit): backwards along the bit within that.
  for (int i = 0; i < 240; ++i) {
    sample();
    step();
  }
  ASSERT_GT(sink.cartesian_refs.size(), before);
  const Eigen::Vector3d bit = tip.linear().col(2);
  const Eigen::Vector3d moved = sink.cartesian_refs.back().pose.translation() - tip.translation();
  EXPECT_NEAR(moved.norm(), 0.049, 0.004) << moved.transpose();
  EXPECT_GT(-moved.normalized().dot(bit), std::cos(0.4)) << moved.transpose();
  EXPECT_TRUE(sink.holds.empty());
  // The arm follows, the tip well out of the wall: the arm holds there.
  tip_at_depth(-0.06);
  step();
  EXPECT_FALSE(engine.leaving_wall());
  ASSERT_EQ(sink.holds.size(), 1u);
  EXPECT_EQ(sink.logged("the bit is out of the wall; the arm holds there"), 1u) << sink.log_text;
}

TEST_F(LeaveTest, UnderASafetyStopTheBitLeavesOnceTheStopIsReset) {
  tip_at_depth(0.01);
  step();
  inputs.on_safety({false, {"e-stop"}});
  engine.stop();
  EXPECT_TRUE(engine.leaving_wall());
  EXPECT_EQ(sink.logged("once the safety stop is reset"), 1u) << sink.log_text;
  const std::size_t sent = sink.cartesian_refs.size();
  for (int i = 0; i < 4000; ++i) {  // 20 s of the robot's time, longer than retract_timeout
    sample();
    step();
  }
  EXPECT_EQ(sink.cartesian_refs.size(), sent) << "commanded the robot during a safety stop";
  EXPECT_TRUE(engine.leaving_wall());
  inputs.on_safety({true, {}});
  sample();
  step();
  EXPECT_EQ(sink.logged("the safety stop is reset: leaving the wall now"), 1u) << sink.log_text;
  EXPECT_GT(sink.cartesian_refs.size(), sent);
  tip_at_depth(-0.06);
  step();
  EXPECT_FALSE(engine.leaving_wall());
  EXPECT_EQ(sink.holds.size(), 1u);
}

TEST_F(LeaveTest, ABitClearOfTheWallIsHeldAtOnce) {
  // The alignment's tip where the arm stands (0.5 m from the hole): nothing to leave.
  engine.stop();
  EXPECT_FALSE(engine.leaving_wall());
  EXPECT_EQ(sink.holds.size(), 1u);
}

// Odometry drifted while the whole body moved: the blob is seen 3 cm off its prediction, and
// the posture is planned again, the arm alone, for the hole where the camera sees it.
// While drilling, the thrust folds back as the hottest arm drive's RMS nears safety's bound
// (Params::Thermal), and the feed stops at fold_end until the drive cooled; said in the log once
// each.
TEST_F(LeaveTest, TheThrustFoldsBackAsTheArmsDrivesHeatUpAndTheFeedStopsAtTheBound) {
  std::string hot;
  double continuous = 0.0;
  for (const std::string& j : rig->model().arm().joints) {
    const model::JointLimits& l = rig->model().limits().at(j);
    if (l.continuous_torque > continuous) {
      continuous = l.continuous_torque;
      hot = j;
    }
  }
  const auto load = [&](double share, double seconds) {
    std::vector<double> efforts(joints.names.size(), 1.0);
    efforts[static_cast<std::size_t>(std::find(joints.names.begin(), joints.names.end(), hot) - joints.names.begin())] =
        share * continuous;
    for (int i = 0; i < static_cast<int>(std::lround(seconds / 0.005)); ++i) {
      stamp_ns += 5'000'000;
      inputs.on_joints(stamp_ns, joints, Inputs::Clock::now(), efforts);
      step();
    }
  };
  engine.drill(hole, 0.03);
  // Within the drilling's 30 s time limit: the bit stands still, so it is in contact at once.
  load(0.9, 9.0);  // RMS 0.82 of continuous
  EXPECT_EQ(sink.logged("thrust folds back"), 0u) << sink.log_text;
  load(1.0, 7.0);  // RMS 0.96: past fold_start (0.95), short of fold_end (1.05)
  EXPECT_EQ(sink.logged("blob 1: the arm's drives at 0.95 of their continuous torque (RMS): the thrust folds back"), 1u)
      << sink.log_text;
  EXPECT_EQ(sink.logged("the feed stops"), 0u) << sink.log_text;
  load(1.1, 8.0);  // RMS 1.07
  EXPECT_EQ(sink.logged("blob 1: the arm's drives at 1.05 of their continuous torque (RMS): the feed stops until "
                        "they cool below 0.95"),
            1u)
      << sink.log_text;
  EXPECT_EQ(engine.drilling().progress, Progress::kRunning) << sink.log_text;
}

TEST_F(RigEngineTest, ADriftedOdometryPlansThePostureAgainWhereTheCameraSeesTheHole) {
  const DrillPoint hole = hole_ahead();
  engine.align(hole);
  fail_until_whole_body();
  answer(PlanState::kSucceeded);
  step();
  const Eigen::Vector3d seen = hole.frame * Eigen::Vector3d(0.03, 0.0, 0.0);  // 3 cm along the wall
  camera_sees_blob_at(seen, tuning.camera.reanchor_frames);
  const std::size_t asked = sink.plans.size();
  step();
  ASSERT_EQ(sink.plans.size(), asked + 1) << sink.log_text;
  const PlanAsk again = sink.plans.back();
  EXPECT_TRUE(again.fixed_base);
  ASSERT_EQ(again.goals.size(), 1u);
  EXPECT_LT((again.goals[0].translation() - seen).norm(), 0.003) << sink.log_text;
  EXPECT_TRUE(sink.cartesian_frames.empty());

  // Stopped on the way there (a safety stop): the hole fails. Before, a posture aborted after
  // the re-measure was taken for "no posture for the arm alone", and the whole body's posture
  // was planned once more.
  answer(PlanState::kFailed, PlanFailure::kExecutionAborted, "execution aborted: safety stop");
  step(10);
  EXPECT_EQ(engine.alignment().progress, Progress::kFailed);
  EXPECT_EQ(engine.alignment().reason, "planner: the hole's drilling posture: execution aborted: safety stop");
  EXPECT_EQ(sink.plans.size(), asked + 1) << sink.log_text;
  EXPECT_TRUE(sink.cartesian_frames.empty());
}

// Measured again and no posture for the arm alone there: the whole body's posture is planned
// once more for the hole where the camera saw it (hole.body_replans).
TEST_F(RigEngineTest, NoArmAlonePostureAtTheHoleMeasuredAgainPlansTheWholeBodyAgain) {
  const DrillPoint hole = hole_ahead();
  engine.align(hole);
  fail_until_whole_body();
  answer(PlanState::kSucceeded);
  step();
  const Eigen::Vector3d seen = hole.frame * Eigen::Vector3d(0.03, 0.0, 0.0);
  camera_sees_blob_at(seen, tuning.camera.reanchor_frames);
  step();
  const std::size_t asked = sink.plans.size();
  answer(PlanState::kFailed, PlanFailure::kUnreachable, "no posture reaches the hole");
  step();
  ASSERT_EQ(sink.plans.size(), asked + 1) << sink.log_text;
  EXPECT_FALSE(sink.plans.back().fixed_base);
  EXPECT_LT((sink.plans.back().goals.at(0).translation() - seen).norm(), 0.003);
  EXPECT_EQ(sink.logged("the whole body's posture planned again for it"), 1u) << sink.log_text;
}


// An ArUco hole (the default pattern table): from its arm-alone posture the camera is turned
// onto the marker first. A safety stop while it turns fails the hole; no further look is asked
// for. Before, the next look attempt was planned and executed.
TEST_F(RigEngineTest, ASafetyStopWhileTheCameraTurnsOntoTheMarkerFailsTheHole) {
  FakeSink marker_sink;
  DrillEngine marker_engine(
      EngineParams{std::string(CONCERT_SOURCE_DIR) + "/services/drill/config/patterns.yaml", {}, tuning},
      inputs, map_frame, marker_sink);
  marker_engine.apply_model(2, rig, "");
  DrillPoint hole = hole_ahead();
  hole.label = "aruco 0 hole 1";
  hole.marker = 0;
  hole.pattern_index = 0;
  marker_engine.align(hole);
  ASSERT_EQ(marker_sink.plans.size(), 1u);
  ASSERT_TRUE(marker_sink.plans[0].fixed_base);
  PlanReply posture = reply(marker_sink.plans[0].request_id, PlanState::kSucceeded);
  posture.path = {{"base_x", "base_y", "base_yaw"}, {{0.0, {0.0, 0.0, 0.0}, {}}}};
  inputs.on_plan(posture);
  marker_engine.step_motion(0.005);
  ASSERT_EQ(marker_sink.plans.size(), 2u) << marker_sink.log_text;
  const PlanAsk look = marker_sink.plans[1];
  EXPECT_GT(look.camera_distance, 0.0);  // the camera, not the bit, onto the marker
  EXPECT_EQ(look.tip_distance, 0.0);
  PlanReply aborted = reply(look.request_id, PlanState::kFailed);
  aborted.failure = PlanFailure::kExecutionAborted;
  aborted.reason = "execution aborted: safety stop";
  inputs.on_plan(aborted);
  for (int i = 2; i < 12; ++i) marker_engine.step_motion(0.005 * i);
  EXPECT_EQ(marker_engine.alignment().progress, Progress::kFailed);
  EXPECT_EQ(marker_engine.alignment().reason, "planner: the look at the hole's mark: execution aborted: safety stop");
  EXPECT_EQ(marker_sink.plans.size(), 2u) << marker_sink.log_text;
  EXPECT_TRUE(marker_sink.cartesian_frames.empty());
}

// A marker hole none of whose whole-body postures lets the camera see the marker: the base is
// placed for it alone (postures drawn further out, each checked for the arm alone onto the hole
// and a look at the marker), moved there, and the camera turned onto the marker before the hole
// is aligned. Without a placement with a look either, the last posture drawn is taken.
struct UnseenMarkerTest : RigEngineTest {
  FakeSink ms;
  DrillEngine me{EngineParams{std::string(CONCERT_SOURCE_DIR) + "/services/drill/config/patterns.yaml", {}, tuning},
                 inputs, map_frame, ms};
  std::vector<std::uint32_t> answered;
  bool views_only = false;  // a look is found only from beside the marker (view_slant)

  void SetUp() override {
    RigEngineTest::SetUp();
    me.apply_model(2, rig, "");
  }

  // Answers every plan request not answered yet: a posture for the bit (the hole's, the arm
  // alone or the whole body, or a placement's draw) found, the arm alone's from where the base
  // stands not; a look at the marker found when `looks` says so.
  void answer_pending(bool looks) {
    for (const PlanAsk& r : std::vector<PlanAsk>(ms.plans)) {
      if (std::find(answered.begin(), answered.end(), r.request_id) != answered.end()) continue;
      answered.push_back(r.request_id);
      const bool look = r.camera_distance > 0.0;
      const bool standing = r.fixed_base && r.tip_distance > 0.0 && r.start_position.empty() && !r.execute;
      const bool found = look ? (views_only ? r.view_slant > 0.0 : looks)
                              : !(standing || (r.fixed_base && r.execute && r.start_position.empty()));
      PlanReply p = reply(r.request_id, found ? PlanState::kSucceeded : PlanState::kFailed);
      if (found) {
        p.path.names = {"base_x", "base_y", "base_yaw"};
        p.path.samples = {{0.0, {0.0, 0.0, 0.0}, {}}};
        for (const std::string& j : rig->model().arm().joints) {
          p.path.names.push_back(j);
          p.path.samples[0].position.push_back(0.0);
        }
      } else {
        p.failure = PlanFailure::kUnreachable;
        p.reason = "no feasible posture";
      }
      inputs.on_plan(p);
    }
  }

  DrillPoint marker_hole() const {
    DrillPoint hole = hole_ahead();
    hole.label = "aruco 0 hole 1";
    hole.marker = 0;
    hole.pattern_index = 0;
    return hole;
  }

  // Aligns the hole, the arm alone never reaching it and no whole-body posture with a look,
  // until the robot is sent a trajectory (bounded).
  void until_trajectory(bool placement_looks) {
    me.align(marker_hole());
    for (int i = 0; i < 400 && ms.trajectories.empty(); ++i) {
      const bool placing = ms.logged("placed for this hole alone") > 0;
      answer_pending(placing && placement_looks);
      me.step_motion(now += 0.005);
    }
  }
};

TEST_F(UnseenMarkerTest, TheBaseIsPlacedForTheHoleAloneThenTheMarkerLookedAt) {
  until_trajectory(true);
  ASSERT_EQ(ms.trajectories.size(), 1u) << ms.log_text;
  EXPECT_EQ(ms.logged("whole-body postures drawn; the base placed for this hole alone"), 1u) << ms.log_text;
  // The placement's draw: the whole body, planned only, the bit further out than the hole's.
  const auto draw = std::find_if(ms.plans.begin(), ms.plans.end(), [](const PlanAsk& r) {
    return !r.fixed_base && !r.execute && r.tip_distance > 0.2;
  });
  ASSERT_NE(draw, ms.plans.end()) << ms.log_text;
  EXPECT_NEAR(draw->tip_distance, tuning.motion.standoff + tuning.hole.align_margin + tuning.placement.draws[0].out,
              1e-9);
  EXPECT_EQ(ms.logged("the whole body to posture 1 drawn"), 1u) << ms.log_text;
  // The move ran: the camera turned onto the marker from where the base stands, executed.
  const std::size_t asked = ms.plans.size();
  inputs.on_trajectory(ms.trajectories.back(), {Progress::kSucceeded, "", ""});
  me.step_motion(now += 0.005);
  ASSERT_EQ(ms.plans.size(), asked + 1) << ms.log_text;
  EXPECT_GT(ms.plans.back().camera_distance, 0.0);
  EXPECT_TRUE(ms.plans.back().fixed_base);
  EXPECT_TRUE(ms.plans.back().execute);
  EXPECT_EQ(me.alignment().progress, Progress::kRunning);
}

TEST_F(UnseenMarkerTest, WithoutAPlacementWithALookTheLastPostureDrawnIsTaken) {
  until_trajectory(false);
  ASSERT_EQ(ms.trajectories.size(), 1u) << ms.log_text;
  EXPECT_EQ(ms.logged("the base placed for this hole alone"), 1u) << ms.log_text;
  EXPECT_EQ(ms.logged("no placement reaches it with a look at marker 0 either; the last whole-body posture drawn taken"),
            1u)
      << ms.log_text;
  EXPECT_EQ(me.alignment().progress, Progress::kRunning);
}

// No look on the marker's normal from the whole body's posture, one from beside it (a low row on
// morphology A): the posture is taken with that look, nothing placed for the hole alone; the
// look asked last is the view from any side within looks.attempts' slant, as near as frames the
// marker and out to its `further` beyond the posture's distance.
TEST_F(UnseenMarkerTest, AWholeBodyPostureWhenceTheCameraSeesTheMarkerOnlyFromBesideIsTaken) {
  views_only = true;
  const LookAttempt& view = tuning.looks.attempts.back();
  ASSERT_GT(view.slant, 0.0);
  until_trajectory(false);
  ASSERT_EQ(ms.trajectories.size(), 1u) << ms.log_text;
  EXPECT_EQ(ms.logged("placed for this hole alone"), 0u) << ms.log_text;
  EXPECT_EQ(ms.logged("the last whole-body posture drawn taken"), 0u) << ms.log_text;
  const auto views = std::count_if(ms.plans.begin(), ms.plans.end(), [](const PlanAsk& r) { return r.view_slant > 0.0; });
  EXPECT_EQ(views, 1) << ms.log_text;
  const auto asked = std::find_if(ms.plans.begin(), ms.plans.end(), [](const PlanAsk& r) { return r.view_slant > 0.0; });
  ASSERT_NE(asked, ms.plans.end());
  EXPECT_DOUBLE_EQ(asked->view_slant, view.slant);
  EXPECT_GT(asked->view_near, 0.0);
  EXPECT_GE(asked->camera_distance, asked->view_near + view.further - 1e-9);
  EXPECT_TRUE(asked->fixed_base);
  EXPECT_EQ(asked->tip_distance, 0.0);
  EXPECT_FALSE(asked->start_position.empty()) << "the look is checked from the end of the posture drawn";
  // The posture ran: the camera is turned onto the marker along the look checked.
  inputs.on_trajectory(ms.trajectories.back(), {Progress::kSucceeded, "", ""});
  me.step_motion(now += 0.005);
  EXPECT_EQ(ms.trajectories.size(), 2u) << ms.log_text;
  EXPECT_EQ(me.alignment().progress, Progress::kRunning);
}

TEST_F(UnseenMarkerTest, PlacingForAnUnseenHoleCanBeTurnedOff) {
  tuning.hole.place_unseen = false;
  DrillEngine off{EngineParams{std::string(CONCERT_SOURCE_DIR) + "/services/drill/config/patterns.yaml", {}, tuning},
                  inputs, map_frame, ms};
  off.apply_model(2, rig, "");
  off.align(marker_hole());
  for (int i = 0; i < 400 && ms.trajectories.empty(); ++i) {
    answer_pending(false);
    off.step_motion(now += 0.005);
  }
  ASSERT_EQ(ms.trajectories.size(), 1u) << ms.log_text;
  EXPECT_EQ(ms.logged("placed for this hole alone"), 0u) << ms.log_text;
  EXPECT_EQ(ms.logged("whole-body postures drawn; the last one taken"), 1u) << ms.log_text;
}

}  // namespace
}  // namespace concert::drill
