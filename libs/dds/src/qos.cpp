#include "concert/dds/qos.hpp"

namespace concert::dds {

using namespace eprosima::fastdds::dds;

DataWriterQos writer_qos(QosClass qos) {
  const QosSpec spec = qos_spec(qos);
  DataWriterQos q = DATAWRITER_QOS_DEFAULT;
  q.reliability().kind = spec.reliable ? RELIABLE_RELIABILITY_QOS : BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind = spec.transient_local ? TRANSIENT_LOCAL_DURABILITY_QOS : VOLATILE_DURABILITY_QOS;
  q.history().kind = KEEP_LAST_HISTORY_QOS;
  q.history().depth = spec.history_depth;
  q.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, kHeartbeatPeriodMs * 1'000'000u);
  // Keep-last never blocks, but bound the time a reliable write may wait for a slow reader.
  q.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(0, 1'000'000);
  q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return q;
}

DataReaderQos reader_qos(QosClass qos) {
  const QosSpec spec = qos_spec(qos);
  DataReaderQos q = DATAREADER_QOS_DEFAULT;
  q.reliability().kind = spec.reliable ? RELIABLE_RELIABILITY_QOS : BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind = spec.transient_local ? TRANSIENT_LOCAL_DURABILITY_QOS : VOLATILE_DURABILITY_QOS;
  q.history().kind = KEEP_LAST_HISTORY_QOS;
  q.history().depth = spec.history_depth;
  q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return q;
}

}  // namespace concert::dds
