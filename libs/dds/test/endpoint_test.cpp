#include <gtest/gtest.h>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iostream>
#include <thread>
#include <vector>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/status_reporter.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

namespace concert::dds {
namespace {

using namespace std::chrono_literals;

msg::RobotModel model(uint32_t version) {
  msg::RobotModel m;
  m.version(version);
  m.content_hash("h" + std::to_string(version));
  m.urdf(std::string(100'000, 'u'));  // larger than one UDP datagram
  m.modules({"a", "b"});
  return m;
}

TEST(Endpoint, SampleArrivesEqualBetweenParticipants) {
  Participant a({.name = "a"}), b({.name = "b"});
  Writer<msg::RobotModel> writer(a, topics::robot_model);
  Reader<msg::RobotModel> reader(b, topics::robot_model);
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  ASSERT_TRUE(writer.write(model(3)));
  auto got = reader.wait(5s);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, model(3));
}

TEST(Endpoint, LateJoinerGetsTheLastLatchedSampleOnly) {
  Participant a({.name = "a"});
  Writer<msg::RobotModel> writer(a, topics::robot_model);
  writer.write(model(1));
  writer.write(model(2));
  Participant b({.name = "late"});
  const auto start = std::chrono::steady_clock::now();
  Reader<msg::RobotModel> reader(b, topics::robot_model);
  auto got = reader.wait(20s);
  ASSERT_TRUE(got.has_value()) << "the late joiner never got the latched value";
  EXPECT_EQ(got->version(), 2u);
  // Reported, not asserted (no wall-clock bounds in tests): DDS latency is shown by bench_dds.
  const auto took = std::chrono::steady_clock::now() - start;
  std::cout << "latched value reached the late joiner after "
            << std::chrono::duration_cast<std::chrono::milliseconds>(took).count() << " ms\n";
  // A bounded observation window, not a timing assumption: nothing marks the end of the
  // historical samples a late joiner is sent, so "no older value follows" can only be watched for.
  EXPECT_FALSE(reader.wait(300ms).has_value()) << "KEEP_LAST 1: only the last value is owed";
}

msg::PlanResult plan_result(uint32_t request) {
  msg::PlanResult r;
  r.request_id(request);
  r.state(msg::PLAN_SUCCEEDED);
  r.reason("request " + std::to_string(request));
  return r;
}

// Keyed topics have an instance per request (plan results, trajectory statuses, nav goals, drill
// missions). Fast DDS's default resource limits hold 10 instances: the 11th request's result
// never reached its reader (a drill mission waited for ever for its 4th hole's posture).
TEST(Endpoint, EveryRequestOfAKeyedTopicArrivesPastTenInstances) {
  Participant a({.name = "a"}), b({.name = "b"});
  Writer<msg::PlanResult> writer(a, topics::plan_result);
  Reader<msg::PlanResult> reader(b, topics::plan_result);
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  constexpr uint32_t kRequests = 3 * kLiveInstances;
  for (uint32_t id = 1; id <= kRequests; ++id) {
    ASSERT_TRUE(writer.write(plan_result(id))) << "request " << id;
    const auto got = reader.wait(5s);
    ASSERT_TRUE(got.has_value()) << "request " << id << " never arrived";
    EXPECT_EQ(*got, plan_result(id));
  }
  // The writer keeps the newest kLiveInstances instances for late joiners and unregisters the
  // older ones (its memory stays bounded over hours of requests).
  Participant c({.name = "late"});
  Reader<msg::PlanResult> late(c, topics::plan_result);
  std::vector<uint32_t> latched;
  while (const auto got = late.wait(latched.size() < kLiveInstances ? 5000ms : 300ms)) {
    latched.push_back(got->request_id());
    if (latched.size() > 2 * kLiveInstances) break;
  }
  ASSERT_EQ(latched.size(), kLiveInstances);
  std::sort(latched.begin(), latched.end());
  EXPECT_EQ(latched.front(), kRequests - kLiveInstances + 1);
  EXPECT_EQ(latched.back(), kRequests);
}

TEST(Endpoint, CallbackReaderAndQosFromTheCatalogue) {
  Participant p({.name = "p"});
  std::atomic<int> received{0};
  Reader<msg::JointState> reader(p, topics::joint_state, [&](const msg::JointState& s, const auto&) {
    if (s.name().size() == 2) ++received;
  });
  Writer<msg::JointState> writer(p, topics::joint_state);
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  msg::JointState s;
  s.name({"j1", "j2"});
  // Best effort: written again every 50 ms until it comes (bounded: 20 s).
  for (int i = 0; i < 400 && received == 0; ++i) {
    writer.write(s);
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_GT(received.load(), 0);
  eprosima::fastdds::dds::DataWriterQos q;
  writer.get()->get_qos(q);
  EXPECT_EQ(q.reliability().kind, eprosima::fastdds::dds::BEST_EFFORT_RELIABILITY_QOS);
  EXPECT_EQ(q.history().depth, 1);
}

TEST(Endpoint, TopicsOutsideTheCatalogueAreRefused) {
  Participant p({.name = "p"});
  try {
    Writer<msg::RobotModel> w(p, TopicHandle<msg::RobotModel>{"concert/model/typo"});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("concert/model/typo"), std::string::npos);
  }
  EXPECT_THROW((Writer<msg::RobotModel>(p, TopicHandle<msg::RobotModel>{"concert/robot/joint_state"})),
               std::invalid_argument);
}

TEST(Endpoint, BadProfilesFileIsNamed) {
  try {
    Participant p({.name = "p", .profiles_file = "/nonexistent/profiles.xml"});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/profiles.xml"), std::string::npos);
  }
}

// The three-PC deployment profile loads and says what the README promises. (No participant is
// made from it: its peers are the robot's addresses, not this machine's.)
TEST(Endpoint, DeploymentProfileParses) {
  auto* factory = eprosima::fastdds::dds::DomainParticipantFactory::get_instance();
  ASSERT_EQ(factory->load_XML_profiles_file(CONCERT_SOURCE_DIR "/deploy/dds/fastdds_profiles.xml"),
            eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK);
  eprosima::fastdds::dds::DomainParticipantQos qos;
  ASSERT_EQ(factory->get_participant_qos_from_profile("concert_participant", qos),
            eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK);
  EXPECT_EQ(qos.wire_protocol().builtin.initialPeersList.size(), 3u);
  EXPECT_FALSE(qos.transport().use_builtin_transports);
  // UDP only, with socket buffers that hold a camera frame pair: no shared memory, which a
  // process killed with SIGKILL leaves broken for the processes restarted after it.
  ASSERT_EQ(qos.transport().user_transports.size(), 1u);
  const auto udp = std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(
      qos.transport().user_transports.front());
  ASSERT_NE(udp, nullptr);
  EXPECT_EQ(udp->receiveBufferSize, kSocketBufferBytes);
  EXPECT_EQ(udp->sendBufferSize, kSocketBufferBytes);
}

TEST(Endpoint, StatusReporterPublishesStateChanges) {
  Participant p({.name = "p"});
  Reader<msg::ServiceStatus> reader(p, topics::status);
  {
    StatusReporter status(p, "unit_test", "host1");
    status.report(msg::SERVICE_READY, 7, "ok");
    bool ready = false;
    for (int i = 0; i < 50 && !ready; ++i) {
      if (auto s = reader.wait(100ms)) {
        EXPECT_EQ(s->service(), "unit_test");
        EXPECT_EQ(s->id(), status_instance_id("unit_test", "host1"));
        ready = s->state() == msg::SERVICE_READY && s->model_version() == 7;
      }
    }
    EXPECT_TRUE(ready);
  }
  bool stopped = false;
  for (int i = 0; i < 50 && !stopped; ++i) {
    if (auto s = reader.wait(100ms)) stopped = s->state() == msg::SERVICE_STOPPED;
  }
  EXPECT_TRUE(stopped);
}

}  // namespace
}  // namespace concert::dds
