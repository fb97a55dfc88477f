// Contract tests: every catalogue topic crosses real DDS between two processes, in every
// vendor direction (Fast DDS -> Fast DDS, Fast DDS -> Cyclone, Cyclone -> Fast DDS), and
// arrives with every field equal; endpoints use the catalogue's QoS; late joiners of latched
// topics get the last sample.
#include <gtest/gtest.h>

#include <map>
#include <thread>

#include "concert/dds/catalogue.hpp"
#include "peer_common.hpp"
#include "process.hpp"

namespace concert::contract {
namespace {

using namespace std::chrono_literals;
using testing::Process;

struct Vendor {
  const char* name;
  const char* peer;
};
const Vendor kFast{"fast", CONTRACT_PEER_FAST};
const Vendor kCyclone{"cyclone", CONTRACT_PEER_CYCLONE};

std::map<std::string, idl::Json> events(const Process& p, const std::string& kind) {
  std::map<std::string, idl::Json> out;
  for (const auto& line : testing::lines(p.out())) {
    const auto j = idl::Json::parse(line);
    if (j.at("event") == kind) out[j.at("topic").get<std::string>()] = j;
  }
  return out;
}

void expect_qos(const idl::Json& qos, const dds::TopicInfo& t, const std::string& who) {
  const auto spec = dds::qos_spec(t.qos);
  EXPECT_EQ(qos.at("reliable"), spec.reliable) << who << " on " << t.name;
  EXPECT_EQ(qos.at("transient_local"), spec.transient_local) << who << " on " << t.name;
  if (qos.contains("depth")) {
    EXPECT_EQ(qos.at("depth"), spec.history_depth) << who << " on " << t.name;
  }
}

/// Reader first, then a writer that waits for it; every topic must arrive with every field equal.
void cross(const Vendor& writer_vendor, const Vendor& reader_vendor, uint32_t seed) {
  Process reader({reader_vendor.peer, "read", "--timeout-ms", "30000"});
  Process writer({writer_vendor.peer, "write", "--seed", std::to_string(seed), "--wait-readers",
                  "--timeout-ms", "30000", "--linger-ms", "30000", "--repeat-ms", "200"});
  const auto code = reader.wait(40s);
  writer.stop(5s);
  ASSERT_TRUE(code.has_value()) << "reader did not finish";
  EXPECT_EQ(*code, 0) << reader.out() << reader.err() << writer.err();
  const auto received = events(reader, "received");
  const auto written = events(writer, "written");
  for (const auto& t : dds::catalogue()) {
    const std::string name(t.name);
    SCOPED_TRACE(std::string(writer_vendor.name) + " -> " + reader_vendor.name + ": " + name);
    ASSERT_TRUE(received.count(name)) << "not received";
    const auto& got = received.at(name);
    EXPECT_EQ(got.at("sample"), expected_sample(t, seed)) << "fields differ";
    // Fast DDS 2.9 reads only XCDR1; both vendors must put XCDR1 on the wire.
    EXPECT_EQ(got.at("wire"), "XCDR1 little-endian");
    expect_qos(got.at("local_qos"), t, std::string(reader_vendor.name) + " reader");
    // What each vendor read of the other side's discovery announcement (SEDP): Cyclone's
    // matched-endpoint data, Fast DDS's discovery listener.
    ASSERT_TRUE(got.contains("remote_qos")) << reader_vendor.name << " saw no writer announcement";
    expect_qos(got.at("remote_qos"), t, "writer as announced on the wire");
    ASSERT_TRUE(written.count(name));
    expect_qos(written.at(name).at("local_qos"), t, std::string(writer_vendor.name) + " writer");
    ASSERT_TRUE(written.at(name).contains("remote_qos"))
        << writer_vendor.name << " saw no reader announcement";
    expect_qos(written.at(name).at("remote_qos"), t, "reader as announced on the wire");
  }
}

/// Full-size camera images (640x480: 921,600 bytes RGB8, 614,400 bytes 16UC1) cross in every
/// vendor direction with every byte equal: Fast DDS <-> Fast DDS through shared memory, Fast DDS
/// <-> Cyclone through UDP (fragmented).
void cross_full_images(const Vendor& writer_vendor, const Vendor& reader_vendor, uint32_t seed) {
  const std::string topics = "concert/sensors/camera/rgb,concert/sensors/camera/depth";
  Process reader({reader_vendor.peer, "read", "--topics", topics, "--full-images", "--timeout-ms", "30000"});
  Process writer({writer_vendor.peer, "write", "--topics", topics, "--full-images", "--seed", std::to_string(seed),
                  "--wait-readers", "--timeout-ms", "30000", "--linger-ms", "30000", "--repeat-ms", "200"});
  const auto code = reader.wait(40s);
  writer.stop(5s);
  ASSERT_TRUE(code.has_value()) << "reader did not finish";
  EXPECT_EQ(*code, 0) << reader.out() << reader.err() << writer.err();
  const auto received = events(reader, "received");
  for (const char* name : {"concert/sensors/camera/rgb", "concert/sensors/camera/depth"}) {
    SCOPED_TRACE(std::string(writer_vendor.name) + " -> " + reader_vendor.name + ": " + name);
    ASSERT_TRUE(received.count(name)) << "not received";
    const auto expected = expected_sample(*dds::find_topic(name), seed, true);
    const auto& got = received.at(name).at("sample");
    EXPECT_EQ(got.at("data").size(), expected.at("data").size());
    EXPECT_EQ(got, expected) << "fields differ";
  }
}

TEST(Contract, FullImagesFastToFast) { cross_full_images(kFast, kFast, 31); }
TEST(Contract, FullImagesFastToCyclone) { cross_full_images(kFast, kCyclone, 32); }
TEST(Contract, FullImagesCycloneToFast) { cross_full_images(kCyclone, kFast, 33); }

TEST(Contract, FastToFast) { cross(kFast, kFast, 11); }
TEST(Contract, FastToCyclone) { cross(kFast, kCyclone, 12); }
TEST(Contract, CycloneToFast) { cross(kCyclone, kFast, 13); }

/// A writer publishes twice on every latched topic and keeps running; a reader started later
/// receives the second sample only.
void late_joiner(const Vendor& writer_vendor, const Vendor& reader_vendor, uint32_t seed) {
  size_t latched = 0;
  for (const auto& t : dds::catalogue()) latched += t.qos == dds::QosClass::kLatched;
  Process writer({writer_vendor.peer, "write", "--topics", "latched", "--seed", std::to_string(seed),
                  "--stale-first", "--linger-ms", "30000"});
  for (int i = 0; i < 300 && events(writer, "written").size() < latched && writer.running(); ++i) {
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_EQ(events(writer, "written").size(), latched) << writer.err();
  std::this_thread::sleep_for(300ms);
  Process reader({reader_vendor.peer, "read", "--topics", "latched", "--timeout-ms", "10000"});
  const auto code = reader.wait(20s);
  writer.stop(5s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 0) << reader.out() << reader.err();
  const auto received = events(reader, "received");
  for (const auto& t : dds::catalogue()) {
    if (t.qos != dds::QosClass::kLatched) continue;
    SCOPED_TRACE(std::string(writer_vendor.name) + " -> late " + reader_vendor.name + ": " + std::string(t.name));
    ASSERT_TRUE(received.count(std::string(t.name)));
    EXPECT_EQ(received.at(std::string(t.name)).at("sample"), expected_sample(t, seed)) << "not the last sample";
  }
}

TEST(Contract, LateJoinerFastToFast) { late_joiner(kFast, kFast, 21); }
TEST(Contract, LateJoinerFastToCyclone) { late_joiner(kFast, kCyclone, 22); }
TEST(Contract, LateJoinerCycloneToFast) { late_joiner(kCyclone, kFast, 23); }

}  // namespace
}  // namespace concert::contract
