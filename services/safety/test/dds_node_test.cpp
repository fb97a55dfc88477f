// Safety adapter over real DDS (one process): inputs in, SafetyState out; and the heartbeat
// of StatusReporter that the liveliness check relies on.
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <functional>
#include <sstream>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "dds/conversions.hpp"
#include "safety/latched_state.hpp"
#include "dds/safety_node.hpp"
#include "test_helpers.hpp"

namespace concert::safety::dds {
namespace {

using namespace std::chrono_literals;
using test::wait_state;

/// Polls `done` every 20 ms for at most `timeout`.
bool eventually(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return done();
}

msg::EStopInput estop(msg::EStopSource source, bool engaged) {
  msg::EStopInput in;
  in.source(source);
  in.engaged(engaged);
  in.reason("test");
  return in;
}


TEST(StatusHeartbeat, StatusIsRepublishedPeriodicallyThenStops) {
  Participant p({.name = "hb"});
  Reader<msg::ServiceStatus> reader(p, topics::status);
  int beats = 0;
  int64_t last_stamp = 0;
  bool stopped = false;
  {
    concert::dds::StatusReporter status(p, "hb_test", "h1", 50ms);
    EXPECT_EQ(status.heartbeat(), 50ms);
    status.report(msg::SERVICE_READY, 3, "ok");
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (beats < 5 && std::chrono::steady_clock::now() < deadline) {
      if (auto s = reader.wait(100ms); s && s->state() == msg::SERVICE_READY) {
        EXPECT_EQ(s->model_version(), 3u);
        EXPECT_EQ(s->message(), "ok");
        EXPECT_GT(s->stamp_ns(), last_stamp);
        last_stamp = s->stamp_ns();
        ++beats;
      }
    }
  }
  EXPECT_EQ(beats, 5);
  for (int i = 0; i < 50 && !stopped; ++i) {
    if (auto s = reader.wait(100ms)) stopped = s->state() == msg::SERVICE_STOPPED;
  }
  EXPECT_TRUE(stopped);
}

TEST(StatusHeartbeat, HostNameFollowsConcertHost) {
  setenv("CONCERT_HOST", "manip-pc", 1);
  EXPECT_EQ(concert::dds::host_name(), "manip-pc");
  unsetenv("CONCERT_HOST");
  EXPECT_NE(concert::dds::host_name(), "manip-pc");
}

class SafetyNodeTest : public ::testing::Test {
 protected:
  SafetyNodeTest() {
    Params params;
    params.liveliness_timeout = 400ms;
    params.check_period = 20ms;
    node_ = std::make_unique<SafetyNode>(participant_, params, log_);
    spinner_ = std::thread([this] { node_->spin(stop_); });
  }
  ~SafetyNodeTest() override {
    stop_ = true;
    spinner_.join();
  }

  Participant participant_{{.name = "safety_node_test"}};
  std::ostringstream log_;
  std::unique_ptr<SafetyNode> node_;
  std::atomic<bool> stop_{false};
  std::thread spinner_;
  Reader<msg::SafetyState> states_{participant_, topics::safety_state};
};

TEST_F(SafetyNodeTest, EStopLatchesUntilReleasedAndReset) {
  Writer<msg::EStopInput> inputs(participant_, topics::estop);
  Writer<msg::SafetyReset> resets(participant_, topics::safety_reset);
  ASSERT_TRUE(wait_state(
      states_, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 10s));

  ASSERT_TRUE(inputs.write(estop(msg::ESTOP_WIRELESS, true)));
  ASSERT_TRUE(wait_state(
      states_,
      [](const auto& s) {
        return s.mode() == msg::SAFETY_STOPPED && s.reset_required() && s.causes().size() == 1 &&
               s.causes()[0] == "estop: wireless engaged (test)" && s.engaged_inputs().size() == 1 &&
               s.engaged_inputs()[0] == msg::ESTOP_WIRELESS;
      },
      10s));

  msg::SafetyReset reset;
  reset.request_id(1);
  reset.source("unit test");
  ASSERT_TRUE(resets.write(reset));
  EXPECT_TRUE(eventually(
      [&] {
        return log_.str().find("refused: e-stop input(s) still engaged: wireless") !=
               std::string::npos;
      },
      10s))
      << log_.str();
  EXPECT_EQ(node_->status().mode, Mode::kStopped);

  ASSERT_TRUE(inputs.write(estop(msg::ESTOP_WIRELESS, false)));
  // Once the node has taken the release, the stop must still be latched (no reset yet).
  ASSERT_TRUE(eventually([&] { return node_->engaged_inputs().empty(); }, 10s)) << log_.str();
  EXPECT_EQ(node_->status().mode, Mode::kStopped);
  // The release alone goes out as a new state: still stopped, nothing engaged.
  EXPECT_TRUE(wait_state(
      states_,
      [](const auto& s) { return s.mode() == msg::SAFETY_STOPPED && s.engaged_inputs().empty(); }, 10s));
  EXPECT_TRUE(node_->status().reset_required);
  // The release and the reset travel on different topics: on a loaded machine the reset can
  // be handled before the release. Like an operator, reset again (bounded) until accepted.
  bool running = false;
  for (uint32_t id = 2; id < 22 && !running; ++id) {
    reset.request_id(id);
    ASSERT_TRUE(resets.write(reset));
    running = wait_state(
        states_, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING && s.causes().empty(); },
        500ms);
  }
  EXPECT_TRUE(running) << log_.str();
}

// A client that has not heard the answer writes its reset again (concert safety reset resends
// every second): the copy is the same press and must not clear a stop that came after it.
TEST_F(SafetyNodeTest, AResetWrittenAgainIsTakenOnceAndCannotClearALaterStop) {
  Writer<msg::EStopInput> inputs(participant_, topics::estop);
  Writer<msg::SafetyReset> resets(participant_, topics::safety_reset);
  ASSERT_TRUE(wait_state(
      states_, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 10s));
  const auto stop_and_release = [&] {
    ASSERT_TRUE(inputs.write(estop(msg::ESTOP_WIRELESS, true)));
    ASSERT_TRUE(eventually([&] { return node_->status().mode == Mode::kStopped; }, 10s));
    ASSERT_TRUE(inputs.write(estop(msg::ESTOP_WIRELESS, false)));
  };
  stop_and_release();
  msg::SafetyReset reset;
  reset.source("unit test");
  reset.stamp_ns(1'000'000);
  // The operator's press (request ids from 100, as often as the release needs to be heard).
  bool running = false;
  uint32_t id = 100;
  for (; id < 120 && !running; ++id) {
    reset.request_id(id);
    ASSERT_TRUE(resets.write(reset));
    running = eventually([&] { return node_->status().mode == Mode::kRunning; }, 500ms);
  }
  ASSERT_TRUE(running) << log_.str();
  const uint32_t accepted = id - 1;

  log_.str("");
  stop_and_release();
  reset.request_id(accepted);  // the accepted press, written again
  ASSERT_TRUE(resets.write(reset));
  EXPECT_TRUE(eventually(
      [&] {
        return log_.str().find("reset " + std::to_string(accepted) +
                               " by unit test seen again, ignored") != std::string::npos;
      },
      10s))
      << log_.str();
  EXPECT_EQ(node_->status().mode, Mode::kStopped) << log_.str();
  // A new press (a new stamp; again until the release has been heard) resets it.
  running = false;
  for (int64_t stamp = 2'000'000; stamp < 2'000'020 && !running; ++stamp) {
    reset.stamp_ns(stamp);
    ASSERT_TRUE(resets.write(reset));
    running = eventually([&] { return node_->status().mode == Mode::kRunning; }, 500ms);
  }
  EXPECT_TRUE(running) << log_.str();
}

TEST_F(SafetyNodeTest, SilentTaskServiceStopsWithItsName) {
  Writer<msg::ServiceStatus> statuses(participant_, topics::status);
  msg::ServiceStatus beat;
  beat.id(concert::dds::status_instance_id("planner", "manip"));
  beat.service("planner");
  beat.host("manip");
  beat.state(msg::SERVICE_READY);
  for (int i = 0; i < 10; ++i) {  // 0.5 s of heartbeats: alive
    ASSERT_TRUE(statuses.write(beat));
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_EQ(node_->status().mode, Mode::kRunning);
  ASSERT_TRUE(wait_state(
      states_,
      [](const auto& s) {
        return s.mode() == msg::SAFETY_STOPPED && s.causes().size() == 1 &&
               s.causes()[0].find("liveliness: planner@manip silent for") == 0;
      },
      10s))
      << log_.str();
}

// A safety service restarted while the watched services keep beating (the chaos test's
// planner-then-safety round): the stop in its state file survives. The status topic is
// latched, so the new process's reader gets the heartbeats at once; a heartbeat handled before
// the restore persisted the fresh RUNNING over the file's stop, which the restore then read
// back.
TEST(SafetyNodeRestore, HeartbeatsDuringTheRestartDoNotReplaceTheLatchedStop) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("safety_restore_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "safety_state.yaml").string();
  LatchedState stopped;
  stopped.mode = Mode::kStopped;
  stopped.causes = {"liveliness: planner@manip restarted"};
  stopped.cause_keys = {"restarted:planner@manip"};
  stopped.watched = {{"planner@manip", "old"}};

  Participant services({.name = "services"});
  Writer<msg::ServiceStatus> statuses(services, topics::status);
  std::atomic<bool> beating{true};
  std::thread beats([&] {
    msg::ServiceStatus beat;
    beat.id(concert::dds::status_instance_id("planner", "manip"));
    beat.service("planner");
    beat.host("manip");
    beat.state(msg::SERVICE_READY);
    for (int i = 0; i < 20000 && beating; ++i) {  // bounded: 20 s at most
      statuses.write(beat);
      std::this_thread::sleep_for(1ms);
    }
  });
  Params params;
  params.liveliness_timeout = 2s;
  for (int restart = 0; restart < 8; ++restart) {
    save_latched_state(file, stopped);
    Participant participant({.name = "safety"});
    std::ostringstream log;
    SafetyNode node(participant, params, log, file);
    std::this_thread::sleep_for(100ms);  // heartbeats flowing into the restored node
    EXPECT_EQ(node.status().mode, Mode::kStopped) << "restart " << restart << ":\n" << log.str();
    EXPECT_EQ(load_latched_state(file).mode, Mode::kStopped) << "restart " << restart << ":\n" << log.str();
  }
  beating = false;
  beats.join();
  std::filesystem::remove_all(dir);
}

TEST_F(SafetyNodeTest, JointBeyondModelLimitStops) {
  Writer<msg::RobotModel> models(participant_, topics::robot_model);
  Writer<msg::JointState> joints(participant_, topics::joint_state);
  msg::RobotModel model;
  model.version(5);
  msg::JointInfo j;
  j.name("J1_A");
  j.lower(-1.0);
  j.upper(1.0);
  j.velocity(2.0);
  j.peak_torque(80.0);
  j.continuous_torque(80.0);
  model.joints({j});
  ASSERT_TRUE(models.write(model));
  ASSERT_TRUE(eventually(
      [&] { return log_.str().find("limits of model v5 (1 joints)") != std::string::npos; }, 10s));
  ASSERT_TRUE(joints.wait_for_readers(1, 10s));

  msg::JointState state;
  state.model_version(5);
  state.name({"J1_A"});
  state.position({0.5});
  state.velocity({0.0});
  state.effort({10.0});
  // Best-effort stream: send until the node has checked some samples (bounded).
  for (int i = 0; i < 200 && node_->checked_samples() < 5; ++i) {
    joints.write(state);
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_GE(node_->checked_samples(), 5u);
  EXPECT_EQ(node_->status().mode, Mode::kRunning);

  state.effort({95.0});
  for (int i = 0; i < 200 && node_->status().mode == Mode::kRunning; ++i) {
    joints.write(state);
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_EQ(node_->status().mode, Mode::kStopped);
  EXPECT_EQ(node_->status().causes[0], "limits: joint J1_A effort 95.00 beyond the peak torque +-88.00 (model v5)");
}

TEST(SafetyConversions, EStopSourcesRoundTrip) {
  for (std::size_t i = 0; i < kEStopSourceCount; ++i) {
    const auto s = static_cast<EStopSource>(i);
    EXPECT_EQ(to_core(to_msg(s)), s);
  }
  EXPECT_FALSE(to_core(static_cast<msg::EStopSource>(42)));
}

}  // namespace
}  // namespace concert::safety::dds
