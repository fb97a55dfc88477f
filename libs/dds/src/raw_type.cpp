#include "concert/dds/raw_type.hpp"

#include <cstring>

#include <fastrtps/utils/md5.h>

#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"

namespace concert::dds {

RawPubSubType::RawPubSubType(const std::string& type_name, bool keyed) {
  setName(type_name.c_str());
  // The size Fast DDS preallocates sample buffers at (they grow for larger samples); raw_*_qos
  // endpoints allocate each sample at its own size instead.
  m_typeSize = 64 * 1024;
  m_isGetKeyDefined = keyed;
  const auto* def = idl::Schema::builtin().find_struct(type_name);
  key_layout_ = keyed && def != nullptr && def->keyed();
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
  if (key_layout_) {
    try {
      if (const auto key = idl::key_hash_of_cdr(idl::Schema::builtin(), getName(), bytes)) {
        for (size_t i = 0; i < 16; ++i) handle->value[i] = (*key)[i];
        return true;
      }
    } catch (const idl::CdrError&) {
      // Falls through: the bytes do not decode as the type, the sample gets an instance of its own.
    }
  }
  MD5 md5;
  md5.init();
  md5.update(bytes.data(), static_cast<unsigned int>(bytes.size()));
  md5.finalize();
  for (size_t i = 0; i < 16; ++i) handle->value[i] = md5.digest[i];
  return true;
}

}  // namespace concert::dds
