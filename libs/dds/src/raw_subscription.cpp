#include "concert/dds/raw_subscription.hpp"

#include <stdexcept>

#include "concert/dds/catalogue.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/idl_schema/schema.hpp"

namespace concert::dds {

using namespace eprosima::fastdds::dds;

std::optional<Resolved> from_catalogue(const std::string& topic) {
  const auto info = find_topic(topic);
  if (!info) return std::nullopt;
  const auto spec = qos_spec(info->qos);
  Resolved r;
  r.type = info->type_name;
  r.keyed = idl::Schema::builtin().at(info->type_name).keyed();
  r.reliable = spec.reliable;
  r.transient_local = spec.transient_local;
  r.ours = true;
  return r;
}

RawSubscription::RawSubscription(Participant& participant, const std::string& topic,
                                 const Resolved& r, Callback cb, Matched matched)
    : participant_(participant), callback_(std::move(cb)), matched_(std::move(matched)) {
  auto* t = participant.topic(topic, TypeSupport(new RawPubSubType(r.type, r.keyed)));
  auto qos = raw_reader_qos(r.reliable ? QosClass::kCommand : QosClass::kStream);
  qos.durability().kind =
      r.transient_local ? TRANSIENT_LOCAL_DURABILITY_QOS : VOLATILE_DURABILITY_QOS;
  qos.history().depth = 1000;
  reader_ = participant.subscriber()->create_datareader(
      t, qos, this, StatusMask::data_available() << StatusMask::subscription_matched());
  if (reader_ == nullptr) throw std::runtime_error("cannot subscribe to '" + topic + "'");
}

RawSubscription::~RawSubscription() {
  reader_->set_listener(nullptr);
  participant_.subscriber()->delete_datareader(reader_);
}

void RawSubscription::on_data_available(DataReader* reader) {
  RawSample sample;
  SampleInfo info;
  while (reader->take_next_sample(&sample, &info) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) callback_(sample.bytes, info);
  }
}

void RawSubscription::on_subscription_matched(DataReader*,
                                              const SubscriptionMatchedStatus& status) {
  if (matched_) matched_(status.current_count);
}

}  // namespace concert::dds
