// The project database models the paper's robots (section 6.1 morphologies A, B, C; a torso
// with two arms) with FK equal to eq. (1)-(2).

#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include "modelgen/model_generator.hpp"
#include "test_support.hpp"

using namespace concert;
using namespace concert::modelgen;
using namespace concert::modelgen::test;

namespace {

using ::testing::HasSubstr;

void check_model(const topology::ModuleTree& tree, const GeneratedModel& model, unsigned seed) {
  const auto& db = own_db();
  const urdf::ModelInterfaceSharedPtr u = urdf::parseURDF(model.urdf);
  ASSERT_TRUE(u);
  double mass = 0.0;
  for (const auto& m : tree.modules) mass += db.at(m.key).mass();
  EXPECT_NEAR(model.tree.mass(), mass, 1e-9);
  std::mt19937 rng(seed);
  for (int s = 0; s < 10; ++s) {
    std::map<std::string, double> qn;
    std::map<int, std::map<int, double>> qm;
    for (const PhysicalJoint& j : model.tree.joints) {
      if (j.description == nullptr) continue;
      const double v = std::uniform_real_distribution<double>(std::max(-3.0, j.description->limits.lower),
                                                              std::min(3.0, j.description->limits.upper))(rng);
      qn[j.name] = v;
      qm[j.module][static_cast<int>(j.description - db.at(model.modules[static_cast<size_t>(j.module)]).joints.data())] = v;
    }
    for (const EndEffectorInfo& e : model.end_effectors) {
      const Eigen::Isometry3d a = test::urdf_fk(*u, e.frame, qn);
      const Eigen::Isometry3d b = test::description_fk(db, tree, e.module, 0, qm);
      EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9) << e.frame;
      EXPECT_LT((a.linear() - b.linear()).norm(), 1e-9) << e.frame;
    }
  }
}

}  // namespace

TEST(OwnDatabase, MorphologiesAandBOfTheDrillingExperiments) {
  const ModelGenerator gen(own_db());
  for (const auto* arm : {&kMorphologyA, &kMorphologyB}) {
    const topology::ModuleTree tree = make_tree(mobile_robot(*arm), &own_db());
    const GeneratedModel model = gen.generate(tree);
    check_model(tree, model, 3u);
    ASSERT_EQ(model.chains.size(), 5u);
    EXPECT_EQ(model.chains[4].role, concert::model::ChainRole::kArm);
    EXPECT_EQ(model.chains[4].joints.size(), 6u);
    EXPECT_EQ(model.chains[4].tip_link, "tcp_E");
    EXPECT_EQ(model.end_effectors.back().name, "drill_E");
    EXPECT_GE(model.tree.body_index("camera_E"), 0);
    // Table 1 limits reach the joint list: J1_E is a Straight A (Large A).
    const JointInfo& j1 = model.joints[8];
    EXPECT_EQ(j1.name, "J1_E");
    EXPECT_DOUBLE_EQ(j1.velocity, 2.14);
    EXPECT_DOUBLE_EQ(j1.continuous_torque, 160.0);
    EXPECT_DOUBLE_EQ(model.joints[0].velocity, 8.1);  // steering, Medium
    EXPECT_EQ(model.joints[0].control_mode, "position");
    EXPECT_EQ(model.joints[1].control_mode, "velocity");  // wheel, Small B
  }
  // Morphology B's extra link sits after the third joint: L_3_link_1_E.
  const GeneratedModel b = gen.generate(make_tree(mobile_robot(kMorphologyB), &own_db()));
  EXPECT_GE(b.tree.body_index("L_3_link_1_E"), 0);
  const GeneratedModel a = gen.generate(make_tree(mobile_robot(kMorphologyA), &own_db()));
  EXPECT_LT(a.tree.body_index("L_3_link_1_E"), 0);
  // The arm is 0.4 m longer when stretched (all joints at zero).
  const auto ua = urdf::parseURDF(a.urdf);
  const auto ub = urdf::parseURDF(b.urdf);
  const double la = (test::urdf_fk(*ua, "tcp_E", {}).translation() - test::urdf_fk(*ua, "L_0_proximal_E", {}).translation()).norm();
  const double lb = (test::urdf_fk(*ub, "tcp_E", {}).translation() - test::urdf_fk(*ub, "L_0_proximal_E", {}).translation()).norm();
  EXPECT_NEAR(lb - la, 0.4, 0.05);
}

TEST(OwnDatabase, MorphologyCAndTwoArmTorso) {
  const ModelGenerator gen(own_db());
  std::vector<std::string> c = kMorphologyA;
  c.insert(c.begin(), "concert_base_link_600");
  const topology::ModuleTree tc = make_tree(mobile_robot(c), &own_db());
  check_model(tc, gen.generate(tc), 5u);

  const topology::ModuleTree tree = make_tree(two_arm_torso(), &own_db());
  Customisation custom;
  custom.addons.push_back({"sanding_tool_G", "concert_sanding_force_sensor"});
  const GeneratedModel model = gen.generate(tree, custom);
  check_model(tree, gen.generate(tree), 9u);
  ASSERT_EQ(model.chains.size(), 7u);
  EXPECT_EQ(model.chains[5].base_link, "L_0_hub_2_E");
  EXPECT_EQ(model.chains[5].joints, (std::vector<std::string>{"J1_F", "J2_F", "J3_F"}));
  EXPECT_EQ(model.chains[6].tip_link, "tcp_G");
  EXPECT_EQ(model.end_effectors[4].name, "gripper_F");
  EXPECT_EQ(model.end_effectors[5].name, "sanding_tool_G");
  EXPECT_GE(model.tree.body_index("ft_sensor_G"), 0);
  EXPECT_THAT(model.srdf, HasSubstr("<end_effector name=\"gripper_F\" parent_link=\"tcp_F\""));
  EXPECT_TRUE(urdf::parseURDF(model.urdf));
}
