// The gateway's DDS adapter over real DDS: a catalogue sample reaches a browser client as the
// JSON of its IDL fields, an operator command reaches DDS as a typed sample (with the fixed
// fields of the allow-list), a refused field is an error to the client, and camera images
// arrive as JPEG frames while a client watches.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "concert/dds/topics.hpp"
#include "dds/bridge.hpp"

namespace concert::gui {
namespace {

using namespace std::chrono_literals;
namespace topics = concert::dds::topics;

struct Sink : ClientSink {
  std::mutex mutex;
  std::vector<Json> text;
  std::vector<std::string> binary;
  void send(ClientId, std::string m, bool bin) override {
    std::lock_guard lock(mutex);
    if (bin) {
      binary.push_back(std::move(m));
    } else {
      text.push_back(Json::parse(m));
    }
  }
  size_t buffered_bytes(ClientId) override { return 0; }
  std::optional<Json> find(const std::function<bool(const Json&)>& pred) {
    std::lock_guard lock(mutex);
    for (const auto& m : text) {
      if (pred(m)) return m;
    }
    return std::nullopt;
  }
  size_t frames() {
    std::lock_guard lock(mutex);
    return binary.size();
  }
};

/// Polls `f` every 20 ms up to `timeout`.
template <class F>
bool eventually(F f, std::chrono::milliseconds timeout = 10s) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    if (f()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return f();
}

int64_t now() { return std::chrono::steady_clock::now().time_since_epoch().count(); }

class BridgeTest : public testing::Test {
 protected:
  BridgeTest()
      : gateway_({.name = "concert-gui"}),
        peer_({.name = "peer"}),
        hub_(dds::catalogue_topics(), HubParams{}, log_),
        bridge_(gateway_, hub_, JpegParams{}, log_) {
    hub_.attach(&bridge_, &sink_);
    hub_.connect(1, "127.0.0.1:4242");
  }
  ~BridgeTest() override { hub_.attach(nullptr, nullptr); }
  void say(const Json& m) { hub_.on_message(1, m.dump(), now()); }

  std::ostringstream log_;
  concert::dds::Participant gateway_;
  concert::dds::Participant peer_;
  Sink sink_;
  Hub hub_;
  dds::Bridge bridge_;
};

TEST_F(BridgeTest, ALatchedSampleReachesTheClientAsJsonOfItsIdlFields) {
  concert::dds::Writer<msg::SafetyState> writer(peer_, topics::safety_state);
  msg::SafetyState state;
  state.mode(msg::SAFETY_STOPPED);
  state.reset_required(true);
  state.causes({"estop: wireless"});
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  ASSERT_TRUE(writer.write(state));
  // Subscribed after the sample: the hub kept the latest for the late subscriber.
  ASSERT_TRUE(eventually([&] {
    const auto rates = hub_.rates(now());
    return std::any_of(rates.begin(), rates.end(),
                       [](const TopicRate& r) { return r.topic == "concert/safety/state" && r.count > 0; });
  }));
  say({{"op", "subscribe"}, {"topic", "concert/safety/state"}});
  const auto sample = sink_.find([](const Json& m) { return m["op"] == "sample"; });
  ASSERT_TRUE(sample);
  EXPECT_EQ(sample->at("topic"), "concert/safety/state");
  EXPECT_EQ(sample->at("data")["mode"], "SAFETY_STOPPED");
  EXPECT_EQ(sample->at("data")["reset_required"], true);
  EXPECT_EQ(sample->at("data")["causes"][0], "estop: wireless");
}

TEST_F(BridgeTest, AnEStopFromTheBrowserIsATypedSoftwareStopOnDds) {
  std::mutex mutex;
  std::vector<msg::EStopInput> got;
  concert::dds::Reader<msg::EStopInput> reader(peer_, topics::estop, [&](const msg::EStopInput& s, const auto&) {
    std::lock_guard lock(mutex);
    got.push_back(s);
  });
  ASSERT_TRUE(reader.wait_for_writers(1, 5s));
  say({{"op", "publish"}, {"topic", "concert/safety/estop"},
       {"data", {{"source", "ESTOP_BUTTON_FRONT_LEFT"}, {"engaged", true}, {"reason", "operator"}}}, {"id", 1}});
  ASSERT_TRUE(eventually([&] { std::lock_guard lock(mutex); return !got.empty(); }));
  std::lock_guard lock(mutex);
  EXPECT_EQ(got[0].source(), msg::ESTOP_SOFTWARE);  // the allow-list pins the source
  EXPECT_TRUE(got[0].engaged());
  EXPECT_EQ(got[0].reason(), "operator");
  EXPECT_GT(got[0].stamp_ns(), 0);
  EXPECT_TRUE(sink_.find([](const Json& m) { return m["op"] == "ack" && m["id"] == 1; }));
  EXPECT_THAT(log_.str(), testing::HasSubstr("command from 127.0.0.1:4242"));
}

TEST_F(BridgeTest, AResetNamesTheClientAndABadFieldIsRefusedByName) {
  std::mutex mutex;
  std::vector<msg::SafetyReset> got;
  concert::dds::Reader<msg::SafetyReset> reader(peer_, topics::safety_reset, [&](const msg::SafetyReset& s, const auto&) {
    std::lock_guard lock(mutex);
    got.push_back(s);
  });
  ASSERT_TRUE(reader.wait_for_writers(1, 5s));
  say({{"op", "publish"}, {"topic", "concert/safety/reset"}, {"data", {{"request_id", 9}, {"colour", "red"}}}, {"id", 2}});
  const auto error = sink_.find([](const Json& m) { return m["op"] == "error" && m["id"] == 2; });
  ASSERT_TRUE(error);
  EXPECT_THAT(error->at("error").get<std::string>(), testing::HasSubstr("colour"));
  say({{"op", "publish"}, {"topic", "concert/safety/reset"}, {"data", {{"request_id", 9}}}, {"id", 3}});
  ASSERT_TRUE(eventually([&] { std::lock_guard lock(mutex); return !got.empty(); }));
  std::lock_guard lock(mutex);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].request_id(), 9u);
  EXPECT_EQ(got[0].source(), "concert gui (127.0.0.1:4242)");
}

TEST_F(BridgeTest, CameraImagesArriveAsJpegFramesWhileWatched) {
  concert::dds::Writer<msg::Image> writer(peer_, topics::camera_rgb);
  say({{"op", "subscribe"}, {"topic", "concert/sensors/camera/rgb"}, {"max_hz", 10}});
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  msg::Image image;
  image.sensor_id(concert::dds::sensor_id("camera_E"));
  image.sensor("camera_E");
  image.encoding("rgb8");
  image.width(64);
  image.height(48);
  image.step(64 * 3);
  image.data(std::vector<uint8_t>(64 * 48 * 3, 200));
  ASSERT_TRUE(eventually([&] {
    writer.write(image);
    return sink_.frames() > 0;
  }));
  std::string frame;
  {
    std::lock_guard lock(sink_.mutex);
    frame = sink_.binary[0];
  }
  const auto nl = frame.find('\n');
  ASSERT_NE(nl, std::string::npos);
  const Json header = Json::parse(frame.substr(0, nl));
  EXPECT_EQ(header["sensor"], "camera_E");
  EXPECT_EQ(header["format"], "jpeg");
  const std::vector<uint8_t> jpeg(frame.begin() + static_cast<long>(nl) + 1, frame.end());
  const cv::Mat decoded = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  ASSERT_FALSE(decoded.empty());
  EXPECT_EQ(decoded.cols, 64);
  EXPECT_EQ(decoded.rows, 48);
  EXPECT_NEAR(decoded.at<cv::Vec3b>(10, 10)[1], 200, 3);
}

TEST_F(BridgeTest, NoReaderOnACommandTopicUnlessABrowserWatchesIt) {
  // `concert sim swap` waits for a reader of concert/sim/command, then writes a volatile
  // command: a gateway reader there would let it write before the simulator listens.
  concert::dds::Writer<msg::SimCommand> writer(peer_, topics::sim_command);
  EXPECT_FALSE(writer.wait_for_readers(1, 1500ms));
  say({{"op", "subscribe"}, {"topic", "concert/sim/command"}});
  EXPECT_TRUE(writer.wait_for_readers(1, 5s));
  say({{"op", "unsubscribe"}, {"topic", "concert/sim/command"}});
  EXPECT_TRUE(eventually([&] { return writer.matched_readers() == 0; }));
}

}  // namespace
}  // namespace concert::gui
