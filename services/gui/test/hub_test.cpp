#include "gui/hub.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

namespace concert::gui {
namespace {

using testing::HasSubstr;
constexpr int64_t kMs = 1'000'000;

struct FakeBus : Bus {
  std::vector<std::pair<std::string, Json>> published;
  std::vector<std::pair<std::string, bool>> wanted;
  bool fail = false;
  void publish(const std::string& topic, const Json& sample) override {
    if (fail) throw std::runtime_error("field 'bogus' is not a field of the type");
    published.emplace_back(topic, sample);
  }
  void set_wanted(const std::string& topic, bool w) override { wanted.emplace_back(topic, w); }
};

struct FakeSink : ClientSink {
  std::map<ClientId, std::vector<Json>> text;
  std::map<ClientId, int> binary;
  size_t backlog = 0;
  void send(ClientId c, std::string m, bool bin) override {
    if (bin) {
      ++binary[c];
    } else {
      text[c].push_back(Json::parse(m));
    }
  }
  size_t buffered_bytes(ClientId) override { return backlog; }
  std::vector<Json> of(ClientId c, const std::string& op) {
    std::vector<Json> out;
    for (const auto& m : text[c]) {
      if (m["op"] == op) out.push_back(m);
    }
    return out;
  }
};

class HubTest : public testing::Test {
 protected:
  HubTest()
      : hub_({{"concert/safety/state", "concert::msg::SafetyState", TopicKind::kState, ""},
              {"concert/safety/estop", "concert::msg::EStopInput", TopicKind::kState, ""},
              {"concert/robot/joint_state", "concert::msg::JointState", TopicKind::kStream, ""},
              {"concert/sensors/camera/rgb", "concert::msg::Image", TopicKind::kImage, ""},
              {"concert/robot/joint_command", "concert::msg::JointCommand", TopicKind::kCommand, ""}},
             HubParams{}, log_) {
    hub_.attach(&bus_, &sink_);
  }
  void say(ClientId c, const Json& m) { hub_.on_message(c, m.dump(), 42); }

  std::ostringstream log_;
  FakeBus bus_;
  FakeSink sink_;
  Hub hub_;
};

TEST_F(HubTest, HelloListsTopicsAndWhichAreCommandable) {
  hub_.connect(1, "127.0.0.1:5000");
  const auto hello = sink_.of(1, "hello");
  ASSERT_EQ(hello.size(), 1u);
  EXPECT_EQ(hello[0]["client"], "127.0.0.1:5000");
  bool estop = false, joint = false;
  for (const auto& t : hello[0]["topics"]) {
    if (t["topic"] == "concert/safety/estop") estop = t["commandable"].get<bool>();
    if (t["topic"] == "concert/robot/joint_command") joint = !t["commandable"].get<bool>();
  }
  EXPECT_TRUE(estop);
  EXPECT_TRUE(joint);
}

TEST_F(HubTest, StateTopicsGiveTheLatestSampleToALateSubscriberAndEveryNewOne) {
  int decodes = 0;
  hub_.on_sample("concert/safety/state", "", [&] { ++decodes; return Json{{"mode", "SAFETY_RUNNING"}}; }, 0);
  EXPECT_EQ(decodes, 1);  // kept for late subscribers even with nobody listening
  hub_.connect(1, "a");
  say(1, {{"op", "subscribe"}, {"topic", "concert/safety/state"}});
  auto samples = sink_.of(1, "sample");
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_EQ(samples[0]["data"]["mode"], "SAFETY_RUNNING");
  for (int64_t i = 0; i < 5; ++i) {
    hub_.on_sample("concert/safety/state", "", [] { return Json{{"mode", "SAFETY_STOPPED"}}; }, i * kMs);
  }
  EXPECT_EQ(sink_.of(1, "sample").size(), 6u);  // state samples are never rate-limited
}

TEST_F(HubTest, StreamsAreRateLimitedPerClientAndDecodedOnlyWhenDue) {
  hub_.connect(1, "slow");
  hub_.connect(2, "fast");
  say(1, {{"op", "subscribe"}, {"topic", "concert/robot/joint_state"}, {"max_hz", 5}});
  say(2, {{"op", "subscribe"}, {"topic", "concert/robot/joint_state"}, {"max_hz", 1000}});  // capped at 30
  EXPECT_EQ(sink_.of(2, "ack")[0]["max_hz"], 30.0);
  int decodes = 0;
  for (int64_t i = 0; i < 1000; ++i) {
    hub_.on_sample("concert/robot/joint_state", "", [&] { ++decodes; return Json{{"i", i}}; }, i * kMs);
  }
  EXPECT_EQ(sink_.of(1, "sample").size(), 5u);
  EXPECT_EQ(sink_.of(2, "sample").size(), 30u);
  EXPECT_LE(decodes, 35);  // decoded once per due sample, not 1000 times
  EXPECT_GE(hub_.dropped(), 1000u * 2 - 35);
  const auto rates = hub_.rates(999 * kMs);
  const auto js = std::find_if(rates.begin(), rates.end(), [](auto& r) { return r.topic == "concert/robot/joint_state"; });
  EXPECT_NEAR(js->hz, 1000.0, 1.0);
}

TEST_F(HubTest, ABackloggedClientGetsNoStreamSamplesButStillGetsState) {
  hub_.connect(1, "wifi");
  say(1, {{"op", "subscribe"}, {"topic", "concert/robot/joint_state"}});
  say(1, {{"op", "subscribe"}, {"topic", "concert/safety/state"}});
  sink_.backlog = 10u << 20;
  hub_.on_sample("concert/robot/joint_state", "", [] { return Json::object(); }, 0);
  hub_.on_sample("concert/safety/state", "", [] { return Json::object(); }, 0);
  const auto samples = sink_.of(1, "sample");
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_EQ(samples[0]["topic"], "concert/safety/state");
}

TEST_F(HubTest, CameraFramesAreWantedOnlyWhileSomeoneWatchesAndEncodedOnce) {
  hub_.connect(1, "a");
  hub_.connect(2, "b");
  say(1, {{"op", "subscribe"}, {"topic", "concert/sensors/camera/rgb"}});
  say(2, {{"op", "subscribe"}, {"topic", "concert/sensors/camera/rgb"}});
  ASSERT_EQ(bus_.wanted.size(), 1u);
  EXPECT_TRUE(bus_.wanted[0].second);
  int encodes = 0;
  hub_.on_frame("concert/sensors/camera/rgb", "cam", [&] { ++encodes; return std::optional<std::string>("jpeg"); }, 0);
  EXPECT_EQ(encodes, 1);
  EXPECT_EQ(sink_.binary[1], 1);
  EXPECT_EQ(sink_.binary[2], 1);
  hub_.on_frame("concert/sensors/camera/rgb", "cam", [&] { ++encodes; return std::optional<std::string>("x"); }, kMs);
  EXPECT_EQ(encodes, 1);  // 2 Hz by default: not due 1 ms later
  hub_.disconnect(1);
  EXPECT_EQ(bus_.wanted.size(), 1u);
  say(2, {{"op", "unsubscribe"}, {"topic", "concert/sensors/camera/rgb"}});
  ASSERT_EQ(bus_.wanted.size(), 2u);
  EXPECT_FALSE(bus_.wanted[1].second);
}

TEST_F(HubTest, AllowListedCommandsArePublishedAndLoggedWithTheirOrigin) {
  hub_.connect(7, "192.168.1.20:51544");
  say(7, {{"op", "publish"}, {"topic", "concert/safety/estop"}, {"data", {{"engaged", true}}}, {"id", 11}});
  ASSERT_EQ(bus_.published.size(), 1u);
  EXPECT_EQ(bus_.published[0].second["source"], "ESTOP_SOFTWARE");
  EXPECT_EQ(sink_.of(7, "ack")[0]["id"], 11);
  EXPECT_THAT(log_.str(), HasSubstr("command from 192.168.1.20:51544 (client 7) on concert/safety/estop"));
  EXPECT_EQ(hub_.commands_published(), 1u);
}

TEST_F(HubTest, OtherCommandsAreRefusedLoggedAndNeverPublished) {
  hub_.connect(3, "10.0.0.9:1");
  say(3, {{"op", "publish"}, {"topic", "concert/robot/joint_command"}, {"data", Json::object()}, {"id", 5}});
  EXPECT_TRUE(bus_.published.empty());
  const auto errors = sink_.of(3, "error");
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0]["id"], 5);
  EXPECT_THAT(errors[0]["error"].get<std::string>(), HasSubstr("not an operator command"));
  EXPECT_THAT(log_.str(), HasSubstr("REFUSED from 10.0.0.9:1"));
  // A command the bus refuses (bad field) is an error too, with the reason.
  bus_.fail = true;
  say(3, {{"op", "publish"}, {"topic", "concert/safety/estop"}, {"data", {{"bogus", 1}}}});
  EXPECT_THAT(sink_.of(3, "error").back()["error"].get<std::string>(), HasSubstr("bogus"));
  EXPECT_EQ(hub_.commands_refused(), 2u);
}

TEST_F(HubTest, UnknownTopicsAndBadMessagesGetErrors) {
  hub_.connect(1, "a");
  say(1, {{"op", "subscribe"}, {"topic", "no/such"}});
  hub_.on_message(1, "garbage", 0);
  const auto errors = sink_.of(1, "error");
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_THAT(errors[0]["error"].get<std::string>(), HasSubstr("no/such"));
  EXPECT_THAT(errors[1]["error"].get<std::string>(), HasSubstr("not JSON"));
}

TEST_F(HubTest, ASampleThatDoesNotDecodeIsLoggedNotFatal) {
  hub_.connect(1, "a");
  say(1, {{"op", "subscribe"}, {"topic", "concert/safety/state"}});
  hub_.on_sample("concert/safety/state", "", []() -> Json { throw std::runtime_error("short"); }, 0);
  EXPECT_TRUE(sink_.of(1, "sample").empty());
  EXPECT_THAT(log_.str(), HasSubstr("does not decode: short"));
}

}  // namespace
}  // namespace concert::gui
