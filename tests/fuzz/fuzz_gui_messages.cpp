// The operator GUI gateway's client messages (services/gui: every WebSocket text message a
// browser on the site network sends). Up to 16 messages, one per line of the input, go through
// the hub as from one connected client, with samples arriving between them. The hub must answer
// each with JSON (an ack, an error naming the problem, samples), publish only allow-listed
// topics with the allow-list's fixed fields and only what the signed-in role may send, and never
// throw. An input whose first line is "#auth" runs against a gateway that requires sign-in (one
// operator, "otto" / "operator-password", hashed at argon2id's least cost so sign-ins stay cheap).
// Documented failure: none: a bad message is answered with an error.
//
// Seeds: one message of each op, commands for every allow-listed topic, sign-in sessions, and bad
// messages.
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz.hpp"
#include "gui/allow_list.hpp"
#include "gui/auth.hpp"
#include "gui/hub.hpp"

namespace {

using namespace concert;
using gui::Json;

struct Bus : gui::Bus {
  std::optional<gui::Role> role;  // the most the signed-in client may send; nullopt: no sign-in
  void publish(const std::string& topic, const Json& sample) override {
    CONCERT_FUZZ_CHECK(gui::find_operator_command(topic) != nullptr,
                       "published a topic the allow-list does not hold: " + topic);
    if (role) {
      CONCERT_FUZZ_CHECK(gui::find_operator_command(topic)->role <= *role,
                         "published " + topic + " for a role that may not send it");
    }
    CONCERT_FUZZ_CHECK(sample.is_object(), "published a sample that is not an object");
    // A type's field the browser got wrong is refused by the DDS side; the hub must relay that.
    if (sample.contains("bogus")) throw std::runtime_error("'bogus' is not a field of the type");
  }
  void set_wanted(const std::string&, bool) override {}
};

struct Sink : gui::ClientSink {
  size_t replies = 0;
  void send(gui::ClientId, std::string message, bool binary) override {
    if (binary) return;
    const Json j = Json::parse(message, nullptr, false);
    CONCERT_FUZZ_CHECK(!j.is_discarded() && j.is_object() && j.contains("op"),
                       "the hub sent a text message that is not a JSON object with an op");
    ++replies;
  }
  size_t buffered_bytes(gui::ClientId) override { return 0; }
};

std::vector<gui::TopicEntry> topics() {
  std::vector<gui::TopicEntry> t = {
      {"concert/safety/state", "concert::msg::SafetyState", gui::TopicKind::kState, ""},
      {"concert/robot/joint_state", "concert::msg::JointState", gui::TopicKind::kStream, ""},
      {"concert/sensors/camera/rgb", "concert::msg::Image", gui::TopicKind::kImage, ""}};
  for (const gui::OperatorCommand& c : gui::operator_commands()) {
    t.push_back({std::string(c.topic), "", gui::TopicKind::kCommand, std::string(c.what)});
  }
  return t;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::ostringstream log;
  Bus bus;
  Sink sink;
  gui::Hub hub(topics(), gui::HubParams{}, log);
  hub.attach(&bus, &sink);
  const std::string_view text = fuzz::text_of(data, size);
  const bool signed_in = text.rfind("#auth\n", 0) == 0;
  std::unique_ptr<gui::Auth> auth;
  if (signed_in) {
    gui::UserStore users(gui::HashCost::kMinimal);
    users.add("otto", gui::Role::kOperator, "operator-password");
    auth = std::make_unique<gui::Auth>(std::move(users), gui::AuthParams{.session_ttl_s = 1});
    hub.require_auth(auth.get(), false);
    bus.role = gui::Role::kOperator;
  }
  hub.connect(1, "192.0.2.10:50000");
  int64_t now = 1'000'000'000;
  for (const std::string_view line : fuzz::split(signed_in ? text.substr(6) : text, '\n', 16)) {
    const size_t before = sink.replies;
    hub.on_message(1, line, now);
    CONCERT_FUZZ_CHECK(sink.replies > before, "a client message went unanswered");
    now += 7'000'000;
    hub.on_sample("concert/safety/state", "", [] { return Json{{"mode", "SAFETY_RUNNING"}}; }, now);
    hub.on_sample("concert/robot/joint_state", "", [] { return Json{{"position", {0.1}}}; }, now);
    hub.on_frame("concert/sensors/camera/rgb", "front", [] { return std::optional<std::string>(); },
                 now);
    hub.heartbeat(now);
  }
  hub.broadcast_rates(now);
  hub.disconnect(1);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add("subscribe.json",
            R"({"op": "subscribe", "topic": "concert/robot/joint_state", "max_hz": 5, "id": 1})");
  seeds.add("unsubscribe.json", R"({"op": "unsubscribe", "topic": "concert/safety/state"})");
  seeds.add("ping.json", R"({"op": "ping", "id": 9})");
  int n = 0;
  for (const gui::OperatorCommand& c : gui::operator_commands()) {
    seeds.add("publish_" + std::to_string(n++) + ".json",
              R"({"op": "publish", "topic": ")" + std::string(c.topic) +
                  R"(", "data": {"engaged": true, "stamp_ns": 0}, "id": 3})");
  }
  seeds.add("session.jsonl",
            "{\"op\": \"subscribe\", \"topic\": \"concert/safety/state\"}\n"
            "{\"op\": \"subscribe\", \"topic\": \"concert/sensors/camera/rgb\", \"max_hz\": 100}\n"
            "{\"op\": \"publish\", \"topic\": \"concert/safety/estop\", \"data\": "
            "{\"source\": \"ESTOP_WIRELESS\", \"engaged\": true}}\n"
            "{\"op\": \"publish\", \"topic\": \"concert/robot/joint_command\", \"data\": {}}\n"
            "{\"op\": \"publish\", \"topic\": \"concert/drill/mission\", \"data\": {\"bogus\": 1}}\n"
            "{\"op\": \"unsubscribe\", \"topic\": \"concert/sensors/camera/rgb\"}\n");
  seeds.add("auth.jsonl",
            "#auth\n"
            "{\"op\": \"subscribe\", \"topic\": \"concert/safety/state\"}\n"
            "{\"op\": \"login\", \"user\": \"otto\", \"password\": \"wrong\", \"id\": 1}\n"
            "{\"op\": \"login\", \"user\": \"otto\", \"password\": \"operator-password\", \"id\": 2}\n"
            "{\"op\": \"publish\", \"topic\": \"concert/sim/command\", \"data\": {}}\n"
            "{\"op\": \"publish\", \"topic\": \"concert/safety/reset\", \"data\": {}}\n"
            "{\"op\": \"login\", \"token\": \"00\"}\n"
            "{\"op\": \"pair\", \"code\": \"12345678\"}\n"
            "{\"op\": \"logout\", \"id\": 3}\n"
            "{\"op\": \"publish\", \"topic\": \"concert/safety/estop\", \"data\": {}}\n");
  seeds.add("bad.txt", "{\"op\": 5}\n[1, 2]\nnot json\n{\"op\": \"subscribe\"}\n");
  seeds.add_tokens(kJsonTokens);
  seeds.add_tokens({"op", "subscribe", "unsubscribe", "publish", "ping", "login", "pair", "logout", "user",
                    "password", "token", "code", "otto", "operator-password", "#auth\n", "topic", "data", "id",
                    "max_hz", "concert/safety/state", "concert/robot/joint_state",
                    "concert/sensors/camera/rgb"});
}
