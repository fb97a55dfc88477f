#include "concert/dds/qos.hpp"

namespace concert::dds {

using namespace eprosima::fastdds::dds;

namespace {

/// The settings writers and readers share: reliability, durability and keep-last depth of the
/// class, with preallocated (growable) sample memory.
template <class EndpointQos>
EndpointQos endpoint_qos(EndpointQos q, const QosSpec& spec) {
  q.reliability().kind = spec.reliable ? RELIABLE_RELIABILITY_QOS : BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind =
      spec.transient_local ? TRANSIENT_LOCAL_DURABILITY_QOS : VOLATILE_DURABILITY_QOS;
  q.history().kind = KEEP_LAST_HISTORY_QOS;
  q.history().depth = spec.history_depth;
  // Keyed topics get an instance per request (plan results, trajectory statuses, nav goals,
  // drill missions): no bound on instances (<= 0: unlimited), and samples bounded by the
  // keep-last depth of each instance. Writers unregister their oldest instances (Writer).
  q.resource_limits().max_instances = 0;
  q.resource_limits().max_samples = 0;
  q.resource_limits().max_samples_per_instance = spec.history_depth;
  q.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  // No data sharing (Fast DDS's automatic shared-memory delivery of bounded types between
  // local processes): like the shared-memory transport (participant.cpp), it keeps state in
  // /dev/shm that a process killed with SIGKILL leaves behind; every sample goes through the
  // participant's transport.
  q.data_sharing().off();
  return q;
}

/// Memory of a raw type's samples: each payload allocated at its sample's size when written or
/// received, and freed when the history lets it go. Fast DDS's preallocation calloc's
/// allocated_samples (100) payloads of the type's maximum size per topic before anything is sent,
/// and keeps a payload that once held a large sample (a plan with its path) that large: the GUI
/// gateway's 37 raw endpoints held 167 MB before any sample arrived.
template <class EndpointQos>
EndpointQos raw_memory(EndpointQos q) {
  q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_RESERVE_MEMORY_MODE;
  q.resource_limits().allocated_samples = 1;
  return q;
}

}  // namespace

DataWriterQos writer_qos(QosClass qos) {
  DataWriterQos q = endpoint_qos(DATAWRITER_QOS_DEFAULT, qos_spec(qos));
  q.reliable_writer_qos().times.heartbeatPeriod =
      eprosima::fastrtps::Duration_t(0, kHeartbeatPeriodMs * 1'000'000u);
  // Keep-last never blocks, but bound the time a reliable write may wait for a slow reader.
  q.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(0, 1'000'000);
  if (qos_spec(qos).asynchronous) q.publish_mode().kind = ASYNCHRONOUS_PUBLISH_MODE;
  return q;
}

DataReaderQos reader_qos(QosClass qos) {
  return endpoint_qos(DATAREADER_QOS_DEFAULT, qos_spec(qos));
}

DataWriterQos raw_writer_qos(QosClass qos) { return raw_memory(writer_qos(qos)); }

DataReaderQos raw_reader_qos(QosClass qos) { return raw_memory(reader_qos(qos)); }

}  // namespace concert::dds
