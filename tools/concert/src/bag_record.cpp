// `concert bag record`: DDS readers (one per topic, its class's QoS) hand each sample to a
// queue; one thread writes the queue into the MCAP file, chunk by chunk.
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "bag.hpp"
#include "concert/common/clock.hpp"
#include "concert/common/text.hpp"
#include "concert/dds/participant.hpp"
#include "concert/idl_schema/schema.hpp"
#include "raw_subscription.hpp"

namespace concert::tool::bag_verbs {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

/// Samples received but not written yet may take this much memory; beyond it a sample is
/// dropped (and counted) rather than let the recorder grow without bound when the disk is slower
/// than the topics (about 5 s of three cameras' RGB + depth at 15 Hz).
constexpr size_t kQueueBytes = 256u << 20;
/// The open chunk is written at least this often, so a crash loses at most about this much.
constexpr auto kFlushPeriod = 1s;

struct Pending {
  uint16_t channel;
  uint64_t log_time, publish_time;
  std::vector<uint8_t> bytes;
};

struct TopicCounts {
  uint64_t received = 0, dropped = 0;
};

/// The hand-over between the DDS threads and the writing thread.
class Queue {
 public:
  /// Takes `bytes` unless the queue is full; stamps the sample with its log time, non-decreasing
  /// across topics, so the file's order is time order.
  bool push(uint16_t channel, int64_t publish_ns, std::vector<uint8_t>& bytes) {
    {
      std::lock_guard lock(mutex_);
      auto& counts = counts_[channel];
      ++counts.received;
      if (bytes_ + bytes.size() > kQueueBytes) {
        ++counts.dropped;
        return false;
      }
      const auto now = static_cast<uint64_t>(now_ns());
      last_ = std::max(last_, now);
      bytes_ += bytes.size();
      items_.push_back({channel, last_, publish_ns > 0 ? static_cast<uint64_t>(publish_ns) : last_,
                        std::move(bytes)});
    }
    ready_.notify_one();
    return true;
  }
  /// Waits up to `timeout` for samples; takes them all (empty after `close()` and drained).
  std::deque<Pending> take(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return !items_.empty() || closed_; });
    std::deque<Pending> out;
    out.swap(items_);
    bytes_ = 0;
    return out;
  }
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    ready_.notify_one();
  }
  bool closed() {
    std::lock_guard lock(mutex_);
    return closed_ && items_.empty();
  }
  std::map<uint16_t, TopicCounts> counts() {
    std::lock_guard lock(mutex_);
    return counts_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Pending> items_;
  size_t bytes_ = 0;
  uint64_t last_ = 0;
  bool closed_ = false;
  std::map<uint16_t, TopicCounts> counts_;
};

}  // namespace

int record(const RecordOptions& o, std::ostream& out, std::ostream& err) {
  std::vector<std::string> topics;
  std::set<std::string> seen;
  if (o.topics.empty()) {
    for (const auto& t : dds::catalogue()) topics.emplace_back(t.name);
  }
  for (const auto& t : o.topics) {
    if (!dds::find_topic(t)) {
      throw cli::UsageError("topic '" + t +
                            "' is not in the catalogue (`concert topic list` shows the topics)");
    }
    if (seen.insert(t).second) topics.push_back(t);
  }
  const bag::Compression compression = bag::parse_compression(o.compression);
  if (!o.force && std::filesystem::exists(o.output)) {
    throw cli::Failure(o.output + " exists (--force overwrites it)");
  }
  const int32_t domain = o.dds.domain_id();

  bag::Writer writer(o.output,
                     {.compression = compression, .library = "concert bag record (libs/bag)"});
  const auto& schema = idl::Schema::builtin();
  std::map<std::string, uint16_t> schema_ids;
  std::vector<std::pair<std::string, Resolved>> channels;  // by channel id
  for (const auto& topic : topics) {
    const auto info = dds::find_topic(topic);
    const Resolved r = *from_catalogue(topic);
    auto [it, added] = schema_ids.emplace(r.type, 0);
    if (added) it->second = writer.add_schema(r.type, kSchemaEncoding, schema.idl(r.type));
    writer.add_channel(it->second, topic, kMessageEncoding,
                       {{kQosKey, qos_name(info->qos)}, {kKeyedKey, r.keyed ? "true" : "false"}});
    channels.emplace_back(topic, r);
  }

  Queue queue;
  std::exception_ptr write_error;
  std::atomic<bool> write_failed{false};
  std::thread writing([&] {
    try {
      std::map<uint16_t, uint32_t> sequence;
      auto last_flush = Clock::now();
      while (!queue.closed()) {
        for (auto& p : queue.take(100ms)) {
          writer.write({p.channel, sequence[p.channel]++, p.log_time, p.publish_time, p.bytes});
        }
        if (Clock::now() - last_flush >= kFlushPeriod) {
          writer.flush();
          last_flush = Clock::now();
        }
      }
    } catch (...) {
      write_error = std::current_exception();
      write_failed = true;
    }
  });

  const auto start = Clock::now();
  const auto start_ns = now_ns();
  std::mutex err_mutex;
  {
    dds::Participant participant({.name = "concert-bag-record", .domain_id = domain});
    std::vector<std::unique_ptr<RawSubscription>> subscriptions;
    for (size_t i = 0; i < channels.size(); ++i) {
      const auto& [topic, r] = channels[i];
      const auto channel = static_cast<uint16_t>(i);
      subscriptions.push_back(std::make_unique<RawSubscription>(
          participant, topic, r,
          [&queue, channel](std::vector<uint8_t>& bytes,
                            const eprosima::fastdds::dds::SampleInfo& info) {
            queue.push(channel, info.source_timestamp.to_ns(), bytes);
          },
          [&err, &err_mutex, topic = topic](int32_t writers) {
            std::lock_guard lock(err_mutex);
            err << "concert bag record: " << topic << ": " << writers << " writer(s)" << std::endl;
          }));
    }
    {
      std::lock_guard lock(err_mutex);
      err << "concert bag record: recording " << topics.size() << " topic(s) on domain " << domain
          << " into " << o.output << "; Ctrl-C stops" << std::endl;
    }
    const auto deadline = start + std::chrono::duration<double>(o.dds.timeout_s);
    while (!interrupted() && !write_failed && (o.dds.timeout_s == 0 || Clock::now() < deadline)) {
      std::this_thread::sleep_for(20ms);
    }
    subscriptions.clear();  // no more samples
  }
  queue.close();
  writing.join();
  if (write_error) std::rethrow_exception(write_error);

  const auto counts = queue.counts();
  uint64_t dropped = 0;
  bag::Metadata recording{kRecordingMetadata, {}};
  for (const auto& [channel, c] : counts) {
    dropped += c.dropped;
    if (c.dropped)
      recording.entries["dropped " + channels[channel].first] = std::to_string(c.dropped);
  }
  char host[256] = "";
  gethostname(host, sizeof host - 1);
  recording.entries["domain"] = std::to_string(domain);
  recording.entries["host"] = host;
  recording.entries["start"] = utc_text(static_cast<uint64_t>(start_ns));
  recording.entries["dropped"] = std::to_string(dropped);
  writer.add_metadata(recording);
  writer.close();

  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  const auto& st = writer.statistics();
  if (o.dds.json) {
    nlohmann::ordered_json j = {{"file", o.output},
                                {"messages", st.message_count},
                                {"dropped", dropped},
                                {"seconds", elapsed},
                                {"bytes", writer.file_size()},
                                {"topics", nlohmann::ordered_json::object()}};
    for (size_t i = 0; i < channels.size(); ++i) {
      const auto c = counts.find(static_cast<uint16_t>(i));
      j["topics"][channels[i].first] = {
          {"messages", c == counts.end() ? 0 : c->second.received - c->second.dropped},
          {"dropped", c == counts.end() ? 0 : c->second.dropped}};
    }
    out << j.dump() << "\n";
  } else {
    out << "recorded " << st.message_count << " message(s) on " << counts.size() << " of "
        << topics.size() << " topic(s) in " << std::fixed << std::setprecision(1) << elapsed
        << " s into " << o.output << " (" << std::setprecision(2)
        << static_cast<double>(writer.file_size()) / 1e6 << " MB)";
    if (dropped) out << "; " << dropped << " dropped (the disk did not keep up)";
    out << "\n";
  }
  return 0;
}

}  // namespace concert::tool::bag_verbs
