#pragma once
// A Fast DDS type that carries serialized samples as bytes, for tools that handle any topic
// (concert topic echo/hz): it matches writers of any type name, ours or not.

#include <cstdint>
#include <string>
#include <vector>

#include <fastdds/dds/topic/TopicDataType.hpp>

namespace concert::dds {

/// A sample as serialized bytes, encapsulation header included.
struct RawSample {
  std::vector<uint8_t> bytes;
};

class RawPubSubType : public eprosima::fastdds::dds::TopicDataType {
 public:
  /// `keyed` must match the writers' topic kind, or Fast DDS does not match them.
  RawPubSubType(const std::string& type_name, bool keyed);

  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override;
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override;
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override;
  void* createData() override;
  void deleteData(void* data) override;
  /// Without the type's key layout, each sample is its own instance (MD5 of its bytes).
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle, bool force_md5) override;
};

}  // namespace concert::dds
