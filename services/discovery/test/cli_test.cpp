#include "discovery/cli.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/scan_io.hpp"
#include "test_data.hpp"

namespace concert::discovery {
namespace {

using ::testing::HasSubstr;

using namespace concert::test_data;

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("concert_discovery_cli_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    const auto catalog = topology::EscCatalog::load(kPublicDb);
    const auto assembly = simbus::load_assembly(kExamples + "/concert_paper_robot.yaml");
    const auto scan = simbus::simulate_scan(assembly, catalog);
    std::ofstream(dir_ / "robot.yaml") << topology::scan_to_yaml(scan);
    std::ofstream(dir_ / "robot.json") << topology::scan_to_json(scan).dump();
    std::ofstream(dir_ / "robot_0123.yaml") << topology::scan_to_yaml(
        simbus::simulate_scan(assembly, catalog, topology::PortOrder::kNumeric0123));
    auto bad = scan;
    bad.slaves[2].active_ports = 0b0010;  // port 0 closed: the tree is undefined from slave 3 on
    std::ofstream(dir_ / "bad.yaml") << topology::scan_to_yaml(bad);
    auto lying = scan;
    lying.slaves[2].topology = 4;  // disagrees with active_ports 0b0011: a warning
    std::ofstream(dir_ / "lying.yaml") << topology::scan_to_yaml(lying);
    std::ofstream(dir_ / "broken.yaml") << "slaves:\n  - {position: 1, active_ports: 1}\n";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  int run(std::vector<std::string> args) {
    out_.str("");
    err_.str("");
    args.insert(args.begin(), "discover");
    return cli::run("concert", {register_verbs}, args, out_, err_);
  }
  std::string file(const char* name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;
  std::ostringstream out_, err_;
};

TEST_F(Cli, JsonOutputHasEverySlaveAndModule) {
  for (const char* name : {"robot.yaml", "robot.json"}) {
    ASSERT_EQ(run({"--scan", file(name), "--module-db", kPublicDb, "--json"}), 0) << err_.str();
    const auto j = nlohmann::json::parse(out_.str());
    ASSERT_EQ(j["slaves"].size(), 19u);
    ASSERT_EQ(j["modules"].size(), 18u);
    const auto& first = j["slaves"][0];
    EXPECT_EQ(first["position"], 1);
    EXPECT_EQ(first["parent_position"], 0);
    EXPECT_TRUE(first["parent_port"].is_null());
    EXPECT_EQ(first["active_ports"], 15);
    EXPECT_EQ(first["mod_type"], 2);
    EXPECT_EQ(first["mod_id"], 3);
    EXPECT_EQ(first["mod_size"], 0);
    EXPECT_EQ(first["mod_rev"], 0);
    EXPECT_EQ(first["robot_id"], 100);
    EXPECT_EQ(first["module"], 0);
    EXPECT_EQ(j["slaves"][1]["parent_port"], 3);
    EXPECT_EQ(j["slaves"][1]["module"], 0);
    EXPECT_EQ(j["slaves"][10]["parent_port"], 2);
    EXPECT_EQ(j["slaves"][10]["module_key"], "module_joint_yaw_A_concert");
    EXPECT_EQ(j["modules"][9]["parent_connector"], 5);
  }
}

TEST_F(Cli, TextOutputAndPortOrder) {
  ASSERT_EQ(run({"--scan", file("robot.yaml"), "--module-db", kPublicDb}), 0) << err_.str();
  EXPECT_THAT(out_.str(), HasSubstr("#0 mobile_platform_concert (hub) slaves 1,2 robot_id 100"));
  EXPECT_THAT(out_.str(), HasSubstr("[5] #9 module_joint_yaw_A_concert (joint) slave 11"));
  ASSERT_EQ(run({"--scan", file("robot_0123.yaml"), "--port-order", "0123", "--module-db",
                 kPublicDb, "--json"}),
            0)
      << err_.str();
  const auto j = nlohmann::json::parse(out_.str());
  EXPECT_EQ(j["slaves"][1]["parent_port"], 1);
}

TEST_F(Cli, BadInputGivesOneLineAndNonZero) {
  EXPECT_EQ(run({"--module-db", kPublicDb}), 2);
  EXPECT_EQ(err_.str(), "concert discover: --scan is required (see `concert discover --help`)\n");
  EXPECT_EQ(run({"--scan"}), 2);
  EXPECT_THAT(err_.str(), HasSubstr("concert discover: --scan: 1 required FILE missing"));
  EXPECT_EQ(run({"--scan", file("robot.yaml"), "--port-order", "0321"}), 2);
  EXPECT_THAT(err_.str(), HasSubstr("--port-order: 0321 not in {0312,0123}"));
  EXPECT_EQ(run({"--scan", file("robot.yaml"), "--frobnicate"}), 2);
  EXPECT_THAT(err_.str(), HasSubstr("not expected: --frobnicate"));
  EXPECT_EQ(run({"--help"}), 0);
  EXPECT_THAT(out_.str(), HasSubstr("--port-order"));

  // An error: the tree rebuilt so far is printed, the error goes to stderr too, exit code 1.
  EXPECT_EQ(run({"--scan", file("bad.yaml"), "--module-db", kPublicDb, "--json"}), 1);
  EXPECT_EQ(err_.str(), "concert discover: " + file("bad.yaml") +
                            ": slave 3: port 0 (upstream) is closed in active_ports 0b0010: every "
                            "slave is reached through port 0 (module mounted upside down?)\n");
  {
    const auto j = nlohmann::json::parse(out_.str());
    EXPECT_EQ(j["slaves"].size(), 2u);  // the power board and the hub board
    ASSERT_EQ(j["errors"].size(), 1u);
    EXPECT_EQ(j["errors"][0]["position"], 3);
    EXPECT_TRUE(j["warnings"].empty());
  }
  // A warning: the whole tree, exit code 0.
  EXPECT_EQ(run({"--scan", file("lying.yaml"), "--module-db", kPublicDb}), 0) << err_.str();
  EXPECT_NE(out_.str().find("warning: slave 3: topology says 4 open ports but active_ports "
                            "0b0011 has 2; using active_ports"),
            std::string::npos)
      << out_.str();
  EXPECT_THAT(out_.str(), HasSubstr("18 modules, 19 slaves"));
  EXPECT_EQ(run({"--scan", file("broken.yaml"), "--module-db", kPublicDb}), 1);
  EXPECT_THAT(err_.str(), HasSubstr(file("broken.yaml") + ": slaves[0]: missing field 'mod_type'"));
  EXPECT_EQ(run({"--scan", file("missing.yaml"), "--module-db", kPublicDb}), 1);
  EXPECT_THAT(err_.str(), HasSubstr("missing.yaml: cannot open the scan file"));
  EXPECT_EQ(run({"--scan", file("robot.yaml"), "--module-db", file("nodb")}), 1);
  EXPECT_THAT(err_.str(), HasSubstr("nodb: module database folder not found"));
  EXPECT_TRUE(out_.str().empty());
  // A database without most modules: the tree is still rebuilt from the ports, with the
  // unknown modules flagged and one warning each.
  std::filesystem::create_directories(dir_ / "db");
  std::ofstream(dir_ / "db" / "esc_index.yaml")
      << "modules:\n  - {mod_type: 1, mod_id: 4, mod_size: 4, mod_rev: 0, key: yaw}\n";
  EXPECT_EQ(run({"--scan", file("robot.yaml"), "--module-db", file("db")}), 0) << err_.str();
  EXPECT_THAT(out_.str(), HasSubstr("#0 UNKNOWN (mod_type 2, mod_id 3, mod_size 0, mod_rev 0) (hub)"));
  EXPECT_NE(out_.str().find("warning: slave 1: unknown module identity (mod_type 2, mod_id 3"),
            std::string::npos)
      << out_.str();
  EXPECT_THAT(out_.str(), HasSubstr("[?] #10 yaw (joint) slave 11"));
}

TEST_F(Cli, SeveralDatabasesMerge) {
  std::filesystem::create_directories(dir_ / "db");
  std::ofstream(dir_ / "db" / "esc_index.yaml")
      << "modules:\n  - {mod_type: 3, mod_id: 3, mod_size: 4, mod_rev: 0, key: my_drill}\n";
  ASSERT_EQ(run({"--scan", file("robot.yaml"), "--module-db", kPublicDb, "--module-db",
                 file("db"), "--json"}),
            0)
      << err_.str();
  EXPECT_EQ(nlohmann::json::parse(out_.str())["modules"][17]["key"], "my_drill");
}

}  // namespace
}  // namespace concert::discovery

namespace concert::discovery {
namespace {

TEST_F(Cli, DefaultIsTheProjectDatabase) {
  // Without --module-db: <source>/data/module_db (the project database, with its own keys).
  ASSERT_EQ(run({"--scan", file("robot.yaml"), "--json"}), 0) << err_.str();
  const auto j = nlohmann::json::parse(out_.str());
  EXPECT_EQ(j["modules"][0]["key"], "concert_mobile_base_hub");
  EXPECT_EQ(j["modules"].size(), 18u);
}

}  // namespace
}  // namespace concert::discovery
