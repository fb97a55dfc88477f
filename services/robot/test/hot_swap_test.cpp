// Hot swap through the whole pipeline: the simulated assembly changes while running, the bus
// gives a new scan, discovery rebuilds the tree, modelgen the model, and the robot core
// accepts it (and refuses a model of the old hardware).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "concert/module_db/module_db.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/reconstruction.hpp"
#include "concert/model_generation/generator.hpp"
#include "robot/robot_core.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "test_helpers.hpp"

namespace concert::robot {
namespace {

namespace fs = std::filesystem;
using sim::AssemblyBuilder;
using sim::SimulatedRobot;
const fs::path kPublicDb = fs::path(CONCERT_SHARED_DATA) / "concert_resources";
const fs::path kPaperRobot = fs::path(CONCERT_SOURCE_DIR) / "libs" / "simbus" / "examples" / "concert_paper_robot.yaml";

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

// What the discovery and modelgen services do with a scan.
std::string model_from_scan(const topology::EscScan& scan) {
  static const module_db::ModuleDatabase db = module_db::load_module_database(kPublicDb);
  const auto tree = topology::discover(scan, topology::EscCatalog::load(kPublicDb));
  return model_generation::ModelGenerator(db).generate(tree).urdf;
}

TEST(AssemblyBuilder, PaperRobotGivesScanTreeAndUrdf) {
  const AssemblyBuilder builder({kPublicDb});
  const SimulatedRobot robot = builder.build(kPaperRobot);
  EXPECT_EQ(robot.tree.modules.size(), 18u);
  EXPECT_EQ(robot.scan.slaves.size(), 19u);  // one ESC per module, two in the base hub
  EXPECT_NE(robot.urdf.find("J1_A"), std::string::npos);
  EXPECT_THROW((void)builder.build("/nonexistent/assembly.yaml"), std::runtime_error);
  try {
    (void)builder.build_from_text("modules:\n  - {name: base, key: no_such_module}\n", "bad.yaml");
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_module"), std::string::npos) << e.what();
  }
}

TEST(HotSwap, NewScanNewModelAccepted) {
  const AssemblyBuilder builder({kPublicDb});
  const std::string paper = read_text(kPaperRobot);
  const SimulatedRobot a = builder.build_from_text(paper, "paper.yaml");
  SimHardware sim(a, World{}, {});
  RobotCore core(sim);
  core.set_model(model_from_scan(a.scan), 1);
  test::run_cycles(core, 300);
  ASSERT_TRUE(core.ready());

  // Replace the drill by the spraying tool.
  const SimulatedRobot b = builder.build_from_text(
      replace(paper, "key: module_drill_concert", "key: module_spraying_tool_concert"), "spray.yaml");
  EXPECT_NE(b.scan, a.scan);
  sim.swap_model(b);
  test::run_cycles(core, 100);
  EXPECT_FALSE(core.ready());
  core.set_model(model_from_scan(b.scan), 2);
  EXPECT_TRUE(core.ready());

  // Add a passive link before the tool: same joints, longer arm.
  const SimulatedRobot c = builder.build_from_text(
      replace(paper, "  - {name: drill, key: module_drill_concert, parent: yaw_3, connector: 1, robot_id: 60}",
              "  - {name: link_3, key: module_link_straight_200_concert, parent: yaw_3, connector: 1}\n"
              "  - {name: drill, key: module_drill_concert, parent: link_3, connector: 1, robot_id: 60}"),
      "link.yaml");
  EXPECT_EQ(c.tree.modules.size(), a.tree.modules.size() + 1);
  sim.swap_model(c);
  test::run_cycles(core, 100);
  core.set_model(model_from_scan(c.scan), 3);
  EXPECT_TRUE(core.ready());

  // Remove the rear-right leg: the previous model no longer matches the hardware.
  const SimulatedRobot d = builder.build_from_text(
      replace(replace(paper, "  - {name: steer_rr, key: module_steering_concert_fl_rr, parent: base, connector: 4, robot_id: 41}\n", ""),
              "  - {name: wheel_rr, key: module_wheel_concert, parent: steer_rr, connector: 1, robot_id: 42}\n", ""),
      "three_legs.yaml");
  EXPECT_EQ(d.scan.slaves.size(), a.scan.slaves.size() - 2);
  sim.swap_model(d);
  test::run_cycles(core, 100);
  EXPECT_THROW(core.set_model(model_from_scan(c.scan), 4), ModelMismatchError);
  core.set_model(model_from_scan(d.scan), 4);
  EXPECT_TRUE(core.ready());
  EXPECT_EQ(core.legs().size(), 3u);
  test::run_cycles(core, 500);
  const RobotState s = core.state();
  EXPECT_EQ(s.model_version, 4u);
  for (const auto& joint : core.arm_joints()) {
    EXPECT_NEAR(s.position[test::hw_index(s, joint)], 0.0, 0.03) << joint;  // held through every swap
  }
}

// The project's own module database (data/module_db), as `concert up` uses it.
TEST(ProjectDatabase, DemoDrillRobotStandsDrivesAndHoldsItsArm) {
  const AssemblyBuilder builder({fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db"});
  const SimulatedRobot robot = builder.build_from_text(R"(modules:
  - {name: base, key: concert_mobile_base_hub, robot_id: [100, 101]}
  - {name: steer_fl, key: concert_steering_fl_rr, parent: base, connector: 1, robot_id: 11}
  - {name: wheel_fl, key: concert_wheel, parent: steer_fl, connector: 1, robot_id: 12}
  - {name: steer_fr, key: concert_steering_fr_rl, parent: base, connector: 2, robot_id: 21}
  - {name: wheel_fr, key: concert_wheel, parent: steer_fr, connector: 1, robot_id: 22}
  - {name: steer_rl, key: concert_steering_fr_rl, parent: base, connector: 3, robot_id: 31}
  - {name: wheel_rl, key: concert_wheel, parent: steer_rl, connector: 1, robot_id: 32}
  - {name: steer_rr, key: concert_steering_fl_rr, parent: base, connector: 4, robot_id: 41}
  - {name: wheel_rr, key: concert_wheel, parent: steer_rr, connector: 1, robot_id: 42}
  - {name: yaw_1, key: concert_straight_a, parent: base, connector: 5, robot_id: 51}
  - {name: elbow_1, key: concert_elbow_a, parent: yaw_1, connector: 1, robot_id: 52}
  - {name: link_1, key: concert_link_400, parent: elbow_1, connector: 1}
  - {name: elbow_2, key: concert_elbow_a, parent: link_1, connector: 1, robot_id: 53}
  - {name: yaw_2, key: concert_straight_b, parent: elbow_2, connector: 1, robot_id: 54}
  - {name: link_2, key: concert_link_400, parent: yaw_2, connector: 1}
  - {name: elbow_3, key: concert_elbow_b, parent: link_2, connector: 1, robot_id: 55}
  - {name: yaw_3, key: concert_straight_b, parent: elbow_3, connector: 1, robot_id: 56}
  - {name: tool, key: concert_drill, parent: yaw_3, connector: 1, robot_id: 60}
)",
                                                       "demo.yaml");
  SimHardware sim(robot.urdf, World{}, {});
  RobotCore core(sim);
  core.set_model(robot.urdf, 1);
  EXPECT_EQ(core.legs().size(), 4u);
  EXPECT_EQ(core.arm_joints().size(), 6u);
  test::run_cycles(core, 500);
  EXPECT_NEAR(sim.base_pose().translation().z(), mobile_base::standing_height(core.legs()), 0.02);
  test::drive_base(core, {1, 0.0, 0.2, 0.0}, 2000);
  const RobotState s = core.state();
  EXPECT_NEAR(s.odometry.vy, 0.2, 0.02);
  EXPECT_NEAR(s.odometry.y, sim.base_pose().translation().y(), 0.05);
  for (const auto& joint : core.arm_joints()) {
    EXPECT_NEAR(s.position[test::hw_index(s, joint)], 0.0, 0.02) << joint;
  }
}

}  // namespace
}  // namespace concert::robot
