// `concert bag record|info|play` over real DDS: publishers of every QoS class (latched samples
// published before the recorder starts, keyed and unkeyed, reliable and best-effort, camera
// images) recorded by the `concert` process read back equal sample for sample; Foxglove's MCAP
// reader (tools/mcap_check, @mcap/core + @foxglove/omgidl-serialization) accepts the file and
// decodes every message to the same values; the running discovery service is recorded, and its
// recorded scan played into a fresh one gives the same tree; `play` publishes with the recorded
// timing (latched topics latched) and `concert topic echo` sees it; a recorder killed
// mid-recording leaves a file `info`, `play` and the independent reader read up to its last
// complete record.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "concert/bag/mcap.hpp"
#include "concert/dds/participant.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "process.hpp"
#include "raw_subscription.hpp"

namespace concert {
namespace {

using ::testing::HasSubstr;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using testing::Process;
using Json = idl::Json;

const std::string kMcapCheck = std::string(CONCERT_SOURCE_DIR) + "/tools/mcap_check/mcap_check.mjs";

testing::Outcome concert(std::vector<std::string> args) {
  args.insert(args.begin(), CONCERT_BIN);
  const auto r = testing::run(args, 90s);
  EXPECT_NE(r.code, -1) << "concert did not terminate";
  return r;
}

/// The independent reader's report (first line) and decoded messages (the other lines).
std::vector<Json> mcap_check(const std::string& file, std::vector<std::string> flags = {}) {
  std::vector<std::string> argv = {CONCERT_NODE, kMcapCheck, file};
  argv.insert(argv.end(), flags.begin(), flags.end());
  const auto r = testing::run(argv, 120s);
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  std::vector<Json> out;
  for (const auto& line : testing::lines(r.out)) out.push_back(Json::parse(line));
  return out;
}

/// A writer of one catalogue topic with its class's QoS, writing samples given as JSON.
class Publisher {
 public:
  Publisher(dds::Participant& p, const std::string& topic) : participant_(p), topic_(topic) {
    const auto info = *dds::find_topic(topic);
    type_ = info.type_name;
    const bool keyed = idl::Schema::builtin().at(type_).keyed();
    auto* t =
        p.topic(topic, eprosima::fastdds::dds::TypeSupport(new dds::RawPubSubType(type_, keyed)));
    writer_ = p.publisher()->create_datawriter(t, dds::raw_writer_qos(info.qos));
  }
  ~Publisher() { participant_.publisher()->delete_datawriter(writer_); }
  /// Writes `sample` (every field given); returns its bytes.
  std::vector<uint8_t> write(const Json& sample) {
    const auto& s = idl::Schema::builtin();
    dds::RawSample raw{idl::encode(s, type_, sample), idl::key_hash(s, type_, sample)};
    EXPECT_TRUE(writer_->write(&raw)) << topic_;
    sent_.push_back(raw.bytes);
    return raw.bytes;
  }
  int32_t readers() {
    eprosima::fastdds::dds::PublicationMatchedStatus m;
    writer_->get_publication_matched_status(m);
    return m.current_count;
  }
  bool matched() { return readers() > 0; }
  void wait_acknowledged() {
    writer_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(20, 0));
  }
  const std::string& type() const { return type_; }
  const std::vector<std::vector<uint8_t>>& sent() const { return sent_; }

 private:
  dds::Participant& participant_;
  std::string topic_, type_;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
  std::vector<std::vector<uint8_t>> sent_;
};

Json sample(const std::string& type, uint32_t seed) {
  return idl::sample_with_every_field_set(idl::Schema::builtin(), type, seed);
}

/// Waits (bounded) until the recorder's stderr says each topic has a writer.
void wait_recording(Process& recorder, const std::vector<std::string>& topics) {
  const auto deadline = Clock::now() + 30s;
  for (const auto& t : topics) {
    while (recorder.err().find(t + ": 1 writer(s)") == std::string::npos &&
           Clock::now() < deadline && recorder.running())
      std::this_thread::sleep_for(20ms);
    ASSERT_THAT(recorder.err(), HasSubstr(t + ": 1 writer(s)")) << recorder.err();
  }
}

/// The recorded bytes are those written, or those followed by the zero padding to a multiple of 4
/// bytes that Fast DDS adds to samples it sends from a writer's history (late joiners).
bool same_sample(const std::vector<uint8_t>& recorded, const std::vector<uint8_t>& written) {
  if (recorded == written) return true;
  return recorded.size() > written.size() && recorded.size() - written.size() <= 3 &&
         recorded.size() % 4 == 0 && std::equal(written.begin(), written.end(), recorded.begin()) &&
         std::all_of(recorded.begin() + static_cast<std::ptrdiff_t>(written.size()), recorded.end(),
                     [](uint8_t b) { return b == 0; });
}

/// Every message of a file per topic, in order: bytes and times.
struct Recorded {
  std::vector<uint8_t> bytes;
  uint64_t log_time, publish_time;
  uint32_t sequence;
};
std::map<std::string, std::vector<Recorded>> read_file(bag::Reader& reader) {
  std::map<std::string, std::vector<Recorded>> by_topic;
  reader.read_messages([&](const bag::Message& m, const bag::Channel& c) {
    by_topic[c.topic].push_back(
        {{m.data.begin(), m.data.end()}, m.log_time, m.publish_time, m.sequence});
    return true;
  });
  return by_topic;
}

/// Messages per topic in a file still being recorded, up to its last flushed chunk (the recorder
/// writes its open chunk every second); empty while the file cannot be read yet.
std::map<std::string, size_t> recorded_so_far(const std::string& file) {
  std::map<std::string, size_t> counts;
  try {
    bag::Reader growing(file);
    for (const auto& [topic, messages] : read_file(growing)) counts[topic] = messages.size();
  } catch (const std::exception&) {
    counts.clear();
  }
  return counts;
}

TEST(BagCli, RecordsEveryQosClassSampleForSampleAndFoxglovesReaderAgrees) {
  testing::TempDir dir("bag-cli");
  const std::string file = dir.path() + "/run.mcap";
  dds::Participant participant({.name = "bag-test-publisher"});
  Publisher estop(participant, "concert/safety/estop");           // latched, keyed by an enum
  Publisher status(participant, "concert/system/status");         // latched, keyed
  Publisher joints(participant, "concert/robot/joint_state");     // stream
  Publisher command(participant, "concert/robot/joint_command");  // command
  Publisher rgb(participant, "concert/sensors/camera/rgb");       // large stream, keyed
  // Latched samples written before the recorder starts: it must get the current one of each
  // instance.
  for (uint32_t i = 0; i < 2; ++i) {
    Json s = sample(estop.type(), 10 + i);
    s["source"] = i == 0 ? "ESTOP_WIRELESS" : "ESTOP_SOFTWARE";
    estop.write(s);
  }
  Json first_status = sample(status.type(), 20);
  first_status["id"] = 4242;
  status.write(first_status);

  const std::vector<std::string> topics = {
      "concert/safety/estop", "concert/system/status", "concert/robot/joint_state",
      "concert/robot/joint_command", "concert/sensors/camera/rgb"};
  std::vector<std::string> argv = {CONCERT_BIN, "bag", "record"};
  argv.insert(argv.end(), topics.begin(), topics.end());
  argv.insert(argv.end(), {"-o", file, "--timeout", "120"});
  Process recorder(argv);
  wait_recording(recorder, topics);
  for (Publisher* p : {&joints, &rgb}) {  // best-effort: both directions matched before writing
    const auto deadline = Clock::now() + 20s;
    while (!p->matched() && Clock::now() < deadline) std::this_thread::sleep_for(10ms);
    ASSERT_TRUE(p->matched());
  }
  // Both directions matched: the recorder's reader said "1 writer(s)" (wait_recording), the
  // writers have their reader.

  for (uint32_t i = 0; i < 200; ++i) {
    joints.write(sample(joints.type(), 100 + i));
    if (i % 20 == 0) command.write(sample(command.type(), 500 + i));
    if (i % 40 == 0) {
      Json image = sample(rgb.type(), 700 + i);
      image["sensor_id"] = 7 + i % 80;
      image["data"] = std::vector<uint8_t>(64 * 48 * 3, static_cast<uint8_t>(i));
      rgb.write(image);
    }
    if (i == 100) {
      Json s = sample(status.type(), 21);
      s["id"] = 4242;
      status.write(s);
    }
    std::this_thread::sleep_for(5ms);
  }
  for (Publisher* p : {&estop, &status, &command}) p->wait_acknowledged();
  // The streams' samples in flight reach the file too before the recorder stops: wait (bounded)
  // until the file as it grows holds what is checked below.
  const auto in_file = [&] {
    auto got = recorded_so_far(file);
    return got[topics[0]] == estop.sent().size() && got[topics[1]] == status.sent().size() &&
           got[topics[3]] == command.sent().size() &&
           got[topics[2]] * 100 >= joints.sent().size() * 95 &&
           got[topics[4]] * 100 >= rgb.sent().size() * 95;
  };
  for (const auto until = Clock::now() + 30s; !in_file() && Clock::now() < until;)
    std::this_thread::sleep_for(100ms);
  ASSERT_EQ(recorder.stop(20s), 0) << recorder.err();  // SIGINT: the file is closed properly
  EXPECT_THAT(recorder.out(), HasSubstr("into " + file));

  bag::Reader reader(file);
  ASSERT_TRUE(reader.complete()) << reader.problem();
  const auto recorded = read_file(reader);
  const auto& summary = reader.summary();
  // Reliable topics: exactly what was written (latched: the current sample of each instance).
  for (Publisher* p : {&estop, &status, &command}) {
    const std::string topic = p == &estop ? topics[0] : p == &status ? topics[1] : topics[3];
    ASSERT_TRUE(recorded.count(topic)) << topic;
    const auto& got = recorded.at(topic);
    ASSERT_EQ(got.size(), p->sent().size()) << topic;
    for (size_t i = 0; i < got.size(); ++i)
      EXPECT_TRUE(same_sample(got[i].bytes, p->sent()[i])) << topic << " #" << i;
  }
  // Best-effort streams: in order, nothing that was not sent, (nearly) all of it on loopback.
  for (Publisher* p : {&joints, &rgb}) {
    const std::string topic = p == &joints ? topics[2] : topics[4];
    ASSERT_TRUE(recorded.count(topic)) << topic;
    const auto& got = recorded.at(topic);
    size_t next = 0;
    for (const auto& m : got) {
      while (next < p->sent().size() && !same_sample(m.bytes, p->sent()[next])) ++next;
      ASSERT_LT(next, p->sent().size())
          << topic << ": a recorded sample that was not sent, or out of order";
      ++next;
    }
    EXPECT_GE(got.size() * 100, p->sent().size() * 95)
        << topic << ": " << got.size() << " of " << p->sent().size();
  }
  uint64_t last = 0;
  for (const auto& [topic, messages] : recorded) {
    for (const auto& m : messages) {
      EXPECT_GE(m.log_time + 1'000'000, m.publish_time)
          << topic << ": published after it was recorded";
      EXPECT_LE(m.log_time, m.publish_time + 2'000'000'000ULL) << topic;
    }
  }
  reader.read_messages([&](const bag::Message& m, const bag::Channel&) {
    EXPECT_GE(m.log_time, last) << "file order is log time order";
    last = m.log_time;
    return true;
  });
  for (const auto& [id, c] : summary.channels) {
    const auto& schema = summary.schemas.at(c.schema_id);
    EXPECT_EQ(schema.encoding, "omgidl");
    EXPECT_EQ(c.message_encoding, "cdr");
    EXPECT_EQ(schema.name, dds::find_topic(c.topic)->type_name);
    EXPECT_EQ(schema.data, idl::Schema::builtin().idl(schema.name));
  }
  EXPECT_EQ(summary.channels.at(0).metadata.at("qos"), "latched");
  EXPECT_EQ(summary.channels.at(4).metadata.at("qos"), "large_stream");

  // `concert bag info` says the same.
  const auto info = concert({"bag", "info", file, "--json"});
  ASSERT_EQ(info.code, 0) << info.err;
  const Json j = Json::parse(info.out);
  EXPECT_TRUE(j.at("complete").get<bool>());
  EXPECT_EQ(j.at("messages").get<uint64_t>(), summary.statistics.message_count);
  for (const auto& t : j.at("topics")) {
    const std::string topic = t.at("topic");
    EXPECT_EQ(t.at("messages").get<size_t>(),
              recorded.count(topic) ? recorded.at(topic).size() : 0u)
        << topic;
  }
  EXPECT_EQ(j.at("metadata").at("concert_recording").at("dropped"), "0");
  const auto text = concert({"bag", "info", file});
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_THAT(text.out, HasSubstr("complete:    yes"));
  EXPECT_THAT(text.out, HasSubstr("concert::msg::JointState"));
  EXPECT_THAT(text.out, HasSubstr("duration:"));

  // Foxglove's reader: indexed and streamed, every message decoded from the IDL in the file
  // to the values of the sample that was written.
  const auto check = mcap_check(file, {"--messages"});
  ASSERT_FALSE(check.empty());
  const Json& report = check[0];
  EXPECT_EQ(report.at("statistics").at("messageCount").get<uint64_t>(),
            summary.statistics.message_count);
  EXPECT_EQ(report.at("stream").at("messages").get<uint64_t>(), summary.statistics.message_count);
  EXPECT_TRUE(report.at("stream").at("done").get<bool>());
  for (const auto& c : report.at("channels")) {
    const std::string topic = c.at("topic");
    const size_t n = recorded.count(topic) ? recorded.at(topic).size() : 0;
    EXPECT_EQ(c.at("indexed").get<size_t>(), n) << topic;
    EXPECT_EQ(c.at("streamed").get<size_t>(), n) << topic;
    EXPECT_EQ(c.at("schema_encoding"), "omgidl");
  }
  std::map<std::string, size_t> index;
  size_t compared = 0;
  for (size_t i = 1; i < check.size(); ++i) {
    const std::string topic = check[i].at("topic");
    const auto& expected = recorded.at(topic).at(index[topic]++);
    const std::string type(dds::find_topic(topic)->type_name);
    // Its values (enums as numbers, 64-bit integers exact) encode to the recorded bytes.
    EXPECT_TRUE(same_sample(expected.bytes,
                            idl::encode(idl::Schema::builtin(), type, check[i].at("value"))))
        << topic;
    EXPECT_EQ(check[i].at("log_time").get<uint64_t>(), expected.log_time);
    ++compared;
  }
  EXPECT_EQ(compared, summary.statistics.message_count);
}

/// Arrival times of the samples of `topic` in this process.
class Arrivals {
 public:
  Arrivals(dds::Participant& p, const std::string& topic)
      : sub_(p, topic, *tool::from_catalogue(topic),
             [this](std::vector<uint8_t>& bytes, const auto&) {
               std::lock_guard lock(mutex_);
               times_.push_back(Clock::now());
               bytes_.push_back(bytes);
             }) {}
  size_t size() {
    std::lock_guard lock(mutex_);
    return times_.size();
  }
  std::vector<Clock::time_point> times() {
    std::lock_guard lock(mutex_);
    return times_;
  }
  std::vector<std::vector<uint8_t>> bytes() {
    std::lock_guard lock(mutex_);
    return bytes_;
  }

 private:
  std::mutex mutex_;
  std::vector<Clock::time_point> times_;
  std::vector<std::vector<uint8_t>> bytes_;
  tool::RawSubscription sub_;
};

/// A recording written with libs/bag: commands at irregular recorded times and a latched status.
struct Fixture {
  std::vector<uint64_t> offsets_ms = {0, 120, 150, 400, 410, 700, 1000};
  std::vector<std::vector<uint8_t>> commands;
  std::vector<uint8_t> status;
};
Fixture write_fixture(const std::string& file) {
  Fixture f;
  const auto& s = idl::Schema::builtin();
  bag::Writer w(file);
  const std::string cmd = "concert::msg::JointCommand", st = "concert::msg::ServiceStatus";
  const uint16_t c =
      w.add_channel(w.add_schema(cmd, "omgidl", s.idl(cmd)), "concert/robot/joint_command", "cdr");
  const uint16_t l =
      w.add_channel(w.add_schema(st, "omgidl", s.idl(st)), "concert/system/status", "cdr");
  const uint64_t t0 = 1'700'000'000'000'000'000ULL;
  f.status = idl::encode(s, st, sample(st, 3));
  w.write({l, 0, t0, t0, f.status});
  for (size_t i = 0; i < f.offsets_ms.size(); ++i) {
    f.commands.push_back(idl::encode(s, cmd, sample(cmd, 40 + static_cast<uint32_t>(i))));
    const uint64_t t = t0 + f.offsets_ms[i] * 1'000'000;
    w.write({c, static_cast<uint32_t>(i), t, t, f.commands.back()});
  }
  w.close();
  return f;
}

TEST(BagCli, PlayPublishesWithTheRecordedTimingAndTopicEchoSeesIt) {
  testing::TempDir dir("bag-cli");
  const std::string file = dir.path() + "/fixture.mcap";
  const Fixture f = write_fixture(file);
  const auto& s = idl::Schema::builtin();
  dds::Participant participant({.name = "bag-test-reader"});
  Arrivals commands(participant, "concert/robot/joint_command");
  Arrivals status(participant, "concert/system/status");
  for (const double rate : {1.0, 2.0}) {
    SCOPED_TRACE("rate " + std::to_string(rate));
    const size_t before = commands.size();
    Process play({CONCERT_BIN, "bag", "play", file, "--rate", std::to_string(rate), "--wait", "20",
                  "--json"});
    if (rate == 1.0) {
      // The status was played first; a reader that joins later still gets it: latched.
      const auto joined = Clock::now() + 20s;
      while (commands.size() < before + 2 && Clock::now() < joined)
        std::this_thread::sleep_for(5ms);
      ASSERT_GE(commands.size(), before + 2);
      // In this process: the play's last 0.9 s is the window, and a `concert topic echo`
      // process started now missed it under load (its start and discovery took longer; the
      // writers go with the play).
      dds::Participant late_participant({.name = "bag-test-late-joiner"});
      Arrivals late(late_participant, "concert/system/status");
      const auto heard = Clock::now() + 10s;
      while (late.size() < 1 && Clock::now() < heard) std::this_thread::sleep_for(5ms);
      ASSERT_GE(late.size(), 1u) << "a late joiner did not get the latched status";
      EXPECT_EQ(late.bytes()[0], f.status);
    }
    ASSERT_EQ(play.wait(30s), 0) << play.err();
    const Json report = Json::parse(play.out());
    EXPECT_EQ(report.at("messages"), 8);
    EXPECT_EQ(report.at("topics").at("concert/robot/joint_command"), 7);
    const auto deadline = Clock::now() + 10s;
    while (commands.size() < before + 7 && Clock::now() < deadline)
      std::this_thread::sleep_for(10ms);
    ASSERT_EQ(commands.size(), before + 7);
    const auto times = commands.times();
    const auto bytes = commands.bytes();
    for (size_t i = 0; i < 7; ++i) {
      EXPECT_EQ(bytes[before + i], f.commands[i]) << i;
      if (i == 0) continue;
      // The recorded interval, scaled by the rate, within 40 ms (a loaded 2-core machine).
      const double want = static_cast<double>(f.offsets_ms[i] - f.offsets_ms[i - 1]) / rate;
      const double got =
          std::chrono::duration<double, std::milli>(times[before + i] - times[before + i - 1])
              .count();
      EXPECT_NEAR(got, want, 40.0) << "interval before command " << i;
    }
    const double total =
        std::chrono::duration<double, std::milli>(times[before + 6] - times[before]).count();
    EXPECT_NEAR(total, 1000.0 / rate, 40.0);
  }
  ASSERT_GE(status.size(), 1u);
  EXPECT_EQ(status.bytes()[0], f.status);

  // --loop plays again until --timeout; `concert topic echo` sees 7 commands in a row of the
  // recording's cycle (it may join mid-pass).
  Process echo({CONCERT_BIN, "topic", "echo", "concert/robot/joint_command", "--count", "7",
                "--timeout", "60"});
  const auto looped =
      concert({"bag", "play", file, "--loop", "--timeout", "4", "--wait", "5", "--json"});
  ASSERT_EQ(looped.code, 0) << looped.err;
  const Json l = Json::parse(looped.out);
  EXPECT_GE(l.at("passes").get<int>(), 2);
  EXPECT_GE(l.at("topics").at("concert/robot/joint_command").get<int>(), 14);
  ASSERT_EQ(echo.wait(30s), 0) << echo.err();
  // Ctrl-C stops a looping play (once its commands come: bounded wait).
  const size_t commands_before = commands.size();
  Process endless({CONCERT_BIN, "bag", "play", file, "--loop", "--wait", "0", "--json"});
  for (const auto until = Clock::now() + 30s;
       commands.size() <= commands_before && Clock::now() < until;)
    std::this_thread::sleep_for(10ms);
  EXPECT_GT(commands.size(), commands_before) << "the looping play published nothing";
  EXPECT_EQ(endless.stop(10s), 0) << endless.err();
  EXPECT_GE(Json::parse(endless.out()).at("messages").get<int>(), 1);
  const auto lines = testing::lines(echo.out());
  ASSERT_EQ(lines.size(), 7u);
  size_t first = 7;
  for (size_t k = 0; k < 7; ++k) {
    if (Json::parse(lines[0]) == idl::decode(s, "concert::msg::JointCommand", f.commands[k]))
      first = k;
  }
  ASSERT_LT(first, 7u) << lines[0];
  for (size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(Json::parse(lines[i]),
              idl::decode(s, "concert::msg::JointCommand", f.commands[(first + i) % 7]))
        << i;
  }
}

TEST(BagCli, ARecorderKilledMidRecordingLeavesAFileReadableUpToItsLastCompleteRecord) {
  testing::TempDir dir("bag-cli");
  const std::string file = dir.path() + "/killed.mcap";
  dds::Participant participant({.name = "bag-test-publisher"});
  Publisher joints(participant, "concert/robot/joint_state");
  Process recorder({CONCERT_BIN, "bag", "record", "concert/robot/joint_state", "-o", file,
                    "--compression", "lz4"});
  wait_recording(recorder, {"concert/robot/joint_state"});
  const auto deadline = Clock::now() + 20s;
  while (!joints.matched() && Clock::now() < deadline) std::this_thread::sleep_for(10ms);
  uint32_t written = 0;
  const auto write_for = [&](uint32_t count) {  // at 500 Hz
    for (const uint32_t end = written + count; written < end; ++written) {
      joints.write(sample(joints.type(), written));
      std::this_thread::sleep_for(2ms);
    }
  };
  // The recorder writes its open chunk every second: until the file holds a flushed chunk of
  // 100 samples or more (bounded: 30000 samples, 60 s), then 0.6 s more, in its open chunk.
  do {
    write_for(50);
  } while (recorded_so_far(file)["concert/robot/joint_state"] < 100 && written < 30000);
  write_for(300);
  ::kill(recorder.pid(), SIGKILL);
  recorder.wait(10s);

  bag::Reader reader(file);
  EXPECT_FALSE(reader.complete());
  const auto recorded = read_file(reader);
  ASSERT_TRUE(recorded.count("concert/robot/joint_state"));
  const size_t n = recorded.at("concert/robot/joint_state").size();
  EXPECT_GE(n, 100u) << "at least the first flushed chunk";
  EXPECT_LT(n, joints.sent().size());
  for (size_t i = 0; i < n; ++i) {
    const auto& bytes = recorded.at("concert/robot/joint_state")[i].bytes;
    EXPECT_NE(std::find(joints.sent().begin(), joints.sent().end(), bytes), joints.sent().end());
  }

  const auto info = concert({"bag", "info", file});
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_THAT(info.out, HasSubstr("complete:    no: "));
  EXPECT_THAT(info.err, HasSubstr("cut short"));
  EXPECT_THAT(info.out, HasSubstr("messages:    " + std::to_string(n)));

  const auto play = concert({"bag", "play", file, "--rate", "20", "--wait", "0", "--json"});
  ASSERT_EQ(play.code, 0) << play.err;
  EXPECT_THAT(play.err, HasSubstr("cut short"));
  EXPECT_EQ(Json::parse(play.out).at("messages").get<size_t>(), n);

  // Foxglove's stream reader reads the same messages and stops where the file ends.
  const auto check = mcap_check(file, {"--stream-only"});
  ASSERT_FALSE(check.empty());
  EXPECT_EQ(check[0].at("stream").at("messages").get<size_t>(), n);
  EXPECT_FALSE(check[0].at("stream").at("done").get<bool>());
  EXPECT_EQ(check[0].at("decoded").at("concert/robot/joint_state").get<size_t>(), n);
}

#ifdef CONCERT_DISCOVERY_BIN
TEST(BagCli, TheRunningDiscoveryServiceRecordedThenItsScanReplayedIntoAFreshOne) {
  // The real discovery service turns a real scan of the CONCERT robot (../shared/data) into the
  // module tree; the recording holds the scan, the tree and the service's status, the same as
  // `concert topic echo` received them.
  testing::TempDir dir("bag-cli");
  const std::string file = dir.path() + "/stack.mcap";
  const std::vector<std::string> topics = {"concert/ethercat/scan", "concert/topology/module_tree",
                                           "concert/system/status"};
  Process recorder({CONCERT_BIN, "bag", "record", topics[0], topics[1], topics[2], "-o", file});
  Process discovery({CONCERT_DISCOVERY_BIN, "--module-db",
                     std::string(CONCERT_SHARED_DATA) + "/concert_resources"});
  Process echo({CONCERT_BIN, "topic", "echo", topics[1], "--count", "1", "--timeout", "60"});
  wait_recording(recorder, {topics[1], topics[2]});
  const auto scan =
      concert({"scan", "publish", "--scan",
               std::string(CONCERT_SHARED_DATA) + "/ethercat/concert_robot_18slaves.yaml", "--hold",
               "3", "--timeout", "20", "--json"});
  ASSERT_EQ(scan.code, 0) << scan.err;
  ASSERT_EQ(echo.wait(60s), 0) << echo.err();
  const Json tree = Json::parse(testing::lines(echo.out()).at(0));
  ASSERT_EQ(recorder.stop(20s), 0) << recorder.err();
  ::kill(discovery.pid(), SIGTERM);
  discovery.wait(15s);

  bag::Reader reader(file);
  ASSERT_TRUE(reader.complete()) << reader.problem();
  const auto recorded = read_file(reader);
  const auto& s = idl::Schema::builtin();
  ASSERT_EQ(recorded.count(topics[0]), 1u) << "no scan recorded";
  ASSERT_EQ(recorded.at(topics[1]).size(), 1u);
  EXPECT_EQ(idl::decode(s, "concert::msg::ModuleTree", recorded.at(topics[1])[0].bytes), tree);
  EXPECT_EQ(
      idl::decode(s, "concert::msg::EscScan", recorded.at(topics[0])[0].bytes).at("slaves").size(),
      18u)
      << "the 18 slaves of the real scan";
  bool discovery_status = false;
  for (const auto& m : recorded.at(topics[2])) {
    discovery_status |=
        idl::decode(s, "concert::msg::ServiceStatus", m.bytes).at("service") == "discovery";
  }
  EXPECT_TRUE(discovery_status);
  const auto check = mcap_check(file);
  ASSERT_FALSE(check.empty());
  EXPECT_EQ(check[0].at("decoded").at(topics[1]).get<int>(), 1);
  EXPECT_EQ(check[0].at("statistics").at("messageCount").get<uint64_t>(),
            reader.summary().statistics.message_count);

  // The recorded scan, played into a fresh discovery service, gives the same tree again.
  Process again({CONCERT_DISCOVERY_BIN, "--module-db",
                 std::string(CONCERT_SHARED_DATA) + "/concert_resources"});
  Process tree_again({CONCERT_BIN, "topic", "echo", topics[1], "--count", "1", "--timeout", "60"});
  const auto play = concert({"bag", "play", file, "--topics", topics[0], "--wait", "20"});
  ASSERT_EQ(play.code, 0) << play.err;
  ASSERT_EQ(tree_again.wait(60s), 0) << tree_again.err() << again.err();
  Json replayed = Json::parse(testing::lines(tree_again.out()).at(0));
  Json original = tree;
  replayed.erase("stamp_ns");
  original.erase("stamp_ns");
  EXPECT_EQ(replayed, original);
  ::kill(again.pid(), SIGTERM);
  again.wait(15s);
}
#endif

TEST(BagCli, BadInputIsRefusedNamingWhatIsWrong) {
  testing::TempDir dir("bag-cli");
  const std::string text = dir.path() + "/notes.txt";
  std::ofstream(text) << "not a recording\n";
  auto r = concert({"bag", "info", text});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr(text + ": not an MCAP file"));
  r = concert({"bag", "play", dir.path() + "/missing.mcap"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("missing.mcap: cannot open"));
  r = concert({"bag", "record", "no/such_topic", "-o", dir.path() + "/a.mcap"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("topic 'no/such_topic' is not in the catalogue"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() + "/a.mcap"));
  r = concert({"bag", "record", "-o", text});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr(text + " exists (--force overwrites it)"));
  r = concert({"bag", "record", "-o", dir.path() + "/b.mcap", "--compression", "gzip"});
  EXPECT_EQ(r.code, 2);
  r = concert({"bag", "play", text, "--rate", "0"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--rate"));
}

}  // namespace
}  // namespace concert
