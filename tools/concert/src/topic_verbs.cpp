#include "topic_verbs.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <iomanip>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "args.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "graph.hpp"

namespace concert::cli {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

std::atomic<bool> g_interrupted{false};

void on_sigint(int) { g_interrupted = true; }

std::string qos_text(bool reliable, bool transient_local) {
  return std::string(reliable ? "reliable" : "best-effort") + " " + (transient_local ? "transient-local" : "volatile");
}

/// How to subscribe to a topic: its type and the QoS that matches its writers.
struct Resolved {
  std::string type;
  bool keyed = false;
  bool reliable = false;
  bool transient_local = false;
  bool ours = false;
};

Resolved resolve(DomainGraph& graph, const std::string& topic, int wait_ms, int32_t domain) {
  Resolved r;
  if (const auto info = dds::find_topic(topic)) {
    const auto spec = dds::qos_spec(info->qos);
    r.type = info->type_name;
    r.keyed = idl::Schema::builtin().at(info->type_name).keyed();
    r.reliable = spec.reliable;
    r.transient_local = spec.transient_local;
    r.ours = true;
    return r;
  }
  const auto deadline = Clock::now() + std::chrono::milliseconds(wait_ms);
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
    throw Failure("topic '" + topic + "' is not in the catalogue and no writer of it was seen on domain " +
                  std::to_string(domain) + " within " + std::to_string(wait_ms) + " ms");
  }
  r.type = writers.front().type;
  r.keyed = writers.front().keyed;
  r.reliable = std::all_of(writers.begin(), writers.end(), [](const auto& w) { return w.reliable; });
  r.transient_local = std::all_of(writers.begin(), writers.end(), [](const auto& w) { return w.transient_local; });
  return r;
}

/// A reader of any topic that hands over each sample's bytes and arrival time.
class RawSubscription : public eprosima::fastdds::dds::DataReaderListener {
 public:
  using Callback = std::function<void(const std::vector<uint8_t>&, Clock::time_point)>;

  RawSubscription(dds::Participant& participant, const std::string& topic, const Resolved& r, Callback cb)
      : participant_(participant), callback_(std::move(cb)) {
    auto* t = participant.topic(topic, eprosima::fastdds::dds::TypeSupport(new dds::RawPubSubType(r.type, r.keyed)));
    auto qos = dds::reader_qos(r.reliable ? dds::QosClass::kCommand : dds::QosClass::kStream);
    qos.durability().kind = r.transient_local ? eprosima::fastdds::dds::TRANSIENT_LOCAL_DURABILITY_QOS
                                              : eprosima::fastdds::dds::VOLATILE_DURABILITY_QOS;
    qos.history().depth = 1000;
    reader_ = participant.subscriber()->create_datareader(t, qos, this,
                                                          eprosima::fastdds::dds::StatusMask::data_available());
    if (reader_ == nullptr) throw Failure("cannot subscribe to '" + topic + "'");
  }
  ~RawSubscription() override {
    reader_->set_listener(nullptr);
    participant_.subscriber()->delete_datareader(reader_);
  }

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    dds::RawSample sample;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) callback_(sample.bytes, Clock::now());
    }
  }

 private:
  dds::Participant& participant_;
  Callback callback_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
};

/// Runs until `count` samples (0 = no limit), the timeout (0 = none) or Ctrl-C.
void run_until(const std::function<size_t()>& received, long count, long timeout_ms) {
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!g_interrupted && (count == 0 || received() < static_cast<size_t>(count)) &&
         (timeout_ms == 0 || Clock::now() < deadline)) {
    std::this_thread::sleep_for(5ms);
  }
}

int list(Args& a, std::ostream& out, int32_t domain) {
  const long wait_ms = a.integer("--wait-ms", 1500, 0, 600000);
  const bool json = a.flag("--json");
  a.finish();
  DomainGraph graph(domain, "concert-topic-list");
  std::this_thread::sleep_for(std::chrono::milliseconds(wait_ms));
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
  auto join = [](const std::set<std::string>& s) {
    std::string r;
    for (const auto& x : s) r += (r.empty() ? "" : ", ") + x;
    return r;
  };
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
  if (rows.empty()) out << "(no topics seen on domain " << domain << " within " << wait_ms << " ms)\n";
  return 0;
}

int info(Args& a, std::ostream& out, int32_t domain) {
  const std::string topic = a.positional("topic name");
  const long wait_ms = a.integer("--wait-ms", 1500, 0, 600000);
  a.finish();
  DomainGraph graph(domain, "concert-topic-info");
  std::this_thread::sleep_for(std::chrono::milliseconds(wait_ms));
  const auto endpoints = graph.endpoints_of(topic);
  const auto cat = dds::find_topic(topic);
  if (!cat && endpoints.empty()) {
    throw Failure("topic '" + topic + "' is not in the catalogue and was not seen on domain " + std::to_string(domain) +
                  " within " + std::to_string(wait_ms) + " ms");
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
  const std::string type = cat ? std::string(cat->type_name) : endpoints.front().type;
  if (idl::Schema::builtin().find_struct(type) != nullptr) {
    out << "shape:\n" << idl::Schema::builtin().shape(type);
  }
  return 0;
}

/// Options shared by echo and hz: which topic, and when to stop.
struct Follow {
  std::string topic;
  long count;
  long timeout_ms;
  long wait_ms;
};

Follow follow_options(Args& a) {
  Follow f;
  f.topic = a.positional("topic name");
  f.count = a.integer("--count", 0, 0, 1'000'000'000);
  f.timeout_ms = a.integer("--timeout-ms", 0, 0, 86'400'000);
  f.wait_ms = a.integer("--wait-ms", 2000, 0, 600000);
  return f;
}

int echo(Args& a, std::ostream& out, std::ostream& err, int32_t domain) {
  const auto [topic, count, timeout_ms, wait_ms] = follow_options(a);
  a.finish();
  DomainGraph graph(domain, "concert-topic-echo");
  const Resolved r = resolve(graph, topic, static_cast<int>(wait_ms), domain);
  const auto& schema = idl::Schema::builtin();
  if (schema.find_struct(r.type) == nullptr) {
    throw Failure("topic '" + topic + "' has type '" + r.type +
                  "', which is not in the project's IDL: its samples cannot be decoded (`concert topic hz` works on any topic)");
  }
  std::mutex mutex;
  size_t printed = 0;
  RawSubscription sub(graph.participant(), topic, r, [&](const std::vector<uint8_t>& bytes, Clock::time_point) {
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
  run_until([&] { std::lock_guard lock(mutex); return printed; }, count, timeout_ms);
  std::lock_guard lock(mutex);
  if (count != 0 && printed < static_cast<size_t>(count) && !g_interrupted) {
    err << "concert topic echo: received " << printed << " of " << count << " samples on '" << topic << "' within "
        << timeout_ms << " ms\n";
    return 1;
  }
  return 0;
}

int hz(Args& a, std::ostream& out, std::ostream& err, int32_t domain) {
  const auto [topic, count, timeout_ms, wait_ms] = follow_options(a);
  const bool json = a.flag("--json");
  a.finish();
  if (count == 0 && timeout_ms == 0) err << "concert topic hz: measuring until Ctrl-C\n";
  DomainGraph graph(domain, "concert-topic-hz");
  const Resolved r = resolve(graph, topic, static_cast<int>(wait_ms), domain);
  std::mutex mutex;
  std::vector<Clock::time_point> arrivals;
  RawSubscription sub(graph.participant(), topic, r, [&](const std::vector<uint8_t>&, Clock::time_point t) {
    std::lock_guard lock(mutex);
    arrivals.push_back(t);
  });
  run_until([&] { std::lock_guard lock(mutex); return arrivals.size(); }, count, timeout_ms);
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

}  // namespace

int run_topic(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::signal(SIGINT, on_sigint);
  Args a(args);
  const std::string verb = a.positional("topic verb: list, info, echo or hz");
  const auto domain_arg = a.value("--domain");
  const int32_t domain = domain_arg ? dds::parse_domain_id(*domain_arg, "--domain") : dds::domain_id_from_env();
  if (verb == "list") return list(a, out, domain);
  if (verb == "info") return info(a, out, domain);
  if (verb == "echo") return echo(a, out, err, domain);
  if (verb == "hz") return hz(a, out, err, domain);
  throw UsageError("unknown topic verb '" + verb + "' (list, info, echo, hz)");
}

}  // namespace concert::cli
