#include "concert/dds/endpoint.hpp"

#include <stdexcept>
#include <thread>

#include "concert/common/text.hpp"
#include "concert/dds/qos.hpp"
#include "concert/security/table.hpp"

namespace concert::dds::detail {

using namespace eprosima::fastdds::dds;

namespace {
TopicInfo checked(std::string_view name, const TypeSupport& type) {
  const auto info = find_topic(name);
  if (!info) throw std::invalid_argument("topic '" + std::string(name) + "' is not in the topic catalogue");
  if (info->type_name != type.get_type_name()) {
    throw std::invalid_argument("topic '" + std::string(name) + "' carries '" + std::string(info->type_name) +
                                "' in the catalogue, not '" + type.get_type_name() + "'");
  }
  return *info;
}
}  // namespace

void MatchTracker::on_publication_matched(DataWriter* /*writer*/, const PublicationMatchedStatus& status) {
  eprosima::fastrtps::rtps::GUID_t guid;
  eprosima::fastrtps::rtps::iHandle2GUID(guid, status.last_subscription_handle);
  std::lock_guard lock(mutex_);
  if (status.current_count_change > 0) {
    readers_.insert(guid);
  } else if (status.current_count_change < 0) {
    readers_.erase(guid);
  }
}

bool MatchTracker::matched_participant(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) const {
  std::lock_guard lock(mutex_);
  return std::any_of(readers_.begin(), readers_.end(), [&](const auto& g) { return g.guidPrefix == prefix; });
}

DataWriter* create_writer(Participant& participant, std::string_view name, TypeSupport type, MatchTracker* tracker) {
  const TopicInfo info = checked(name, type);
  Topic* topic = participant.topic(std::string(name), type);
  DataWriter* writer = participant.publisher()->create_datawriter(
      topic, writer_qos(info.qos), tracker, tracker != nullptr ? StatusMask::publication_matched() : StatusMask::none());
  if (writer == nullptr) {
    throw std::runtime_error("cannot create a DDS writer on '" + std::string(name) + "'" +
                             why_refused(participant, name, true));
  }
  return writer;
}

DataReader* create_reader(Participant& participant, std::string_view name, TypeSupport type,
                          DataReaderListener* listener) {
  const TopicInfo info = checked(name, type);
  Topic* topic = participant.topic(std::string(name), type);
  DataReader* reader = participant.subscriber()->create_datareader(
      topic, reader_qos(info.qos), listener, listener ? StatusMask::data_available() : StatusMask::none());
  if (reader == nullptr) {
    throw std::runtime_error("cannot create a DDS reader on '" + std::string(name) + "'" +
                             why_refused(participant, name, false));
  }
  return reader;
}

void delete_writer(Participant& participant, DataWriter* writer) {
  if (writer != nullptr) participant.publisher()->delete_datawriter(writer);
}

void delete_reader(Participant& participant, DataReader* reader) {
  if (reader != nullptr) {
    reader->set_listener(nullptr);
    participant.subscriber()->delete_datareader(reader);
  }
}

int32_t matched_count(DataWriter* writer) {
  PublicationMatchedStatus status;
  writer->get_publication_matched_status(status);
  return status.current_count;
}

int32_t matched_count(DataReader* reader) {
  SubscriptionMatchedStatus status;
  reader->get_subscription_matched_status(status);
  return status.current_count;
}

bool wait_until(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace concert::dds::detail

namespace concert::dds {

std::string why_refused(const Participant& participant, std::string_view topic, bool writer) {
  if (participant.security_identity().empty()) return "";
  const std::string& id = participant.security_identity();
  const std::string where = "CONCERT_SECURITY=" + participant.security_dir();
  if (!writer) return " (" + where + ": the permissions of '" + id + "' do not allow reading it)";
  const auto writers = security::writers_of(topic);
  if (!security::may_write(id, topic)) {
    return ": identity '" + id + "' may not publish it (" +
           (writers.empty() ? std::string("nobody may") : "only " + join(writers, ", ") + " may") +
           "; " + where + ")";
  }
  return ": the permissions in " + participant.security_dir() + " do not let '" + id +
         "' publish it, though this build's table does (made before the topic was added? `concert "
         "security init " + participant.security_dir() + " --force` makes them again)";
}

}  // namespace concert::dds
