#include <gtest/gtest.h>

#include <set>

#include "concert/dds/catalogue.hpp"
#include "concert/dds/topics.hpp"
#include "concert/idl_schema/schema.hpp"

namespace concert::dds {
namespace {

template <class T> std::pair<std::string, std::string> bound(TopicHandle<T> h) {
  typename PubSubOf<T>::type pubsub;
  return {std::string(h.name), pubsub.getName()};
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

TEST(Catalogue, StatusInstanceIdsAreStableAndDistinct) {
  EXPECT_EQ(status_instance_id("planner", "manip"), status_instance_id("planner", "manip"));
  std::set<uint32_t> ids;
  for (const char* s : {"robot", "safety", "discovery", "modelgen", "nav", "planner", "drill", "collab", "surface_finish"}) {
    for (const char* h : {"rt", "nav", "manip"}) EXPECT_TRUE(ids.insert(status_instance_id(s, h)).second);
  }
}

}  // namespace
}  // namespace concert::dds
