// The real scan of the CONCERT robot (../shared/data/ethercat/concert_robot_18slaves.yaml) is
// the fixture that decides where our simulated bus and our discovery could share a wrong
// assumption: it must rebuild to the tree the paper's Appendix A gives, and the simulated bus
// must produce it field for field from an assembly file of the same robot.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/scan_io.hpp"
#include "concert/topology/reconstruction.hpp"
#include "test_data.hpp"

namespace concert::topology {
namespace {

using Severity = TreeIssue::Severity;

using namespace concert::test_data;

const std::string kRealScan = kRealScans + "/concert_robot_18slaves.yaml";
const std::string kAssembly = kExamples + "/concert_robot_18slaves.yaml";

struct Link {
  int32_t parent_position;
  int32_t parent_port;  // -1: on the master
  bool operator==(const Link&) const = default;
};

std::vector<Link> links_of(const ModuleTree& tree) {
  std::vector<Link> out;
  for (const auto& s : tree.slaves) out.push_back({s.parent_position, s.parent_port.value_or(-1)});
  return out;
}

// Appendix A on this ring, with every ESC forwarding 0 -> 3 -> 1 -> 2: the power board (1)
// takes the hub board on port 3 first, then the rear-right leg on port 1 and the arm on port 2;
// the hub board (2) takes the front-left leg on port 3, front-right on 1, rear-left on 2; every
// two-port board (steering, wheel, joint, link) passes the frame on through port 1.
const std::vector<Link> kAppendixA = {
    {0, -1},          // 1 power board, on the master
    {1, 3},           // 2 hub board
    {2, 3},  {3, 1},  // 3, 4 front-left steering + wheel
    {2, 1},  {5, 1},  // 5, 6 front-right
    {2, 2},  {7, 1},  // 7, 8 rear-left
    {1, 1},  {9, 1},  // 9, 10 rear-right
    {1, 2},  {11, 1}, {12, 1}, {13, 1}, {14, 1}, {15, 1}, {16, 1}, {17, 1},  // 11..18 the arm
};

TEST(RealScan, RebuildsToTheTreeOfAppendixA) {
  const EscScan scan = load_scan(kRealScan);
  ASSERT_EQ(scan.slaves.size(), 18u);
  for (const std::string& db : {kPublicDb, kProjectDb}) {
    const ModuleTree tree = Discovery(EscCatalog::load(db)).rebuild(scan);
    EXPECT_TRUE(tree.issues.empty()) << db << ": " << tree_to_text(tree);
    EXPECT_EQ(links_of(tree), kAppendixA) << db;
    ASSERT_EQ(tree.modules.size(), 17u) << db;  // the two boards of the base are one module
    EXPECT_EQ(tree.modules[0].slave_positions, (std::vector<int32_t>{1, 2}));
    EXPECT_EQ(tree.modules[0].kind, ModuleKind::kHub);
    // Legs on base connectors 1..4 in ring order, the arm on connector 5.
    const std::vector<int32_t> leg_connectors{1, 2, 3, 4};
    for (std::size_t leg = 0; leg < 4; ++leg) {
      const auto& steering = tree.modules[1 + 2 * leg];
      const auto& wheel = tree.modules[2 + 2 * leg];
      EXPECT_EQ(steering.parent_module, 0);
      EXPECT_EQ(steering.parent_connector, leg_connectors[leg]);
      EXPECT_EQ(steering.kind, ModuleKind::kJoint);
      EXPECT_EQ(wheel.kind, ModuleKind::kWheel);
      EXPECT_EQ(wheel.parent_module, steering.index);
      EXPECT_EQ(wheel.parent_connector, 1);
    }
    EXPECT_EQ(tree.modules[9].parent_module, 0);
    EXPECT_EQ(tree.modules[9].parent_connector, 5);
    for (std::size_t m = 10; m < 17; ++m) {
      EXPECT_EQ(tree.modules[m].parent_module, static_cast<int32_t>(m) - 1) << m;
      EXPECT_EQ(tree.modules[m].parent_connector, 1) << m;
    }
    int joints = 0;
    int links = 0;
    for (std::size_t m = 9; m < 17; ++m) {
      joints += tree.modules[m].kind == ModuleKind::kJoint ? 1 : 0;
      links += tree.modules[m].kind == ModuleKind::kLink ? 1 : 0;
    }
    EXPECT_EQ(joints, 6) << "a 6-joint arm";
    EXPECT_EQ(links, 2) << "with two passive links";
  }
}

TEST(RealScan, TheSimulatedBusGivesItFieldForField) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const auto assembly = simbus::load_assembly(kAssembly);
  const EscScan real = load_scan(kRealScan);
  const EscScan simulated = simbus::simulate_scan(assembly, catalog);
  ASSERT_EQ(simulated.slaves.size(), real.slaves.size());
  for (std::size_t i = 0; i < real.slaves.size(); ++i) {
    const auto& r = real.slaves[i];
    const auto& s = simulated.slaves[i];
    EXPECT_EQ(s.position, r.position) << i;
    EXPECT_EQ(s.identity, r.identity) << "slave " << r.position;
    EXPECT_EQ(int{s.active_ports}, int{r.active_ports}) << "slave " << r.position;
    EXPECT_EQ(s.topology, r.topology) << "slave " << r.position;
    EXPECT_EQ(s.esc_type, r.esc_type) << "slave " << r.position;
    EXPECT_EQ(s.robot_id, r.robot_id) << "slave " << r.position;
  }
  EXPECT_EQ(simulated, real);
  // And discovery gives the tree the assembly describes.
  EXPECT_EQ(discover(real, catalog), simbus::tree_from_assembly(assembly, catalog));
}

TEST(RealScan, TwoPortBoardsOpenOnlyPortsZeroAndOne) {
  // The fact the simulated bus used to get wrong: joints, wheels and links use ports 0 and 1.
  for (const auto& s : load_scan(kRealScan).slaves) {
    if (s.identity.mod_type == 2) continue;  // hub boards have four ports
    EXPECT_EQ(s.active_ports & 0b1100, 0) << "slave " << s.position;
  }
}

TEST(RealScan, BlankIdentitiesGiveTheTreeWithUnknownModulesAndWarnings) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const EscScan real = load_scan(kRealScan);
  const ModuleTree reference = Discovery(catalog).rebuild(real);

  // A link board (slave 14) with an unprogrammed identity EEPROM: an unknown module where the
  // link was; the joint below it hangs on it with an unknown connector.
  EscScan blank_link = real;
  blank_link.slaves[13].identity = EscIdentity{};
  ModuleTree tree = Discovery(catalog).rebuild(blank_link);
  EXPECT_FALSE(tree.has_errors()) << tree_to_text(tree);
  ASSERT_EQ(tree.issues.size(), 1u);
  EXPECT_EQ(tree.issues[0].severity, Severity::kWarning);
  EXPECT_EQ(tree.issues[0].position, 14);
  EXPECT_NE(tree.issues[0].message.find("blank module identity"), std::string::npos);
  EXPECT_EQ(links_of(tree), kAppendixA);
  EXPECT_EQ(tree.unknown_modules(), (std::vector<int32_t>{12}));
  EXPECT_EQ(tree.modules[12].kind, ModuleKind::kUnknown);
  EXPECT_EQ(tree.modules[12].slave_positions, (std::vector<int32_t>{14}));
  EXPECT_EQ(tree.modules[12].parent_connector, 1);
  EXPECT_EQ(tree.modules[13].parent_module, 12);
  EXPECT_EQ(tree.modules[13].parent_connector, -1);

  // The hub board blank: it sits where the base's layout puts its hub board, so it is taken as
  // that ESC and the module tree is the reference tree.
  EscScan blank_board = real;
  blank_board.slaves[1].identity = EscIdentity{};
  tree = Discovery(catalog).rebuild(blank_board);
  ASSERT_EQ(tree.issues.size(), 1u);
  EXPECT_EQ(tree.issues[0].severity, Severity::kWarning);
  EXPECT_EQ(tree.issues[0].text(),
            "slave 2: reports a blank identity (all zero: identity EEPROM not programmed?) where "
            "module #0 mobile_platform_concert (hub) has its ESC (mod_type 2, mod_id 4, "
            "mod_size 0, mod_rev 0); taken as that ESC");
  EXPECT_EQ(tree.modules, reference.modules);
  EXPECT_TRUE(tree.unknown_modules().empty());
}

TEST(RealScan, TopologyDisagreementsAreWarningsResolvedFromActivePorts) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const EscScan real = load_scan(kRealScan);
  EscScan lying = real;
  lying.slaves[4].topology = 3;   // steering board says 3, active_ports 0b0011 has 2
  lying.slaves[17].topology = 2;  // last elbow says 2, active_ports 0b0001 has 1
  const ModuleTree tree = Discovery(catalog).rebuild(lying);
  EXPECT_FALSE(tree.has_errors());
  ASSERT_EQ(tree.count(Severity::kWarning), 2u);
  EXPECT_EQ(tree.issues[0].position, 5);
  EXPECT_EQ(tree.issues[1].position, 18);
  EXPECT_EQ(links_of(tree), kAppendixA);
  EXPECT_EQ(tree.modules, Discovery(catalog).rebuild(real).modules);
}

TEST(RealScan, TheSimulatedBusReproducesBlankBoardsAndTopologyDisagreements) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  auto assembly = simbus::load_assembly(kAssembly);
  simbus::Fault blank_board{simbus::FaultType::kUnknownIdentity, "base", std::nullopt, {}};
  blank_board.esc = 1;  // the hub board
  simbus::Fault lying{simbus::FaultType::kWrongTopology, "steer_fr", std::nullopt, {}};
  lying.topology = 3;
  assembly.faults = {blank_board, lying};
  EscScan expected = load_scan(kRealScan);
  expected.slaves[1].identity = EscIdentity{};
  expected.slaves[4].topology = 3;
  EXPECT_EQ(simbus::simulate_scan(assembly, catalog), expected);
}

TEST(RealScan, UndefinedPartsAreErrorsAndTheRestIsKept) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  EscScan scan = load_scan(kRealScan);
  scan.slaves.pop_back();  // the last elbow is gone, but the link before it says port 1 is open
  const ModuleTree tree = Discovery(catalog).rebuild(scan);
  ASSERT_TRUE(tree.has_errors());
  EXPECT_EQ(tree.slaves.size(), 17u);
  EXPECT_EQ(tree.issues.back().text(),
            "slave 17: port 1 is open but no slave hangs on it (broken link?)");
  EXPECT_THROW((void)Discovery(catalog).run(scan), DiscoveryError);
}

}  // namespace
}  // namespace concert::topology
