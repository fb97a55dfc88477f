// `concert topic` verbs against real running writers: a Fast DDS peer publishing every
// catalogue topic at 100 Hz, and Cyclone's ddsperf as a program that is not ours.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <thread>

#include "peer_common.hpp"
#include "process.hpp"

namespace concert {
namespace {

using ::testing::HasSubstr;

using namespace std::chrono_literals;
using testing::Process;

constexpr uint32_t kSeed = 5;
const std::string kCycloneLocalhost =
    "CYCLONEDDS_URI=file://" CONCERT_SOURCE_DIR "/deploy/dds/cyclonedds_localhost.xml";

std::string domain() {
  const char* d = std::getenv("CONCERT_DOMAIN_ID");
  return d ? d : "0";
}

testing::Outcome concert(std::vector<std::string> args) {
  args.insert(args.begin(), CONCERT_BIN);
  const auto r = testing::run(args, 60s);
  EXPECT_NE(r.code, -1) << "concert did not terminate";
  return r;
}

class TopicCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    writer_ = new Process({CONTRACT_PEER_FAST, "write", "--seed", std::to_string(kSeed), "--repeat-ms", "10",
                           "--linger-ms", "120000"});
    foreign_ = new Process({"/usr/bin/ddsperf", "-i", domain(), "-D", "120", "pub", "50Hz"}, {kCycloneLocalhost});
    ASSERT_TRUE(writer_->wait_for_output("concert/safety/state", 20s)) << writer_->err();
  }
  static void TearDownTestSuite() {
    delete writer_;
    delete foreign_;
  }
  static Process* writer_;
  static Process* foreign_;
};
Process* TopicCli::writer_ = nullptr;
Process* TopicCli::foreign_ = nullptr;

TEST_F(TopicCli, ListShowsEveryTopicOursAndOthers) {
  // Discovery of ~30 endpoints can take longer than one listing's wait on a loaded machine:
  // list again (at most 4 times) until every topic has shown up, as a user would.
  testing::Outcome r;
  std::map<std::string, idl::Json> by_topic;
  for (int attempt = 0; attempt < 4; ++attempt) {
    r = concert({"topic", "list", "--json", "--timeout", "2.5"});
    ASSERT_EQ(r.code, 0) << r.err;
    by_topic.clear();
    for (const auto& row : idl::Json::parse(r.out)) by_topic[row.at("topic").get<std::string>()] = row;
    size_t seen = 0;
    for (const auto& t : dds::catalogue()) seen += by_topic.count(std::string(t.name));
    if (seen == dds::catalogue().size() && by_topic.size() > seen) break;
  }
  for (const auto& t : dds::catalogue()) {
    const std::string name(t.name);
    ASSERT_TRUE(by_topic.count(name)) << name << " missing in " << r.out;
    EXPECT_EQ(by_topic[name].at("type"), t.type_name);
    EXPECT_GE(by_topic[name].at("writers").get<int>(), 1);
    EXPECT_TRUE(by_topic[name].at("catalogue").get<bool>());
  }
  bool foreign = false;
  for (const auto& [name, row] : by_topic) {
    if (name.find("DDSPerf") != std::string::npos && !row.at("catalogue").get<bool>()) foreign = true;
  }
  EXPECT_TRUE(foreign) << "ddsperf's topics not listed: " << r.out;
}

TEST_F(TopicCli, InfoShowsTypeQosEndpointsAndShape) {
  const auto r = concert({"topic", "info", "concert/robot/joint_state", "--timeout", "2"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("concert::msg::JointState"));
  EXPECT_THAT(r.out, HasSubstr("writer"));
  EXPECT_THAT(r.out, HasSubstr("best-effort volatile"));
  EXPECT_THAT(r.out, HasSubstr("sequence<double> position"));
}

TEST_F(TopicCli, EchoPrintsSamplesWithFieldNames) {
  const auto r = concert(
      {"topic", "echo", "concert/robot/cartesian_command", "--count", "3", "--timeout", "15"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto lines = testing::lines(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  const auto expected = contract::expected_sample(*dds::find_topic("concert/robot/cartesian_command"), kSeed);
  for (const auto& line : lines) EXPECT_EQ(idl::Json::parse(line), expected);
}

TEST_F(TopicCli, HzMeasuresTheRateOfAnyTopic) {
  auto r = concert(
      {"topic", "hz", "concert/robot/odometry", "--count", "30", "--timeout", "15", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = idl::Json::parse(r.out);
  EXPECT_EQ(j.at("samples"), 30);
  EXPECT_GT(j.at("rate_hz").get<double>(), 0.0);
  EXPECT_LE(j.at("period_ms").at("min").get<double>(), j.at("period_ms").at("max").get<double>());
  // A topic of a program that is not ours: its type is unknown, but it can be timed.
  r = concert({"topic", "hz", "DDSPerfRDataKS", "--count", "5", "--timeout", "15", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(idl::Json::parse(r.out).at("samples"), 5);
}

TEST_F(TopicCli, ClearErrors) {
  auto r = concert({"topic", "echo", "no/such_topic", "--wait", "0.5", "--count", "1"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("no/such_topic"));
  r = concert({"topic", "echo", "DDSPerfRDataKS", "--count", "1", "--timeout", "5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("not in the project's IDL"));
  r = concert({"topic", "frob"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("frob"));
  r = concert({"topic", "list", "--domain", "999"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--domain"));
  r = concert({"topic", "echo", "concert/robot/odometry", "--count", "x"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--count"));
  // A topic without writers times out with a count of what arrived.
  r = concert({"topic", "echo", "concert/robot/ee_wrench", "--domain", "231", "--count", "1",
               "--timeout", "0.5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("received 0 of 1"));
}

}  // namespace
}  // namespace concert
