// The drill's mission engine (drill/engine.hpp) without DDS: a fake sink records what it would
// send, Inputs gets what the planner and the robot would answer, the test ticks the clock.
#include "drill/engine.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

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
  std::string log_text;

  void plan(const PlanAsk& ask) override { plans.push_back(ask); }
  void trajectory(std::uint32_t id, std::uint32_t, const std::vector<std::string>&,
                  const std::vector<PathSample>&) override {
    trajectories.push_back(id);
  }
  void navigate(std::uint32_t, std::uint32_t, const BasePose&) override {}
  void cancel_navigation() override { ++cancels; }
  void hold(std::uint32_t, const JointPositions& arm) override { holds.push_back(arm); }
  void cartesian(std::uint32_t, const std::string&, const CartesianReference&) override {}
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

}  // namespace
}  // namespace concert::drill
