#pragma once
// Schema-driven XCDR1 (plain CDR) encoding and decoding of samples as JSON. The bytes include
// the 4-byte encapsulation header, exactly as they travel in a DDS DATA submessage.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "concert/idl_schema/schema.hpp"

namespace concert::idl {
/// Samples as JSON objects whose keys keep the IDL field order.
using Json = nlohmann::ordered_json;
}  // namespace concert::idl

namespace concert::idl {

/// Raised for bytes that do not decode as the type, or JSON that does not fit it; the message
/// names the field path (e.g. "slaves[3].mod_id") and what is wrong.
class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Encodes a JSON object of the struct type as little-endian XCDR1 with encapsulation header.
/// Enums may be given by enumerator name or value. Every field must be present.
std::vector<uint8_t> encode(const Schema& schema, std::string_view type, const Json& value);

/// Data representation named by a payload's encapsulation header, e.g. "XCDR1 little-endian".
std::string representation(std::span<const uint8_t> bytes);

/// Decodes XCDR1 bytes (with encapsulation header, either endianness) into a JSON object with
/// field names; enums become enumerator names. Trailing bytes beyond padding are an error.
Json decode(const Schema& schema, std::string_view type, std::span<const uint8_t> bytes);

/// `partial` (a JSON object of the struct type, possibly with fields left out) completed with
/// the default value of every missing field, recursively: 0, false, "", empty sequences,
/// arrays of defaults, the first enumerator. Throws CdrError naming the field path of a field
/// the type does not have (and listing those it has) or of an object where none fits.
Json complete(const Schema& schema, std::string_view type, const Json& partial);

/// The DDS key hash of a sample of a keyed type, as Fast DDS and Cyclone compute it: the key
/// fields serialized as big-endian CDR, zero-padded to 16 bytes. nullopt for a type without
/// key, or one whose key can exceed 16 bytes (strings, sequences: the hash would be an MD5).
std::optional<std::array<uint8_t, 16>> key_hash(const Schema& schema, std::string_view type,
                                                const Json& sample);

/// key_hash() of a sample given as its CDR bytes (with encapsulation header): only the fields up
/// to the last key field are decoded. Throws CdrError when those do not decode.
std::optional<std::array<uint8_t, 16>> key_hash_of_cdr(const Schema& schema, std::string_view type,
                                                       std::span<const uint8_t> bytes);

/// A sample with every field set to a non-default value derived from `seed`: non-empty
/// sequences and strings, every array element, non-zero numbers. Deterministic.
Json sample_with_every_field_set(const Schema& schema, std::string_view type, uint32_t seed);

}  // namespace concert::idl
