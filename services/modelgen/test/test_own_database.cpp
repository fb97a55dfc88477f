// The project database models the paper's robots (section 6.1 morphologies A, B, C; a torso
// with two arms) with FK equal to eq. (1)-(2).

#include <filesystem>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include "modelgen/model_generator.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace concert;
using namespace concert::modelgen;
using concert::modelgen::test::make_tree;
using concert::modelgen::test::Row;

namespace {

using ::testing::HasSubstr;

const module_db::ModuleDatabase& own_db() {
  static const module_db::ModuleDatabase db = module_db::load_module_database(fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db");
  return db;
}

/// Mobile base with four legs; then the arm `arm` on connector 5.
std::vector<Row> mobile_robot(const std::vector<std::string>& arm) {
  std::vector<Row> r{{"concert_mobile_base_hub", -1, -1}};
  const char* steering[] = {"concert_steering_fl_rr", "concert_steering_fr_rl", "concert_steering_fr_rl", "concert_steering_fl_rr"};
  for (int leg = 0; leg < 4; ++leg) {
    r.emplace_back(steering[leg], 0, leg + 1);
    r.emplace_back("concert_wheel", static_cast<int>(r.size()) - 1, 1);
  }
  int parent = 0;
  int connector = 5;
  for (const std::string& key : arm) {
    r.emplace_back(key, parent, connector);
    parent = static_cast<int>(r.size()) - 1;
    connector = 1;
  }
  return r;
}

// Section 6.1: morphology A = Straight A, Elbow A, Straight A, Elbow A, Straight B, link 0.4,
// Elbow B, Drill; B adds a 0.4 m link after the third joint; C adds the base link in front.
const std::vector<std::string> kMorphologyA{"concert_straight_a", "concert_elbow_a",  "concert_straight_a", "concert_elbow_a",
                                            "concert_straight_b", "concert_link_400", "concert_elbow_b",    "concert_drill"};
const std::vector<std::string> kMorphologyB{"concert_straight_a", "concert_elbow_a",  "concert_straight_a", "concert_link_400", "concert_elbow_a",
                                            "concert_straight_b", "concert_link_400", "concert_elbow_b",    "concert_drill"};

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

  std::vector<Row> rows = mobile_robot({"concert_base_link_600", "concert_torso_hub"});
  const int torso = static_cast<int>(rows.size()) - 1;
  rows.emplace_back("concert_elbow_a", torso, 1);
  rows.emplace_back("concert_link_elbow_90", static_cast<int>(rows.size()) - 1, 1);
  rows.emplace_back("concert_straight_b", static_cast<int>(rows.size()) - 1, 1);
  rows.emplace_back("concert_active_gripper_panel", static_cast<int>(rows.size()) - 1, 1);
  rows.emplace_back("concert_elbow_b", torso, 2);
  rows.emplace_back("concert_link_elbow_45", static_cast<int>(rows.size()) - 1, 1);
  rows.emplace_back("concert_sanding_tool", static_cast<int>(rows.size()) - 1, 1);
  const topology::ModuleTree tree = make_tree(rows, &own_db());
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
