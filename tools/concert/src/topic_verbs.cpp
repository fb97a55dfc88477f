#include "topic_verbs.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <csignal>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <iomanip>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "concert/common/text.hpp"
#include "concert/dds/catalogue.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "graph.hpp"
#include "raw_subscription.hpp"

namespace concert::tool {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
using cli::Failure;
using cli::UsageError;

std::atomic<bool> g_interrupted{false};

void on_sigint(int) { g_interrupted = true; }

std::string seconds_text(double s) {
  std::ostringstream out;
  out << s;
  return out.str();
}

std::string qos_text(bool reliable, bool transient_local) {
  return std::string(reliable ? "reliable" : "best-effort") + " " + (transient_local ? "transient-local" : "volatile");
}

Resolved resolve(DomainGraph& graph, const std::string& topic, double wait_s, int32_t domain) {
  if (auto ours = from_catalogue(topic)) return *ours;
  Resolved r;
  const auto deadline = Clock::now() + std::chrono::duration<double>(wait_s);
  std::vector<EndpointInfo> writers;
  while (!g_interrupted) {
    writers.clear();
    for (auto& e : graph.endpoints_of(topic)) {
      if (e.writer) writers.push_back(e);
    }
    if (!writers.empty() || Clock::now() >= deadline) break;
    std::this_thread::sleep_for(20ms);
  }
  if (writers.empty()) {
    throw Failure("topic '" + topic +
                  "' is not in the catalogue and no writer of it was seen on domain " +
                  std::to_string(domain) + " within " + seconds_text(wait_s) + " s");
  }
  r.type = writers.front().type;
  r.keyed = writers.front().keyed;
  r.reliable = std::all_of(writers.begin(), writers.end(), [](const auto& w) { return w.reliable; });
  r.transient_local = std::all_of(writers.begin(), writers.end(), [](const auto& w) { return w.transient_local; });
  return r;
}

/// Runs until `count` samples (0 = no limit), the timeout (0 = none) or Ctrl-C.
void run_until(const std::function<size_t()>& received, long count, double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (!g_interrupted && (count == 0 || received() < static_cast<size_t>(count)) &&
         (timeout_s == 0 || Clock::now() < deadline)) {
    std::this_thread::sleep_for(5ms);
  }
}

int list(const cli::DdsOptions& o, std::ostream& out) {
  const int32_t domain = o.domain_id();
  const bool json = o.json;
  DomainGraph graph(domain, "concert-topic-list");
  std::this_thread::sleep_for(o.timeout());
  struct Row {
    std::set<std::string> types;
    int writers = 0, readers = 0;
    std::set<std::string> qos;
  };
  std::map<std::string, Row> rows;
  for (const auto& e : graph.endpoints()) {
    auto& row = rows[e.topic];
    row.types.insert(e.type);
    (e.writer ? row.writers : row.readers)++;
    row.qos.insert(std::string(e.writer ? "W " : "R ") + qos_text(e.reliable, e.transient_local));
  }
  if (json) {
    idl::Json arr = idl::Json::array();
    for (const auto& [topic, row] : rows) {
      arr.push_back({{"topic", topic}, {"type", join(row.types)}, {"writers", row.writers}, {"readers", row.readers},
                     {"qos", row.qos}, {"catalogue", dds::find_topic(topic).has_value()}});
    }
    out << arr.dump(2) << "\n";
    return 0;
  }
  out << std::left << std::setw(36) << "TOPIC" << std::setw(42) << "TYPE" << std::setw(4) << "W" << std::setw(4)
      << "R" << "QOS\n";
  for (const auto& [topic, row] : rows) {
    out << std::setw(36) << topic << std::setw(42) << join(row.types) << std::setw(4) << row.writers << std::setw(4)
        << row.readers << join(row.qos) << "\n";
  }
  if (rows.empty()) {
    out << "(no topics seen on domain " << domain << " within " << o.timeout_s << " s)\n";
  }
  return 0;
}

int info(const std::string& topic, const cli::DdsOptions& o, std::ostream& out) {
  const int32_t domain = o.domain_id();
  DomainGraph graph(domain, "concert-topic-info");
  std::this_thread::sleep_for(o.timeout());
  const auto endpoints = graph.endpoints_of(topic);
  const auto cat = dds::find_topic(topic);
  if (!cat && endpoints.empty()) {
    throw Failure("topic '" + topic + "' is not in the catalogue and was not seen on domain " +
                  std::to_string(domain) + " within " + seconds_text(o.timeout_s) + " s");
  }
  const std::string type = cat ? std::string(cat->type_name) : endpoints.front().type;
  const bool known = idl::Schema::builtin().find_struct(type) != nullptr;
  if (o.json) {
    idl::Json j = {{"topic", topic}, {"type", type}, {"catalogue", cat.has_value()}};
    if (cat) {
      j["qos"] = dds::to_string(cat->qos);
      j["about"] = cat->description;
    }
    j["endpoints"] = idl::Json::array();
    for (const auto& e : endpoints) {
      j["endpoints"].push_back({{"kind", e.writer ? "writer" : "reader"},
                                {"participant", e.participant},
                                {"type", e.type},
                                {"qos", qos_text(e.reliable, e.transient_local)},
                                {"keyed", e.keyed}});
    }
    if (known) j["shape"] = idl::Schema::builtin().shape(type);
    out << j.dump(2) << "\n";
    return 0;
  }
  out << "topic:  " << topic << "\n";
  if (cat) {
    out << "type:   " << cat->type_name << "\n"
        << "qos:    " << dds::to_string(cat->qos) << "\n"
        << "about:  " << cat->description << "\n";
  }
  out << "endpoints on domain " << domain << ":" << (endpoints.empty() ? " none" : "") << "\n";
  for (const auto& e : endpoints) {
    out << "  " << (e.writer ? "writer" : "reader") << "  " << std::left << std::setw(28)
        << (e.participant.empty() ? "(unnamed)" : e.participant) << e.type << "  "
        << qos_text(e.reliable, e.transient_local) << (e.keyed ? "  keyed" : "") << "\n";
  }
  if (known) out << "shape:\n" << idl::Schema::builtin().shape(type);
  return 0;
}

/// Options shared by echo, hz and pub: which topic, how many samples, when to stop.
struct Follow {
  std::string topic;
  long count = 0;
  double wait_s = 2.0;  ///< how long to wait for a writer (reader) to show up
  cli::DdsOptions dds;  ///< dds.timeout_s: stop after this long (0: no limit)
};

int echo(const Follow& f, std::ostream& out, std::ostream& err) {
  const std::string& topic = f.topic;
  const long count = f.count;
  const int32_t domain = f.dds.domain_id();
  DomainGraph graph(domain, "concert-topic-echo");
  const Resolved r = resolve(graph, topic, f.wait_s, domain);
  const auto& schema = idl::Schema::builtin();
  if (schema.find_struct(r.type) == nullptr) {
    throw Failure("topic '" + topic + "' has type '" + r.type +
                  "', which is not in the project's IDL: its samples cannot be decoded (`concert topic hz` works on any topic)");
  }
  std::mutex mutex;
  size_t printed = 0;
  RawSubscription sub(graph.participant(), topic, r, [&](const std::vector<uint8_t>& bytes, const auto&) {
    std::lock_guard lock(mutex);
    if (count != 0 && printed >= static_cast<size_t>(count)) return;
    try {
      out << idl::decode(schema, r.type, bytes).dump() << std::endl;
    } catch (const idl::CdrError& e) {
      err << "concert topic echo: a sample on '" << topic << "' does not decode as " << r.type << ": " << e.what()
          << std::endl;
    }
    ++printed;
  });
  run_until(
      [&] {
        std::lock_guard lock(mutex);
        return printed;
      },
      count, f.dds.timeout_s);
  std::lock_guard lock(mutex);
  if (count != 0 && printed < static_cast<size_t>(count) && !g_interrupted) {
    err << "concert topic echo: received " << printed << " of " << count << " samples on '" << topic
        << "' within " << f.dds.timeout_s << " s\n";
    return 1;
  }
  return 0;
}

int hz(const Follow& f, std::ostream& out, std::ostream& err) {
  const std::string& topic = f.topic;
  const long count = f.count;
  const bool json = f.dds.json;
  const int32_t domain = f.dds.domain_id();
  if (count == 0 && f.dds.timeout_s == 0) err << "concert topic hz: measuring until Ctrl-C\n";
  DomainGraph graph(domain, "concert-topic-hz");
  const Resolved r = resolve(graph, topic, f.wait_s, domain);
  std::mutex mutex;
  std::vector<Clock::time_point> arrivals;
  RawSubscription sub(graph.participant(), topic, r, [&](const std::vector<uint8_t>&, const auto&) {
    const auto t = Clock::now();
    std::lock_guard lock(mutex);
    arrivals.push_back(t);
  });
  run_until(
      [&] {
        std::lock_guard lock(mutex);
        return arrivals.size();
      },
      count, f.dds.timeout_s);
  std::lock_guard lock(mutex);
  if (arrivals.size() < 2) {
    err << "concert topic hz: " << arrivals.size() << " sample(s) on '" << topic << "': too few for a rate\n";
    return 1;
  }
  std::vector<double> periods;
  for (size_t i = 1; i < arrivals.size(); ++i) {
    periods.push_back(std::chrono::duration<double, std::milli>(arrivals[i] - arrivals[i - 1]).count());
  }
  double mean = 0, sq = 0;
  for (double p : periods) mean += p;
  mean /= static_cast<double>(periods.size());
  for (double p : periods) sq += (p - mean) * (p - mean);
  const double std_ms = std::sqrt(sq / static_cast<double>(periods.size()));
  const double rate = 1000.0 / mean;
  const auto [min_it, max_it] = std::minmax_element(periods.begin(), periods.end());
  if (json) {
    out << idl::Json{{"topic", topic}, {"samples", arrivals.size()}, {"rate_hz", rate},
                     {"period_ms", {{"mean", mean}, {"min", *min_it}, {"max", *max_it}, {"std", std_ms}}}}
               .dump()
        << "\n";
  } else {
    out << std::fixed << std::setprecision(3) << topic << ": rate " << rate << " Hz over " << arrivals.size()
        << " samples; period mean " << mean << " ms, min " << *min_it << ", max " << *max_it << ", std " << std_ms
        << " ms\n";
  }
  return 0;
}

/// `concert topic pub`: what to publish and how.
struct Publish {
  std::string topic;
  std::string json;
  long count = 1;
  double rate_hz = 10.0;
  double wait_s = 1.0;  ///< wait for readers to match before the first sample
  cli::DdsOptions dds;  ///< dds.timeout_s: wait for acknowledgements (reliable topics)
};

int pub(const Publish& p, std::ostream& out) {
  const auto info = dds::find_topic(p.topic);
  if (!info) {
    throw UsageError("topic '" + p.topic +
                     "' is not in the catalogue (`concert topic list` shows the topics; "
                     "`concert topic info TOPIC` a topic's fields)");
  }
  const std::string type(info->type_name);
  const auto& schema = idl::Schema::builtin();
  // Everything about the sample is checked before joining the domain.
  idl::Json sample;
  std::vector<uint8_t> bytes;
  std::optional<std::array<uint8_t, 16>> key;
  try {
    sample = idl::complete(schema, type, idl::Json::parse(p.json));
    bytes = idl::encode(schema, type, sample);
    key = idl::key_hash(schema, type, sample);
  } catch (const idl::Json::exception& e) {  // not JSON, or a number out of range
    throw UsageError("JSON: " + std::string(e.what()));
  } catch (const idl::CdrError& e) {
    throw UsageError("JSON for " + type + ": " + e.what());
  }
  const int32_t domain = p.dds.domain_id();
  dds::Participant participant({.name = "concert-topic-pub", .domain_id = domain});
  auto* topic = participant.topic(
      p.topic,
      eprosima::fastdds::dds::TypeSupport(new dds::RawPubSubType(type, schema.at(type).keyed())));
  auto* writer = participant.publisher()->create_datawriter(topic, dds::raw_writer_qos(info->qos));
  if (writer == nullptr) {
    throw Failure("cannot create a writer on '" + p.topic + "'" + dds::why_refused(participant, p.topic, true));
  }
  const auto deadline = Clock::now() + std::chrono::duration<double>(p.wait_s);
  eprosima::fastdds::dds::PublicationMatchedStatus matched;
  while (!g_interrupted && Clock::now() < deadline) {
    writer->get_publication_matched_status(matched);
    if (matched.current_count > 0) break;
    std::this_thread::sleep_for(10ms);
  }
  writer->get_publication_matched_status(matched);
  dds::RawSample raw{bytes, key};
  const auto period = std::chrono::duration<double>(p.rate_hz > 0.0 ? 1.0 / p.rate_hz : 0.0);
  auto next = Clock::now();
  long written = 0;
  for (; written < p.count && !g_interrupted; ++written) {
    std::this_thread::sleep_until(next);
    if (!writer->write(&raw))
      throw Failure("writing sample " + std::to_string(written + 1) + " on '" + p.topic +
                    "' failed");
    if (p.dds.json) out << sample.dump() << std::endl;
    next += std::chrono::duration_cast<Clock::duration>(period);
  }
  const auto ns = static_cast<int64_t>(p.dds.timeout_s * 1e9);
  const bool acknowledged =
      writer->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
          static_cast<int32_t>(ns / 1'000'000'000), static_cast<uint32_t>(ns % 1'000'000'000))) ==
      eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  participant.publisher()->delete_datawriter(writer);
  if (!p.dds.json) {
    out << "published " << written << " sample(s) of " << type << " on " << p.topic << " (domain "
        << domain << ", " << matched.current_count << " reader(s) matched)\n";
  }
  if (!acknowledged && matched.current_count > 0) {
    throw Failure("the readers of '" + p.topic + "' did not acknowledge the samples within " +
                  seconds_text(p.dds.timeout_s) + " s");
  }
  return 0;
}

}  // namespace

void register_topic_verbs(cli::Cli& concert) {
  CLI::App& topic =
      concert.group(concert.app(), "topic", "topics on the domain: list, info, echo, hz, pub");
  auto follow = [&concert](CLI::App& verb, Follow& f, const std::string& count_help) {
    verb.add_option("TOPIC", f.topic, "topic name")->required();
    verb.add_option("--count", f.count, count_help)->type_name("N")->check(cli::count());
    concert.add_dds_options(verb, f.dds, 0.0, "stop after S seconds (0: no limit)");
    cli::Cli::add_seconds_option(
        verb, "--wait", "--wait-ms", f.wait_s,
        "how long to wait for a writer of a topic that is not in the catalogue");
  };

  auto list_options = std::make_shared<cli::DdsOptions>();
  CLI::App& list_verb = concert.verb(
      topic, "list",
      "topics on the domain (ours and others'), with types, writer/reader counts and QoS",
      [&concert, list_options] { return list(*list_options, concert.out()); });
  concert.add_dds_options(list_verb, *list_options, 1.5, "how long to listen for endpoints");
  cli::Cli::add_deprecated_ms_option(list_verb, "--wait-ms", list_options->timeout_s,
                                     list_verb.get_option("--timeout"));

  auto info_topic = std::make_shared<std::string>();
  auto info_options = std::make_shared<cli::DdsOptions>();
  CLI::App& info_verb =
      concert.verb(topic, "info", "type, QoS, endpoints and type shape of a topic",
                   [&concert, info_topic, info_options] {
                     return info(*info_topic, *info_options, concert.out());
                   });
  info_verb.add_option("TOPIC", *info_topic, "topic name")->required();
  concert.add_dds_options(info_verb, *info_options, 1.5, "how long to listen for endpoints");
  cli::Cli::add_deprecated_ms_option(info_verb, "--wait-ms", info_options->timeout_s,
                                     info_verb.get_option("--timeout"));

  auto echo_options = std::make_shared<Follow>();
  CLI::App& echo_verb =
      concert.verb(topic, "echo", "samples as JSON, one object per line (--json: the same)",
                   [&concert, echo_options] {
                     std::signal(SIGINT, on_sigint);
                     return echo(*echo_options, concert.out(), concert.err());
                   });
  follow(echo_verb, *echo_options, "stop after N samples (0: no limit)");

  auto hz_options = std::make_shared<Follow>();
  CLI::App& hz_verb =
      concert.verb(topic, "hz", "arrival rate statistics of any topic", [&concert, hz_options] {
        std::signal(SIGINT, on_sigint);
        return hz(*hz_options, concert.out(), concert.err());
      });
  follow(hz_verb, *hz_options, "stop after N samples (0: no limit)");

  auto pub_options = std::make_shared<Publish>();
  CLI::App& pub_verb = concert.verb(
      topic, "pub",
      "publish a sample given as JSON on a catalogue topic (missing fields: zero/empty)",
      [&concert, pub_options] {
        std::signal(SIGINT, on_sigint);
        return pub(*pub_options, concert.out());
      });
  pub_verb.add_option("TOPIC", pub_options->topic, "catalogue topic name")->required();
  pub_verb
      .add_option("JSON", pub_options->json,
                  "the sample as a JSON object, e.g. '{\"source\": \"SOFTWARE\"}'")
      ->required();
  pub_verb.add_option("--count", pub_options->count, "publish N samples")
      ->type_name("N")
      ->check(cli::number(1, 1e9, true))
      ->default_str("1");
  pub_verb
      .add_option("--rate", pub_options->rate_hz,
                  "samples per second when --count > 1 (0: as fast as possible)")
      ->type_name("HZ")
      ->check(cli::number(0))
      ->default_str("10");
  concert.add_dds_options(pub_verb, pub_options->dds, 5.0,
                          "how long to wait for reliable readers to acknowledge the samples");
  cli::Cli::add_seconds_option(pub_verb, "--wait", "", pub_options->wait_s,
                               "how long to wait for readers to match before the first sample");
}

}  // namespace concert::tool
