// MCAP recordings (libs/bag: `concert bag info` and `concert bag play` read files that may come
// from another machine, another tool, or a recorder killed mid-write). The reader must read a
// complete file from its summary and a damaged one up to its last good record, and otherwise
// throw BagError; nothing it reports may point outside what it read. Documented failure:
// BagError.
//
// Seeds: small recordings written by libs/bag's own writer (no compression, zstd, lz4; two
// channels, metadata), each also cut short at three places, as a killed recorder leaves them.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "concert/bag/mcap.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;

void read(const std::string& path) {
  try {
    bag::Reader reader(path);
    const bag::Summary& summary = reader.summary();
    for (const auto& [id, channel] : summary.channels) {
      CONCERT_FUZZ_CHECK(id == channel.id, "a channel filed under another id");
    }
    uint64_t messages = 0;
    uint64_t bytes = 0;
    reader.read_messages([&](const bag::Message& m, const bag::Channel& c) {
      CONCERT_FUZZ_CHECK(m.channel_id == c.id, "a message handed over with another channel");
      for (const uint8_t b : m.data) bytes += b;  // every byte readable (ASan checks)
      return ++messages < 100000;
    });
    volatile uint64_t sink = messages + bytes;
    (void)sink;
  } catch (const bag::BagError&) {
  }
}

std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  read(fuzz::input_file("input.mcap", fuzz::text_of(data, size)).string());
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  for (const bag::Compression compression :
       {bag::Compression::kNone, bag::Compression::kZstd, bag::Compression::kLz4}) {
    const std::string name = "rec_" + std::string(bag::to_string(compression));
    const std::filesystem::path file = input_file(name + ".mcap", "");
    {
      bag::WriterOptions options;
      options.compression = compression;
      options.chunk_size = 256;  // several chunks in a small file
      bag::Writer writer(file.string(), options);
      const uint16_t schema = writer.add_schema("concert::msg::Text", "omgidl",
                                                "module concert { module msg { struct Text { "
                                                "string text; }; }; };");
      const uint16_t a = writer.add_channel(schema, "concert/a", "cdr", {{"qos", "latched"}});
      const uint16_t b = writer.add_channel(0, "concert/b", "cdr");
      for (uint32_t i = 0; i < 40; ++i) {
        const std::string payload(8 + i % 13, static_cast<char>('a' + i % 26));
        const auto* bytes = reinterpret_cast<const uint8_t*>(payload.data());
        writer.write({i % 3 == 0 ? b : a, i, 1000u * i, 1000u * i + 7, {bytes, payload.size()}});
      }
      writer.add_metadata({"concert_recording", {{"dropped", "0"}}});
      writer.close();
    }
    const std::string content = file_bytes(file);
    seeds.add(name + ".mcap", content);
    for (const size_t cut : {content.size() / 3, content.size() / 2, content.size() - 9}) {
      seeds.add(name + "_cut" + std::to_string(cut) + ".mcap", content.substr(0, cut));
    }
  }
  seeds.add_tokens({"\x89MCAP0\r\n", "omgidl", "cdr", "zstd", "lz4", "concert_recording"});
}
