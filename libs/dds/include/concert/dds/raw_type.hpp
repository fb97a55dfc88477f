#pragma once
// A Fast DDS type that carries serialized samples as bytes, for tools that handle any topic
// (concert topic echo/hz): it matches writers of any type name, ours or not.

#include <array>
#include <cstdint>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <optional>
#include <string>
#include <vector>

namespace concert::dds {

/// A sample as serialized bytes, encapsulation header included.
struct RawSample {
  std::vector<uint8_t> bytes;
  /// For writing a keyed type: its key hash (idl::key_hash); unset: MD5 of the bytes.
  std::optional<std::array<uint8_t, 16>> key;
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
  /// The sample's `key` when set; else, for a type of our IDL (idl::Schema::builtin()), the key
  /// hash of its key fields as Fast DDS and Cyclone compute it. A reader computes it for every
  /// sample: Fast DDS writers send the key hash only to a reader that expects inline QoS, and
  /// Cyclone's do not match such a reader. Without the type's key layout (a type not ours, a
  /// sample that does not decode) each sample is its own instance: the MD5 of its bytes, held by
  /// the reader for as long as its writer lives.
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle, bool force_md5) override;

 private:
  bool key_layout_ = false;  // the builtin schema knows the type's key fields
};

}  // namespace concert::dds
