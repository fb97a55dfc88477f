// The modelgen node over real DDS (private domain): tree in -> latched GeneratedModel out, same
// tree -> no new version, bad tree -> model kept, customisation -> new version, late joiners.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include <chrono>
#include <sstream>

#include "concert/dds/participant.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "dds/conversions.hpp"
#include "dds/modelgen_node.hpp"
#include "modelgen/cli.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace concert;
using namespace std::chrono_literals;

namespace {

using ::testing::HasSubstr;

msg::ModuleTree tree_msg(const topology::ModuleTree& tree, uint32_t version) {
  return topology::dds::to_msg(tree, version, 0, 0);
}

/// Spins the node until `reader` has a sample or 5 s pass.
std::optional<msg::RobotModel> spin_for_model(modelgen::dds::ModelgenNode& node, concert::dds::Reader<msg::RobotModel>& reader,
                                              std::chrono::milliseconds limit = 5000ms) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    node.spin_once(50ms);
    if (auto m = reader.take()) return m;
  }
  return std::nullopt;
}

}  // namespace

TEST(ModelgenNode, PublishesVersionedModelsOverDds) {
  const module_db::ModuleDatabase db = module_db::load_module_database(fs::path(CONCERT_SHARED_DATA) / "concert_resources");
  modelgen::ModelgenService service(db);
  concert::dds::Participant node_participant({.name = "modelgen_under_test"});
  concert::dds::Participant test_participant({.name = "modelgen_test"});
  std::ostringstream log;
  // Alone on the wire: no model to resume from (listened for 0.2 s).
  modelgen::dds::ModelgenNode node(node_participant, service, log, 200ms);
  concert::dds::Writer<msg::ModuleTree> trees(test_participant, concert::dds::topics::module_tree);
  concert::dds::Writer<msg::ModelCustomisation> requests(test_participant, concert::dds::topics::customisation);
  concert::dds::Reader<msg::RobotModel> models(test_participant, concert::dds::topics::robot_model);
  ASSERT_TRUE(trees.wait_for_readers(1, 5000ms));
  ASSERT_TRUE(requests.wait_for_readers(1, 5000ms));
  ASSERT_TRUE(models.wait_for_writers(1, 5000ms));

  const topology::ModuleTree big = modelgen::test::make_tree(modelgen::test::public_eighteen_module_robot(), &db);
  ASSERT_TRUE(trees.write(tree_msg(big, 1)));
  const auto m1 = spin_for_model(node, models);
  ASSERT_TRUE(m1.has_value()) << log.str();
  EXPECT_EQ(m1->version(), 1u);
  EXPECT_EQ(m1->tree_version(), 1u);
  EXPECT_EQ(m1->modules().size(), 18u);
  EXPECT_EQ(m1->joints().size(), 14u);
  EXPECT_EQ(m1->chains().size(), 5u);
  EXPECT_EQ(m1->end_effectors().size(), 5u);
  EXPECT_EQ(m1->content_hash(), service.current()->content_hash);
  EXPECT_TRUE(urdf::parseURDF(m1->urdf()));
  EXPECT_EQ(m1->joints()[1].upper(), 1e300);  // continuous wheel joint

  // Same tree again: no new version on the wire.
  ASSERT_TRUE(trees.write(tree_msg(big, 2)));
  EXPECT_FALSE(spin_for_model(node, models, 600ms).has_value());
  EXPECT_THAT(log.str(), HasSubstr("not republished"));

  // A tree that cannot be modelled: error in the log, model kept.
  ASSERT_TRUE(trees.write(tree_msg(modelgen::test::make_tree({{"mobile_platform_concert", -1, -1}, {"nope", 0, 5}}), 3)));
  EXPECT_FALSE(spin_for_model(node, models, 600ms).has_value());
  EXPECT_THAT(log.str(), HasSubstr("tree 3: module 1 ('nope')"));
  EXPECT_EQ(service.current()->version, 1u);

  // Customisation: refused as a whole when one add-on does not fit (the panel gripper takes
  // none), then accepted: a new version with the homing posture.
  msg::ModelCustomisation request;
  request.request_id(5);
  request.base_version(1);
  request.homing_joints({"J2_E"});
  request.homing_positions({0.4});
  msg::AddonChoice addon;
  addon.module_name("ee_E");
  addon.addon("drillbit_6_SDSplus");
  request.addons().push_back(addon);
  ASSERT_TRUE(requests.write(request));
  EXPECT_FALSE(spin_for_model(node, models, 600ms).has_value());
  EXPECT_THAT(log.str(), HasSubstr("customisation request 5: customisation addons[0]: module 'passive_end_effector_panel' accepts no add-ons"));
  request.request_id(6);
  request.addons().clear();
  ASSERT_TRUE(requests.write(request));
  const auto m2 = spin_for_model(node, models);
  ASSERT_TRUE(m2.has_value()) << log.str();
  EXPECT_EQ(m2->version(), 2u);
  EXPECT_THAT(m2->srdf(), HasSubstr("<joint name=\"J2_E\" value=\"0.4\"/>"));

  // A late joiner gets the current model at once (transient-local).
  concert::dds::Reader<msg::RobotModel> late(test_participant, concert::dds::topics::robot_model);
  const auto latched = late.wait(5000ms);
  ASSERT_TRUE(latched.has_value());
  EXPECT_EQ(latched->version(), m2->version());

  // `concert model show` prints the live model.
  std::ostringstream out;
  std::ostringstream err;
  ASSERT_EQ(cli::run("concert", {modelgen::register_verbs}, {"model", "show", "--timeout", "5"},
                     out, err),
            0)
      << err.str();
  EXPECT_THAT(out.str(), HasSubstr("robot model version 2 (" + service.current()->content_hash + ")"));
  EXPECT_THAT(out.str(), HasSubstr("  E (arm) base_link -> tcp_E: J1_E J2_E J3_E J4_E J5_E J6_E"));
  EXPECT_THAT(out.str(), HasSubstr("  ee_E (other) chain E frame tcp_E module passive_end_effector_panel"));
  std::ostringstream json;
  ASSERT_EQ(cli::run("concert", {modelgen::register_verbs},
                     {"model", "show", "--json", "--timeout", "5"}, json, err),
            0)
      << err.str();
  const auto j = nlohmann::json::parse(json.str());
  EXPECT_EQ(j.at("version"), 2);
  EXPECT_EQ(j.at("content_hash"), service.current()->content_hash);
  ASSERT_FALSE(j.at("joints").empty());
  EXPECT_GT(j.at("joints")[0].at("peak_torque").get<double>(), 0.0);
  EXPECT_GT(j.at("joints")[0].at("continuous_torque").get<double>(), 0.0);
  EXPECT_EQ(j.at("chains").size(), service.current()->chains.size());
  EXPECT_FALSE(j.contains("urdf"));  // the description files are left out
}

TEST(ModelShow, NoModelIsAClearError) {
  std::ostringstream out;
  std::ostringstream err;
  const auto run = [&](const std::vector<std::string>& args) {
    return cli::run("concert", {modelgen::register_verbs}, args, out, err);
  };
  EXPECT_EQ(run({"model", "show", "--timeout", "0.3"}), 1);
  EXPECT_THAT(err.str(), HasSubstr("concert model show: no robot model received within 0.3 s"));
  EXPECT_EQ(run({"model", "show", "--timeout", "-1"}), 2);
  EXPECT_THAT(err.str(), HasSubstr("--timeout: '-1' is not a number >= 0"));
}
