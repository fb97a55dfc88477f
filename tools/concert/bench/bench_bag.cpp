// Benchmark (not a test): record throughput.
//  1. libs/bag's writer alone, into a file: messages/s and MB/s for 1 kHz joint states (18
//     joints) and 640x480 RGB images, with each chunk compression.
//  2. End to end: `concert bag record` (its own process) of a publisher in this process writing
//     joint states at 1 kHz and RGB + depth 640x480 at 15 Hz for 10 s over DDS: samples recorded
//     of those written, MB/s, the recorder's CPU time.
// Usage: bench_bag [--seconds S]   (figures in README.md, with the machine they were taken on)
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

#include "concert/bag/mcap.hpp"
#include "concert/cli/cli.hpp"
#include "concert/dds/participant.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "process.hpp"

namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using concert::idl::Json;

const auto& schema() { return concert::idl::Schema::builtin(); }

std::vector<uint8_t> joint_state(uint32_t i) {
  Json s = concert::idl::complete(schema(), "concert::msg::JointState", Json::object());
  for (int j = 0; j < 18; ++j) {
    s["name"].push_back("joint_" + std::to_string(j));
    s["position"].push_back(0.001 * i + j);
    s["velocity"].push_back(0.5 * j);
    s["effort"].push_back(-0.25 * j);
  }
  s["stamp_ns"] = i;
  return concert::idl::encode(schema(), "concert::msg::JointState", s);
}

/// A camera frame: a smooth gradient with noise (compresses like a real image, not like zeros).
std::vector<uint8_t> image(uint32_t i, bool depth) {
  Json s = concert::idl::complete(schema(), "concert::msg::Image", Json::object());
  s["sensor_id"] = depth ? 2 : 1;
  s["width"] = 640;
  s["height"] = 480;
  s["encoding"] = depth ? "16UC1" : "rgb8";
  s["step"] = depth ? 1280 : 1920;
  std::vector<uint8_t> data(640u * 480u * (depth ? 2u : 3u));
  uint32_t noise = 12345 + i;
  for (size_t k = 0; k < data.size(); ++k) {
    noise = noise * 1664525u + 1013904223u;
    data[k] = static_cast<uint8_t>((k / 7 + i) % 200 + (noise >> 29));
  }
  s["data"] = data;
  return concert::idl::encode(schema(), "concert::msg::Image", s);
}

double cpu_seconds(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(stat, line);
  std::istringstream in(line.substr(line.rfind(')') + 2));
  std::string field;
  unsigned long utime = 0, stime = 0;
  for (int i = 3; i <= 15 && in >> field; ++i) {
    if (i == 14) utime = std::stoul(field);
    if (i == 15) stime = std::stoul(field);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

void writer_alone(const std::string& dir) {
  std::printf("libs/bag writer alone (file in %s):\n", dir.c_str());
  std::printf("  %-24s %-6s %12s %10s %10s %8s\n", "messages", "comp.", "messages/s", "MB/s in",
              "MB/s file", "ratio");
  struct Case {
    const char* name;
    std::vector<std::vector<uint8_t>> samples;
    int count;
  };
  std::vector<Case> cases;
  cases.push_back({"JointState (18 joints)", {}, 200000});
  for (uint32_t i = 0; i < 1000; ++i) cases.back().samples.push_back(joint_state(i));
  cases.push_back({"Image 640x480 rgb8", {}, 300});
  for (uint32_t i = 0; i < 8; ++i) cases.back().samples.push_back(image(i, false));
  for (const auto& c : cases) {
    for (const auto compression :
         {concert::bag::Compression::kNone, concert::bag::Compression::kZstd,
          concert::bag::Compression::kLz4}) {
      const std::string file = dir + "/writer.mcap";
      uint64_t bytes = 0;
      const auto start = Clock::now();
      {
        concert::bag::Writer w(file, {.compression = compression});
        const uint16_t ch =
            w.add_channel(w.add_schema("T", "omgidl", "struct T { long x; };"), "t", "cdr");
        for (int i = 0; i < c.count; ++i) {
          const auto& data = c.samples[static_cast<size_t>(i) % c.samples.size()];
          w.write({ch, static_cast<uint32_t>(i), static_cast<uint64_t>(i) * 1000,
                   static_cast<uint64_t>(i) * 1000, data});
          bytes += data.size();
        }
        w.close();
      }
      const double s = std::chrono::duration<double>(Clock::now() - start).count();
      const auto file_bytes = std::filesystem::file_size(file);
      std::printf("  %-24s %-6s %12.0f %10.1f %10.1f %8.2f\n", c.name,
                  std::string(concert::bag::to_string(compression)).c_str(), c.count / s,
                  static_cast<double>(bytes) / s / 1e6, static_cast<double>(file_bytes) / s / 1e6,
                  static_cast<double>(bytes) / static_cast<double>(file_bytes));
    }
  }
}

struct Writer {
  Writer(concert::dds::Participant& p, const std::string& topic) {
    const auto info = *concert::dds::find_topic(topic);
    const bool keyed = schema().at(info.type_name).keyed();
    auto* t = p.topic(topic, eprosima::fastdds::dds::TypeSupport(new concert::dds::RawPubSubType(
                                 std::string(info.type_name), keyed)));
    writer = p.publisher()->create_datawriter(t, concert::dds::raw_writer_qos(info.qos));
  }
  bool matched() const {
    eprosima::fastdds::dds::PublicationMatchedStatus m;
    writer->get_publication_matched_status(m);
    return m.current_count > 0;
  }
  eprosima::fastdds::dds::DataWriter* writer;
};

void end_to_end(const std::string& dir, double seconds) {
  const std::string file = dir + "/e2e.mcap";
  concert::testing::Process recorder({CONCERT_BIN, "bag", "record", "concert/robot/joint_state",
                                      "concert/sensors/camera/rgb", "concert/sensors/camera/depth",
                                      "-o", file});
  concert::dds::Participant participant({.name = "bench-bag"});
  Writer joints(participant, "concert/robot/joint_state");
  Writer rgb(participant, "concert/sensors/camera/rgb");
  Writer depth(participant, "concert/sensors/camera/depth");
  const auto deadline = Clock::now() + 30s;
  while (!(joints.matched() && rgb.matched() && depth.matched()) && Clock::now() < deadline)
    std::this_thread::sleep_for(10ms);
  std::this_thread::sleep_for(500ms);
  std::vector<std::vector<uint8_t>> frames, depths, states;
  for (uint32_t i = 0; i < 4; ++i) {
    frames.push_back(image(i, false));
    depths.push_back(image(i, true));
  }
  for (uint32_t i = 0; i < 1000; ++i) states.push_back(joint_state(i));
  const double cpu_before = cpu_seconds(recorder.pid());
  uint64_t written = 0, written_images = 0, bytes = 0;
  const auto start = Clock::now();
  auto next = start;
  for (uint64_t tick = 0; next - start < std::chrono::duration<double>(seconds); ++tick) {
    std::this_thread::sleep_until(next);
    concert::dds::RawSample s{states[tick % states.size()], std::nullopt};
    joints.writer->write(&s);
    ++written;
    bytes += s.bytes.size();
    if (tick % 67 == 0) {  // 15 Hz
      concert::dds::RawSample f{frames[(tick / 67) % frames.size()],
                                std::array<uint8_t, 16>{0, 0, 0, 1}};
      concert::dds::RawSample d{depths[(tick / 67) % depths.size()],
                                std::array<uint8_t, 16>{0, 0, 0, 2}};
      rgb.writer->write(&f);
      depth.writer->write(&d);
      written_images += 2;
      bytes += f.bytes.size() + d.bytes.size();
    }
    next += 1ms;
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  std::this_thread::sleep_for(1s);
  const double cpu = cpu_seconds(recorder.pid()) - cpu_before;
  recorder.stop(30s);
  concert::bag::Reader reader(file);
  const auto& st = reader.summary().statistics;
  uint64_t recorded_images = 0;
  for (const auto& [id, c] : reader.summary().channels) {
    if (c.topic != "concert/robot/joint_state")
      recorded_images += st.channel_message_counts.count(id) ? st.channel_message_counts.at(id) : 0;
  }
  std::printf("\nconcert bag record, end to end over DDS (%.1f s, zstd):\n", elapsed);
  std::printf(
      "  written: %lu joint states (%.0f Hz) + %lu images (RGB + depth 640x480, 15 Hz each): %.1f "
      "MB/s\n",
      static_cast<unsigned long>(written), static_cast<double>(written) / elapsed,
      static_cast<unsigned long>(written_images), static_cast<double>(bytes) / elapsed / 1e6);
  std::printf(
      "  recorded: %lu joint states, %lu images (%.1f %% / %.1f %%); file %.1f MB (%.1f MB/s)\n",
      static_cast<unsigned long>(st.message_count - recorded_images),
      static_cast<unsigned long>(recorded_images),
      100.0 * static_cast<double>(st.message_count - recorded_images) /
          static_cast<double>(written),
      100.0 * static_cast<double>(recorded_images) / static_cast<double>(written_images),
      static_cast<double>(reader.summary().file_size) / 1e6,
      static_cast<double>(reader.summary().file_size) / elapsed / 1e6);
  std::printf("  recorder CPU: %.2f s for %.1f s (%.0f %% of one core)\n", cpu, elapsed,
              100.0 * cpu / elapsed);
}

int bench(double seconds) {
  concert::testing::TempDir dir("bench-bag");
  writer_alone(dir.path());
  end_to_end(dir.path(), seconds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli("bench_bag",
                        "Record throughput: libs/bag's writer alone into a file, then `concert bag "
                        "record` of 1 kHz joint states and RGB + depth 640x480 at 15 Hz over DDS.",
                        std::cout, std::cerr);
  double seconds = 10.0;
  cli.app()
      .add_option("--seconds", seconds, "length of the end-to-end recording [s]")
      ->capture_default_str()
      ->check(concert::cli::positive_seconds());
  cli.on_run(cli.app(), [&seconds] { return bench(seconds); });
  return cli.run(argc, argv);
}
