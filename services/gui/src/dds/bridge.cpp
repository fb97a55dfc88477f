#include "dds/bridge.hpp"

#include <chrono>
#include <cstdio>

#include "concert/dds/catalogue.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/raw_type.hpp"
#include "concert/dds/topics.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"
#include "gui/protocol.hpp"

namespace concert::gui::dds {

using concert::dds::QosClass;
namespace fdds = eprosima::fastdds::dds;

namespace {

int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

TopicKind kind_of(QosClass qos) {
  switch (qos) {
    case QosClass::kLatched: return TopicKind::kState;
    case QosClass::kStream: return TopicKind::kStream;
    case QosClass::kLargeStream: return TopicKind::kImage;
    case QosClass::kCommand: return TopicKind::kCommand;
  }
  return TopicKind::kCommand;
}

/// The DDS instance a sample belongs to, as the browser sees it: "" for an unkeyed type.
std::string instance_of(const fdds::SampleInfo& info, bool keyed) {
  if (!keyed) return "";
  std::string out;
  char hex[3];
  for (size_t i = 0; i < 16; ++i) {
    std::snprintf(hex, sizeof hex, "%02x", static_cast<unsigned>(info.instance_handle.value[i]));
    out += hex;
  }
  return out;
}

}  // namespace

std::vector<TopicEntry> catalogue_topics() {
  std::vector<TopicEntry> out;
  for (const auto& t : concert::dds::catalogue()) {
    out.push_back({std::string(t.name), std::string(t.type_name), kind_of(t.qos), std::string(t.description)});
  }
  return out;
}

/// A camera topic's typed reader: the image bytes go to the JPEG encoder, not through JSON.
struct Bridge::Images {
  concert::dds::Reader<msg::Image> reader;
  Images(concert::dds::Participant& p, concert::dds::TopicHandle<msg::Image> topic,
         concert::dds::Reader<msg::Image>::Callback cb)
      : reader(p, topic, std::move(cb)) {}
};

Bridge::Bridge(concert::dds::Participant& participant, Hub& hub, JpegParams jpeg, std::ostream& log)
    : participant_(participant), hub_(hub), jpeg_(jpeg), log_(log) {
  const auto& schema = idl::Schema::builtin();
  for (const auto& t : concert::dds::catalogue()) {
    // Camera images (0.9 MB each) and command topics are subscribed only while a browser wants
    // them (set_wanted). A reader on a command topic would change what its writers see: a tool
    // that waits for "a reader" before writing a volatile command (`concert sim swap`) could
    // write before the service's reader matched, and the command would be lost.
    if (t.qos == QosClass::kLargeStream || t.qos == QosClass::kCommand) continue;
    subscriptions_.push_back(raw_subscription(std::string(t.name)));
  }
  for (const auto& c : operator_commands()) {
    const auto info = concert::dds::find_topic(c.topic);
    if (!info) {
      log_ << "concert_gui: allow-listed topic " << c.topic << " is not in this build's catalogue" << std::endl;
      continue;
    }
    const std::string topic(c.topic);
    const std::string type(info->type_name);
    auto* t = participant.topic(topic, fdds::TypeSupport(new concert::dds::RawPubSubType(type, schema.at(type).keyed())));
    auto* writer = participant.publisher()->create_datawriter(t, concert::dds::raw_writer_qos(info->qos));
    if (writer == nullptr) {
      throw std::runtime_error("cannot create a writer on '" + topic + "'" +
                               concert::dds::why_refused(participant, topic, true));
    }
    writers_[topic] = writer;
  }
}

std::unique_ptr<concert::dds::RawSubscription> Bridge::raw_subscription(const std::string& topic) {
  const auto& schema = idl::Schema::builtin();
  const auto resolved = concert::dds::from_catalogue(topic);
  const std::string type = resolved->type;
  const bool keyed = resolved->keyed;
  return std::make_unique<concert::dds::RawSubscription>(
      participant_, topic, *resolved,
      [this, topic, type, keyed, &schema](std::vector<uint8_t>& bytes, const fdds::SampleInfo& info) {
        hub_.on_sample(topic, instance_of(info, keyed),
                       [&] { return idl::decode(schema, type, std::span<const uint8_t>(bytes)); }, steady_ns());
      });
}

Bridge::~Bridge() {
  {
    std::lock_guard lock(images_mutex_);
    images_.clear();
    commands_.clear();
  }
  subscriptions_.clear();
  for (auto& [topic, writer] : writers_) participant_.publisher()->delete_datawriter(writer);
}

void Bridge::publish(const std::string& topic, const Json& sample) {
  const auto it = writers_.find(topic);
  if (it == writers_.end()) throw std::runtime_error("no writer for '" + topic + "'");
  const auto& schema = idl::Schema::builtin();
  const std::string type(concert::dds::find_topic(topic)->type_name);
  idl::Json complete;
  concert::dds::RawSample raw;
  try {
    // Fields left out get their defaults; an unknown field or a wrong type is refused by name.
    complete = idl::complete(schema, type, idl::Json::parse(sample.dump()));
    raw.bytes = idl::encode(schema, type, complete);
    raw.key = idl::key_hash(schema, type, complete);
  } catch (const std::exception& e) {
    throw std::runtime_error(type + ": " + e.what());
  }
  if (!it->second->write(&raw)) throw std::runtime_error("DDS write on '" + topic + "' failed");
}

void Bridge::set_wanted(const std::string& topic, bool wanted) {
  const auto info = concert::dds::find_topic(topic);
  if (!info) return;
  std::lock_guard lock(images_mutex_);
  if (info->qos == QosClass::kCommand) {
    if (!wanted) {
      commands_.erase(topic);
    } else if (commands_.count(topic) == 0) {
      commands_[topic] = raw_subscription(topic);
    }
    return;
  }
  if (info->qos != QosClass::kLargeStream) return;
  if (!wanted) {
    images_.erase(topic);
    return;
  }
  if (images_.count(topic) > 0) return;
  auto cb = [this, topic](const msg::Image& image, const fdds::SampleInfo& sample_info) {
    hub_.on_frame(
        topic, instance_of(sample_info, true),
        [&]() -> std::optional<std::string> {
          ImageView view{image.encoding(), image.width(), image.height(), image.step(), image.depth_scale(),
                         image.data().data(), image.data().size()};
          std::string error;
          auto jpeg = encode_jpeg(view, jpeg_, error);
          if (!jpeg) {
            log_ << "concert_gui: " << topic << " " << image.sensor() << ": " << error << std::endl;
            return std::nullopt;
          }
          const Json header = {{"op", "frame"},        {"topic", topic},
                               {"sensor", image.sensor()}, {"width", image.width()},
                               {"height", image.height()}, {"encoding", image.encoding()},
                               {"stamp_ns", image.stamp_ns()}, {"format", "jpeg"}};
          return frame_message(header, *jpeg);
        },
        steady_ns());
  };
  images_[topic] = std::make_unique<Images>(participant_, concert::dds::TopicHandle<msg::Image>{topic.c_str()}, cb);
}

}  // namespace concert::gui::dds
