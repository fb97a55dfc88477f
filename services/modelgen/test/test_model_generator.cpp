#include <algorithm>
#include <filesystem>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include "modelgen/bundle.hpp"
#include "modelgen/model_generator.hpp"
#include "modelgen/versioning.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace concert;
using namespace concert::modelgen;
using namespace concert::modelgen::test;

namespace {

using ::testing::HasSubstr;

/// Message of the ModelError that generating `tree` with the add-ons `addons` throws, or
/// "(no error)".
std::string addons_error(const ModelGenerator& gen, const topology::ModuleTree& tree,
                         const decltype(Customisation::addons)& addons) {
  Customisation custom;
  custom.addons = addons;
  return error_of([&] { gen.generate(tree, custom); });
}

/// Checks every end-effector frame of `model` against eq. (1)-(2) at seeded random joint values.
void expect_fk_matches(const module_db::ModuleDatabase& db, const topology::ModuleTree& tree, const GeneratedModel& model,
                       unsigned seed, int samples) {
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(model.urdf);
  ASSERT_TRUE(urdf_model) << "urdfdom rejected the URDF";
  std::mt19937 rng(seed);
  for (int s = 0; s < samples; ++s) {
    std::map<std::string, double> q_by_name;
    std::map<int, std::map<int, double>> q_by_module;
    for (const PhysicalJoint& j : model.tree.joints) {
      if (j.description == nullptr) continue;
      const double lo = std::max(j.description->limits.lower, -3.0);
      const double hi = std::min(j.description->limits.upper, 3.0);
      const double v = std::uniform_real_distribution<double>(lo, hi)(rng);
      q_by_name[j.name] = v;
      const module_db::ModuleDescription& d = db.at(model.modules[static_cast<size_t>(j.module)]);
      q_by_module[j.module][static_cast<int>(j.description - d.joints.data())] = v;
    }
    ASSERT_FALSE(model.end_effectors.empty());
    for (const EndEffectorInfo& e : model.end_effectors) {
      const Eigen::Isometry3d a = test::urdf_fk(*urdf_model, e.frame, q_by_name);
      const Eigen::Isometry3d b = test::description_fk(db, tree, e.module, 0, q_by_module);
      EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9) << e.frame << " sample " << s;
      EXPECT_LT((a.linear() - b.linear()).norm(), 1e-9) << e.frame << " sample " << s;
    }
  }
}

}  // namespace

TEST(PublicRobot, EighteenModulesLoadParseAndKeepTheirMass) {
  const auto& db = public_db();
  const topology::ModuleTree tree = make_tree(test::public_eighteen_module_robot(), &db);
  ASSERT_EQ(tree.modules.size(), 18u);
  const GeneratedModel model = ModelGenerator(db).generate(tree);
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(model.urdf);
  ASSERT_TRUE(urdf_model);
  double module_mass = 0.0;
  for (const auto& m : tree.modules) module_mass += db.at(m.key).mass();
  double urdf_mass = 0.0;
  std::vector<urdf::LinkSharedPtr> links;
  urdf_model->getLinks(links);
  for (const auto& l : links) {
    if (l->inertial) urdf_mass += l->inertial->mass;
  }
  EXPECT_NEAR(urdf_mass, module_mass, 1e-9);
  EXPECT_NEAR(model.tree.mass(), module_mass, 1e-9);
  EXPECT_EQ(urdf_model->getRoot()->name, "base_link");
  // 4 x (steering + wheel) + 6 arm joints; fixed joints kept.
  EXPECT_EQ(model.joints.size(), 14u);
  EXPECT_EQ(links.size(), model.tree.bodies.size());
  EXPECT_EQ(urdf_model->joints_.size(), model.tree.joints.size());
  ASSERT_EQ(model.chains.size(), 5u);
  for (int leg = 0; leg < 4; ++leg) {
    const ChainInfo& c = model.chains[static_cast<size_t>(leg)];
    EXPECT_EQ(c.role, concert::model::ChainRole::kLeg);
    EXPECT_EQ(c.base_link, "base_link");
    EXPECT_EQ(c.tip_link, "wheel_" + c.name);
    EXPECT_EQ(c.joints, (std::vector<std::string>{"J1_" + c.name, "J2_" + c.name}));
  }
  const ChainInfo& arm = model.chains[4];
  EXPECT_EQ(arm.name, "E");
  EXPECT_EQ(arm.role, concert::model::ChainRole::kArm);
  EXPECT_EQ(arm.tip_link, "tcp_E");
  EXPECT_EQ(arm.joints, (std::vector<std::string>{"J1_E", "J2_E", "J3_E", "J4_E", "J5_E", "J6_E"}));
  ASSERT_EQ(model.end_effectors.size(), 5u);
  EXPECT_EQ(model.end_effectors[4].name, "ee_E");
  EXPECT_EQ(model.end_effectors[4].module_key, "passive_end_effector_panel");
  EXPECT_EQ(model.end_effectors[0].name, "wheel_A");
  // Section 4.3.3 naming: link index counts passive links since the last moving joint.
  for (const char* name : {"L_0_proximal_E", "L_1_E", "L_1_proximal_E", "L_2_link_1_E", "L_2_proximal_E", "L_4_link_1_E",
                           "L_6_ee_E", "L_2_A", "L_1_proximal_A"}) {
    EXPECT_GE(model.tree.body_index(name), 0) << name;
  }
  EXPECT_EQ(model.modules.front(), "mobile_platform_concert");
  // Wheels are continuous joints under velocity control; arm joints impedance.
  const auto wheel = std::find_if(model.joints.begin(), model.joints.end(), [](const JointInfo& j) { return j.name == "J2_A"; });
  ASSERT_NE(wheel, model.joints.end());
  EXPECT_EQ(wheel->control_mode, "velocity");
  EXPECT_EQ(wheel->type, module_db::JointType::kContinuous);
  EXPECT_EQ(model.joints[8].name, "J1_E");
  EXPECT_EQ(model.joints[8].control_mode, "impedance");
  EXPECT_DOUBLE_EQ(model.joints[8].velocity, 2.14);
  EXPECT_EQ(model.content_hash.size(), 7u + 64u);
}

TEST(PublicRobot, TcpForwardKinematicsMatchesModuleDescriptions) {
  const auto& db = public_db();
  const topology::ModuleTree tree = make_tree(test::public_eighteen_module_robot(), &db);
  const GeneratedModel model = ModelGenerator(db).generate(tree);
  expect_fk_matches(db, tree, model, 42u, 25);
}

TEST(PublicRobot, TorsoHubTwoArmsAndBaseLinkFk) {
  const auto& db = public_db();
  const std::vector<Row> rows{{"mobile_platform_concert", -1, -1},
                              {"module_base_link_600_concert", 0, 5},
                              {"module_Y_torso_concert", 1, 1},
                              {"module_joint_elbow_A_concert", 2, 1},
                              {"module_link_elbow_45_concert", 3, 1},
                              {"module_joint_yaw_B_concert", 4, 1},
                              {"module_drill_concert", 5, 1},
                              {"module_joint_elbow_B_concert", 2, 2},
                              {"module_joint_yaw_B_concert", 7, 1},
                              {"module_spraying_tool_concert", 8, 1}};
  const topology::ModuleTree tree = make_tree(rows, &db);
  const GeneratedModel model = ModelGenerator(db).generate(tree);
  ASSERT_TRUE(urdf::parseURDF(model.urdf));
  ASSERT_EQ(model.chains.size(), 3u);
  EXPECT_EQ(model.chains[0].name, "A");
  EXPECT_EQ(model.chains[0].role, concert::model::ChainRole::kOther);
  EXPECT_EQ(model.chains[0].tip_link, "L_0_hub_2_A");
  EXPECT_EQ(model.chains[1].name, "B");
  EXPECT_EQ(model.chains[1].base_link, "L_0_hub_2_A");
  EXPECT_EQ(model.chains[1].tip_link, "tcp_B");
  EXPECT_EQ(model.chains[2].tip_link, "tcp_C");
  EXPECT_GE(model.tree.body_index("L_0_link_1_A"), 0);
  EXPECT_GE(model.tree.body_index("L_1_link_1_B"), 0);
  EXPECT_EQ(model.end_effectors[0].name, "drill_B");
  EXPECT_EQ(model.end_effectors[1].name, "spraying_tool_C");
  expect_fk_matches(db, tree, model, 7u, 10);
}

TEST(Naming, SameRobotSameNamesWhateverTheModuleOrder) {
  const auto& db = public_db();
  const std::vector<Row> rows = test::public_eighteen_module_robot();
  const topology::ModuleTree tree = make_tree(rows, &db);
  const ModelGenerator gen(db);
  const GeneratedModel a = gen.generate(tree);
  const GeneratedModel b = gen.generate(tree);
  EXPECT_EQ(a.urdf, b.urdf);
  EXPECT_EQ(a.srdf, b.srdf);
  EXPECT_EQ(a.config_yaml, b.config_yaml);
  EXPECT_EQ(a.content_hash, b.content_hash);
  // Same robot, modules listed in another (still parent-first) order: same texts.
  // Order: base, arm first, then the legs in reverse.
  std::vector<int> order{0};
  for (int i = 9; i < 18; ++i) order.push_back(i);
  for (int leg = 3; leg >= 0; --leg) {
    order.push_back(1 + 2 * leg);
    order.push_back(2 + 2 * leg);
  }
  std::vector<int> new_index(rows.size());
  for (size_t i = 0; i < order.size(); ++i) new_index[static_cast<size_t>(order[i])] = static_cast<int>(i);
  std::vector<Row> permuted;
  for (int old : order) {
    Row r = rows[static_cast<size_t>(old)];
    if (std::get<1>(r) >= 0) std::get<1>(r) = new_index[static_cast<size_t>(std::get<1>(r))];
    permuted.push_back(r);
  }
  const GeneratedModel c = gen.generate(make_tree(permuted, &db));
  EXPECT_EQ(a.urdf, c.urdf);
  EXPECT_EQ(a.srdf, c.srdf);
  // A different robot gets a different hash.
  std::vector<Row> shorter(rows.begin(), rows.end() - 1);
  EXPECT_NE(gen.generate(make_tree(shorter, &db)).content_hash, a.content_hash);
}

TEST(Errors, TreesThatCannotBeModelled) {
  module_db::ModuleDatabase db = public_db();
  module_db::ModuleDescription small = db.at("module_joint_elbow_A_concert");
  small.key = "elbow_small_input";
  small.esc.reset();
  small.connectors[static_cast<size_t>(small.input_connector())].size = "small";
  db.add_module(small);
  const ModelGenerator gen(db);
  EXPECT_EQ(error_of([&] { gen.generate(make_tree({{"mobile_platform_concert", -1, -1}, {"no_such_module", 0, 5}})); }),
            "module 1 ('no_such_module'): no module description with key 'no_such_module' in the module database");
  EXPECT_EQ(error_of([&] { gen.generate(make_tree({{"mobile_platform_concert", -1, -1}, {"elbow_small_input", 0, 5}})); }),
            "module 1 ('elbow_small_input'): connector size mismatch: input '16_input' is 'small' but output connector 5 "
            "('2300_connector_5') of module 0 ('mobile_platform_concert') is 'large'");
  EXPECT_EQ(error_of([&] { gen.generate(make_tree({{"mobile_platform_concert", -1, -1}, {"module_joint_yaw_A_concert", 0, 6}})); }),
            "module 1 ('module_joint_yaw_A_concert'): parent module 0 ('mobile_platform_concert') has no output connector 6 (it has 5)");
  EXPECT_NE(error_of([&] {
              gen.generate(make_tree({{"mobile_platform_concert", -1, -1}, {"passive_end_effector_panel", 0, 5}, {"module_joint_yaw_A_concert", 1, 1}}));
            }).find("which has no output connectors"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              gen.generate(make_tree({{"mobile_platform_concert", -1, -1}, {"module_joint_yaw_A_concert", 0, 5}, {"module_joint_yaw_A_concert", 0, 5}}));
            }).find("is already used"),
            std::string::npos);
  topology::ModuleTree unknown = make_tree({{"mobile_platform_concert", -1, -1}, {"", 0, 5}});
  unknown.modules[1].identity = {1, 99, 4, 0};
  unknown.modules[1].slave_positions = {3};
  EXPECT_EQ(error_of([&] { gen.generate(unknown); }),
            "module 1 at slave 3: unknown ESC identity (mod_type 1, mod_id 99, mod_size 4, mod_rev 0)");
  EXPECT_EQ(error_of([&] { gen.generate(topology::ModuleTree{}); }), "module tree is empty");
  // A key unknown here but an identity known: the identity names the module.
  topology::ModuleTree foreign = make_tree({{"mobile_platform_concert", -1, -1}, {"their_elbow_a", 0, 5}});
  foreign.modules[1].identity = {1, 6, 4, 0};
  EXPECT_EQ(gen.generate(foreign).modules[1], "module_joint_elbow_A_concert");
}

TEST(Versioning, StrictlyIncreasingAndUnchangedContentIsNotRepublished) {
  const auto& db = public_db();
  const ModelGenerator gen(db);
  ModelVersioner versioner;
  const topology::ModuleTree big = make_tree(test::public_eighteen_module_robot(), &db);
  const topology::ModuleTree small = make_tree({{"mobile_platform_concert", -1, -1}, {"module_joint_yaw_A_concert", 0, 5}}, &db);
  auto u1 = versioner.offer(gen.generate(big, {}, 1));
  EXPECT_TRUE(u1.published);
  EXPECT_EQ(u1.version, 1u);
  auto u2 = versioner.offer(gen.generate(big, {}, 2));
  EXPECT_FALSE(u2.published);
  EXPECT_EQ(u2.version, 1u);
  EXPECT_EQ(versioner.current()->tree_version, 2u);
  auto u3 = versioner.offer(gen.generate(small, {}, 3));
  EXPECT_TRUE(u3.published);
  EXPECT_EQ(u3.version, 2u);
  // A tree that cannot be modelled throws before reaching the versioner: current model kept.
  const std::string hash = versioner.current()->content_hash;
  EXPECT_THROW(versioner.offer(gen.generate(make_tree({{"mobile_platform_concert", -1, -1}, {"nope", 0, 1}}), {}, 4)), ModelError);
  EXPECT_EQ(versioner.current()->version, 2u);
  EXPECT_EQ(versioner.current()->content_hash, hash);
  auto u4 = versioner.offer(gen.generate(big, {}, 5));
  EXPECT_TRUE(u4.published);
  EXPECT_EQ(u4.version, 3u);
  ModelVersioner resumed(8);
  EXPECT_EQ(resumed.offer(gen.generate(big)).version, 8u);
}

TEST(Customisation, HomingAndAddonsMakeANewModel) {
  const auto& db = public_db();
  const ModelGenerator gen(db);
  const std::vector<Row> rows{{"mobile_platform_concert", -1, -1},
                              {"module_joint_yaw_A_concert", 0, 5},
                              {"module_joint_elbow_A_concert", 1, 1},
                              {"module_drill_concert", 2, 1}};
  const topology::ModuleTree tree = make_tree(rows, &db);
  const GeneratedModel plain = gen.generate(tree);
  Customisation custom;
  custom.home["J2_A"] = 0.5;
  custom.addons.push_back({"drill_A", "drillbit_16_SDSplus"});
  custom.addons.push_back({"drill_A", "drill_handle"});
  const GeneratedModel custom_model = gen.generate(tree, custom);
  EXPECT_NE(custom_model.content_hash, plain.content_hash);
  EXPECT_THAT(custom_model.srdf, HasSubstr("<joint name=\"J2_A\" value=\"0.5\"/>"));
  EXPECT_NEAR(custom_model.tree.mass(), plain.tree.mass() + 0.8 + 0.33, 1e-9);
  EXPECT_EQ(custom_model.end_effectors[0].addons, (std::vector<std::string>{"drillbit_16_SDSplus", "drill_handle"}));
  const auto pu = urdf::parseURDF(plain.urdf);
  const auto cu = urdf::parseURDF(custom_model.urdf);
  ASSERT_TRUE(pu && cu);
  const Eigen::Isometry3d tp = test::urdf_fk(*pu, "tcp_A", {});
  const Eigen::Isometry3d tc = test::urdf_fk(*cu, "tcp_A", {});
  EXPECT_NEAR((tc.translation() - tp.translation()).norm(), 0.336, 1e-9);
  EXPECT_NEAR((tc.translation() - tp.translation()).dot(tp.linear().col(2)), 0.336, 1e-9);
  // Bad customisations are errors naming what is wrong.
  Customisation out_of_range;
  out_of_range.home["J1_A"] = 9.0;
  EXPECT_NE(error_of([&] { gen.generate(tree, out_of_range); }).find("J1_A = 9.000000 is outside the limits"), std::string::npos);
  Customisation no_joint;
  no_joint.home["J9_Z"] = 0.0;
  EXPECT_EQ(error_of([&] { gen.generate(tree, no_joint); }), "customisation home: no moving joint 'J9_Z' in this robot");
  EXPECT_EQ(addons_error(gen, tree, {{"drill_A", "drillbit_99"}}), "customisation addons[0]: unknown add-on 'drillbit_99'");
  EXPECT_EQ(addons_error(gen, tree, {{"L_1_A", "drillbit_16_SDSplus"}}),
            "customisation addons[0]: module 'module_joint_yaw_A_concert' accepts no add-ons");
  EXPECT_THAT(addons_error(gen, tree, {{"drill_A", "drillbit_16_SDSplus"}, {"drill_A", "drillbit_6_SDSplus"}}),
              HasSubstr("already has a 'drillbit' add-on"));
}

TEST(Bundle, WritesFilesAndManifest) {
  const auto& db = public_db();
  ModelVersioner versioner(3);
  versioner.offer(ModelGenerator(db).generate(make_tree(test::public_eighteen_module_robot(), &db), {}, 11));
  const GeneratedModel& model = *versioner.current();
  const fs::path dir = fs::temp_directory_path() / ("concert_modelgen_bundle_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  write_bundle(model, dir / "bundle");
  for (const char* f : {"robot.urdf", "robot.srdf", "controller.yaml", "manifest.yaml"}) EXPECT_TRUE(fs::exists(dir / "bundle" / f)) << f;
  const auto [version, hash] = read_bundle_version(dir / "bundle");
  EXPECT_EQ(version, 3u);
  EXPECT_EQ(hash, model.content_hash);
  EXPECT_TRUE(urdf::parseURDFFile((dir / "bundle" / "robot.urdf").string()));
  fs::remove_all(dir);
}

TEST(Customisation, PassiveGripperWithoutEscIsMountedByHand) {
  // The network cannot see a passive gripper: the discovered tree lacks it, and the user adds
  // it as a customisation. The result equals the model of the full 18-module tree.
  const auto& db = public_db();
  const ModelGenerator gen(db);
  std::vector<Row> rows = test::public_eighteen_module_robot();
  const GeneratedModel full = gen.generate(make_tree(rows, &db));
  rows.pop_back();
  const topology::ModuleTree seen = make_tree(rows, &db);
  for (const char* where : {"E", "L_6_E"}) {
    Customisation custom;
    custom.addons.push_back({where, "passive_end_effector_panel"});
    const GeneratedModel mounted = gen.generate(seen, custom);
    EXPECT_EQ(mounted.urdf, full.urdf) << where;
    EXPECT_EQ(mounted.srdf, full.srdf) << where;
    EXPECT_EQ(mounted.content_hash, full.content_hash) << where;
  }
  EXPECT_EQ(addons_error(gen, seen, {{"L_5_E", "passive_end_effector_panel"}}),
            "customisation addons[0]: module 'module_joint_elbow_B_concert' (L_5_E) has no free output connector for "
            "'passive_end_effector_panel'");
  EXPECT_EQ(addons_error(gen, seen, {{"Z", "passive_end_effector_panel"}}),
            "customisation addons[0].module_name: no body or chain 'Z' to mount 'passive_end_effector_panel' on");
  EXPECT_EQ(addons_error(gen, seen, {{"E", "module_drill_concert"}}),
            "customisation addons[0]: module 'module_drill_concert' has an ESC and is discovered, not added by hand");
}
