#include "concert/topology/esc_catalog.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace concert::topology {
namespace {

const std::string kPublicDb = std::string(CONCERT_SHARED_DATA) + "/concert_resources";

std::string error_of(const std::string& yaml) {
  try {
    (void)EscCatalog::parse(yaml, "test.yaml");
  } catch (const CatalogError& e) {
    return e.what();
  }
  return "";
}

TEST(EscCatalog, LoadsThePublicIndex) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  EXPECT_EQ(catalog.entries().size(), 19u);
  const EscType* elbow = catalog.find(EscIdentity{1, 6, 4, 0});
  ASSERT_NE(elbow, nullptr);
  EXPECT_EQ(elbow->key, "module_joint_elbow_A_concert");
  EXPECT_EQ(elbow->file, "json/concert/module_joint_elbow_A_concert.json");
  EXPECT_EQ(elbow->kind, ModuleKind::kJoint);
  EXPECT_EQ(catalog.find_key("module_wheel_concert")->kind, ModuleKind::kWheel);
  EXPECT_EQ(catalog.find(EscIdentity{1, 6, 4, 1}), nullptr);
}

TEST(EscCatalog, MobileBaseHubHasTwoEscsAndFiveConnectors) {
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const ModuleLayout layout = catalog.layout(EscIdentity{2, 3, 0, 0});
  EXPECT_EQ(layout.key, "mobile_platform_concert");
  ASSERT_EQ(layout.escs.size(), 2u);
  EXPECT_EQ(layout.escs[1].identity, (EscIdentity{2, 4, 0, 0}));
  EXPECT_EQ(layout.escs[1].parent_esc, 0);
  EXPECT_EQ(layout.escs[1].parent_port, 3);
  ASSERT_EQ(layout.outputs(), 5);
  // connector -> (esc, port) as the public file's mobile_base_ports say
  const int expected[5][2] = {{1, 3}, {1, 1}, {1, 2}, {0, 1}, {0, 2}};
  for (int c = 1; c <= 5; ++c) {
    const auto* placement = layout.connector(c);
    ASSERT_NE(placement, nullptr) << c;
    EXPECT_EQ(placement->esc, expected[c - 1][0]) << c;
    EXPECT_EQ(placement->port, expected[c - 1][1]) << c;
  }
  EXPECT_EQ(layout.esc_at(0, 3), 1);
  EXPECT_FALSE(layout.esc_at(0, 1));
  EXPECT_EQ(layout.connector_at(1, 3), 1);
  EXPECT_FALSE(layout.connector_at(0, 3));
  // The hub board alone is its own (non-structural) module with connectors 1..3.
  const ModuleLayout board = catalog.layout(EscIdentity{2, 4, 0, 0});
  EXPECT_EQ(board.key, "mobile_platform_concert_non_structural");
  EXPECT_EQ(board.escs.size(), 1u);
  EXPECT_EQ(board.outputs(), 3);
}

TEST(EscCatalog, DefaultConnectorsFollowTheBoards) {
  // Two-port boards (joints, links) put their output on port 1 whatever the frame order
  // (real CONCERT scans: active_ports 3); four-port hub boards follow the frame order 3, 1, 2.
  const EscCatalog catalog = EscCatalog::load(kPublicDb);
  const ModuleLayout elbow = catalog.layout(EscIdentity{1, 6, 4, 0}, PortOrder::kReal0312);
  ASSERT_EQ(elbow.outputs(), 1);
  EXPECT_EQ(elbow.connector(1)->port, 1);
  EXPECT_EQ(elbow.escs[0].board, topology::EscBoard::kTwoPort);
  EXPECT_EQ(elbow.escs[0].esc_type, 21);
  EXPECT_EQ(catalog.layout(EscIdentity{1, 6, 4, 0}, PortOrder::kNumeric0123).connector(1)->port,
            1);
  EXPECT_EQ(catalog.layout(EscIdentity{4, 6, 4, 0}).connector(1)->port, 1);  // link 0.4 m
  EXPECT_EQ(catalog.layout(EscIdentity{4, 6, 4, 0}).escs[0].esc_type, 1280);
  const ModuleLayout torso = catalog.layout(EscIdentity{2, 5, 4, 0});
  ASSERT_EQ(torso.outputs(), 3);
  EXPECT_EQ(torso.connector(1)->port, 3);
  EXPECT_EQ(torso.connector(2)->port, 1);
  EXPECT_EQ(torso.connector(3)->port, 2);
  EXPECT_EQ(torso.escs[0].board, EscBoard::kFourPort);
  // The Mobile Base Hub: power board (type 50) and hub board (type 256), as the real scan shows.
  const ModuleLayout base = catalog.layout(EscIdentity{2, 3, 0, 0});
  ASSERT_EQ(base.escs.size(), 2u);
  EXPECT_EQ(base.escs[0].esc_type, 50);
  EXPECT_EQ(base.escs[1].esc_type, 256);
  EXPECT_EQ(catalog.layout(EscIdentity{3, 3, 4, 0}).outputs(), 0);  // drill
  EXPECT_EQ(catalog.layout(EscIdentity{5, 1, 5, 0}).outputs(), 0);  // wheel
  EXPECT_EQ(catalog.layout(EscIdentity{6, 1, 4, 0}).outputs(), 1);  // base link
}

TEST(EscCatalog, ExtensionsKeyOutputsPortsAndModulePorts) {
  const EscCatalog catalog = EscCatalog::parse(R"(
modules:
  - {mod_type: 1, mod_id: 1, mod_size: 2, mod_rev: 3, file: a/b/my_joint.json}
  - {mod_type: 1, mod_id: 2, mod_size: 2, mod_rev: 3, file: x.json, key: renamed}
  - {mod_type: 2, mod_id: 9, mod_size: 0, mod_rev: 0, key: torso, outputs: 2}
  - {mod_type: 2, mod_id: 8, mod_size: 0, mod_rev: 0, key: wired, ports: [{port: 2, leads_to: 1}, {port: 1, leads_to: 2}]}
  - {mod_type: 2, mod_id: 3, mod_size: 0, mod_rev: 0, key: power}
  - {mod_type: 2, mod_id: 4, mod_size: 0, mod_rev: 0, key: board}
  - {mod_type: 1, mod_id: 3, mod_size: 0, mod_rev: 0, key: fourport_joint, esc_ports: 4, esc_type: 77, outputs: 2}
module_ports:
  - {mod_type: 2, mod_id: 3, port: 3, leads_to: hub_board}
  - {mod_type: 2, mod_id: 3, port: 2, leads_to: 2}
  - {mod_type: 2, mod_id: 4, port: 3, leads_to: 1}
)",
                                               "ext.yaml");
  EXPECT_EQ(catalog.find(EscIdentity{1, 1, 2, 3})->key, "my_joint");
  EXPECT_EQ(catalog.find(EscIdentity{1, 2, 2, 3})->key, "renamed");
  const ModuleLayout torso = catalog.layout(EscIdentity{2, 9, 0, 0}, PortOrder::kNumeric0123);
  ASSERT_EQ(torso.outputs(), 2);
  EXPECT_EQ(torso.connector(2)->port, 2);
  const ModuleLayout wired = catalog.layout(EscIdentity{2, 8, 0, 0});
  EXPECT_EQ(wired.connector(1)->port, 2);
  EXPECT_EQ(wired.connector(2)->port, 1);
  const ModuleLayout power = catalog.layout(EscIdentity{2, 3, 0, 0});
  ASSERT_EQ(power.escs.size(), 2u);
  EXPECT_EQ(power.escs[1].identity, (EscIdentity{2, 4, 0, 0}));
  EXPECT_EQ(power.outputs(), 2);
  EXPECT_EQ(power.connector(1)->esc, 1);
  const ModuleLayout joint4 = catalog.layout(EscIdentity{1, 3, 0, 0});
  EXPECT_EQ(joint4.escs[0].board, EscBoard::kFourPort);
  EXPECT_EQ(joint4.escs[0].esc_type, 77);
  EXPECT_EQ(joint4.connector(1)->port, 3);
  EXPECT_EQ(joint4.connector(2)->port, 1);
}

TEST(EscCatalog, MergeLaterEntriesOverride) {
  EscCatalog a = EscCatalog::parse(
      "modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0, key: old}\n", "a");
  const EscCatalog b = EscCatalog::parse(
      "modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0, key: new}\n"
      "  - {mod_type: 4, mod_id: 1, mod_size: 0, mod_rev: 0, key: link}\n",
      "b");
  a.merge(b);
  EXPECT_EQ(a.entries().size(), 2u);
  EXPECT_EQ(a.find(EscIdentity{1, 1, 0, 0})->key, "new");
}

TEST(EscCatalog, ErrorsNameTheFileRowAndField) {
  struct Case {
    std::string catalogue;
    std::string error;  // a part of the expected message
  };
  const std::vector<Case> cases = {
      {"modules: []", "non-empty"},
      {"modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, file: a.json}",
       "test.yaml: modules[0]: missing field 'mod_rev'"},
      {"modules:\n  - {mod_type: 9, mod_id: 1, mod_size: 0, mod_rev: 0, key: a}",
       "modules[0].mod_type: 9"},
      {"modules:\n  - {mod_type: x, mod_id: 1, mod_size: 0, mod_rev: 0, key: a}",
       "modules[0].mod_type: 'x' is not an integer"},
      {"modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0}", "needs 'file' or 'key'"},
      {"modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0, key: a}\n"
       "  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0, key: b}",
       "modules[1]: identity (mod_type 1, mod_id 1, mod_size 0, "
       "mod_rev 0) already defined by test.yaml: modules[0]"},
      {"modules:\n  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, ports: [{port: 0, "
       "leads_to: 1}]}",
       "modules[0].ports[0].port: 0 is not a downstream ESC port"},
      {"modules:\n  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, ports: [{port: 1, "
       "leads_to: 1}, {port: 2, leads_to: 1}]}",
       "connector 1 is wired to two ports"},
      {"modules:\n  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, ports: [{port: 1, "
       "leads_to: left}]}",
       "leads_to: expected a connector number"},
      {"modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, outputs: 2}",
       "outputs 2 needs port rows (its 2-port ESC board has 1 port after port 0)"},
      {"modules:\n  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, outputs: 4}",
       "outputs 4 needs port rows"},
      {"modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, ports: [{port: 3, "
       "leads_to: 1}]}",
       "port 3 but a joint's ESC board has ports 0 and 1 only"},
      {"modules:\n  - {mod_type: 1, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, esc_ports: 3}",
       "modules[0].esc_ports: 3 is not a board's port count (2 or 4)"},
      {"modules:\n  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: a}\nmodule_ports:\n"
       "  - {mod_type: 2, mod_id: 7, port: 1, leads_to: 1}",
       "module_ports[0]: no module row has mod_type 2 and mod_id 7"},
      {"modules:\n  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: a}\nmodule_ports:\n"
       "  - {mod_type: 2, mod_id: 1, port: 3, leads_to: hub_board}",
       "cannot tell which ESC is the hub board"},
      {"modules:\n  - {mod_type: 2, mod_id: 1, mod_size: 0, mod_rev: 0, key: a, ports: [{port: 3, "
       "leads_to: hub_board, secondary: {mod_type: 2, mod_id: 2, mod_size: 0, mod_rev: 0}}]}",
       "hub board ESC (mod_type 2, mod_id 2, mod_size 0, "
       "mod_rev 0) on port 3 is not in the catalogue"},
      {"modules: [\n", "not valid YAML"},
  };
  for (const Case& c : cases) {
    const std::string error = error_of(c.catalogue);
    EXPECT_NE(error.find(c.error), std::string::npos) << c.catalogue << "\ngave: " << error;
  }
  EXPECT_THROW((void)EscCatalog::load("/nonexistent/db"), CatalogError);
  EXPECT_THROW((void)EscCatalog().layout(EscIdentity{1, 1, 1, 1}), CatalogError);
}

TEST(PortOrder, ParsesAndNamesBothOrders) {
  EXPECT_EQ(parse_port_order("0312"), PortOrder::kReal0312);
  EXPECT_EQ(parse_port_order("0123"), PortOrder::kNumeric0123);
  EXPECT_FALSE(parse_port_order("0321"));
  EXPECT_EQ(to_string(PortOrder::kNumeric0123), "0123");
  EXPECT_EQ(frame_order(PortOrder::kReal0312), (std::array<int32_t, 4>{0, 3, 1, 2}));
  EXPECT_EQ(module_kind_from_mod_type(5), ModuleKind::kWheel);
  EXPECT_FALSE(module_kind_from_mod_type(7));
}

}  // namespace
}  // namespace concert::topology
