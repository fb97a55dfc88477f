// The JSON codec of `concert topic pub` (libs/idl_schema): a sample given as JSON for a topic
// of the catalogue, completed with defaults, encoded as CDR, with its instance key. Documented
// failures: the JSON parser's exceptions (not JSON, a number out of range) and CdrError (both
// reported as a wrong command line); none may come from completing, encoding or the key.
// Properties: what pub would send decodes as `concert topic echo` decodes it, re-encodes to the
// same bytes, and keeps its key hash.
//
// Input: a topic name (e.g. concert/safety/estop), a newline, the JSON text. Seeds: for every
// topic of the catalogue, its type's sample with every field set, its default sample and `{}`.
#include <algorithm>

#include "concert/dds/catalogue.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"
#include "fuzz.hpp"

using namespace concert;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string_view> parts = fuzz::split(fuzz::text_of(data, size), '\n', 2);
  if (parts.size() != 2) return 0;
  const auto topic = dds::find_topic(parts[0]);
  if (!topic) return 0;  // pub refuses topics outside the catalogue
  const idl::Schema& schema = idl::Schema::builtin();
  const std::string type(topic->type_name);
  idl::Json sample;
  std::vector<uint8_t> bytes;
  std::optional<std::array<uint8_t, 16>> key;
  idl::Json given;
  try {
    given = idl::Json::parse(parts[1]);
  } catch (const idl::Json::exception&) {  // pub: "JSON: ...", a wrong command line
    return 0;
  }
  try {
    sample = idl::complete(schema, type, given);
    bytes = idl::encode(schema, type, sample);
    key = idl::key_hash(schema, type, sample);
  } catch (const idl::CdrError&) {
    return 0;
  }
  idl::Json echoed;
  try {
    echoed = idl::decode(schema, type, bytes);
  } catch (const idl::CdrError& e) {
    CONCERT_FUZZ_CHECK(false, std::string("pub would send a sample echo cannot decode: ") +
                                  e.what() + "\n" + sample.dump());
  }
  const std::string text = echoed.dump();
  CONCERT_FUZZ_CHECK(idl::encode(schema, type, echoed) == bytes,
                     "the decoded sample re-encodes differently: " + text);
  CONCERT_FUZZ_CHECK(idl::key_hash(schema, type, echoed) == key,
                     "the decoded sample has another key hash: " + text);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  const idl::Schema& schema = idl::Schema::builtin();
  for (const dds::TopicInfo& t : dds::catalogue()) {
    const std::string type(t.type_name);
    if (schema.find_struct(type) == nullptr) continue;
    std::string name(t.name);
    std::replace(name.begin(), name.end(), '/', '_');
    const std::string head = std::string(t.name) + "\n";
    seeds.add(name + "_full", head + idl::sample_with_every_field_set(schema, type, 1).dump());
    seeds.add(name + "_default", head + idl::complete(schema, type, idl::Json::object()).dump());
    seeds.add(name + "_empty", head + "{}");
    seeds.add_tokens({head});
  }
  seeds.add_tokens(kJsonTokens);
}
