#include "graph.hpp"

#include <sstream>

namespace concert::tool {

using eprosima::fastrtps::rtps::ParticipantDiscoveryInfo;
using eprosima::fastrtps::rtps::ReaderDiscoveryInfo;
using eprosima::fastrtps::rtps::WriterDiscoveryInfo;

namespace {
template <class T> std::string text(const T& v) {
  std::ostringstream out;
  out << v;
  return out.str();
}
}  // namespace

DomainGraph::DomainGraph(int32_t domain_id, const std::string& name) {
  participant_ = std::make_unique<dds::Participant>(
      dds::ParticipantOptions{.name = name, .domain_id = domain_id, .listener = this});
}

DomainGraph::~DomainGraph() { participant_.reset(); }

void DomainGraph::on_participant_discovery(eprosima::fastdds::dds::DomainParticipant*, ParticipantDiscoveryInfo&& info) {
  std::lock_guard lock(mutex_);
  participants_[text(info.info.m_guid.guidPrefix)] = info.info.m_participantName.to_string();
}

template <class ProxyData>
void DomainGraph::record(const ProxyData& data, bool writer, bool removed) {
  std::lock_guard lock(mutex_);
  const std::string guid = text(data.guid());
  if (removed) {
    endpoints_.erase(guid);
    return;
  }
  EndpointInfo e;
  e.writer = writer;
  e.topic = data.topicName().to_string();
  e.type = data.typeName().to_string();
  e.participant = participants_[text(data.guid().guidPrefix)];
  e.reliable = data.m_qos.m_reliability.kind == eprosima::fastdds::dds::RELIABLE_RELIABILITY_QOS;
  e.transient_local = data.m_qos.m_durability.kind != eprosima::fastdds::dds::VOLATILE_DURABILITY_QOS;
  e.keyed = data.topicKind() == eprosima::fastrtps::rtps::WITH_KEY;
  endpoints_[guid] = e;
}

void DomainGraph::on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant*, WriterDiscoveryInfo&& info) {
  record(info.info, true,
         info.status == WriterDiscoveryInfo::REMOVED_WRITER);
}

void DomainGraph::on_subscriber_discovery(eprosima::fastdds::dds::DomainParticipant*, ReaderDiscoveryInfo&& info) {
  record(info.info, false,
         info.status == ReaderDiscoveryInfo::REMOVED_READER);
}

std::vector<EndpointInfo> DomainGraph::endpoints() const {
  std::lock_guard lock(mutex_);
  std::vector<EndpointInfo> out;
  for (const auto& [guid, e] : endpoints_) out.push_back(e);
  return out;
}

std::vector<EndpointInfo> DomainGraph::endpoints_of(const std::string& topic) const {
  std::vector<EndpointInfo> out;
  for (auto& e : endpoints()) {
    if (e.topic == topic) out.push_back(e);
  }
  return out;
}

}  // namespace concert::tool
