// assembly -> simulated scan -> discovery -> model equals assembly -> model directly.

#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include <filesystem>
#include <random>
#include <sstream>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/scan_io.hpp"
#include "concert/topology/reconstruction.hpp"
#include "modelgen/model_generator.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace concert;

namespace {

struct Db {
  fs::path dir;
  module_db::ModuleDatabase db;
  topology::EscCatalog catalog;
  explicit Db(fs::path d) : dir(d), db(module_db::load_module_database(d)), catalog(topology::EscCatalog::load(d)) {}
};

void expect_round_trip(const Db& d, const simbus::Assembly& assembly, const std::string& what) {
  const modelgen::ModelGenerator gen(d.db);
  const topology::ModuleTree direct = simbus::tree_from_assembly(assembly, d.catalog);
  const topology::ModuleTree discovered = topology::discover(simbus::simulate_scan(assembly, d.catalog), d.catalog);
  const modelgen::GeneratedModel a = gen.generate(direct);
  const modelgen::GeneratedModel b = gen.generate(discovered);
  EXPECT_EQ(a.content_hash, b.content_hash) << what;
  EXPECT_EQ(a.urdf, b.urdf) << what;
  EXPECT_EQ(a.modules.size(), assembly.modules.size()) << what;
}

}  // namespace

TEST(RoundTrip, PublicDatabaseExampleAssemblies) {
  const Db d(fs::path(CONCERT_SHARED_DATA) / "concert_resources");
  for (const char* file : {"concert_paper_robot.yaml", "concert_torso_two_arms.yaml"}) {
    expect_round_trip(d, simbus::load_assembly(fs::path(SIMBUS_EXAMPLES) / file), file);
  }
  // The Mobile Base Hub's two ESCs are one module and one body.
  const simbus::Assembly paper = simbus::load_assembly(fs::path(SIMBUS_EXAMPLES) / "concert_paper_robot.yaml");
  const topology::ModuleTree tree = topology::discover(simbus::simulate_scan(paper, d.catalog), d.catalog);
  ASSERT_EQ(tree.modules[0].slave_positions.size(), 2u);
  const modelgen::GeneratedModel model = modelgen::ModelGenerator(d.db).generate(tree);
  int base_bodies = 0;
  // (its sensor frames are massless frame links, not bodies)
  for (const modelgen::PhysicalBody& b : model.tree.bodies) base_bodies += b.module == 0 && !b.massless ? 1 : 0;
  EXPECT_EQ(base_bodies, 1);
}

TEST(RoundTrip, RealScanGivesTheModelOfItsAssemblyFile) {
  // The real CONCERT scan -> discovery -> model, against the model of an assembly file of the
  // same robot (no scan involved): every link at the same place for random postures.
  const Db d(fs::path(CONCERT_SHARED_DATA) / "concert_resources");
  const topology::EscScan real = topology::load_scan(fs::path(CONCERT_SHARED_DATA) / "ethercat" /
                                                     "concert_robot_18slaves.yaml");
  const topology::ModuleTree tree = topology::discover(real, d.catalog);
  ASSERT_TRUE(tree.issues.empty());
  const simbus::Assembly assembly =
      simbus::load_assembly(fs::path(SIMBUS_EXAMPLES) / "concert_robot_18slaves.yaml");
  const modelgen::ModelGenerator gen(d.db);
  const modelgen::GeneratedModel from_scan = gen.generate(tree);
  const modelgen::GeneratedModel from_assembly =
      gen.generate(simbus::tree_from_assembly(assembly, d.catalog));
  const auto scan_urdf = urdf::parseURDF(from_scan.urdf);
  const auto assembly_urdf = urdf::parseURDF(from_assembly.urdf);
  ASSERT_TRUE(scan_urdf && assembly_urdf);
  ASSERT_EQ(from_scan.joints.size(), 14u);  // 4 steering + 4 wheels + 6 arm joints
  std::vector<std::shared_ptr<urdf::Link>> links;
  assembly_urdf->getLinks(links);
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> angle(-1.5, 1.5);
  for (int posture = 0; posture < 20; ++posture) {
    std::map<std::string, double> q;
    for (const auto& j : from_assembly.joints) q[j.name] = angle(rng);
    for (const auto& link : links) {
      ASSERT_TRUE(scan_urdf->getLink(link->name)) << link->name;
      const Eigen::Isometry3d a = modelgen::test::urdf_fk(*assembly_urdf, link->name, q);
      const Eigen::Isometry3d b = modelgen::test::urdf_fk(*scan_urdf, link->name, q);
      EXPECT_LT((a.matrix() - b.matrix()).norm(), 1e-12) << link->name << " posture " << posture;
    }
  }
  // The project database knows the same identities: the real robot gets a model there too.
  const Db project(fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db");
  const modelgen::GeneratedModel own =
      modelgen::ModelGenerator(project.db).generate(topology::discover(real, project.catalog));
  EXPECT_EQ(own.joints.size(), 14u);
}

TEST(RoundTrip, ProjectDatabaseRobots) {
  const Db d(fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db");
  // The paper's morphology B and a torso with two arms, as the generator tests build them.
  expect_round_trip(d, modelgen::test::to_assembly(modelgen::test::mobile_robot(modelgen::test::kMorphologyB)),
                    "morphology B");
  expect_round_trip(d, modelgen::test::to_assembly(modelgen::test::two_arm_torso()), "torso");
}

TEST(RoundTrip, RandomRobotsOfTheProjectDatabase) {
  // Property: for seeded random robots built from every module with an ESC, the discovered tree
  // gives the same model as the assembly, and every end-effector's URDF FK equals eq. (1)-(2).
  const Db d(fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db");
  std::vector<std::string> keys;
  for (const auto& e : d.catalog.entries()) {
    if (e.key != "concert_mobile_base_hub") keys.push_back(e.key);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::mt19937 rng(20240611u);
  for (int robot = 0; robot < 40; ++robot) {
    simbus::Assembly a;
    a.modules.push_back({"m0", "concert_mobile_base_hub", "", 0, {}});
    std::vector<std::pair<std::string, int>> free{{"m0", 1}, {"m0", 2}, {"m0", 3}, {"m0", 4}, {"m0", 5}};
    const int size = std::uniform_int_distribution<int>(2, 30)(rng);
    while (static_cast<int>(a.modules.size()) < size && !free.empty()) {
      const size_t slot = std::uniform_int_distribution<size_t>(0, free.size() - 1)(rng);
      const auto [parent, connector] = free[slot];
      free.erase(free.begin() + static_cast<long>(slot));
      const std::string key = keys[std::uniform_int_distribution<size_t>(0, keys.size() - 1)(rng)];
      // Streamed rather than "m" + ...: GCC 12 at -O3 flags that with a -Wrestrict false positive.
      std::ostringstream module_name;
      module_name << "m" << a.modules.size();
      const std::string name = module_name.str();
      a.modules.push_back({name, key, parent, connector, {}});
      const size_t outputs = d.db.at(key).output_connectors().size();
      for (size_t c = 1; c <= outputs; ++c) free.emplace_back(name, static_cast<int>(c));
    }
    const std::string what = "robot " + std::to_string(robot) + ":\n" + simbus::assembly_to_yaml(a);
    expect_round_trip(d, a, what);
    const topology::ModuleTree tree = simbus::tree_from_assembly(a, d.catalog);
    const modelgen::GeneratedModel model = modelgen::ModelGenerator(d.db).generate(tree);
    const auto u = urdf::parseURDF(model.urdf);
    ASSERT_TRUE(u) << what;
    std::map<std::string, double> qn;
    std::map<int, std::map<int, double>> qm;
    for (const modelgen::PhysicalJoint& j : model.tree.joints) {
      if (j.description == nullptr) continue;
      const double v = std::uniform_real_distribution<double>(-1.0, 1.0)(rng);
      qn[j.name] = v;
      qm[j.module][static_cast<int>(j.description - d.db.at(model.modules[static_cast<size_t>(j.module)]).joints.data())] = v;
    }
    for (const modelgen::EndEffectorInfo& e : model.end_effectors) {
      const Eigen::Isometry3d x = modelgen::test::urdf_fk(*u, e.frame, qn);
      const Eigen::Isometry3d y = modelgen::test::description_fk(d.db, tree, e.module, 0, qm);
      ASSERT_LT((x.translation() - y.translation()).norm(), 1e-9) << e.frame << "\n" << what;
      ASSERT_LT((x.linear() - y.linear()).norm(), 1e-9) << e.frame << "\n" << what;
    }
  }
}
