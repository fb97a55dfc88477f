// The schema-driven CDR decoder of `concert topic echo` (libs/idl_schema decode): samples of
// any of the project's types as they arrive from the wire, from any writer. Documented failure:
// CdrError. Properties: a decoded sample re-encodes (encode) and decodes again to the same JSON;
// its key hash does not change on the way.
//
// Input: the IDL type name (e.g. concert::msg::EscScan), a newline, the serialized payload with
// its 4-byte encapsulation header. Seeds: every type's sample with every field set and its
// default sample (XCDR1 little-endian as Fast DDS writes them), and the full sample with a
// big-endian and an XCDR2 header.
#include <algorithm>

#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;

/// `bytes` with another encapsulation id in its header (the body stays little-endian XCDR1):
/// the decoder's big-endian and XCDR2 paths get inputs to mutate.
std::vector<uint8_t> with_header(std::vector<uint8_t> bytes, uint8_t id) {
  bytes[1] = id;
  return bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string_view> parts = fuzz::split(fuzz::text_of(data, size), '\n', 2);
  if (parts.size() != 2) return 0;
  const idl::Schema& schema = idl::Schema::builtin();
  const std::string type(parts[0]);
  if (schema.find_struct(type) == nullptr) return 0;  // echo refuses types not in the IDL
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(parts[1].data()),
                                       parts[1].size());
  idl::Json sample;
  try {
    sample = idl::decode(schema, type, bytes);
  } catch (const idl::CdrError&) {
    return 0;
  }
  const std::string text = sample.dump();
  std::vector<uint8_t> again;
  try {
    again = idl::encode(schema, type, sample);
  } catch (const idl::CdrError& e) {
    CONCERT_FUZZ_CHECK(false,
                       std::string("a decoded sample does not encode: ") + e.what() + "\n" + text);
  }
  idl::Json back;
  try {
    back = idl::decode(schema, type, again);
  } catch (const idl::CdrError& e) {
    CONCERT_FUZZ_CHECK(
        false, std::string("a re-encoded sample does not decode: ") + e.what() + "\n" + text);
  }
  CONCERT_FUZZ_CHECK(back.dump() == text,
                     "decode(encode(sample)) differs:\n" + text + "\n" + back.dump());
  CONCERT_FUZZ_CHECK(idl::key_hash(schema, type, sample) == idl::key_hash(schema, type, back),
                     "the key hash changed through encode/decode: " + text);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.words_from_seeds(false);  // binary payloads: only the type names are words
  const idl::Schema& schema = idl::Schema::builtin();
  for (const std::string& type : schema.struct_names()) {
    std::string name = type;
    std::replace(name.begin(), name.end(), ':', '_');
    const auto add = [&](const std::string& suffix, const std::vector<uint8_t>& bytes) {
      seeds.add(name + suffix, type + "\n" + std::string(bytes.begin(), bytes.end()));
    };
    const std::vector<uint8_t> full =
        idl::encode(schema, type, idl::sample_with_every_field_set(schema, type, 1));
    add("_full", full);
    add("_full_be_header", with_header(full, 0x00));
    add("_full_xcdr2_header", with_header(full, 0x07));
    add("_default", idl::encode(schema, type, idl::complete(schema, type, idl::Json::object())));
    seeds.add_tokens({type + "\n"});
  }
}
