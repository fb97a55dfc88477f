#include "concert/topology/scan_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace concert::topology {
namespace {

std::string error_of(const std::string& text, bool json = false) {
  try {
    if (json) {
      (void)parse_scan_json(text, "scan.json");
    } else {
      (void)parse_scan_yaml(text, "scan.yaml");
    }
  } catch (const ScanFormatError& e) {
    return e.what();
  }
  return "";
}

void expect_two_slaves(const EscScan& scan) {
  ASSERT_EQ(scan.slaves.size(), 2u);
  EXPECT_EQ(scan.slaves[0].position, 1);
  EXPECT_EQ(scan.slaves[0].active_ports, 15);
  EXPECT_EQ(scan.slaves[0].topology, 4);
  EXPECT_EQ(scan.slaves[0].esc_type, 50);
  EXPECT_EQ(scan.slaves[0].identity, (EscIdentity{2, 3, 0, 0}));
  EXPECT_EQ(scan.slaves[0].robot_id, 201);
  EXPECT_EQ(scan.slaves[1].position, 2);
  EXPECT_EQ(scan.slaves[1].active_ports, 1);
  EXPECT_EQ(scan.slaves[1].identity, (EscIdentity{1, 6, 4, 0}));
  EXPECT_EQ(scan.slaves[1].robot_id, 12);
}

TEST(ScanIo, ListUnderSlaves) {
  expect_two_slaves(parse_scan_yaml(R"(
slaves:
  - {position: 1, active_ports: 15, topology: 4, esc_type: 50, mod_type: 2, mod_id: 3, mod_size: 0, mod_rev: 0, robot_id: 201}
  - {position: 2, active_ports: 1, topology: 1, esc_type: 50, mod_type: 1, mod_id: 6, mod_size: 4, mod_rev: 0, robot_id: 12}
)", "s"));
}

TEST(ScanIo, MappingKeyedByPosition) {
  // The form the CONCERT EtherCAT master reports; entries may leave `position` out.
  expect_two_slaves(parse_scan_yaml(R"(
2: {active_ports: 1, esc_type: 50, mod_id: 6, mod_rev: 0, mod_size: 4, mod_type: 1, robot_id: 12, topology: 1}
1: {active_ports: 15, esc_type: 50, mod_id: 3, mod_rev: 0, mod_size: 0, mod_type: 2, position: 1, robot_id: 201, topology: 4}
)", "s"));
}

TEST(ScanIo, MappingKeyedByRobotId) {
  expect_two_slaves(parse_scan_yaml(R"(
slaves:
  12: {active_ports: 1, esc_type: 50, mod_id: 6, mod_rev: 0, mod_size: 4, mod_type: 1, position: 2, robot_id: 12, topology: 1}
  201: {active_ports: 15, esc_type: 50, mod_id: 3, mod_rev: 0, mod_size: 0, mod_type: 2, position: 1, robot_id: 201, topology: 4}
)", "s"));
}

TEST(ScanIo, JsonListAndKeyed) {
  expect_two_slaves(parse_scan_json(R"({"slaves": [
 {"position": 1, "active_ports": 15, "topology": 4, "esc_type": 50, "mod_type": 2, "mod_id": 3, "mod_size": 0, "mod_rev": 0, "robot_id": 201},
 {"position": 2, "active_ports": 1, "topology": 1, "esc_type": 50, "mod_type": 1, "mod_id": 6, "mod_size": 4, "mod_rev": 0, "robot_id": 12}]})",
                                    "s.json"));
  expect_two_slaves(parse_scan_json(R"({
 "201": {"position": 1, "active_ports": 15, "topology": 4, "esc_type": 50, "mod_type": 2, "mod_id": 3, "mod_size": 0, "mod_rev": 0, "robot_id": 201},
 "2": {"active_ports": 1, "topology": 1, "esc_type": 50, "mod_type": 1, "mod_id": 6, "mod_size": 4, "mod_rev": 0, "robot_id": 12}})",
                                    "s.json"));
}

TEST(ScanIo, OptionalFieldsGetDefaults) {
  const EscScan scan = parse_scan_yaml(
      "slaves:\n  - {position: 1, active_ports: 9, mod_type: 1, mod_id: 6, mod_size: 4, "
      "mod_rev: 0}\n",
      "s");
  ASSERT_EQ(scan.slaves.size(), 1u);
  EXPECT_EQ(scan.slaves[0].topology, 2);  // from the mask
  EXPECT_EQ(scan.slaves[0].robot_id, -1);
  EXPECT_EQ(scan.slaves[0].esc_type, 0);
}

TEST(ScanIo, ErrorsNameFileEntryAndField) {
  EXPECT_EQ(error_of("slaves:\n  - {position: 1, active_ports: 1, mod_type: 1, mod_id: 6, "
                     "mod_size: 4}\n"),
            "scan.yaml: slaves[0]: missing field 'mod_rev' (line 2)");
  struct Case {
    std::string scan;
    std::string error;  // a part of the expected message
    bool json = false;
  };
  const std::vector<Case> cases = {
      {"slaves:\n"
       "  - {position: 1, active_ports: 16, mod_type: 1, mod_id: 6, mod_size: 4, mod_rev: 0}\n",
       "slaves[0].active_ports: 16 is not a 4-bit port mask"},
      {"slaves:\n"
       "  - {position: one, active_ports: 1, mod_type: 1, mod_id: 6, mod_size: 4, mod_rev: 0}\n",
       "slaves[0].position: 'one' is not an integer"},
      {"slaves:\n  - {active_ports: 1, mod_type: 1, mod_id: 6, mod_size: 4, mod_rev: 0}\n",
       "slaves[0]: missing field 'position'"},
      {"7: {position: 2, robot_id: 5, active_ports: 1, mod_type: 1, mod_id: 6, mod_size: 4, "
       "mod_rev: 0}\n",
       "scan.yaml: [7]: key 7 is neither the slave's position 2 nor its robot_id"},
      {"abc: {position: 2, active_ports: 1, mod_type: 1, mod_id: 6, mod_size: 4, mod_rev: 0}\n",
       "key 'abc' is not a slave position or robot_id"},
      {"slaves: 3\n", "expected a list under 'slaves:'"},
      {"", "empty scan file"},
      {"slaves: [\n", "scan.yaml: not valid YAML"},
      {"{\"slaves\": [}", "scan.json: not valid JSON", true},
      {"{\"slaves\": [{\"position\": 1, \"active_ports\": \"x\"}]}",
       "scan.json: slaves[0].active_ports: 'x' is not an integer", true},
  };
  for (const Case& c : cases) {
    const std::string error = error_of(c.scan, c.json);
    EXPECT_NE(error.find(c.error), std::string::npos) << c.scan << "\ngave: " << error;
  }
  EXPECT_THROW((void)load_scan("/nonexistent/scan.yaml"), ScanFormatError);
}

TEST(ScanIo, RoundTripThroughFilesInBothFormats) {
  EscScan scan;
  for (int32_t i = 1; i <= 3; ++i) {
    EscSlave s;
    s.position = i;
    s.active_ports = static_cast<uint8_t>(i == 3 ? 1 : 9);
    s.topology = i == 3 ? 1 : 2;
    s.esc_type = 50;
    s.identity = EscIdentity{1, i, 4, 0};
    s.robot_id = i == 2 ? -1 : 10 + i;
    scan.slaves.push_back(s);
  }
  const auto dir = std::filesystem::temp_directory_path() / "concert_scan_io_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "scan.yaml") << scan_to_yaml(scan);
    std::ofstream(dir / "scan.json") << scan_to_json(scan).dump();
  }
  EXPECT_EQ(load_scan(dir / "scan.yaml"), scan);
  EXPECT_EQ(load_scan(dir / "scan.json"), scan);
  std::filesystem::remove_all(dir);
  // An empty scan too (found by tests/fuzz: "slaves:" alone reads as null, not as no slave).
  EXPECT_EQ(parse_scan_yaml(scan_to_yaml(EscScan{}), "empty.yaml"), EscScan{});
}

TEST(TreeJson, HasTheDiscoverShape) {
  ModuleTree tree;
  SlaveNode root;
  root.slave.position = 1;
  root.slave.active_ports = 9;
  root.slave.topology = 2;
  root.slave.identity = EscIdentity{1, 6, 4, 0};
  root.slave.robot_id = 7;
  root.module_index = 0;
  SlaveNode child;
  child.slave.position = 2;
  child.slave.active_ports = 1;
  child.slave.topology = 1;
  child.slave.identity = EscIdentity{3, 3, 4, 0};
  child.parent_position = 1;
  child.parent_port = 3;
  child.module_index = 1;
  tree.slaves = {root, child};
  tree.modules = {ModuleNode{0, "elbow", ModuleKind::kJoint, {1, 6, 4, 0}, {1}, -1, -1, 7},
                  ModuleNode{1, "drill", ModuleKind::kEndEffector, {3, 3, 4, 0}, {2}, 0, 1, -1}};
  const nlohmann::json j = tree_to_json(tree);
  ASSERT_EQ(j["slaves"].size(), 2u);
  EXPECT_EQ(j["slaves"][0]["parent_position"], 0);
  EXPECT_TRUE(j["slaves"][0]["parent_port"].is_null());
  EXPECT_EQ(j["slaves"][1]["parent_position"], 1);
  EXPECT_EQ(j["slaves"][1]["parent_port"], 3);
  EXPECT_EQ(j["slaves"][1]["module"], 1);
  EXPECT_EQ(j["slaves"][1]["module_key"], "drill");
  EXPECT_EQ(j["slaves"][0]["active_ports"], 9);
  EXPECT_EQ(j["slaves"][0]["robot_id"], 7);
  EXPECT_EQ(j["slaves"][1]["mod_type"], 3);
  EXPECT_EQ(j["modules"][1]["kind"], "end_effector");
  EXPECT_EQ(j["modules"][1]["parent_connector"], 1);
  const std::string text = tree_to_text(tree);
  EXPECT_NE(text.find("#0 elbow (joint) slave 1 robot_id 7"), std::string::npos) << text;
  EXPECT_NE(text.find("`-- [1] #1 drill (end_effector) slave 2"), std::string::npos) << text;

  // What `concert discover --json` prints reads back as the same tree.
  EXPECT_EQ(tree_from_json(j, "tree.json").modules, tree.modules);
  nlohmann::json broken = j;
  broken["modules"][1].erase("parent_connector");
  try {
    tree_from_json(broken, "tree.json");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("tree.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("parent_connector"), std::string::npos) << e.what();
  }
  // Found by tests/fuzz: a key that is not a string threw the JSON library's type_error; an
  // integer beyond int32 was silently cut.
  const auto error_of = [](const nlohmann::json& doc) {
    try {
      tree_from_json(doc, "tree.json");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  broken = j;
  broken["modules"][0]["key"] = 5;
  EXPECT_EQ(error_of(broken), "tree.json: modules[0].key: expected a string");
  broken = j;
  broken["modules"][1]["parent_module"] = 4294967296;
  EXPECT_EQ(error_of(broken), "tree.json: modules[1].parent_module: 4294967296 is out of range");
  broken = j;
  broken["modules"][1]["slave_positions"] = {-2147483649};
  EXPECT_EQ(error_of(broken), "tree.json: modules[1].slave_positions: -2147483649 is out of range");
}

}  // namespace
}  // namespace concert::topology
