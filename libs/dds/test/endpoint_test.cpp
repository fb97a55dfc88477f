#include <gtest/gtest.h>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iostream>
#include <map>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_subscription.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"
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

// Endpoints of a raw type allocate each sample at its size (raw_writer_qos, raw_reader_qos), not
// preallocated at the raw type's 64 KB: samples several times larger, and small ones after them,
// arrive whole between a raw endpoint and a typed one, both ways.
TEST(Endpoint, RawEndpointsCarrySamplesOfAnySize) {
  namespace fdds = eprosima::fastdds::dds;
  const auto& schema = idl::Schema::builtin();
  const std::string topic(topics::robot_model.name);
  const Resolved raw_type = *from_catalogue(topic);
  Participant typed_side({.name = "typed"}), raw_side({.name = "raw"});

  std::mutex mutex;
  std::vector<size_t> typed_got;  // urdf sizes the typed reader received
  Reader<msg::RobotModel> typed_reader(typed_side, topics::robot_model, [&](const msg::RobotModel& m, const auto&) {
    std::lock_guard lock(mutex);
    typed_got.push_back(m.urdf().size());
  });
  auto* t = raw_side.topic(topic, fdds::TypeSupport(new RawPubSubType(raw_type.type, raw_type.keyed)));
  auto* raw_writer = raw_side.publisher()->create_datawriter(t, raw_writer_qos(QosClass::kLatched));
  ASSERT_NE(raw_writer, nullptr);
  std::vector<size_t> raw_got;  // urdf sizes the raw reader decoded
  RawSubscription raw_reader(raw_side, topic, raw_type, [&](std::vector<uint8_t>& bytes, const auto&) {
    const auto m = idl::decode(schema, raw_type.type, std::span<const uint8_t>(bytes));
    std::lock_guard lock(mutex);
    raw_got.push_back(m.at("urdf").get<std::string>().size());
  });
  Writer<msg::RobotModel> typed_writer(typed_side, topics::robot_model);
  ASSERT_TRUE(typed_writer.wait_for_readers(2, 10s)) << "the raw reader did not match";
  const auto arrived = [&](const std::vector<size_t>& got, size_t size) {
    for (int i = 0; i < 1000; ++i) {  // bounded: 10 s
      {
        std::lock_guard lock(mutex);
        if (std::find(got.begin(), got.end(), size) != got.end()) return true;
      }
      std::this_thread::sleep_for(10ms);
    }
    return false;
  };

  uint32_t version = 10;
  for (const size_t size : {size_t{300'000}, size_t{12}, size_t{200'000}}) {
    idl::Json sample = idl::complete(schema, raw_type.type,
                                     {{"version", ++version}, {"urdf", std::string(size, 'r')}});
    RawSample raw{idl::encode(schema, raw_type.type, sample), idl::key_hash(schema, raw_type.type, sample)};
    ASSERT_TRUE(raw_writer->write(&raw)) << size << " bytes";
    EXPECT_TRUE(arrived(typed_got, size)) << "a raw writer's " << size << "-byte model did not reach a typed reader";

    msg::RobotModel m = model(++version);
    m.urdf(std::string(size + 1, 't'));
    ASSERT_TRUE(typed_writer.write(m));
    EXPECT_TRUE(arrived(raw_got, size + 1)) << "a typed writer's " << size + 1 << "-byte model did not reach a raw reader";
  }
  raw_side.publisher()->delete_datawriter(raw_writer);
}

// A raw type computes a keyed sample's instance from its key fields, as the typed endpoints do:
// a reader computes it for every sample (Fast DDS writers send no key hash unless asked). From the whole bytes, each status report of a service was an instance of its own
// in the GUI gateway: 110 000 instances in 10 minutes of a shift, never released.
TEST(Endpoint, ARawTypesInstanceIsItsKeyNotItsBytes) {
  const auto& schema = idl::Schema::builtin();
  const std::string type = "concert::msg::ServiceStatus";
  RawPubSubType raw(type, true);
  const auto handle_of = [&](const idl::Json& partial) {
    RawSample sample{idl::encode(schema, type, idl::complete(schema, type, partial)), std::nullopt};
    eprosima::fastrtps::rtps::InstanceHandle_t handle;
    EXPECT_TRUE(raw.getKey(&sample, &handle, false));
    return handle;
  };
  const auto a1 = handle_of({{"id", 7}, {"service", "planner"}, {"stamp_ns", 1}});
  const auto a2 = handle_of({{"id", 7}, {"service", "planner"}, {"stamp_ns", 2}, {"message", "ready"}});
  const auto b = handle_of({{"id", 8}, {"service", "planner"}, {"stamp_ns", 1}});
  EXPECT_EQ(a1, a2) << "two reports of one service are one instance";
  EXPECT_NE(a1, b);
  const auto key = idl::key_hash(schema, type, idl::complete(schema, type, {{"id", 7}}));
  ASSERT_TRUE(key.has_value());
  for (size_t i = 0; i < 16; ++i) EXPECT_EQ((*key)[i], a1.value[i]) << "byte " << i << " of the key hash typed endpoints compute";

  // A type outside our IDL: no key layout, each sample its own instance.
  RawPubSubType foreign("other::Sample", true);
  RawSample x{{0, 1, 0, 0, 1, 2, 3, 4}, std::nullopt}, y{{0, 1, 0, 0, 1, 2, 3, 5}, std::nullopt};
  eprosima::fastrtps::rtps::InstanceHandle_t hx, hy;
  ASSERT_TRUE(foreign.getKey(&x, &hx, false));
  ASSERT_TRUE(foreign.getKey(&y, &hy, false));
  EXPECT_NE(hx, hy);
}

// The same between two participants: samples travel through the transport (Participant turns
// intra-process delivery off), not handed over with the writer's instance, as in the GUI gateway.
TEST(Endpoint, ARawSubscriptionSeesOneInstancePerKey) {
  {
    Participant writer_side({.name = "writer"}), reader_side({.name = "reader"});
    const std::string topic(topics::status.name);
    std::mutex mutex;
    std::map<std::string, int> reports;  // "id instance" -> samples
    RawSubscription reader(reader_side, topic, *from_catalogue(topic), [&](std::vector<uint8_t>& bytes, const auto& info) {
      const auto m = idl::decode(idl::Schema::builtin(), "concert::msg::ServiceStatus", std::span<const uint8_t>(bytes));
      std::string instance;
      for (size_t k = 0; k < 16; ++k) instance += std::to_string(info.instance_handle.value[k]) + ".";
      std::lock_guard lock(mutex);
      ++reports[std::to_string(m.at("id").get<uint32_t>()) + " " + instance];
    });
    Writer<msg::ServiceStatus> writer(writer_side, topics::status);
    ASSERT_TRUE(writer.wait_for_readers(1, 10s));
    constexpr int kReports = 5;
    for (int i = 0; i < kReports; ++i) {
      for (const uint32_t id : {1u, 2u}) {
        msg::ServiceStatus s;
        s.id(id);
        s.stamp_ns(i);
        s.message("report " + std::to_string(i));
        ASSERT_TRUE(writer.write(s));
      }
      // Each report taken before the next: keep-last 1 per instance.
      const auto received = [&] {
        std::lock_guard lock(mutex);
        int got = 0;
        for (const auto& [id_instance, n] : reports) got += n;
        return got;
      };
      for (int wait = 0; wait < 1000 && received() < 2 * (i + 1); ++wait) std::this_thread::sleep_for(10ms);  // 10 s
    }
    std::lock_guard lock(mutex);
    ASSERT_EQ(reports.size(), 2u) << "one instance per service id, not per report";
    for (const auto& [id_instance, n] : reports) EXPECT_EQ(n, kReports) << id_instance;
  }
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
