#include "concert/dds/catalogue.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <set>

#include "concert/dds/json.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/topics.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/idl_schema/schema.hpp"

namespace concert::dds {
namespace {

template <class T> std::pair<std::string, std::string> bound(TopicHandle<T> h) {
  typename PubSubOf<T>::type pubsub;
  return {std::string(h.name), pubsub.getName()};
}

TEST(Json, ATypedSampleReadsAsTheIdlSaysWithEnumsByName) {
  msg::ServiceStatus st;
  st.id(7);
  st.service("planner");
  st.state(msg::SERVICE_READY);
  st.model_version(3);
  st.model_hash("abc");
  st.message("ready");
  const idl::Json j = to_json(st);
  EXPECT_EQ(j.at("service"), "planner");
  EXPECT_EQ(j.at("state"), "SERVICE_READY");
  EXPECT_EQ(j.at("model_version"), 3);
  EXPECT_EQ(j.at("model_hash"), "abc");
  EXPECT_EQ(j.size(), 9u);  // every field of ServiceStatus, in IDL order
  EXPECT_EQ(j.begin().key(), "id");
}

TEST(Catalogue, EveryTopicHasATypedHandleWithTheSameType) {
  std::vector<std::pair<std::string, std::string>> handles;
  for_each_topic([&](auto handle) { handles.push_back(bound(handle)); });
  ASSERT_EQ(handles.size(), catalogue().size());
  for (const auto& [name, type] : handles) {
    const auto info = find_topic(name);
    ASSERT_TRUE(info.has_value()) << name;
    EXPECT_EQ(info->type_name, type) << name;
  }
}

TEST(Catalogue, NamesAreUniqueAndTypesExistInTheIdl) {
  std::set<std::string_view> names;
  for (const auto& t : catalogue()) {
    EXPECT_TRUE(names.insert(t.name).second) << "duplicate topic " << t.name;
    EXPECT_NE(idl::Schema::builtin().find_struct(t.type_name), nullptr) << t.type_name;
    EXPECT_FALSE(t.description.empty());
  }
  EXPECT_FALSE(find_topic("concert/nope").has_value());
}

// Keys longer than 16 serialized bytes make Fast DDS and Cyclone disagree on the key hash,
// which breaks dispose across vendors.
TEST(Catalogue, KeysFitSixteenSerializedBytes) {
  const auto& schema = idl::Schema::builtin();
  for (const auto& t : catalogue()) {
    size_t size = 0;
    for (const auto& f : schema.at(t.type_name).fields) {
      if (!f.key) continue;
      switch (f.type.kind) {
        case idl::Kind::kInt32: case idl::Kind::kUInt32: case idl::Kind::kEnum: size = (size + 3) / 4 * 4 + 4; break;
        case idl::Kind::kOctet: case idl::Kind::kBool: size += 1; break;
        default: ADD_FAILURE() << t.type_name << "." << f.name << ": key field of variable or unchecked size";
      }
    }
    EXPECT_LE(size, 16u) << t.type_name;
  }
}

TEST(Catalogue, QosClasses) {
  EXPECT_TRUE(qos_spec(find_topic("concert/model/robot_model")->qos).transient_local);
  EXPECT_EQ(qos_spec(QosClass::kLatched).history_depth, 1);
  EXPECT_FALSE(qos_spec(find_topic("concert/robot/joint_state")->qos).reliable);
  EXPECT_EQ(qos_spec(find_topic("concert/robot/joint_state")->qos).history_depth, 1);
  // Camera images: a stream whose writers send from a Fast DDS thread.
  const QosSpec image = qos_spec(find_topic("concert/sensors/camera/rgb")->qos);
  EXPECT_FALSE(image.reliable);
  EXPECT_FALSE(image.transient_local);
  EXPECT_EQ(image.history_depth, 1);
  EXPECT_TRUE(image.asynchronous);
  EXPECT_EQ(writer_qos(QosClass::kLargeStream).publish_mode().kind, eprosima::fastdds::dds::ASYNCHRONOUS_PUBLISH_MODE);
  EXPECT_EQ(writer_qos(QosClass::kStream).publish_mode().kind, eprosima::fastdds::dds::SYNCHRONOUS_PUBLISH_MODE);
}

TEST(Catalogue, DomainIds) {
  EXPECT_EQ(parse_domain_id("0", "x"), 0);
  EXPECT_EQ(parse_domain_id("232", "x"), 232);
  for (const char* bad : {"", "-1", "233", "4a", "one"}) {
    try {
      parse_domain_id(bad, "--domain");
      ADD_FAILURE() << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("--domain"), std::string::npos);
    }
  }
}

TEST(Catalogue, ADomainWhosePortsLieInTheEphemeralRangeIsNamed) {
  // Linux's default range: domain 100 ends at port 32649, below it; 101 and 126 lie inside.
  EXPECT_EQ(domain_port_warning(0, 32768, 60999), "");
  EXPECT_EQ(domain_port_warning(100, 32768, 60999), "");
  EXPECT_EQ(domain_port_warning(232, 32768, 60999), "");  // from 65400: above it
  EXPECT_EQ(domain_port_warning(126, 32768, 60999),
            "concert dds: domain 126 uses UDP ports 38900-39149, inside this machine's ephemeral "
            "port range 32768-60999: another program's socket may take one of them, and a "
            "Cyclone DDS participant of another domain may then join this one; use a domain "
            "whose ports lie below that range (0 to 100 here) or reserve them (sysctl -w "
            "net.ipv4.ip_local_reserved_ports=38900-39149)");
  EXPECT_NE(domain_port_warning(101, 32768, 60999), "");  // 32650-32899 straddles 32768
  EXPECT_NE(domain_port_warning(0, 1024, 65535), "");     // a range that covers everything
}

TEST(Catalogue, StatusInstanceIdsAreStableAndDistinct) {
  EXPECT_EQ(status_instance_id("planner", "manip"), status_instance_id("planner", "manip"));
  std::set<uint32_t> ids;
  for (const char* s : {"robot", "safety", "discovery", "modelgen", "nav", "planner", "drill", "collab", "surface_finish"}) {
    for (const char* h : {"rt", "nav", "manip"}) EXPECT_TRUE(ids.insert(status_instance_id(s, h)).second);
  }
}

}  // namespace
}  // namespace concert::dds

namespace concert::dds {
namespace {

/// The key hash the schema-driven codec computes (for `concert topic pub`) is the one Fast DDS's
/// generated type computes, for every keyed catalogue type: samples written by the tool and by
/// the services land in the same instance.
TEST(KeyHash, SchemaCodecAgreesWithTheGeneratedTypes) {
  const auto& schema = idl::Schema::builtin();
  int keyed = 0;
  for_each_topic([&]<class T>(TopicHandle<T> handle) {
    const std::string type(find_topic(handle.name)->type_name);
    for (uint32_t seed : {1u, 7u, 1234u}) {
      const idl::Json sample = idl::sample_with_every_field_set(schema, type, seed);
      const auto hash = idl::key_hash(schema, type, sample);
      if (!schema.at(type).keyed()) {
        EXPECT_FALSE(hash.has_value()) << type;
        continue;
      }
      ASSERT_TRUE(hash.has_value()) << type;
      const std::vector<uint8_t> bytes = idl::encode(schema, type, sample);
      typename PubSubOf<T>::type pubsub;
      eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(bytes.size()));
      std::memcpy(payload.data, bytes.data(), bytes.size());
      payload.length = static_cast<uint32_t>(bytes.size());
      T typed;
      ASSERT_TRUE(pubsub.deserialize(&payload, &typed)) << type;
      eprosima::fastrtps::rtps::InstanceHandle_t handle_of_typed;
      ASSERT_TRUE(pubsub.getKey(&typed, &handle_of_typed, false)) << type;
      for (size_t i = 0; i < 16; ++i)
        EXPECT_EQ((*hash)[i], handle_of_typed.value[i]) << type << " byte " << i;
      ++keyed;
    }
  });
  EXPECT_GE(keyed, 3 * 3) << "ServiceStatus, EStopInput and PlanResult are keyed";
}

TEST(Complete, FillsDefaultsAndNamesUnknownFields) {
  const auto& schema = idl::Schema::builtin();
  const idl::Json full =
      idl::complete(schema, "concert::msg::EStopInput", idl::Json::parse(R"({"engaged": true})"));
  EXPECT_EQ(full.at("engaged"), true);
  EXPECT_EQ(full.at("reason"), "");
  EXPECT_NO_THROW(idl::encode(schema, "concert::msg::EStopInput", full));
  try {
    idl::complete(schema, "concert::msg::EStopInput", idl::Json::parse(R"({"engagd": true})"));
    FAIL() << "unknown field accepted";
  } catch (const idl::CdrError& e) {
    EXPECT_NE(
        std::string(e.what()).find("engagd: no such field in concert::msg::EStopInput (fields: "),
        std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace concert::dds
