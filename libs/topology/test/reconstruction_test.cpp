#include "concert/topology/reconstruction.hpp"

#include <gtest/gtest.h>

#include "concert/simbus/assembly.hpp"
#include "concert/simbus/testing.hpp"
#include "concert/topology/scan_io.hpp"
#include "scan_builder.hpp"
#include "test_data.hpp"

namespace concert::topology {
namespace {

using test::discover_error;
using test::make_scan;

using namespace concert::test_data;

TEST(Discovery, PaperRobotFromThePublicDatabase) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
  const ModuleTree tree = discover(simbus::simulate_scan(assembly, catalog), catalog);
  ASSERT_EQ(tree.slaves.size(), 19u);
  ASSERT_EQ(tree.modules.size(), 18u);
  // The Mobile Base Hub's two ESCs are one module.
  EXPECT_EQ(tree.modules[0].key, "mobile_platform_concert");
  EXPECT_EQ(tree.modules[0].kind, ModuleKind::kHub);
  EXPECT_EQ(tree.modules[0].slave_positions, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(tree.modules[0].robot_id, 100);
  EXPECT_EQ(tree.slaves[1].module_index, 0);
  EXPECT_EQ(tree.slaves[1].parent_port, 3);
  // Legs on connectors 1..4 in that order, each steering with its wheel.
  for (int leg = 0; leg < 4; ++leg) {
    const auto& steering = tree.modules[static_cast<std::size_t>(1 + 2 * leg)];
    const auto& wheel = tree.modules[static_cast<std::size_t>(2 + 2 * leg)];
    EXPECT_EQ(steering.parent_module, 0);
    EXPECT_EQ(steering.parent_connector, leg + 1);
    EXPECT_EQ(steering.kind, ModuleKind::kJoint);
    EXPECT_EQ(wheel.key, "module_wheel_concert");
    EXPECT_EQ(wheel.parent_module, steering.index);
    EXPECT_EQ(wheel.parent_connector, 1);
  }
  EXPECT_EQ(tree.modules[1].key, "module_steering_concert_fl_rr");
  EXPECT_EQ(tree.modules[3].key, "module_steering_concert_fr_rl");
  // Rear-right leg hangs on the power board's port 1, the arm on its port 2.
  EXPECT_EQ(tree.slaves[8].parent_position, 1);
  EXPECT_EQ(tree.slaves[8].parent_port, 1);
  EXPECT_EQ(tree.modules[9].key, "module_joint_yaw_A_concert");
  EXPECT_EQ(tree.modules[9].parent_connector, 5);
  EXPECT_EQ(tree.slaves[10].parent_port, 2);
  const std::vector<std::string> arm = {"module_joint_yaw_A_concert",
                                        "module_joint_elbow_A_concert",
                                        "module_link_straight_400_concert",
                                        "module_joint_elbow_A_concert",
                                        "module_joint_yaw_B_concert",
                                        "module_link_straight_400_concert",
                                        "module_joint_elbow_B_concert",
                                        "module_joint_yaw_B_concert",
                                        "module_drill_concert"};
  for (std::size_t i = 0; i < arm.size(); ++i) {
    EXPECT_EQ(tree.modules[9 + i].key, arm[i]) << i;
    if (i > 0) {
      EXPECT_EQ(tree.modules[9 + i].parent_module, static_cast<int32_t>(8 + i));
    }
  }
  EXPECT_EQ(tree.modules[11].robot_id, -1);
  EXPECT_EQ(tree.modules[17].kind, ModuleKind::kEndEffector);
  EXPECT_EQ(tree, simbus::tree_from_assembly(assembly, catalog));
}

TEST(Discovery, TorsoTwoArmsAndBothPortOrders) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  for (const char* file : {"concert_paper_robot.yaml", "concert_torso_two_arms.yaml"}) {
    const auto assembly = simbus::load_assembly(kExamples + "/" + file);
    for (PortOrder order : {PortOrder::kReal0312, PortOrder::kNumeric0123}) {
      const ModuleTree tree = discover(simbus::simulate_scan(assembly, catalog, order), catalog,
                                       DiscoveryParams{order});
      EXPECT_EQ(tree, simbus::tree_from_assembly(assembly, catalog, order))
          << file << " " << to_string(order);
    }
  }
  const auto torso = simbus::load_assembly(kExamples + "/concert_torso_two_arms.yaml");
  const ModuleTree tree = discover(simbus::simulate_scan(torso, catalog), catalog);
  EXPECT_EQ(tree.modules[10].key, "module_Y_torso_concert");
  EXPECT_EQ(tree.modules[11].parent_module, 10);
  EXPECT_EQ(tree.modules[11].parent_connector, 1);
  EXPECT_EQ(tree.modules[16].parent_module, 10);
  EXPECT_EQ(tree.modules[16].parent_connector, 2);
  EXPECT_EQ(tree.modules[21].key, "module_spraying_tool_concert");
}

TEST(Discovery, ScanFileKeyedByPositionAsTheMasterReportsIt) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
  const EscScan scan = simbus::simulate_scan(assembly, catalog);
  std::string text;
  for (auto it = scan.slaves.rbegin(); it != scan.slaves.rend(); ++it) {
    text += std::to_string(it->position) + ": {active_ports: " + std::to_string(it->active_ports) +
            ", esc_type: " + std::to_string(it->esc_type) +
            ", mod_id: " + std::to_string(it->identity.mod_id) +
            ", mod_rev: 0, mod_size: " + std::to_string(it->identity.mod_size) +
            ", mod_type: " + std::to_string(it->identity.mod_type) +
            ", position: " + std::to_string(it->position) +
            ", robot_id: " + std::to_string(it->robot_id) +
            ", topology: " + std::to_string(it->topology) + "}\n";
  }
  EXPECT_EQ(discover(parse_scan_yaml(text, "master.yaml"), catalog),
            simbus::tree_from_assembly(assembly, catalog));
}

TEST(Discovery, SlavesMayArriveInAnyOrder) {
  const EscCatalog catalog = simbus::synthetic_catalog();
  EscScan scan = make_scan({{0b0011, test::kJoint, 1}, {0b0001, test::kTool, 2}});
  std::swap(scan.slaves[0], scan.slaves[1]);
  const ModuleTree tree = discover(scan, catalog);
  EXPECT_EQ(tree.modules[1].key, "tool");
  EXPECT_EQ(tree.modules[1].parent_connector, 1);
}

TEST(Discovery, ThreeEscModule) {
  // tri: connector 1 on port 3 of its first ESC, ESC b on port 1 (connectors 2, 3 on its
  // ports 3 and 2), ESC c on port 2 (connector 4 on its port 1).
  const EscCatalog catalog = simbus::synthetic_catalog();
  const EscIdentity tri{2, 5, 1, 0}, tri_b{2, 6, 1, 0}, tri_c{2, 7, 1, 0};
  const EscScan scan = make_scan({{0b1111, tri, 1},
                                  {0b0001, test::kTool, 2},  // connector 1
                                  {0b1101, tri_b, 3},
                                  {0b0001, test::kTool, 4},  // connector 2
                                  {0b0001, test::kTool, 5},  // connector 3
                                  {0b0011, tri_c, 6},
                                  {0b0001, test::kTool, 7}});  // connector 4
  const ModuleTree tree = discover(scan, catalog);
  ASSERT_EQ(tree.modules.size(), 5u);
  EXPECT_EQ(tree.modules[0].slave_positions, (std::vector<int32_t>{1, 3, 6}));
  std::vector<int32_t> connectors;
  for (std::size_t m = 1; m < 5; ++m) connectors.push_back(tree.modules[m].parent_connector);
  EXPECT_EQ(connectors, (std::vector<int32_t>{1, 2, 3, 4}));
  EXPECT_EQ(tree.slaves[5].module_index, 0);
  EXPECT_EQ(tree.slaves[5].parent_port, 2);
}

TEST(Discovery, UnknownIdentityIsAnUnknownModuleInTheTree) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
  assembly.faults.push_back(
      simbus::Fault{simbus::FaultType::kUnknownIdentity, "elbow_1", std::nullopt, {1, 99, 4, 0}});
  const ModuleTree tree = discover(simbus::simulate_scan(assembly, catalog), catalog);
  ASSERT_EQ(tree.issues.size(), 1u);
  EXPECT_EQ(tree.issues[0].severity, TreeIssue::Severity::kWarning);
  EXPECT_EQ(tree.issues[0].text(),
            "slave 12: unknown module identity (mod_type 1, mod_id 99, mod_size 4, mod_rev 0): "
            "not in the ESC catalogue; unknown module in the tree");
  EXPECT_EQ(tree.unknown_modules(), (std::vector<int32_t>{10}));
  const auto& elbow = tree.modules[10];
  EXPECT_FALSE(elbow.known);
  EXPECT_EQ(elbow.key, "");
  EXPECT_EQ(elbow.kind, ModuleKind::kJoint);  // mod_type 1 still says joint
  EXPECT_EQ(elbow.parent_connector, 1);
  EXPECT_EQ(tree.modules[11].parent_module, 10);
  EXPECT_EQ(tree.modules[11].parent_connector, -1);  // the unknown module's connectors are unknown
  EXPECT_EQ(tree.modules.size(), 18u);               // everything else as assembled
}

TEST(Discovery, JointWithTwoChildren) {
  const EscCatalog catalog = simbus::synthetic_catalog();
  const EscScan scan =
      make_scan({{0b1011, test::kJoint}, {0b0001, test::kTool}, {0b0001, test::kTool}});
  // A two-port board with port 3 open contradicts the joint's single output connector.
  EXPECT_EQ(discover_error(scan, catalog),
            "slave 1: module #0 joint (joint) has 2 child modules but joint has 1 output "
            "connector (1 on port 1); slave 2 hangs on port 3 of slave 1");
}

TEST(Discovery, LinkWithTwoChildren) {
  const EscCatalog catalog = simbus::synthetic_catalog();
  const EscScan scan = make_scan({{0b0011, test::kJoint},
                                  {0b1011, test::kLink},
                                  {0b0001, test::kTool},
                                  {0b0001, test::kTool}});
  EXPECT_NE(
      discover_error(scan, catalog).find("slave 2: module #1 link (link) has 2 child modules"),
      std::string::npos);
}

TEST(Discovery, EndEffectorAndWheelWithAnyChild) {
  const EscCatalog catalog = simbus::synthetic_catalog();
  EXPECT_EQ(discover_error(
                make_scan({{0b0011, test::kJoint}, {0b0011, test::kTool}, {0b0001, test::kJoint}}),
                catalog),
            "slave 2: module #1 tool (end_effector) has 1 child module but tool has no output "
            "connector; slave 3 hangs on port 1 of slave 2");
  EXPECT_NE(discover_error(
                make_scan({{0b0011, test::kJoint}, {0b0011, test::kWheel}, {0b0001, test::kTool}}),
                catalog)
                .find("slave 2: module #1 wheel (wheel) has 1 child module"),
            std::string::npos);
}

TEST(Discovery, ChildOnAPortWithoutConnector) {
  // hub2 has connectors 1, 2 on ports 3, 1; a single child on port 2 is on no connector.
  const EscCatalog catalog = simbus::synthetic_catalog();
  EXPECT_EQ(discover_error(make_scan({{0b0101, test::kHub2}, {0b0001, test::kTool}}), catalog),
            "slave 2: hangs on port 2 of slave 1, which is not an output connector of module #0 "
            "hub2 (hub): it has 2 output connectors (1 on port 3, 2 on port 1)");
}

TEST(Discovery, WrongOrMissingSecondaryEsc) {
  const EscCatalog catalog = simbus::synthetic_catalog();
  EXPECT_EQ(discover_error(make_scan({{0b1001, test::kBase}, {0b0001, test::kJoint}}), catalog),
            "slave 2: hangs on port 3 of slave 1, where module #0 base (hub) has its ESC "
            "(mod_type 2, mod_id 4, mod_size 1, mod_rev 0), but reports (mod_type 1, mod_id 1, "
            "mod_size 1, mod_rev 0)");
  EXPECT_EQ(discover_error(make_scan({{0b0011, test::kBase}, {0b0001, test::kTool}}), catalog),
            "slave 1: module #0 base (hub) lacks its ESC (mod_type 2, mod_id 4, mod_size 1, "
            "mod_rev 0) on port 3 of its ESC 1");
}

TEST(Discovery, ScanChecksComeFirst) {
  const EscCatalog catalog = simbus::synthetic_catalog();
  EXPECT_EQ(discover_error(EscScan{}, catalog), "the scan has no slaves");
  EscScan scan = make_scan({{0b0011, test::kJoint}, {0b0001, test::kTool}});
  scan.slaves[1].topology = 3;
  const ModuleTree tree = discover(scan, catalog);  // a warning, not an error
  ASSERT_EQ(tree.issues.size(), 1u);
  EXPECT_NE(tree.issues[0].text().find("slave 2: topology says 3"), std::string::npos);
  scan.slaves[1].active_ports = 0b0010;
  EXPECT_NE(discover_error(scan, catalog).find("slave 2: port 0 (upstream) is closed"),
            std::string::npos);
}

TEST(Discovery, UpsideDownModuleIsCaughtOrChangesTheTree) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const auto faulty = simbus::load_assembly(kExamples + "/faulty_upside_down_elbow.yaml");
  // The elbow's EPU comes after its subtree (yaw_2, drill take the link's port): nothing is
  // left for it to hang on.
  EXPECT_NE(discover_error(simbus::simulate_scan(faulty, catalog), catalog)
                .find("slave 8: no earlier slave has a free open port"),
            std::string::npos);
  // Appendix A Example II: B is seen first and A seems to hang on nothing.
  const EscCatalog synthetic = simbus::synthetic_catalog();
  const auto ex2 = simbus::parse_assembly(
      "modules:\n  - {name: A, key: hub3}\n  - {name: B, key: joint, parent: A, connector: 2}\n"
      "faults:\n  - {type: upside_down, module: A, upstream_port: 2}\n",
      "ex2");
  EXPECT_NE(discover_error(simbus::simulate_scan(ex2, synthetic, PortOrder::kNumeric0123),
                           synthetic, DiscoveryParams{PortOrder::kNumeric0123})
                .find("slave 2: no earlier slave has a free open port"),
            std::string::npos);
}

TEST(Discovery, BrokenLinkGivesTheSmallerTree) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
  assembly.faults.push_back(
      simbus::Fault{simbus::FaultType::kBrokenLink, "yaw_1", std::nullopt, {}});
  const ModuleTree tree = discover(simbus::simulate_scan(assembly, catalog), catalog);
  EXPECT_EQ(tree.modules.size(), 9u);  // base and the four legs
  EXPECT_NE(tree, simbus::tree_from_assembly(assembly, catalog));
}

TEST(Discovery, InconsistentCatalogueIsRefusedAtConstruction) {
  EscCatalog catalog = simbus::synthetic_catalog();
  EscType bad;
  bad.identity = EscIdentity{2, 42, 0, 0};
  bad.key = "bad";
  bad.kind = ModuleKind::kHub;
  bad.ports = {PortLead{1, 1, std::nullopt}, PortLead{2, 1, std::nullopt}};
  EXPECT_THROW(catalog.add(bad), CatalogError);
}

}  // namespace
}  // namespace concert::topology
