#pragma once
// A reader of any topic that hands over each sample's serialized bytes with its SampleInfo:
// `concert topic echo|hz`, `concert bag record` and the GUI gateway subscribe through it.

#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "concert/dds/participant.hpp"

namespace concert::dds {

/// How to subscribe to a topic: its type and the QoS that matches its writers.
struct Resolved {
  std::string type;
  bool keyed = false;
  bool reliable = false;
  bool transient_local = false;
  bool ours = false;  ///< a catalogue topic
};

/// The subscription of a catalogue topic (its type and its class's QoS); nullopt for others.
std::optional<Resolved> from_catalogue(const std::string& topic);

class RawSubscription : public eprosima::fastdds::dds::DataReaderListener {
 public:
  /// Each valid sample: its bytes (the callee may take them) and its SampleInfo.
  using Callback = std::function<void(std::vector<uint8_t>& bytes,
                                      const eprosima::fastdds::dds::SampleInfo& info)>;
  /// The number of writers matched, each time it changes.
  using Matched = std::function<void(int32_t writers)>;

  /// Reliable and transient-local as `r` says (a transient-local reader gets the latched samples
  /// at once), keeping up to 1000 samples per instance until the listener takes them.
  /// Throws std::runtime_error naming the topic when the reader cannot be made.
  RawSubscription(Participant& participant, const std::string& topic, const Resolved& r,
                  Callback cb, Matched matched = {});
  ~RawSubscription() override;
  RawSubscription(const RawSubscription&) = delete;
  RawSubscription& operator=(const RawSubscription&) = delete;

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
  void on_subscription_matched(
      eprosima::fastdds::dds::DataReader* reader,
      const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) override;

 private:
  Participant& participant_;
  Callback callback_;
  Matched matched_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
};

}  // namespace concert::dds
