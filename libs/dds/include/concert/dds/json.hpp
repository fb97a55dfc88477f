#pragma once
// Any typed sample as JSON, through the schema-driven codec (libs/idl_schema): the field names
// of the IDL, enums by enumerator name. One rendering for every `--json` output of a message, so
// no verb writes a message's fields out by hand (and none forgets a field the IDL gains).

#include <span>
#include <stdexcept>
#include <string>

#include <fastdds/rtps/common/SerializedPayload.h>

#include "concert/dds/topics.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"

namespace concert::dds {

/// `sample` serialized as it travels (XCDR1), decoded with the built-in schema of the IDL.
/// Throws std::runtime_error if Fast DDS cannot serialize it, idl::CdrError if the schema and
/// the generated type disagree (a build error; the contract tests check they agree).
template <class T>
idl::Json to_json(const T& sample) {
  typename PubSubOf<T>::type type;
  T& data = const_cast<T&>(sample);  // Fast DDS's serialize takes void*; it does not write.
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&data)());
  if (!type.serialize(&data, &payload)) {
    throw std::runtime_error(std::string("cannot serialize a ") + type.getName() + " sample");
  }
  return idl::decode(idl::Schema::builtin(), type.getName(),
                     std::span<const uint8_t>(payload.data, payload.length));
}

}  // namespace concert::dds
