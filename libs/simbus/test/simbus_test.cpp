#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "concert/common/error_text.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/simbus/random_robot.hpp"
#include "concert/simbus/testing.hpp"

namespace concert::simbus {
namespace {

using topology::EscCatalog;
using topology::EscIdentity;
using topology::EscScan;
using topology::PortOrder;

const std::string kPublicDb = std::string(CONCERT_SHARED_DATA) + "/concert_resources";
const std::string kExamples = std::string(SIMBUS_EXAMPLES);

std::string error_of(const std::string& yaml, const EscCatalog& catalog) {
  return error_text<AssemblyError>([&] { validate(parse_assembly(yaml, "a.yaml"), catalog); }, "");
}

/// The scan of the assembly text `yaml` over the synthetic catalogue.
EscScan synthetic_scan(const std::string& yaml, PortOrder order = PortOrder::kReal0312) {
  return simulate_scan(parse_assembly(yaml, "test"), synthetic_catalog(), order);
}

/// Appendix A, Figure A1: slave B on port 2 of slave A (paper's simplified order 0-1-2-3).
TEST(SimBus, AppendixAExampleOne) {
  const EscScan scan = synthetic_scan(
      "modules:\n  - {name: A, key: hub3, robot_id: 1}\n"
      "  - {name: B, key: joint, parent: A, connector: 2, robot_id: 2}\n",
      PortOrder::kNumeric0123);
  ASSERT_EQ(scan.slaves.size(), 2u);
  EXPECT_EQ(scan.slaves[0].robot_id, 1);
  EXPECT_EQ(scan.slaves[0].active_ports, 0b0101);  // port 0 (master) and port 2 (B)
  EXPECT_EQ(scan.slaves[0].topology, 2);
  EXPECT_EQ(scan.slaves[1].robot_id, 2);
  EXPECT_EQ(scan.slaves[1].active_ports, 0b0001);
  EXPECT_EQ(scan.slaves[1].identity, (EscIdentity{1, 1, 1, 0}));
}

/// Example II: slave A connected upside down: its EPU is met after slave B's.
TEST(SimBus, AppendixAExampleTwoUpsideDown) {
  const EscCatalog catalog = synthetic_catalog();
  const Assembly a = parse_assembly(
      "modules:\n  - {name: A, key: hub3, robot_id: 1}\n"
      "  - {name: B, key: joint, parent: A, connector: 2, robot_id: 2}\n"
      "faults:\n  - {type: upside_down, module: A, upstream_port: 2}\n",
      "ex2");
  // Connector 2 is on port 2 under 0-1-2-3 but on port 1 under the real 0-3-1-2.
  Assembly real = a;
  real.faults[0].upstream_port = 1;
  for (PortOrder order : {PortOrder::kNumeric0123, PortOrder::kReal0312}) {
    const EscScan scan =
        simulate_scan(order == PortOrder::kReal0312 ? real : a, catalog, order);
    ASSERT_EQ(scan.slaves.size(), 2u);
    EXPECT_EQ(scan.slaves[0].robot_id, 2) << to_string(order);
    EXPECT_EQ(scan.slaves[1].robot_id, 1) << to_string(order);
  }
}

TEST(SimBus, RealFrameOrderVisitsPortThreeFirst) {
  const EscCatalog catalog = synthetic_catalog();
  const Assembly a = parse_assembly(R"(
modules:
  - {name: hub, key: hub3, robot_id: 1}
  - {name: on1, key: tool, parent: hub, connector: 1, robot_id: 2}
  - {name: on2, key: tool, parent: hub, connector: 2, robot_id: 3}
  - {name: on3, key: tool, parent: hub, connector: 3, robot_id: 4}
)", "cross");
  // Connector k on the k-th port after 0 in frame order, so ring order = connector order in
  // both orders, but the ports differ.
  for (PortOrder order : {PortOrder::kReal0312, PortOrder::kNumeric0123}) {
    const EscScan scan = simulate_scan(a, catalog, order);
    ASSERT_EQ(scan.slaves.size(), 4u);
    EXPECT_EQ(scan.slaves[0].active_ports, 15);
    EXPECT_EQ(scan.slaves[0].topology, 4);
    for (int i = 1; i < 4; ++i) EXPECT_EQ(scan.slaves[static_cast<std::size_t>(i)].robot_id, i + 1);
    const auto tree = tree_from_assembly(a, catalog, order);
    const int32_t first_port = order == PortOrder::kReal0312 ? 3 : 1;
    EXPECT_EQ(tree.slaves[1].parent_port, first_port);
  }
  // Explicit wiring: connector 1 on port 1, connector 2 on port 3 -> ring order 2, 1 under the
  // real order (port 3 first).
  const EscCatalog wired = EscCatalog::parse(R"(
modules:
  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: hub, ports: [{port: 1, leads_to: 1}, {port: 3, leads_to: 2}]}
  - {mod_type: 3, mod_id: 1, mod_size: 0, mod_rev: 0, key: tool}
)", "wired");
  const Assembly b = parse_assembly(R"(
modules:
  - {name: hub, key: hub}
  - {name: a, key: tool, parent: hub, connector: 1, robot_id: 1}
  - {name: b, key: tool, parent: hub, connector: 2, robot_id: 2}
)", "b");
  const EscScan real = simulate_scan(b, wired, PortOrder::kReal0312);
  EXPECT_EQ(real.slaves[1].robot_id, 2);
  EXPECT_EQ(real.slaves[2].robot_id, 1);
  const EscScan numeric = simulate_scan(b, wired, PortOrder::kNumeric0123);
  EXPECT_EQ(numeric.slaves[1].robot_id, 1);
  EXPECT_EQ(numeric.slaves[2].robot_id, 2);
}

TEST(SimBus, PaperRobotScan) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const Assembly a = load_assembly(kExamples + "/concert_paper_robot.yaml");
  const EscScan scan = simulate_scan(a, catalog);
  ASSERT_EQ(scan.slaves.size(), 19u);
  // Power board first: master on 0, hub board on 3, rear-right leg on 1, arm on 2.
  EXPECT_EQ(scan.slaves[0].identity, (EscIdentity{2, 3, 0, 0}));
  EXPECT_EQ(scan.slaves[0].active_ports, 15);
  EXPECT_EQ(scan.slaves[0].robot_id, 100);
  EXPECT_EQ(scan.slaves[1].identity, (EscIdentity{2, 4, 0, 0}));
  EXPECT_EQ(scan.slaves[1].active_ports, 15);
  EXPECT_EQ(scan.slaves[1].robot_id, 101);
  // Hub board: connector 1 (front-left) on port 3 first, then 2 (port 1), 3 (port 2).
  const int32_t legs[] = {11, 12, 21, 22, 31, 32, 41, 42};
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(scan.slaves[2 + i].robot_id, legs[i]) << i;
  EXPECT_EQ(scan.slaves[2].active_ports, 0b0011);  // steering: input + wheel on port 1
  EXPECT_EQ(scan.slaves[2].esc_type, 21);
  EXPECT_EQ(scan.slaves[3].active_ports, 0b0001);  // wheel
  EXPECT_EQ(scan.slaves[10].robot_id, 51);         // arm after the rear-right leg
  EXPECT_EQ(scan.slaves[12].robot_id, -1);         // passive link
  EXPECT_EQ(scan.slaves[12].identity, (EscIdentity{4, 6, 4, 0}));
  EXPECT_EQ(scan.slaves[18].robot_id, 60);
  EXPECT_EQ(scan.slaves[18].active_ports, 1);
  for (std::size_t i = 0; i < scan.slaves.size(); ++i) {
    EXPECT_EQ(scan.slaves[i].position, static_cast<int32_t>(i) + 1);
  }

  const auto tree = tree_from_assembly(a, catalog);
  ASSERT_EQ(tree.modules.size(), 18u);
  ASSERT_EQ(tree.slaves.size(), 19u);
  EXPECT_EQ(tree.modules[0].key, "mobile_platform_concert");
  EXPECT_EQ(tree.modules[0].slave_positions, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(tree.slaves[1].parent_position, 1);
  EXPECT_EQ(tree.slaves[1].parent_port, 3);
  EXPECT_EQ(tree.slaves[1].module_index, 0);
  EXPECT_EQ(tree.modules[9].key, "module_joint_yaw_A_concert");
  EXPECT_EQ(tree.modules[9].parent_connector, 5);
  EXPECT_EQ(tree.slaves[10].parent_position, 1);
  EXPECT_EQ(tree.slaves[10].parent_port, 2);
  EXPECT_EQ(tree.modules[17].key, "module_drill_concert");
  EXPECT_EQ(tree.modules[17].parent_module, 16);
}

TEST(SimBus, ExamplesAreValid) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  for (const char* file : {"concert_paper_robot.yaml", "concert_torso_two_arms.yaml",
                           "faulty_upside_down_elbow.yaml"}) {
    const Assembly a = load_assembly(kExamples + "/" + file);
    EXPECT_NO_THROW(validate(a, catalog)) << file;
    EXPECT_FALSE(simulate_scan(a, catalog).slaves.empty()) << file;
  }
  const auto torso = tree_from_assembly(load_assembly(kExamples + "/concert_torso_two_arms.yaml"),
                                        catalog);
  EXPECT_EQ(torso.modules.size(), 22u);
  EXPECT_EQ(torso.slaves.size(), 23u);
}

TEST(SimBus, UpsideDownElbowComesAfterItsSubtree) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const Assembly a = load_assembly(kExamples + "/faulty_upside_down_elbow.yaml");
  const EscScan scan = simulate_scan(a, catalog);
  ASSERT_EQ(scan.slaves.size(), 8u);
  std::vector<int32_t> ids;
  for (const auto& s : scan.slaves) ids.push_back(s.robot_id);
  // base (2 ESCs), yaw_1, elbow_1, link_1, then yaw_2 and drill before elbow_2.
  EXPECT_EQ(ids, (std::vector<int32_t>{100, 101, 51, 52, -1, 54, 60, 53}));
  EXPECT_EQ(scan.slaves[7].active_ports, 0b0011);  // ports 0 and 1, swapped roles
}

TEST(SimBus, UpsideDownLeafHasPortZeroClosed) {
  const EscScan scan = synthetic_scan(
      "modules:\n  - {name: j, key: joint}\n  - {name: t, key: tool, parent: j, connector: 1}\n"
      "faults:\n  - {type: upside_down, module: t}\n");
  ASSERT_EQ(scan.slaves.size(), 2u);
  EXPECT_EQ(scan.slaves[1].active_ports, 0b0010);  // entered through port 1, port 0 closed
}

TEST(SimBus, BrokenLinkDropsTheSubtreeAndClosesThePort) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  Assembly a = load_assembly(kExamples + "/concert_paper_robot.yaml");
  a.faults.push_back(Fault{FaultType::kBrokenLink, "link_2", std::nullopt, {}});
  const EscScan scan = simulate_scan(a, catalog);
  ASSERT_EQ(scan.slaves.size(), 15u);  // link_2, elbow_3, yaw_3, drill gone
  EXPECT_EQ(scan.slaves.back().robot_id, 54);
  EXPECT_EQ(scan.slaves.back().active_ports, 1);
  a.faults = {Fault{FaultType::kBrokenLink, "base", std::nullopt, {}}};
  EXPECT_TRUE(simulate_scan(a, catalog).slaves.empty());
}

TEST(SimBus, UnknownIdentityIsReported) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  Assembly a = load_assembly(kExamples + "/concert_paper_robot.yaml");
  a.faults.push_back(Fault{FaultType::kUnknownIdentity, "elbow_1", std::nullopt, {1, 99, 4, 0}});
  const EscScan scan = simulate_scan(a, catalog);
  EXPECT_EQ(scan.slaves[11].identity, (EscIdentity{1, 99, 4, 0}));
  EXPECT_EQ(scan.slaves[11].robot_id, 52);
}

TEST(SimBus, AssemblyYamlRoundTrip) {
  const EscCatalog catalog = synthetic_catalog();
  std::mt19937 rng(7);
  Assembly a = random_assembly(catalog, rng, {});
  a.faults = {Fault{FaultType::kUpsideDown, "m1", 1, {}}, Fault{FaultType::kBrokenLink, "m2", {}, {}},
              Fault{FaultType::kUnknownIdentity, "m3", {}, {9, 9, 9, 9}}};
  const Assembly b = parse_assembly(assembly_to_yaml(a), "again");
  EXPECT_EQ(b.modules, a.modules);
  EXPECT_EQ(b.faults, a.faults);
}

TEST(SimBus, AssemblyErrorsNameFileModuleAndField) {
  const EscCatalog catalog = synthetic_catalog();
  struct Case {
    std::string assembly;
    std::string error;  // a part of the expected message
  };
  const std::vector<Case> cases = {
      {"modules:\n  - {name: a, key: nope}\n",
       "a.yaml: module 'a': key 'nope' is not in the ESC catalogue"},
      {"modules:\n  - {name: a, key: joint}\n  - {name: a, key: joint, parent: a, connector: 1}\n",
       "module 'a': name used twice"},
      {"modules:\n  - {name: a, key: joint}\n  - {name: b, key: joint, parent: a, connector: 2}\n",
       "module 'b': parent 'a' (joint) has no output connector 2 (it has 1)"},
      {"modules:\n  - {name: a, key: joint}\n  - {name: b, key: joint, parent: a, connector: 1}\n"
       "  - {name: c, key: joint, parent: a, connector: 1}\n",
       "module 'c': connector 1 of 'a' is already taken by 'b'"},
      {"modules:\n  - {name: a, key: joint}\n  - {name: b, key: joint}\n",
       "2 modules have no parent"},
      {"modules:\n  - {name: r, key: joint}\n  - {name: a, key: joint, parent: b, connector: 1}\n"
       "  - {name: b, key: joint, parent: a, connector: 1}\n",
       "is not connected to the root (parent cycle)"},
      {"modules:\n  - {name: a, key: joint}\n  - {name: b, key: joint, parent: x, connector: 1}\n",
       "module 'b': parent 'x' is not a module of the assembly"},
      {"modules:\n  - {name: a, key: joint}\n  - {name: b, key: joint, parent: a}\n",
       "modules[1]: module 'b' has a parent but no 'connector'"},
      {"modules:\n  - {name: a, key: joint}\nfaults:\n  - {type: melted, module: a}\n",
       "faults[0].type: 'melted'"},
      {"modules:\n  - {name: a, key: joint}\nfaults:\n  - {type: broken_link, module: z}\n",
       "faults[0]: module 'z' is not in the assembly"},
      {"modules:\n  - {name: a, key: joint, robot_id: [1, 2]}\n", "2 robot_ids for 1 ESC(s)"},
      {"modules: [\n", "not valid YAML"},
  };
  for (const Case& c : cases) {
    const std::string error = error_of(c.assembly, catalog);
    EXPECT_NE(error.find(c.error), std::string::npos) << c.assembly << "gave: " << error;
  }
  EXPECT_THROW((void)load_assembly("/nonexistent.yaml"), AssemblyError);
}

TEST(SimBus, RandomAssembliesAreValidAndDeterministic) {
  const EscCatalog catalog = synthetic_catalog();
  for (uint32_t seed = 0; seed < 50; ++seed) {
    std::mt19937 rng1(seed), rng2(seed);
    const Assembly a = random_assembly(catalog, rng1, {30, 0.6, 0.2, true});
    const Assembly b = random_assembly(catalog, rng2, {30, 0.6, 0.2, true});
    EXPECT_EQ(a.modules, b.modules);
    EXPECT_NO_THROW(validate(a, catalog)) << seed;
    EXPECT_EQ(simulate_scan(a, catalog).slaves.size(), tree_from_assembly(a, catalog).slaves.size());
  }
}

}  // namespace
}  // namespace concert::simbus

namespace concert::simbus {
namespace {

// Random robots of the project's database: valid assemblies of its catalogue with 3-7 arm
// joints; among 30 seeds every tool, the riser and several arm lengths; the same robot for the
// same seed; each written and read back unchanged.
TEST(RandomRobot, ThirtySeedsGiveValidArmsOf3To7JointsWithEveryTool) {
  const topology::EscCatalog catalog =
      topology::EscCatalog::load(std::string(CONCERT_SOURCE_DIR) + "/data/module_db");
  std::set<std::string> tools;
  std::set<int> lengths;
  int risers = 0;
  for (unsigned seed = 1; seed <= 30; ++seed) {
    std::mt19937 rng(seed);
    const Assembly a = random_robot(rng);
    EXPECT_NO_THROW(validate(a, catalog)) << "seed " << seed << ":\n" << assembly_to_yaml(a);
    int joints = 0;
    for (const MountedModule& m : a.modules) {
      const auto& keys = random_robot_joints();
      joints += static_cast<int>(std::count(keys.begin(), keys.end(), m.key));
      if (m.name == "tool") tools.insert(m.key);
      risers += m.key == "concert_base_link_600" ? 1 : 0;
    }
    EXPECT_GE(joints, 3) << "seed " << seed;
    EXPECT_LE(joints, 7) << "seed " << seed;
    lengths.insert(joints);
    std::mt19937 again(seed);
    EXPECT_EQ(random_robot(again).modules, a.modules) << "seed " << seed;
    EXPECT_EQ(parse_assembly(assembly_to_yaml(a), "random").modules, a.modules) << "seed " << seed;
  }
  EXPECT_EQ(tools.size(), random_robot_tools().size());
  EXPECT_GT(risers, 0);
  EXPECT_GE(lengths.size(), 4u);
}

}  // namespace
}  // namespace concert::simbus
