#pragma once
// The gateway's DDS adapter: every catalogue topic to the hub (samples as raw CDR, turned into
// JSON by the schema-driven codec of libs/idl_schema only when a browser gets them, so a new
// IDL type reaches the browser with no code here), camera images as JPEG frames and command
// topics (both subscribed only while a browser watches), and the operator commands the hub admitted, written as CDR
// encoded from their JSON with each topic's catalogue QoS.

#include <map>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <vector>

#include "concert/dds/participant.hpp"
#include "concert/dds/raw_subscription.hpp"
#include "gui/hub.hpp"
#include "gui/image.hpp"

namespace concert::gui::dds {

/// Every catalogue topic as the hub forwards it (kind from its QoS class).
std::vector<TopicEntry> catalogue_topics();

class Bridge : public Bus {
 public:
  /// Subscribes to every catalogue state and stream topic and makes a writer for every
  /// allow-listed topic. Throws std::runtime_error naming a topic it cannot subscribe to.
  Bridge(concert::dds::Participant& participant, Hub& hub, JpegParams jpeg, std::ostream& log);
  ~Bridge() override;

  void publish(const std::string& topic, const Json& sample) override;
  void set_wanted(const std::string& topic, bool wanted) override;

 private:
  struct Images;
  std::unique_ptr<concert::dds::RawSubscription> raw_subscription(const std::string& topic);
  concert::dds::Participant& participant_;
  Hub& hub_;
  JpegParams jpeg_;
  std::ostream& log_;
  std::vector<std::unique_ptr<concert::dds::RawSubscription>> subscriptions_;
  std::map<std::string, eprosima::fastdds::dds::DataWriter*> writers_;
  std::mutex images_mutex_;
  std::map<std::string, std::unique_ptr<Images>> images_;  // camera topic -> its reader
  std::map<std::string, std::unique_ptr<concert::dds::RawSubscription>> commands_;  // while watched
};

}  // namespace concert::gui::dds
