// Downstream users parse the generated URDF with orocos-kdl (libs/kinematics): the models load,
// keep their mass, and KDL's FK agrees with the eq. (1)-(2) composition.

#include <filesystem>
#include <random>

#include <gtest/gtest.h>

#include "concert/kinematics/model.hpp"
#include "modelgen/model_generator.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace concert;

TEST(Downstream, KdlLoadsGeneratedModels) {
  const module_db::ModuleDatabase pub = module_db::load_module_database(fs::path(CONCERT_SHARED_DATA) / "concert_resources");
  const topology::ModuleTree tree = modelgen::test::make_tree(modelgen::test::public_eighteen_module_robot(), &pub);
  const modelgen::GeneratedModel model = modelgen::ModelGenerator(pub).generate(tree);
  const kinematics::Model kdl = kinematics::Model::from_urdf_string(model.urdf, {.planar_base = true});
  EXPECT_EQ(kdl.dof(), 3 + static_cast<int>(model.joints.size()));
  EXPECT_NEAR(kdl.total_mass(), model.tree.mass(), 1e-9);
  kinematics::Data data = kdl.make_data();
  std::mt19937 rng(11u);
  for (int s = 0; s < 10; ++s) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(kdl.dof());
    std::map<int, std::map<int, double>> qm;
    for (const modelgen::PhysicalJoint& j : model.tree.joints) {
      if (j.description == nullptr) continue;
      const double v = std::uniform_real_distribution<double>(-2.0, 2.0)(rng);
      q[kdl.joint_index_or_throw(j.name)] = v;
      qm[j.module][static_cast<int>(j.description - pub.at(model.modules[static_cast<size_t>(j.module)]).joints.data())] = v;
    }
    for (const modelgen::EndEffectorInfo& e : model.end_effectors) {
      const Eigen::Isometry3d a = kdl.frame_pose(data, q, e.frame);
      const Eigen::Isometry3d b = modelgen::test::description_fk(pub, tree, e.module, 0, qm);
      EXPECT_LT((a.translation() - b.translation()).norm(), 1e-6) << e.frame;
      EXPECT_LT((a.linear() - b.linear()).norm(), 1e-6) << e.frame;
    }
  }
}
