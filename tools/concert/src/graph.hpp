#pragma once
// What is on a DDS domain: every remote participant, writer and reader, ours or not, as Fast
// DDS discovery reports them.

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <fastdds/dds/domain/DomainParticipantListener.hpp>

#include "concert/dds/participant.hpp"

namespace concert::tool {

struct EndpointInfo {
  bool writer = false;
  std::string topic;
  std::string type;
  std::string participant;  ///< participant name, if announced
  bool reliable = false;
  bool transient_local = false;
  bool keyed = false;
};

class DomainGraph : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  /// Joins the domain (with the project's network settings) and starts listening.
  DomainGraph(int32_t domain_id, const std::string& name);
  ~DomainGraph() override;

  std::vector<EndpointInfo> endpoints() const;
  std::vector<EndpointInfo> endpoints_of(const std::string& topic) const;
  dds::Participant& participant() { return *participant_; }

  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override;
  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant*,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;
  void on_subscriber_discovery(eprosima::fastdds::dds::DomainParticipant*,
                               eprosima::fastrtps::rtps::ReaderDiscoveryInfo&& info) override;

 private:
  template <class ProxyData> void record(const ProxyData& data, bool writer, bool removed);

  mutable std::mutex mutex_;
  std::map<std::string, std::string> participants_;  // guid prefix -> name
  std::map<std::string, EndpointInfo> endpoints_;    // guid -> endpoint
  std::unique_ptr<dds::Participant> participant_;
};

}  // namespace concert::tool
