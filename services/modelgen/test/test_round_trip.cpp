// assembly -> simulated scan -> discovery -> model equals assembly -> model directly.

#include <filesystem>

#include <gtest/gtest.h>

#include "concert/simbus/assembly.hpp"
#include "discovery/discovery.hpp"
#include "modelgen/model_generator.hpp"

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
  const topology::ModuleTree discovered = discovery::discover(simbus::simulate_scan(assembly, d.catalog), d.catalog);
  const modelgen::RobotModel a = gen.generate(direct);
  const modelgen::RobotModel b = gen.generate(discovered);
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
}

TEST(RoundTrip, ProjectDatabaseRobots) {
  const Db d(fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db");
  const std::string legs = R"(
  - {name: base, key: concert_mobile_base_hub, robot_id: [100, 101]}
  - {name: s1, key: concert_steering_fl_rr, parent: base, connector: 1}
  - {name: w1, key: concert_wheel, parent: s1, connector: 1}
  - {name: s2, key: concert_steering_fr_rl, parent: base, connector: 2}
  - {name: w2, key: concert_wheel, parent: s2, connector: 1}
  - {name: s3, key: concert_steering_fr_rl, parent: base, connector: 3}
  - {name: w3, key: concert_wheel, parent: s3, connector: 1}
  - {name: s4, key: concert_steering_fl_rr, parent: base, connector: 4}
  - {name: w4, key: concert_wheel, parent: s4, connector: 1}
)";
  const std::string morphology_b = "modules:" + legs + R"(
  - {name: j1, key: concert_straight_a, parent: base, connector: 5}
  - {name: j2, key: concert_elbow_a, parent: j1, connector: 1}
  - {name: j3, key: concert_straight_a, parent: j2, connector: 1}
  - {name: l1, key: concert_link_400, parent: j3, connector: 1}
  - {name: j4, key: concert_elbow_a, parent: l1, connector: 1}
  - {name: j5, key: concert_straight_b, parent: j4, connector: 1}
  - {name: l2, key: concert_link_400, parent: j5, connector: 1}
  - {name: j6, key: concert_elbow_b, parent: l2, connector: 1}
  - {name: drill, key: concert_drill, parent: j6, connector: 1}
)";
  const std::string torso = "modules:" + legs + R"(
  - {name: bl, key: concert_base_link_600, parent: base, connector: 5}
  - {name: torso, key: concert_torso_hub, parent: bl, connector: 1}
  - {name: r1, key: concert_elbow_a, parent: torso, connector: 1}
  - {name: r2, key: concert_link_elbow_90, parent: r1, connector: 1}
  - {name: r3, key: concert_active_gripper_tube, parent: r2, connector: 1}
  - {name: q1, key: concert_elbow_b, parent: torso, connector: 2}
  - {name: q2, key: concert_straight_b, parent: q1, connector: 1}
  - {name: q3, key: concert_sanding_tool, parent: q2, connector: 1}
)";
  expect_round_trip(d, simbus::parse_assembly(morphology_b, "morphology_b"), "morphology B");
  expect_round_trip(d, simbus::parse_assembly(torso, "torso"), "torso");
}
