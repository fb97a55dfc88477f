// The table of who may publish what, against the topic catalogue and the issue's rules, and the
// documents generated from it (parsed back with tinyxml2, an independent XML reader).
#include "concert/security/table.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <tinyxml2.h>

#include <algorithm>
#include <set>
#include <string>

#include "concert/dds/catalogue.hpp"
#include "concert/security/dds_config.hpp"
#include "concert/security/documents.hpp"

namespace concert::security {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::UnorderedElementsAre;
using ::testing::UnorderedElementsAreArray;

TEST(SecurityTable, NamesEveryCatalogueTopicOnceInCatalogueOrder) {
  const auto rules = write_rules();
  const auto topics = dds::catalogue();
  ASSERT_EQ(rules.size(), topics.size());
  for (size_t i = 0; i < topics.size(); ++i) {
    EXPECT_EQ(rules[i].topic, topics[i].name) << "row " << i;
    EXPECT_FALSE(rules[i].writers.empty()) << topics[i].name << " has no writer";
    EXPECT_FALSE(rules[i].why.empty()) << topics[i].name;
  }
}

TEST(SecurityTable, EveryWriterIsAnIdentityAndEveryIdentityWritesSomething) {
  std::set<std::string_view> writers;
  for (const auto& r : write_rules()) {
    for (const auto w : r.writers) {
      EXPECT_TRUE(is_identity(w)) << r.topic << ": " << w;
      writers.insert(w);
    }
  }
  EXPECT_EQ(writers.size(), identities().size());
  EXPECT_EQ(identities().back(), kOperator);
  EXPECT_FALSE(is_service_identity(kOperator));
  EXPECT_TRUE(is_service_identity("robot"));
  EXPECT_FALSE(is_identity("concert_plan"));
}

TEST(SecurityTable, FollowsTheIssuesRules) {
  // Only the robot service writes joint state; only the safety service writes safety state.
  EXPECT_THAT(writers_of("concert/robot/joint_state"), ElementsAre("robot"));
  EXPECT_THAT(writers_of("concert/safety/state"), ElementsAre("safety"));
  // Only operator tools write e-stop inputs and resets.
  EXPECT_THAT(writers_of("concert/safety/estop"), ElementsAre(kOperator));
  EXPECT_THAT(writers_of("concert/safety/reset"), ElementsAre(kOperator));
  // The planner and the task services write the robot's commands; no tool does.
  for (const char* command : {"concert/robot/joint_command", "concert/robot/cartesian_command",
                              "concert/robot/base_velocity", "concert/robot/trajectory_command"}) {
    EXPECT_THAT(writers_of(command), UnorderedElementsAre("planner", "nav", "drill", "collab", "surface_finish"))
        << command;
    EXPECT_FALSE(may_write(kOperator, command)) << command;
  }
  EXPECT_TRUE(may_write("planner", "concert/robot/joint_command"));
  EXPECT_FALSE(may_write("robot", "concert/robot/joint_command"));
  EXPECT_FALSE(may_write("planner", "concert/no/such/topic"));
  EXPECT_TRUE(writers_of("concert/no/such/topic").empty());
}

/// The text of every <topic> under `publish` (or subscribe) of a permissions document.
std::vector<std::string> rule_topics(const tinyxml2::XMLElement* allow, const char* kind) {
  std::vector<std::string> topics;
  const auto* rule = allow->FirstChildElement(kind);
  if (rule == nullptr) return topics;
  for (const auto* t = rule->FirstChildElement("topics")->FirstChildElement("topic"); t != nullptr;
       t = t->NextSiblingElement("topic")) {
    topics.emplace_back(t->GetText());
  }
  return topics;
}

TEST(SecurityDocuments, PermissionsGrantExactlyTheTableToTheSubject) {
  const auto t0 = std::chrono::system_clock::from_time_t(1'800'000'000);
  const Validity validity{t0, t0 + std::chrono::hours(24 * 365)};
  for (const auto id : identities()) {
    const std::string xml = permissions_xml(id, validity);
    tinyxml2::XMLDocument doc;
    ASSERT_EQ(doc.Parse(xml.c_str()), tinyxml2::XML_SUCCESS) << id << ": " << doc.ErrorStr();
    const auto* grant =
        doc.RootElement()->FirstChildElement("permissions")->FirstChildElement("grant");
    ASSERT_NE(grant, nullptr);
    EXPECT_EQ(grant->NextSiblingElement("grant"), nullptr) << "one grant per identity";
    EXPECT_EQ(std::string(grant->FirstChildElement("subject_name")->GetText()), subject_name(id));
    EXPECT_STREQ(grant->FirstChildElement("validity")->FirstChildElement("not_before")->GetText(),
                 "2027-01-15T08:00:00");
    EXPECT_STREQ(grant->FirstChildElement("validity")->FirstChildElement("not_after")->GetText(),
                 "2028-01-15T08:00:00");
    EXPECT_STREQ(grant->FirstChildElement("default")->GetText(), "DENY");
    const auto* allow = grant->FirstChildElement("allow_rule");
    ASSERT_NE(allow, nullptr);
    EXPECT_EQ(allow->NextSiblingElement(), grant->FirstChildElement("default")) << "one allow rule";
    const auto* range = allow->FirstChildElement("domains")->FirstChildElement("id_range");
    EXPECT_EQ(range->FirstChildElement("min")->IntText(-1), kFirstDomain);
    EXPECT_EQ(range->FirstChildElement("max")->IntText(-1), kLastDomain);
    const auto expected = topics_written_by(id);
    EXPECT_THAT(rule_topics(allow, "publish"),
                UnorderedElementsAreArray(expected.begin(), expected.end()))
        << id;
    EXPECT_THAT(rule_topics(allow, "subscribe"), ElementsAre("*")) << id;
  }
  EXPECT_EQ(subject_name("robot"), "CN=robot,O=CONCERT");
  EXPECT_THROW(permissions_xml("intruder", validity), std::invalid_argument);
}

TEST(SecurityDocuments, GovernanceProtectsDiscoveryLivelinessMessagesAndEveryTopic) {
  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.Parse(governance_xml().c_str()), tinyxml2::XML_SUCCESS) << doc.ErrorStr();
  const auto* rule =
      doc.RootElement()->FirstChildElement("domain_access_rules")->FirstChildElement("domain_rule");
  ASSERT_NE(rule, nullptr);
  const auto text = [](const tinyxml2::XMLElement* e, const char* name) {
    return std::string(e->FirstChildElement(name)->GetText());
  };
  EXPECT_EQ(text(rule, "allow_unauthenticated_participants"), "false");
  EXPECT_EQ(text(rule, "enable_join_access_control"), "true");
  EXPECT_EQ(text(rule, "discovery_protection_kind"), "ENCRYPT");
  EXPECT_EQ(text(rule, "liveliness_protection_kind"), "ENCRYPT");
  EXPECT_EQ(text(rule, "rtps_protection_kind"), "ENCRYPT");
  const auto* topic =
      rule->FirstChildElement("topic_access_rules")->FirstChildElement("topic_rule");
  EXPECT_EQ(text(topic, "topic_expression"), "*");
  for (const char* flag : {"enable_discovery_protection", "enable_liveliness_protection",
                           "enable_read_access_control", "enable_write_access_control"}) {
    EXPECT_EQ(text(topic, flag), "true") << flag;
  }
  EXPECT_EQ(text(topic, "metadata_protection_kind"), "NONE");
  EXPECT_EQ(text(topic, "data_protection_kind"), "NONE");
  const std::string signed_only =
      governance_xml({.metadata = Protection::kSign, .data = Protection::kSign});
  EXPECT_THAT(signed_only, HasSubstr("<data_protection_kind>SIGN</data_protection_kind>"));
  EXPECT_THAT(signed_only, HasSubstr("<metadata_protection_kind>SIGN</metadata_protection_kind>"));
}

/// Sets an environment variable for one test.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value == nullptr) {
      unsetenv(name);
    } else {
      setenv(name, value, 1);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(SecurityIdentity, ServicesByNameToolsAsOperatorUnlessTold) {
  {
    ScopedEnv unset("CONCERT_SECURITY_IDENTITY", nullptr);
    EXPECT_EQ(resolve_identity("", "robot"), "robot");
    EXPECT_EQ(resolve_identity("", "concert-safety-cli"), "operator");
    EXPECT_EQ(resolve_identity("planner", "concert-safety-cli"), "planner");
    EXPECT_THROW(resolve_identity("root", "x"), std::invalid_argument);
  }
  {
    ScopedEnv set("CONCERT_SECURITY_IDENTITY", "drill");
    EXPECT_EQ(resolve_identity("", "concert_plan"), "drill");
    // A service keeps its own identity whatever its environment says (concert up passes the
    // tool's environment on to the services it starts).
    EXPECT_EQ(resolve_identity("", "safety"), "safety");
  }
  {
    ScopedEnv bad("CONCERT_SECURITY_IDENTITY", "root");
    try {
      resolve_identity("", "concert_plan");
      ADD_FAILURE() << "no exception";
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(),
                  HasSubstr("CONCERT_SECURITY_IDENTITY: 'root' is not an identity (one of robot"));
    }
  }
  ScopedEnv off("CONCERT_SECURITY", "");
  EXPECT_FALSE(pki_from_environment());
  ScopedEnv on("CONCERT_SECURITY", "/etc/concert/pki");
  EXPECT_EQ(pki_from_environment(), std::filesystem::path("/etc/concert/pki"));
}

TEST(SecurityIdentity, VendorSettingsNameTheIdentitysFilesByAbsolutePath) {
  const IdentityFiles f = identity_files("/pki", "nav");
  EXPECT_EQ(f.certificate, "/pki/nav/cert.pem");
  EXPECT_EQ(f.permissions, "/pki/nav/permissions.p7s");
  const auto props = fastdds_properties(f);
  const auto find = [&props](const std::string& name) {
    for (const auto& [k, v] : props) {
      if (k == name) return v;
    }
    return std::string("<missing>");
  };
  EXPECT_EQ(find("dds.sec.auth.plugin"), "builtin.PKI-DH");
  EXPECT_EQ(find("dds.sec.access.plugin"), "builtin.Access-Permissions");
  EXPECT_EQ(find("dds.sec.crypto.plugin"), "builtin.AES-GCM-GMAC");
  EXPECT_EQ(find("dds.sec.auth.builtin.PKI-DH.private_key"), "file:///pki/nav/key.pem");
  EXPECT_EQ(find("dds.sec.access.builtin.Access-Permissions.governance"),
            "file:///pki/governance.p7s");
  const std::string cyclone = cyclone_security_config(identity_files("rel", "nav"), "/plugins");
  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.Parse(cyclone.c_str()), tinyxml2::XML_SUCCESS) << cyclone;
  const auto* sec = doc.RootElement()->FirstChildElement("Domain")->FirstChildElement("Security");
  const auto* auth = sec->FirstChildElement("Authentication");
  EXPECT_STREQ(auth->FirstChildElement("Library")->Attribute("path"),
               "/plugins/libdds_security_auth.so");
  const std::string cert = auth->FirstChildElement("IdentityCertificate")->GetText();
  EXPECT_EQ(cert, "file:" + (std::filesystem::current_path() / "rel/nav/cert.pem").string());
}

}  // namespace
}  // namespace concert::security
