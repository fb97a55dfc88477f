// The MCAP writer and reader: files read back equal message for message with every compression,
// the summary's indexes point at the records they index, a file cut at any byte is read up to
// its last complete record and says so, and corrupt bytes are reported naming the record.
// (tools/mcap_check runs an independent reader, @mcap/core, on files of `concert bag record`.)
#include "concert/bag/mcap.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "concert/common/error_text.hpp"
#include "process.hpp"

namespace concert::bag {
namespace {

using ::testing::HasSubstr;

struct Sent {
  uint16_t channel;
  uint32_t sequence;
  uint64_t log_time, publish_time;
  std::vector<uint8_t> data;
};

std::vector<uint8_t> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void write_bytes(const std::string& path, const std::vector<uint8_t>& bytes, size_t n) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(n));
}

uint64_t le64(const std::vector<uint8_t>& b, uint64_t at) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= uint64_t{b.at(at + static_cast<uint64_t>(i))} << (8 * i);
  return v;
}

/// Writes `count` seeded messages on three channels (one more channel stays empty), sizes from
/// 0 bytes to more than a chunk, and returns them.
std::vector<Sent> write_file(const std::string& path, WriterOptions options, int count,
                             bool flush_often = false) {
  std::mt19937 rng(1234);
  Writer w(path, options);
  const uint16_t s1 = w.add_schema("concert::msg::A", "omgidl",
                                   "module concert { module msg { struct A { long x; }; }; };");
  const uint16_t s2 = w.add_schema("concert::msg::B", "omgidl", "struct B { octet y; };");
  const std::vector<uint16_t> channels = {
      w.add_channel(s1, "concert/a", "cdr", {{"qos", "latched"}}),
      w.add_channel(s2, "concert/b", "cdr"),
      w.add_channel(s1, "concert/a2", "cdr", {{"qos", "stream"}, {"keyed", "true"}})};
  w.add_channel(s2, "concert/never", "cdr");
  std::vector<Sent> sent;
  uint64_t t = 1'700'000'000'000'000'000ULL;
  for (int i = 0; i < count; ++i) {
    Sent m;
    m.channel = channels[static_cast<size_t>(i) % channels.size()];
    m.sequence = static_cast<uint32_t>(i);
    t += std::uniform_int_distribution<uint64_t>(0, 2'000'000)(rng);
    m.log_time = t;
    m.publish_time = t - 1000;
    const size_t size =
        i % 17 == 5 ? options.chunk_size + 100 : std::uniform_int_distribution<size_t>(0, 300)(rng);
    for (size_t k = 0; k < size; ++k)
      m.data.push_back(static_cast<uint8_t>(rng() % 7));  // compressible
    w.write({m.channel, m.sequence, m.log_time, m.publish_time, m.data});
    if (flush_often && i % 5 == 4) w.flush();
    sent.push_back(std::move(m));
  }
  w.add_metadata({"recording", {{"domain", "7"}, {"dropped", "0"}}});
  w.close();
  return sent;
}

std::vector<Sent> read_all(Reader& reader) {
  std::vector<Sent> got;
  reader.read_messages([&](const Message& m, const Channel& c) {
    EXPECT_EQ(m.channel_id, c.id);
    got.push_back(
        {m.channel_id, m.sequence, m.log_time, m.publish_time, {m.data.begin(), m.data.end()}});
    return true;
  });
  return got;
}

void expect_equal(const std::vector<Sent>& got, const std::vector<Sent>& sent, size_t n) {
  ASSERT_EQ(got.size(), n);
  for (size_t i = 0; i < n; ++i) {
    EXPECT_EQ(got[i].channel, sent[i].channel) << i;
    EXPECT_EQ(got[i].sequence, sent[i].sequence) << i;
    EXPECT_EQ(got[i].log_time, sent[i].log_time) << i;
    EXPECT_EQ(got[i].publish_time, sent[i].publish_time) << i;
    EXPECT_EQ(got[i].data, sent[i].data) << i;
  }
}

class Mcap : public ::testing::TestWithParam<Compression> {};

TEST_P(Mcap, ReadsBackMessageForMessageWithTheSummary) {
  testing::TempDir dir("bag-test");
  const std::string path = dir.path() + "/a.mcap";
  const auto sent = write_file(path, {.compression = GetParam(), .chunk_size = 4096}, 400);
  Reader reader(path);
  EXPECT_TRUE(reader.complete()) << reader.problem();
  EXPECT_EQ(reader.problem(), "");
  const Summary& s = reader.summary();
  EXPECT_TRUE(s.from_summary_section);
  EXPECT_EQ(s.library, "concert libs/bag");
  EXPECT_EQ(s.statistics.message_count, 400u);
  EXPECT_EQ(s.statistics.channel_message_counts.at(0), 134u);
  EXPECT_EQ(s.statistics.channel_message_counts.at(1), 133u);
  EXPECT_EQ(s.statistics.channel_message_counts.count(3), 0u) << "no message on concert/never";
  EXPECT_EQ(s.statistics.message_start_time, sent.front().log_time);
  EXPECT_EQ(s.statistics.message_end_time, sent.back().log_time);
  EXPECT_EQ(s.statistics.schema_count, 2u);
  EXPECT_EQ(s.statistics.channel_count, 4u);
  EXPECT_EQ(s.channels.at(3).topic, "concert/never") << "registered channels are in the summary";
  EXPECT_EQ(s.channels.at(2).metadata.at("keyed"), "true");
  EXPECT_EQ(s.schemas.at(1).encoding, "omgidl");
  EXPECT_GT(s.statistics.chunk_count, 10u);
  EXPECT_EQ(s.chunk_indexes.size(), s.statistics.chunk_count);
  ASSERT_EQ(s.metadata.size(), 1u);
  EXPECT_EQ(s.metadata[0].entries.at("domain"), "7");
  EXPECT_EQ(s.compressions.size(), 1u);
  expect_equal(read_all(reader), sent, sent.size());

  // Every index points at the record it indexes.
  const auto bytes = file_bytes(path);
  uint64_t messages_indexed = 0;
  for (const auto& c : s.chunk_indexes) {
    EXPECT_EQ(bytes.at(c.chunk_start_offset), 0x06);
    EXPECT_EQ(le64(bytes, c.chunk_start_offset + 1) + 9, c.chunk_length);
    EXPECT_LE(c.message_start_time, c.message_end_time);
    if (GetParam() == Compression::kNone) {
      EXPECT_EQ(c.compressed_size, c.uncompressed_size);
    }
    for (const auto& [channel, offset] : c.message_index_offsets) {
      EXPECT_EQ(bytes.at(offset), 0x07);
      EXPECT_EQ(bytes.at(offset + 9), channel);
      messages_indexed += (le64(bytes, offset + 1) - 6) / 16;
    }
  }
  EXPECT_EQ(messages_indexed, 400u);
}

TEST_P(Mcap, AFileCutAtAnyByteIsReadUpToItsLastCompleteRecord) {
  testing::TempDir dir("bag-test");
  const std::string path = dir.path() + "/full.mcap";
  const auto sent = write_file(path, {.compression = GetParam(), .chunk_size = 1024}, 60, true);
  const auto bytes = file_bytes(path);
  Reader full(path);
  const auto chunks = full.summary().chunk_indexes;
  const auto statistics = full.summary().statistics;
  const std::string cut_path = dir.path() + "/cut.mcap";
  int checked = 0;
  // Every byte of the file's start and end, and ~300 cuts between (an odd stride, so the cuts
  // fall at every offset within records).
  const size_t stride = bytes.size() / 300 | 1;
  for (size_t n = 0; n < bytes.size(); n += (n < 64 || n + 64 > bytes.size()) ? 1 : stride) {
    write_bytes(cut_path, bytes, n);
    if (n < 8 + 9 + 4 + 4 + 16) {  // magic + Header (empty profile, "concert libs/bag")
      EXPECT_THROW(Reader{cut_path}, BagError) << n;
      continue;
    }
    Reader cut(cut_path);
    EXPECT_FALSE(cut.complete()) << n;
    size_t expected = 0;  // the messages of the chunks that end before the cut
    for (const auto& c : chunks) {
      if (c.chunk_start_offset + c.chunk_length <= n) {
        for (const auto& [channel, offset] : c.message_index_offsets)
          expected += (le64(bytes, offset + 1) - 6) / 16;
      }
    }
    std::vector<Sent> got;
    ASSERT_NO_THROW(got = read_all(cut)) << "cut at " << n;
    expect_equal(got, sent, expected);
    EXPECT_THAT(cut.problem(), HasSubstr("cut short")) << n;
    EXPECT_EQ(cut.summary().statistics.message_count, expected) << n;
    ++checked;
  }
  EXPECT_GT(checked, 300);
  write_bytes(cut_path, bytes, bytes.size() - 3);
  Reader almost(cut_path);
  EXPECT_THAT(almost.problem(), HasSubstr("no footer"));
  EXPECT_EQ(almost.summary().statistics.message_count, statistics.message_count);
  EXPECT_EQ(read_all(almost).size(), sent.size());
}

INSTANTIATE_TEST_SUITE_P(Compressions, Mcap,
                         ::testing::Values(Compression::kNone, Compression::kZstd,
                                           Compression::kLz4),
                         [](const auto& param) { return std::string(to_string(param.param)); });

TEST(McapErrors, CorruptBytesAreReportedNamingTheRecord) {
  testing::TempDir dir("bag-test");
  const std::string path = dir.path() + "/a.mcap";
  write_file(path, {.compression = Compression::kNone, .chunk_size = 1024}, 40);
  const auto bytes = file_bytes(path);
  Reader good(path);
  const auto chunk = good.summary().chunk_indexes.at(2);
  const std::string bad = dir.path() + "/bad.mcap";

  auto flipped = bytes;
  flipped.at(chunk.chunk_start_offset + chunk.chunk_length - 3) ^= 0x40;  // inside its records
  write_bytes(bad, flipped, flipped.size());
  Reader r1(bad);
  const std::string chunk_error = error_text<BagError>([&] { read_all(r1); });
  EXPECT_THAT(chunk_error, HasSubstr(bad + ": Chunk record at byte " +
                                     std::to_string(chunk.chunk_start_offset)));
  EXPECT_THAT(chunk_error, HasSubstr("CRC of its records does not match"));

  flipped = bytes;
  const uint64_t index_at = chunk.message_index_offsets.begin()->second;
  flipped.at(index_at + 20) ^= 0x01;  // a Message Index: only the data section CRC covers it
  write_bytes(bad, flipped, flipped.size());
  Reader r2(bad);
  EXPECT_THAT(error_text<BagError>([&] { read_all(r2); }),
              HasSubstr("data section's CRC does not match"));

  flipped = bytes;
  flipped.at(bytes.size() - 8 - 29 - 5) ^= 0x01;  // in the summary offsets
  write_bytes(bad, flipped, flipped.size());
  EXPECT_THAT(error_text<BagError>([&] { Reader r3(bad); }),
              HasSubstr("summary section's CRC does not match"));

  write_bytes(bad, {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'}, 11);
  EXPECT_EQ(error_text<BagError>([&] { Reader r4(bad); }),
            bad + ": not an MCAP file (it does not start with the MCAP magic bytes)");
  EXPECT_THAT(error_text<BagError>([&] { Reader r5(dir.path() + "/missing.mcap"); }),
              HasSubstr("missing.mcap: cannot open: No such file or directory"));
}

// A file refused by the constructor is closed again (a reader that kept it open ran out of
// file descriptors after some thousand bad files: found by tests/fuzz/fuzz_mcap).
TEST(McapErrors, AFileTheReaderRefusesIsClosed) {
  testing::TempDir dir("bag-test");
  const std::string bad = dir.path() + "/bad.mcap";
  write_bytes(bad, {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'}, 11);
  const auto open_files = [] {
    return std::distance(std::filesystem::directory_iterator("/proc/self/fd"),
                         std::filesystem::directory_iterator{});
  };
  const auto before = open_files();
  for (int i = 0; i < 100; ++i) EXPECT_THROW(Reader r(bad), BagError);
  EXPECT_EQ(open_files(), before);
}

TEST(McapErrors, TheWriterRefusesWhatTheFileCannotHold) {
  testing::TempDir dir("bag-test");
  EXPECT_THROW(Writer(dir.path() + "/no/such/dir/a.mcap"), BagError);
  Writer w(dir.path() + "/a.mcap");
  EXPECT_THROW(w.add_channel(9, "t", "cdr"), BagError);
  const std::vector<uint8_t> data = {1, 2, 3};
  EXPECT_THAT(error_text<BagError>([&] {
                w.write({5, 0, 1, 1, data});
              }),
              HasSubstr("message on channel 5, which was not added"));
  w.close();
  EXPECT_THROW(w.write({0, 0, 1, 1, data}), BagError);
  EXPECT_THROW(parse_compression("gzip"), BagError);
  EXPECT_EQ(parse_compression("lz4"), Compression::kLz4);
}

TEST(Mcap, AnEmptyRecordingIsAValidFile) {
  testing::TempDir dir("bag-test");
  const std::string path = dir.path() + "/empty.mcap";
  {
    Writer w(path, {});
    w.add_channel(w.add_schema("S", "omgidl", "struct S { long x; };"), "t", "cdr");
  }
  Reader r(path);
  EXPECT_TRUE(r.complete());
  EXPECT_EQ(r.summary().statistics.message_count, 0u);
  EXPECT_EQ(r.summary().channels.size(), 1u);
  EXPECT_TRUE(read_all(r).empty());
}

}  // namespace
}  // namespace concert::bag
