// `concert bag play`: one writer per recorded topic (its catalogue QoS; latched topics stay
// latched while playing), messages written at their recorded times scaled by --rate.
#include <algorithm>
#include <chrono>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <iomanip>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "bag.hpp"
#include "concert/dds/participant.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"

namespace concert::tool::bag_verbs {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

/// A recorded topic being played.
struct Track {
  std::string topic;
  std::string type;
  std::shared_ptr<const idl::Schema> schema;  // parsed from the recording
  bool keyed = false;
  dds::QosClass qos = dds::QosClass::kStream;
  eprosima::fastdds::dds::DataWriter* writer = nullptr;
  uint64_t written = 0;
};

}  // namespace

int play(const PlayOptions& o, std::ostream& out, std::ostream& err) {
  bag::Reader reader(o.file);
  const bag::Summary& summary = reader.summary();
  if (!reader.complete())
    err << "concert bag play: " << o.file << ": " << reader.problem() << std::endl;
  for (const auto& t : o.topics) {
    const bool recorded = std::any_of(summary.channels.begin(), summary.channels.end(),
                                      [&](const auto& c) { return c.second.topic == t; });
    if (!recorded)
      throw cli::UsageError("topic '" + t + "' is not in " + o.file +
                            " (`concert bag info` lists them)");
  }
  const std::set<std::string> only(o.topics.begin(), o.topics.end());

  // Each channel's type from the schema the recording carries (the IDL it was recorded with).
  std::map<uint16_t, std::shared_ptr<const idl::Schema>> schemas;
  std::map<uint16_t, Track> tracks;
  for (const auto& [id, c] : summary.channels) {
    if (!only.empty() && !only.count(c.topic)) continue;
    const auto s = summary.schemas.find(c.schema_id);
    if (s == summary.schemas.end() || s->second.encoding != kSchemaEncoding ||
        c.message_encoding != kMessageEncoding) {
      err << "concert bag play: " << c.topic << ": not an OMG IDL schema with CDR messages; skipped"
          << std::endl;
      continue;
    }
    auto& parsed = schemas[s->first];
    if (!parsed) {
      try {
        parsed = std::make_shared<const idl::Schema>(
            idl::Schema::parse(s->second.data, o.file + ": schema " + s->second.name));
      } catch (const idl::SchemaError& e) {
        throw cli::Failure(e.what());
      }
    }
    Track t;
    t.topic = c.topic;
    t.type = s->second.name;
    t.schema = parsed;
    t.keyed = parsed->at(t.type).keyed();
    if (const auto ours = dds::find_topic(c.topic)) {
      t.qos = ours->qos;
      const auto* now = idl::Schema::builtin().find_struct(t.type);
      if (ours->type_name != t.type || now == nullptr ||
          idl::Schema::builtin().shape(t.type) != parsed->shape(t.type)) {
        err << "concert bag play: " << c.topic << ": the recording's type " << t.type
            << " differs from the current IDL's " << ours->type_name << "; played as recorded"
            << std::endl;
      }
    } else if (const auto qos = c.metadata.find(kQosKey); qos != c.metadata.end()) {
      t.qos = parse_qos_name(qos->second).value_or(dds::QosClass::kStream);
    }
    tracks[id] = std::move(t);
  }
  if (tracks.empty()) throw cli::Failure(o.file + ": no topic to play");

  const int32_t domain = o.dds.domain_id();
  dds::Participant participant({.name = "concert-bag-play", .domain_id = domain});
  for (auto& [id, t] : tracks) {
    auto* topic = participant.topic(
        t.topic, eprosima::fastdds::dds::TypeSupport(new dds::RawPubSubType(t.type, t.keyed)));
    t.writer = participant.publisher()->create_datawriter(topic, dds::raw_writer_qos(t.qos));
    if (t.writer == nullptr) throw cli::Failure("cannot create a writer on '" + t.topic + "'");
  }
  // Until every topic has a reader and no further reader has matched for a moment (readers of
  // several programs match one after the other), or --wait runs out.
  const auto wait_until = Clock::now() + std::chrono::duration<double>(o.wait_s);
  constexpr auto kSettle = 300ms;
  auto matches = [&] {
    std::vector<int32_t> counts;
    for (const auto& [id, t] : tracks) {
      eprosima::fastdds::dds::PublicationMatchedStatus m;
      t.writer->get_publication_matched_status(m);
      counts.push_back(m.current_count);
    }
    return counts;
  };
  auto seen = matches();
  auto changed = Clock::now();
  while (!interrupted() && Clock::now() < wait_until) {
    const auto now = matches();
    if (now != seen) {
      seen = now;
      changed = Clock::now();
    }
    const bool all = std::all_of(seen.begin(), seen.end(), [](int32_t n) { return n > 0; });
    if (all && Clock::now() - changed >= kSettle) break;
    std::this_thread::sleep_for(10ms);
  }

  const auto start = Clock::now();
  const auto stop_at = start + std::chrono::duration<double>(o.dds.timeout_s);
  auto should_stop = [&] {
    return interrupted() || (o.dds.timeout_s > 0 && Clock::now() >= stop_at);
  };
  std::vector<double> late_ms;  // how late each write was against its schedule
  uint64_t played = 0;
  int passes = 0;
  do {
    const auto pass_start = Clock::now();
    std::optional<uint64_t> first;
    reader.read_messages([&](const bag::Message& m, const bag::Channel&) {
      auto track = tracks.find(m.channel_id);
      if (track == tracks.end()) return !should_stop();
      if (!first) first = m.log_time;
      const auto due =
          pass_start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                           static_cast<double>(m.log_time - *first) * 1e-9 / o.rate));
      while (Clock::now() < due) {
        if (should_stop()) return false;
        std::this_thread::sleep_until(std::min(due, Clock::now() + 50ms));
      }
      if (should_stop()) return false;
      Track& t = track->second;
      dds::RawSample sample{{m.data.begin(), m.data.end()}, std::nullopt};
      if (t.keyed) {
        try {
          sample.key = idl::key_hash_of_cdr(*t.schema, t.type, m.data);
        } catch (const idl::CdrError& e) {
          err << "concert bag play: " << t.topic << ": message " << m.sequence
              << " does not decode as " << t.type << ": " << e.what() << "; skipped" << std::endl;
          return true;
        }
      }
      if (late_ms.size() < 1'000'000)
        late_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - due).count());
      if (!t.writer->write(&sample)) {
        throw cli::Failure("writing message " + std::to_string(m.sequence) + " on '" + t.topic +
                           "' failed");
      }
      ++t.written;
      ++played;
      return true;
    });
    ++passes;
  } while (o.loop && !should_stop() && played > 0);

  // Reliable readers get what was written before the writers go (bounded).
  for (auto& [id, t] : tracks) {
    if (dds::qos_spec(t.qos).reliable)
      t.writer->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(5, 0));
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  std::sort(late_ms.begin(), late_ms.end());
  const double late_median = late_ms.empty() ? 0.0 : late_ms[late_ms.size() / 2];
  const double late_max = late_ms.empty() ? 0.0 : late_ms.back();
  for (auto& [id, t] : tracks) participant.publisher()->delete_datawriter(t.writer);

  if (o.dds.json) {
    nlohmann::ordered_json j = {{"file", o.file},
                                {"messages", played},
                                {"passes", passes},
                                {"seconds", elapsed},
                                {"rate", o.rate},
                                {"late_ms_median", late_median},
                                {"late_ms_max", late_max},
                                {"complete", reader.complete()},
                                {"topics", nlohmann::ordered_json::object()}};
    for (const auto& [id, t] : tracks) j["topics"][t.topic] = t.written;
    out << j.dump() << "\n";
  } else {
    out << "played " << played << " message(s) on " << tracks.size() << " topic(s) of " << o.file
        << " in " << std::fixed << std::setprecision(2) << elapsed << " s (rate " << o.rate
        << (passes > 1 ? ", " + std::to_string(passes) + " passes" : "")
        << "; writes late by median " << std::setprecision(3) << late_median << " ms, max "
        << late_max << " ms)\n";
  }
  return 0;
}

}  // namespace concert::tool::bag_verbs
