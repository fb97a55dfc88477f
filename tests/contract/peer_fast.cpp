// Contract peer on Fast DDS, using the generated types and the project's DDS layer.
#include <cstring>
#include <array>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/rtps/builtin/data/ReaderProxyData.h>
#include <fastdds/rtps/builtin/data/WriterProxyData.h>
#include <fastdds/rtps/reader/ReaderDiscoveryInfo.h>
#include <fastdds/rtps/writer/WriterDiscoveryInfo.h>

#include "concert/dds/endpoint.hpp"
#include "peer_common.hpp"

namespace idl = concert::idl;
namespace contract = concert::contract;
using namespace std::chrono_literals;

namespace {

/// The generated type, noting the representation of the last payload it decoded.
template <class T> class Recording : public concert::dds::PubSubOf<T>::type {
 public:
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    wire = idl::representation({payload->data, payload->length});
    return concert::dds::PubSubOf<T>::type::deserialize(payload, data);
  }
  std::string wire;
};

template <class T> std::vector<uint8_t> serialize(const T& sample) {
  typename concert::dds::PubSubOf<T>::type pubsub;
  auto* data = const_cast<T*>(&sample);
  eprosima::fastrtps::rtps::SerializedPayload_t payload(pubsub.getSerializedSizeProvider(data)());
  if (!pubsub.serialize(data, &payload)) throw std::runtime_error("Fast DDS could not serialize a sample");
  return {payload.data, payload.data + payload.length};
}

template <class T> T deserialize(const std::vector<uint8_t>& bytes) {
  typename concert::dds::PubSubOf<T>::type pubsub;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(bytes.size()));
  std::memcpy(payload.data, bytes.data(), bytes.size());
  payload.length = static_cast<uint32_t>(bytes.size());
  T sample;
  if (!pubsub.deserialize(&payload, &sample)) throw std::runtime_error("Fast DDS could not decode the sample bytes");
  return sample;
}

idl::Json local_qos(const eprosima::fastdds::dds::DataWriterQos& q) {
  return contract::qos_json(q.reliability().kind == eprosima::fastdds::dds::RELIABLE_RELIABILITY_QOS,
                            q.durability().kind == eprosima::fastdds::dds::TRANSIENT_LOCAL_DURABILITY_QOS,
                            q.history().depth);
}
idl::Json local_qos(const eprosima::fastdds::dds::DataReaderQos& q) {
  return contract::qos_json(q.reliability().kind == eprosima::fastdds::dds::RELIABLE_RELIABILITY_QOS,
                            q.durability().kind == eprosima::fastdds::dds::TRANSIENT_LOCAL_DURABILITY_QOS,
                            q.history().depth);
}

/// The QoS of remote endpoints as their discovery data (SEDP) announced them on the wire, per
/// topic: what this peer checks of the other side, whichever vendor wrote it. History depth is
/// not part of the announcement (-1).
/// Fast DDS also reports the participant's own endpoints through these callbacks: only those
/// of other participants are recorded, writers and readers apart.
class WireQos : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  enum class Side { kWriters, kReaders };

  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override {
    if (info.status != eprosima::fastrtps::rtps::WriterDiscoveryInfo::DISCOVERED_WRITER) return;
    if (info.info.guid().guidPrefix == participant->guid().guidPrefix) return;
    note(Side::kWriters, info.info.topicName().to_string(), info.info.m_qos.m_reliability.kind,
         info.info.m_qos.m_durability.kind);
  }
  void on_subscriber_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                               eprosima::fastrtps::rtps::ReaderDiscoveryInfo&& info) override {
    if (info.status != eprosima::fastrtps::rtps::ReaderDiscoveryInfo::DISCOVERED_READER) return;
    if (info.info.guid().guidPrefix == participant->guid().guidPrefix) return;
    note(Side::kReaders, info.info.topicName().to_string(), info.info.m_qos.m_reliability.kind,
         info.info.m_qos.m_durability.kind);
  }
  /// The announced QoS of a remote writer (or reader) of `topic`, waiting for its discovery
  /// until `deadline`.
  std::optional<idl::Json> of(Side side, const std::string& topic,
                              std::chrono::steady_clock::time_point deadline) {
    auto& seen = seen_[static_cast<int>(side)];
    std::unique_lock lock(mutex_);
    changed_.wait_until(lock, deadline, [&] { return seen.count(topic) > 0; });
    const auto it = seen.find(topic);
    if (it == seen.end()) return std::nullopt;
    return it->second;
  }

 private:
  void note(Side side, const std::string& topic, eprosima::fastdds::dds::ReliabilityQosPolicyKind reliability,
            eprosima::fastdds::dds::DurabilityQosPolicyKind durability) {
    {
      std::lock_guard lock(mutex_);
      seen_[static_cast<int>(side)][topic] =
          contract::qos_json(reliability == eprosima::fastdds::dds::RELIABLE_RELIABILITY_QOS,
                             durability == eprosima::fastdds::dds::TRANSIENT_LOCAL_DURABILITY_QOS, -1);
    }
    changed_.notify_all();
  }
  std::mutex mutex_;
  std::condition_variable changed_;
  std::array<std::map<std::string, idl::Json>, 2> seen_;
};

struct Endpoint {
  concert::dds::TopicInfo info;
  std::shared_ptr<void> keep;
  std::function<std::optional<idl::Json>()> poll;  // read side: next received sample as event
  std::function<void()> write;                      // write side: write the expected sample
  bool done = false;
};

}  // namespace

int main(int argc, char** argv) try {
  const auto args = contract::parse_peer_args(argc, argv);
  WireQos wire_qos;
  concert::dds::Participant participant(
      {.name = args.write ? "contract_fast_writer" : "contract_fast_reader", .listener = &wire_qos});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(args.timeout_ms);
  const auto& schema = idl::Schema::builtin();
  std::vector<Endpoint> endpoints;

  for (const auto& info : args.topics) {
    concert::dds::for_each_topic([&]<class T>(concert::dds::TopicHandle<T> handle) {
      if (handle.name != info.name) return;
      Endpoint ep{info};
      if (args.write) {
        auto writer = std::make_shared<concert::dds::Writer<T>>(participant, handle);
        if (args.wait_readers && !writer->wait_for_readers(1, std::chrono::milliseconds(args.timeout_ms))) {
          throw std::runtime_error(std::string("no reader matched on ") + std::string(info.name));
        }
        auto make = [&](uint32_t seed) {
          return deserialize<T>(idl::encode(schema, info.type_name, contract::expected_sample(info, seed, args.full_images)));
        };
        if (args.stale_first) {
          writer->write(deserialize<T>(idl::encode(schema, info.type_name, contract::stale_sample(info, args.seed))));
        }
        const auto sample = make(args.seed);
        if (!writer->write(sample)) throw std::runtime_error("write failed on " + std::string(info.name));
        ep.write = [writer, sample] { writer->write(sample); };
        eprosima::fastdds::dds::DataWriterQos q;
        writer->get()->get_qos(q);
        idl::Json event = {{"event", "written"}, {"topic", info.name}, {"local_qos", local_qos(q)}};
        if (args.wait_readers) {
          if (auto remote = wire_qos.of(WireQos::Side::kReaders, std::string(info.name), deadline)) {
            event["remote_qos"] = *remote;
          }
        }
        contract::emit(event);
        ep.keep = writer;
      } else {
        // One Recording per type: topics of the same type (the camera images) share the type the
        // participant registered first, and that one decodes their samples.
        eprosima::fastdds::dds::TypeSupport type =
            participant.get()->find_type(typename concert::dds::PubSubOf<T>::type().getName());
        if (type.empty()) type = eprosima::fastdds::dds::TypeSupport(new Recording<T>());
        auto* recording = static_cast<Recording<T>*>(type.get());
        auto* reader = concert::dds::detail::create_reader(participant, handle.name, type, nullptr);
        ep.keep = std::shared_ptr<void>(reader, [&participant](void* r) {
          concert::dds::detail::delete_reader(participant, static_cast<eprosima::fastdds::dds::DataReader*>(r));
        });
        ep.poll = [reader, recording, info, &schema, &wire_qos, deadline]() -> std::optional<idl::Json> {
          T sample;
          eprosima::fastdds::dds::SampleInfo si;
          while (reader->take_next_sample(&sample, &si) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
            if (!si.valid_data) continue;
            eprosima::fastdds::dds::DataReaderQos q;
            reader->get_qos(q);
            idl::Json event{{"event", "received"}, {"topic", info.name},
                            {"sample", idl::decode(schema, info.type_name, serialize(sample))},
                            {"wire", recording->wire}, {"local_qos", local_qos(q)}};
            // A sample came, so its writer was discovered: its announcement is there or comes
            // with the same discovery round.
            if (auto remote = wire_qos.of(WireQos::Side::kWriters, std::string(info.name), deadline)) {
              event["remote_qos"] = *remote;
            }
            return event;
          }
          return std::nullopt;
        };
      }
      endpoints.push_back(std::move(ep));
    });
  }

  const auto start = std::chrono::steady_clock::now();
  if (args.write) {
    auto last = std::chrono::steady_clock::now();
    while (!contract::past(start, args.linger_ms)) {
      if (args.repeat_ms > 0 && contract::past(last, args.repeat_ms)) {
        for (auto& ep : endpoints) ep.write();
        last = std::chrono::steady_clock::now();
      }
      std::this_thread::sleep_for(10ms);
    }
    return 0;
  }
  size_t remaining = endpoints.size();
  while (remaining > 0 && !contract::past(start, args.timeout_ms)) {
    for (auto& ep : endpoints) {
      if (ep.done) continue;
      if (auto event = ep.poll()) {
        contract::emit(*event);
        ep.done = true;
        --remaining;
      }
    }
    std::this_thread::sleep_for(5ms);
  }
  return contract::report_missing(endpoints);
} catch (const std::exception& e) {
  std::cerr << "contract_peer_fast: " << e.what() << std::endl;
  return 2;
}
