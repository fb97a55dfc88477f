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
              {"concert/robot/joint_command", "concert::msg::JointCommand", TopicKind::kCommand, ""},
              {"concert/drill/mission", "concert::msg::DrillMission", TopicKind::kCommand, ""},
              {"concert/model/customisation", "concert::msg::ModelCustomisation", TopicKind::kCommand, ""},
              {"concert/sim/command", "concert::msg::SimCommand", TopicKind::kCommand, ""}},
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

// A per-request state topic gets an instance per request: a late subscriber gets the latest of
// the most recently updated max_instances_kept, not every request of the shift.
TEST(HubMemory, AStateTopicKeepsTheMostRecentlyUpdatedInstancesOnly) {
  std::ostringstream log;
  HubParams params;
  params.max_instances_kept = 3;
  Hub hub({{"concert/planner/result", "concert::msg::PlanResult", TopicKind::kState, ""}}, params, log);
  FakeSink sink;
  hub.attach(nullptr, &sink);
  const auto result = [&](int request, const std::string& state, int64_t t) {
    hub.on_sample("concert/planner/result", std::to_string(request),
                  [&] { return Json{{"request_id", request}, {"state", state}}; }, t);
  };
  for (int request = 1; request <= 4; ++request) result(request, "PLANNED", request * kMs);
  result(2, "SUCCEEDED", 5 * kMs);  // request 2 updated again: now newer than 3 and 4
  result(5, "PLANNED", 6 * kMs);     // makes room by dropping request 3, the least recently updated
  hub.connect(1, "late");
  hub.on_message(1, Json{{"op", "subscribe"}, {"topic", "concert/planner/result"}}.dump(), 7 * kMs);
  std::map<std::string, std::string> got;
  for (const Json& m : sink.of(1, "sample")) got[m["instance"].get<std::string>()] = m["data"]["state"];
  EXPECT_EQ(got, (std::map<std::string, std::string>{{"2", "SUCCEEDED"}, {"4", "PLANNED"}, {"5", "PLANNED"}}));
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
  EXPECT_THAT(log_.str(), HasSubstr("command from 192.168.1.20:51544 (client 7, user local/engineer) on concert/safety/estop"));
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

// ---- sign-in required (a gateway beyond loopback)

class SignedHubTest : public HubTest {
 protected:
  SignedHubTest() : auth_(users(), AuthParams{.session_ttl_s = 100}) { hub_.require_auth(&auth_, true); }
  static UserStore users() {
    UserStore s;
    s.add("vera", Role::kViewer, "viewer-password");
    s.add("otto", Role::kOperator, "operator-password");
    s.add("erin", Role::kEngineer, "engineer-password");
    return s;
  }
  void sign_in(ClientId c, const std::string& user, const std::string& password) {
    say(c, {{"op", "login"}, {"user", user}, {"password", password}, {"id", 1}});
  }
  std::string last_error(ClientId c) {
    const auto e = sink_.of(c, "error");
    return e.empty() ? "" : e.back()["error"].get<std::string>();
  }
  Auth auth_;
};

TEST_F(SignedHubTest, NothingIsShownOrSentBeforeSignIn) {
  hub_.connect(1, "192.168.1.30:4000");
  const auto hello = sink_.of(1, "hello");
  ASSERT_EQ(hello.size(), 1u);
  EXPECT_TRUE(hello[0]["auth"]["required"].get<bool>());
  EXPECT_TRUE(hello[0]["auth"]["pairing"].get<bool>());
  EXPECT_FALSE(hello[0].contains("session"));
  say(1, {{"op", "subscribe"}, {"topic", "concert/safety/state"}, {"id", 2}});
  EXPECT_THAT(last_error(1), HasSubstr("sign in first"));
  hub_.on_sample("concert/safety/state", "", [] { return Json{{"mode", "SAFETY_RUNNING"}}; }, 0);
  EXPECT_TRUE(sink_.of(1, "sample").empty());
  say(1, {{"op", "publish"}, {"topic", "concert/safety/estop"}, {"data", {{"engaged", true}}}, {"id", 3}});
  EXPECT_TRUE(bus_.published.empty()) << "not even the e-stop before sign-in";
  EXPECT_THAT(last_error(1), HasSubstr("sign in first"));
  EXPECT_THAT(log_.str(), HasSubstr("command REFUSED from 192.168.1.30:4000 (client 1, not signed in)"));
  hub_.broadcast_rates(0);
  EXPECT_TRUE(sink_.of(1, "rates").empty());
  hub_.heartbeat(0);
  EXPECT_EQ(sink_.of(1, "heartbeat").size(), 1u) << "the heartbeat goes to every client";
}

TEST_F(SignedHubTest, EachRoleCommandsWhatItMayAndEveryoneMayStopTheRobot) {
  hub_.connect(1, "192.168.1.31:1");
  hub_.connect(2, "192.168.1.32:1");
  hub_.connect(3, "192.168.1.33:1");
  sign_in(1, "vera", "viewer-password");
  sign_in(2, "otto", "operator-password");
  sign_in(3, "erin", "engineer-password");
  for (ClientId c : {1, 2, 3}) {
    const auto s = sink_.of(c, "session");
    ASSERT_EQ(s.size(), 1u) << c;
    EXPECT_EQ(s[0]["id"], 1);
    EXPECT_EQ(s[0]["token"].get<std::string>().size(), 64u);
  }
  EXPECT_EQ(sink_.of(1, "session")[0]["role"], "viewer");
  const auto mission = Json{{"op", "publish"}, {"topic", "concert/drill/mission"}, {"data", {{"yaml", "x"}}}, {"id", 9}};
  const auto homing = Json{{"op", "publish"}, {"topic", "concert/model/customisation"}, {"data", Json::object()}};
  const auto swap = Json{{"op", "publish"}, {"topic", "concert/sim/command"}, {"data", {{"content", "a"}}}};
  const auto estop = Json{{"op", "publish"}, {"topic", "concert/safety/estop"}, {"data", {{"engaged", true}}}};
  say(1, mission);
  EXPECT_THAT(last_error(1), HasSubstr("role viewer may not command 'concert/drill/mission'"));
  EXPECT_THAT(log_.str(), HasSubstr("command REFUSED from 192.168.1.31:1 (client 1, user vera/viewer)"));
  say(1, estop);
  ASSERT_EQ(bus_.published.size(), 1u) << "the viewer's e-stop";
  say(2, mission);
  say(2, homing);
  EXPECT_THAT(last_error(2), HasSubstr("needs engineer"));
  say(2, swap);
  say(3, homing);
  say(3, swap);
  ASSERT_EQ(bus_.published.size(), 4u);
  EXPECT_EQ(bus_.published[1].first, "concert/drill/mission");
  EXPECT_EQ(bus_.published[2].first, "concert/model/customisation");
  EXPECT_EQ(bus_.published[3].first, "concert/sim/command");
  EXPECT_EQ(bus_.published[3].second["kind"], "SIM_SWAP_ASSEMBLY") << "a hot swap, never a new world";
  EXPECT_THAT(log_.str(), HasSubstr("(client 3, user erin/engineer) on concert/sim/command"));
  // The simulator's other command stays with the tools.
  say(3, {{"op", "publish"}, {"topic", "concert/sim/command"}, {"data", {{"kind", "SIM_SET_WORLD"}}}});
  EXPECT_THAT(last_error(3), HasSubstr("not allowed from the GUI"));
  EXPECT_EQ(bus_.published.size(), 4u);
}

TEST_F(SignedHubTest, WrongPasswordsAreRefusedThenSlowedAndTokensResumeUntilTheSessionEnds) {
  hub_.connect(1, "10.9.9.9:1");
  for (int i = 0; i < 20; ++i) sign_in(1, "otto", "nope");
  const auto errors = sink_.of(1, "error");
  ASSERT_EQ(errors.size(), 20u);
  EXPECT_THAT(errors[0]["error"].get<std::string>(), HasSubstr("wrong password"));
  EXPECT_FALSE(errors[0].contains("retry_after_s"));
  EXPECT_THAT(errors[19]["error"].get<std::string>(), HasSubstr("try again in"));
  EXPECT_GE(errors[19]["retry_after_s"].get<double>(), 1.0);
  EXPECT_TRUE(sink_.of(1, "session").empty());
  EXPECT_THAT(log_.str(), HasSubstr("sign-in REFUSED from 10.9.9.9:1 (client 1) as 'otto'"));

  hub_.connect(2, "10.9.9.10:1");
  sign_in(2, "otto", "operator-password");
  const std::string token = sink_.of(2, "session").at(0)["token"];
  // A reloaded page (a new connection) resumes with the token.
  hub_.connect(3, "10.9.9.10:2");
  say(3, {{"op", "login"}, {"token", token}, {"id", 4}});
  ASSERT_EQ(sink_.of(3, "session").size(), 1u);
  say(3, {{"op", "subscribe"}, {"topic", "concert/safety/state"}});
  EXPECT_EQ(sink_.of(3, "ack").size(), 1u);
  // The session ends (100 s): signed out, its subscriptions gone.
  hub_.heartbeat(200'000'000'000);
  ASSERT_EQ(sink_.of(3, "signed_out").size(), 1u);
  EXPECT_THAT(sink_.of(3, "signed_out")[0]["reason"].get<std::string>(), HasSubstr("expired"));
  hub_.on_sample("concert/safety/state", "", [] { return Json{{"mode", "SAFETY_STOPPED"}}; }, 0);
  EXPECT_TRUE(sink_.of(3, "sample").empty());
  // Logout ends a session at once.
  hub_.connect(4, "10.9.9.11:1");
  sign_in(4, "erin", "engineer-password");
  say(4, {{"op", "logout"}});
  EXPECT_EQ(sink_.of(4, "signed_out").size(), 1u);
  say(4, {{"op", "publish"}, {"topic", "concert/safety/estop"}, {"data", Json::object()}});
  EXPECT_THAT(last_error(4), HasSubstr("sign in first"));
}

TEST_F(SignedHubTest, APairingCodeSignsInOnceAsOperator) {
  const std::string code = auth_.new_pairing_code(0);
  hub_.connect(1, "10.1.1.1:1");
  say(1, {{"op", "pair"}, {"code", code}, {"id", 8}});
  const auto s = sink_.of(1, "session");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0]["role"], "operator");
  EXPECT_THAT(log_.str(), HasSubstr("pairing code used by 10.1.1.1:1; a new code: "));
  hub_.connect(2, "10.1.1.2:1");
  say(2, {{"op", "pair"}, {"code", code}});
  EXPECT_THAT(last_error(2), HasSubstr("pairing refused"));
}

TEST_F(HubTest, WithoutSignInEveryClientIsTheLocalEngineer) {
  hub_.connect(1, "127.0.0.1:9");
  const auto hello = sink_.of(1, "hello");
  EXPECT_FALSE(hello[0]["auth"]["required"].get<bool>());
  EXPECT_EQ(hello[0]["session"]["role"], "engineer");
  EXPECT_EQ(hello[0]["heartbeat_ms"], 250);
  std::map<std::string, std::string> roles;
  for (const auto& c : hello[0]["commands"]) roles[c["topic"]] = c["role"];
  EXPECT_EQ(roles["concert/safety/estop"], "viewer");
  EXPECT_EQ(roles["concert/drill/mission"], "operator");
  EXPECT_EQ(roles["concert/model/customisation"], "engineer");
  EXPECT_EQ(roles["concert/sim/command"], "engineer");
  say(1, {{"op", "login"}, {"user", "x"}, {"password", "y"}, {"id", 2}});
  EXPECT_THAT(sink_.of(1, "error").back()["error"].get<std::string>(), HasSubstr("requires no sign-in"));
}

TEST_F(HubTest, AnOlderEStopSampleNeverReplacesANewerOne) {
  hub_.connect(1, "a");
  say(1, {{"op", "subscribe"}, {"topic", "concert/safety/estop"}});
  hub_.on_sample("concert/safety/estop", "sw", [] { return Json{{"engaged", false}, {"stamp_ns", 200}}; }, 0);
  // Another writer's history, handed over late: engaged at 100, released at 200 since.
  hub_.on_sample("concert/safety/estop", "sw", [] { return Json{{"engaged", true}, {"stamp_ns", 100}}; }, 0);
  EXPECT_EQ(sink_.of(1, "sample").size(), 1u);
  hub_.connect(2, "b");
  say(2, {{"op", "subscribe"}, {"topic", "concert/safety/estop"}});
  const auto late = sink_.of(2, "sample");
  ASSERT_EQ(late.size(), 1u);
  EXPECT_FALSE(late[0]["data"]["engaged"].get<bool>()) << "a late tablet sees the input released";
}

TEST_F(HubTest, OversizedMessagesAreRefusedWithTheReason) {
  hub_.connect(1, "a");
  hub_.on_message(1, std::string(kMaxClientMessageBytes + 1, ' '), 0);
  EXPECT_THAT(sink_.of(1, "error").back()["error"].get<std::string>(), HasSubstr("bytes refused"));
  EXPECT_THAT(log_.str(), HasSubstr("message REFUSED from a"));
}

}  // namespace
}  // namespace concert::gui
