#include "concert/dds/raw_type.hpp"

#include <cstring>

#include <fastrtps/utils/md5.h>

namespace concert::dds {

RawPubSubType::RawPubSubType(const std::string& type_name, bool keyed) {
  setName(type_name.c_str());
  // Initial buffer size only: writers and readers reallocate for larger samples.
  m_typeSize = 64 * 1024;
  m_isGetKeyDefined = keyed;
}

bool RawPubSubType::serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) {
  const auto& bytes = static_cast<RawSample*>(data)->bytes;
  if (bytes.size() < 4 || bytes.size() > payload->max_size) return false;
  std::memcpy(payload->data, bytes.data(), bytes.size());
  payload->length = static_cast<uint32_t>(bytes.size());
  payload->encapsulation = bytes[1] & 1 ? CDR_LE : CDR_BE;
  return true;
}

bool RawPubSubType::deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) {
  auto& bytes = static_cast<RawSample*>(data)->bytes;
  bytes.assign(payload->data, payload->data + payload->length);
  return true;
}

std::function<uint32_t()> RawPubSubType::getSerializedSizeProvider(void* data) {
  return [data] { return static_cast<uint32_t>(static_cast<RawSample*>(data)->bytes.size()); };
}

void* RawPubSubType::createData() { return new RawSample(); }

void RawPubSubType::deleteData(void* data) { delete static_cast<RawSample*>(data); }

bool RawPubSubType::getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle, bool /*force_md5*/) {
  if (!m_isGetKeyDefined) return false;
  const auto& sample = *static_cast<RawSample*>(data);
  if (sample.key) {
    for (size_t i = 0; i < 16; ++i) handle->value[i] = (*sample.key)[i];
    return true;
  }
  const auto& bytes = sample.bytes;
  MD5 md5;
  md5.init();
  md5.update(bytes.data(), static_cast<unsigned int>(bytes.size()));
  md5.finalize();
  for (size_t i = 0; i < 16; ++i) handle->value[i] = md5.digest[i];
  return true;
}

}  // namespace concert::dds
