#pragma once
// Fast DDS QoS of each catalogue class. The only place where QoS values are set.

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "concert/dds/catalogue.hpp"

namespace concert::dds {

/// Reliable writers announce heartbeats every 100 ms (Fast DDS's default of 3 s delays the
/// data a late-joining reader is owed by up to 3 s).
inline constexpr int32_t kHeartbeatPeriodMs = 100;

/// Instances of a keyed topic a writer keeps registered: the newest 64 (a late joiner gets their
/// last samples); older ones are unregistered. Readers and writers hold any number of instances
/// (Fast DDS's default of 10 refused the samples of an 11th request's instance).
inline constexpr std::size_t kLiveInstances = 64;

eprosima::fastdds::dds::DataWriterQos writer_qos(QosClass qos);
eprosima::fastdds::dds::DataReaderQos reader_qos(QosClass qos);

/// The same for endpoints of a raw type (RawPubSubType: any topic as serialized bytes), whose
/// sample memory is allocated at each sample's size and freed with the sample: preallocation
/// would size every sample at the raw type's 64 KB, 100 of them per topic.
eprosima::fastdds::dds::DataWriterQos raw_writer_qos(QosClass qos);
eprosima::fastdds::dds::DataReaderQos raw_reader_qos(QosClass qos);

}  // namespace concert::dds
