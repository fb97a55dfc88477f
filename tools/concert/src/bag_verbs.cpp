#include "bag_verbs.hpp"

#include <algorithm>
#include <array>
#include <csignal>
#include <ctime>
#include <functional>
#include <iomanip>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bag.hpp"
#include "concert/common/text.hpp"

namespace concert::tool {
namespace bag_verbs {

std::atomic<bool>& interrupted() {
  static std::atomic<bool> flag{false};
  return flag;
}

namespace {

void on_signal(int) { interrupted() = true; }

/// Runs `body` with Ctrl-C (and SIGTERM) setting interrupted().
int interruptible(const std::function<int()>& body) {
  interrupted() = false;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  return body();
}

constexpr std::array<std::pair<dds::QosClass, const char*>, 4> kQosNames = {{
    {dds::QosClass::kLatched, "latched"},
    {dds::QosClass::kStream, "stream"},
    {dds::QosClass::kCommand, "command"},
    {dds::QosClass::kLargeStream, "large_stream"},
}};

double seconds(uint64_t ns) { return static_cast<double>(ns) * 1e-9; }

/// "1714564800.123456789": exact, where a double would round the nanoseconds.
std::string epoch_text(uint64_t ns) {
  std::ostringstream out;
  out << ns / 1'000'000'000ULL << '.' << std::setw(9) << std::setfill('0') << ns % 1'000'000'000ULL;
  return out.str();
}

}  // namespace

std::string qos_name(dds::QosClass qos) {
  for (const auto& [q, name] : kQosNames) {
    if (q == qos) return name;
  }
  return "stream";
}

std::optional<dds::QosClass> parse_qos_name(const std::string& name) {
  for (const auto& [q, n] : kQosNames) {
    if (name == n) return q;
  }
  return std::nullopt;
}

std::string utc_text(uint64_t ns) {
  const auto s = static_cast<std::time_t>(ns / 1'000'000'000ULL);
  std::tm tm{};
  gmtime_r(&s, &tm);
  std::ostringstream out;
  out << std::put_time(&tm, "%Y-%m-%dT%H:%M:%S") << '.' << std::setw(9) << std::setfill('0')
      << ns % 1'000'000'000ULL << 'Z';
  return out.str();
}

int info(const std::string& file, bool json, std::ostream& out, std::ostream& err) {
  bag::Reader reader(file);
  const bag::Summary& s = reader.summary();
  const auto& st = s.statistics;
  const uint64_t duration = st.message_end_time - st.message_start_time;
  std::vector<std::string> compressions;
  for (const auto& c : s.compressions) compressions.push_back(c.empty() ? "none" : c);
  if (!reader.complete()) err << "concert bag info: " << file << ": " << reader.problem() << "\n";

  if (json) {
    nlohmann::ordered_json j = {{"file", file},
                                {"size_bytes", s.file_size},
                                {"complete", reader.complete()},
                                {"problem", reader.problem()},
                                {"library", s.library},
                                {"compression", compressions},
                                {"chunks", st.chunk_count},
                                {"messages", st.message_count},
                                {"start_ns", st.message_start_time},
                                {"end_ns", st.message_end_time},
                                {"duration_s", seconds(duration)}};
    j["topics"] = nlohmann::ordered_json::array();
    for (const auto& [id, c] : s.channels) {
      const auto schema = s.schemas.find(c.schema_id);
      const auto count = st.channel_message_counts.find(id);
      j["topics"].push_back(
          {{"topic", c.topic},
           {"type", schema == s.schemas.end() ? "" : schema->second.name},
           {"messages", count == st.channel_message_counts.end() ? 0 : count->second},
           {"metadata", c.metadata}});
    }
    j["metadata"] = nlohmann::ordered_json::object();
    for (const auto& m : s.metadata) j["metadata"][m.name] = m.entries;
    out << j.dump(2) << "\n";
    return 0;
  }
  out << "file:        " << file << " (" << std::fixed << std::setprecision(2)
      << static_cast<double>(s.file_size) / 1e6 << " MB)\n";
  out << "complete:    " << (reader.complete() ? "yes" : "no: " + reader.problem()) << "\n";
  out << "written by:  " << (s.library.empty() ? "(not named)" : s.library) << "\n";
  out << "compression: " << (compressions.empty() ? "-" : join(compressions)) << " ("
      << st.chunk_count << " chunk(s))\n";
  out << "messages:    " << st.message_count << "\n";
  if (st.message_count > 0) {
    out << "start:       " << utc_text(st.message_start_time) << " ("
        << epoch_text(st.message_start_time) << ")\n";
    out << "end:         " << utc_text(st.message_end_time) << " ("
        << epoch_text(st.message_end_time) << ")\n";
    out << "duration:    " << std::setprecision(3) << seconds(duration) << " s\n";
  }
  size_t width = 5;
  for (const auto& [id, c] : s.channels) width = std::max(width, c.topic.size());
  out << "\n"
      << std::left << std::setw(static_cast<int>(width) + 2) << "TOPIC" << std::setw(44) << "TYPE"
      << std::right << std::setw(10) << "MESSAGES"
      << "  QOS\n";
  for (const auto& [id, c] : s.channels) {
    const auto schema = s.schemas.find(c.schema_id);
    const auto count = st.channel_message_counts.find(id);
    const auto qos = c.metadata.find(kQosKey);
    out << std::left << std::setw(static_cast<int>(width) + 2) << c.topic << std::setw(44)
        << (schema == s.schemas.end() ? "(no schema)" : schema->second.name) << std::right
        << std::setw(10) << (count == st.channel_message_counts.end() ? 0 : count->second) << "  "
        << (qos == c.metadata.end() ? "" : qos->second) << "\n";
  }
  for (const auto& m : s.metadata) {
    out << "\n" << m.name << ":\n";
    for (const auto& [k, v] : m.entries) out << "  " << k << ": " << v << "\n";
  }
  return 0;
}

}  // namespace bag_verbs

void register_bag_verbs(cli::Cli& concert) {
  using namespace bag_verbs;
  CLI::App& bag =
      concert.group(concert.app(), "bag", "recordings of topics in MCAP files: record, info, play");

  auto rec = std::make_shared<RecordOptions>();
  CLI::App& record_verb = concert.verb(
      bag, "record",
      "record topics (default: every catalogue topic) into an MCAP file until Ctrl-C or --timeout",
      [&concert, rec] {
        return interruptible([&] { return record(*rec, concert.out(), concert.err()); });
      });
  record_verb.add_option("TOPICS", rec->topics, "catalogue topics to record (none: all of them)");
  record_verb.add_option("-o,--output", rec->output, "the MCAP file to write")
      ->required()
      ->type_name("FILE");
  cli::Cli::add_choice(record_verb, "--compression", rec->compression, {"zstd", "lz4", "none"},
                       "chunk compression (default zstd)");
  record_verb.add_flag("--force", rec->force, "overwrite FILE if it exists");
  concert.add_dds_options(record_verb, rec->dds, 0.0, "stop after S seconds (0: at Ctrl-C)");

  auto info_file = std::make_shared<std::string>();
  auto info_json = std::make_shared<bool>(false);
  CLI::App& info_verb = concert.verb(
      bag, "info", "topics, types, message counts, start, end and duration of a recording",
      [&concert, info_file, info_json] {
        return info(*info_file, *info_json, concert.out(), concert.err());
      });
  info_verb.add_option("FILE", *info_file, "an MCAP file")->required();
  info_verb.add_flag("--json", *info_json, "machine-readable output");

  auto pl = std::make_shared<PlayOptions>();
  CLI::App& play_verb = concert.verb(
      bag, "play", "publish a recording again with its timing, each topic with its catalogue QoS",
      [&concert, pl] {
        return interruptible([&] { return play(*pl, concert.out(), concert.err()); });
      });
  play_verb.add_option("FILE", pl->file, "an MCAP file (`concert bag record`)")->required();
  play_verb.add_option("--rate", pl->rate, "speed factor (2: twice as fast)")
      ->type_name("R")
      ->check(cli::number(0.0, 1e6, false, true))
      ->default_str("1");
  play_verb.add_flag("--loop", pl->loop, "start again at the end, until Ctrl-C or --timeout");
  play_verb.add_option("--topics", pl->topics, "play only these topics")->type_name("TOPIC...");
  cli::Cli::add_seconds_option(play_verb, "--wait", "", pl->wait_s,
                               "wait up to S seconds for readers: play starts once every topic has "
                               "one and no other matched for 0.3 s");
  concert.add_dds_options(play_verb, pl->dds, 0.0,
                          "stop after S seconds (0: at the end of the recording)");
}

}  // namespace concert::tool
