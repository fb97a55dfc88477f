// `concert topic pub` through real DDS: a sample given as JSON on a catalogue topic comes back
// field for field through `concert topic echo` and through a typed reader; bad JSON, unknown
// fields and wrong types are refused before anything is published.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>

#include "concert/dds/endpoint.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "process.hpp"

namespace concert {
namespace {

using ::testing::HasSubstr;

using namespace std::chrono_literals;
using testing::Process;

testing::Outcome concert(std::vector<std::string> args) {
  args.insert(args.begin(), CONCERT_BIN);
  const auto r = testing::run(args, 60s);
  EXPECT_NE(r.code, -1) << "concert did not terminate";
  return r;
}

TEST(TopicPub, RoundTripThroughTopicEchoFieldForField) {
  const std::string topic = "concert/robot/cartesian_command";
  Process echo({CONCERT_BIN, "topic", "echo", topic, "--count", "2", "--timeout", "45"});
  // pub waits (bounded) until the echo's reader has matched, then writes twice.
  const auto pub =
      concert({"topic", "pub", topic,
               R"({"end_effector": "tcp_E", "target": {"position": {"x": 1.5, "y": -0.25}},
                                "stiffness": [100, 100, 100, 10, 10, 10], "model_version": 7})",
               "--count", "2", "--rate", "20", "--wait", "30", "--json"});
  ASSERT_EQ(pub.code, 0) << pub.err;
  ASSERT_EQ(echo.wait(50s), 0) << echo.err();
  const auto sent = testing::lines(pub.out);
  const auto received = testing::lines(echo.out());
  ASSERT_EQ(sent.size(), 2u) << pub.out;
  ASSERT_EQ(received.size(), 2u) << echo.out();
  for (size_t i = 0; i < 2; ++i)
    EXPECT_EQ(idl::Json::parse(received[i]), idl::Json::parse(sent[i]));
  const auto sample = idl::Json::parse(received[0]);
  EXPECT_EQ(sample.at("end_effector"), "tcp_E");
  EXPECT_EQ(sample.at("target").at("position").at("x"), 1.5);
  EXPECT_EQ(sample.at("target").at("position").at("y"), -0.25);
  EXPECT_EQ(sample.at("target").at("position").at("z"), 0.0) << "a field left out is zero";
  EXPECT_EQ(sample.at("stiffness").size(), 6u);
  EXPECT_EQ(sample.at("model_version"), 7);
}

TEST(TopicPub, KeyedLatchedSampleReachesATypedReader) {
  dds::Participant participant({.name = "topic_pub_test"});
  dds::Reader<msg::ServiceStatus> statuses(participant, dds::topics::status);
  const auto pub =
      concert({"topic", "pub", "concert/system/status",
               R"({"id": 77, "service": "pub-test", "host": "here", "state": "SERVICE_READY",
                                "model_version": 3, "message": "from the command line"})",
               "--wait", "30"});
  ASSERT_EQ(pub.code, 0) << pub.err;
  EXPECT_THAT(pub.out, HasSubstr("published 1 sample(s) of concert::msg::ServiceStatus on concert/system/status"));
  std::optional<msg::ServiceStatus> got;
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (!got && std::chrono::steady_clock::now() < deadline) {
    auto s = statuses.wait(200ms);
    if (s && s->service() == "pub-test") got = s;
  }
  ASSERT_TRUE(got.has_value()) << "the typed reader got nothing";
  EXPECT_EQ(got->id(), 77u);
  EXPECT_EQ(got->state(), msg::SERVICE_READY);
  EXPECT_EQ(got->model_version(), 3u);
  EXPECT_EQ(got->message(), "from the command line");
}

TEST(TopicPub, BadSamplesAreRefusedNamingTheField) {
  const std::string topic = "concert/robot/cartesian_command";
  auto r = concert({"topic", "pub", topic, R"({"end_effector": "tcp_E",)"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("concert topic pub: JSON: "));
  r = concert({"topic", "pub", topic, R"({"target": {"positon": {"x": 1}}})"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr(
          "target.positon: no such field in concert::msg::Pose (fields: position, orientation)"));
  r = concert({"topic", "pub", topic, R"({"end_effector": 5})"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("end_effector: expected a string"));
  r = concert({"topic", "pub", topic, R"({"target": {"position": {"x": "far"}}})"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("target.position.x: expected a number"));
  r = concert({"topic", "pub", "no/such_topic", "{}"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("topic 'no/such_topic' is not in the catalogue"));
  EXPECT_TRUE(r.out.empty());
}

}  // namespace
}  // namespace concert
