#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/scan_io.hpp"
#include "concert/topology/reconstruction.hpp"
#include "modelgen/bundle.hpp"
#include "modelgen/cli.hpp"

namespace fs = std::filesystem;
using namespace concert;

namespace {

using ::testing::HasSubstr;

const std::string kPublic = (fs::path(CONCERT_SHARED_DATA) / "concert_resources").string();
const std::string kOwn = (fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db").string();
const std::string kPaperRobot = (fs::path(SIMBUS_EXAMPLES) / "concert_paper_robot.yaml").string();

struct CliRun {
  int code;
  std::string out;
  std::string err;
};

CliRun run(const std::vector<std::string>& args) {
  std::ostringstream out;
  std::ostringstream err;
  std::vector<std::string> full = args;
  full.insert(full.begin(), "model");
  const int code = cli::run("concert", {modelgen::register_verbs}, full, out, err);
  return {code, out.str(), err.str()};
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("concert_modelgen_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

}  // namespace

TEST_F(CliTest, AssemblyScanAndTreeGiveTheSameBundle) {
  const std::string out_a = (dir_ / "a").string();
  const CliRun a = run({"generate", "--assembly", kPaperRobot, "--module-db", kPublic, "--out", out_a});
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_THAT(a.out, HasSubstr("wrote model version 1"));
  EXPECT_THAT(a.out, HasSubstr("chain E (arm)"));
  for (const char* f : {"robot.urdf", "robot.srdf", "controller.yaml", "manifest.yaml"}) EXPECT_TRUE(fs::exists(fs::path(out_a) / f));
  EXPECT_TRUE(urdf::parseURDFFile(out_a + "/robot.urdf"));
  const auto [version_a, hash_a] = modelgen::read_bundle_version(out_a);

  // The same robot as a scan file and as a discovered tree (JSON).
  const auto catalog = topology::EscCatalog::load(kPublic);
  const topology::EscScan scan = simbus::simulate_scan(simbus::load_assembly(kPaperRobot), catalog);
  std::ofstream(dir_ / "scan.yaml") << topology::scan_to_yaml(scan);
  std::ofstream(dir_ / "tree.json") << topology::tree_to_json(topology::discover(scan, catalog)).dump(2);
  const CliRun s = run({"generate", "--scan", (dir_ / "scan.yaml").string(), "--module-db", kPublic, "--out", (dir_ / "s").string()});
  ASSERT_EQ(s.code, 0) << s.err;
  const CliRun t = run({"generate", "--tree", (dir_ / "tree.json").string(), "--module-db", kPublic, "--out", (dir_ / "t").string()});
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_EQ(modelgen::read_bundle_version(dir_ / "s").second, hash_a);
  EXPECT_EQ(modelgen::read_bundle_version(dir_ / "t").second, hash_a);
}

TEST_F(CliTest, VersionsGrowOnlyWhenTheContentChanges) {
  const std::string out = (dir_ / "bundle").string();
  ASSERT_EQ(run({"generate", "--assembly", kPaperRobot, "--module-db", kPublic, "--out", out}).code, 0);
  const CliRun again = run({"generate", "--assembly", kPaperRobot, "--module-db", kPublic, "--out", out});
  ASSERT_EQ(again.code, 0);
  EXPECT_THAT(again.out, HasSubstr("unchanged model version 1"));
  const CliRun custom = run({"generate", "--assembly", kPaperRobot, "--module-db", kPublic, "--out", out, "--home", "J2_E=0.5",
                          "--addon", "drill_E=drillbit_12_SDSmax"});
  ASSERT_EQ(custom.code, 0) << custom.err;
  EXPECT_THAT(custom.out, HasSubstr("wrote model version 2"));
  std::ifstream srdf(fs::path(out) / "robot.srdf");
  const std::string text((std::istreambuf_iterator<char>(srdf)), std::istreambuf_iterator<char>());
  EXPECT_THAT(text, HasSubstr("<joint name=\"J2_E\" value=\"0.5\"/>"));
}

TEST_F(CliTest, BothDatabaseFormatsAndSeveralDatabases) {
  // The project database: a hand-written tree JSON of our own keys.
  std::ofstream(dir_ / "tree.json") << R"({"modules": [
    {"index": 0, "key": "concert_mobile_base_hub", "parent_module": -1, "parent_connector": -1},
    {"index": 1, "key": "concert_elbow_a", "parent_module": 0, "parent_connector": 5},
    {"index": 2, "key": "concert_passive_gripper_panel", "parent_module": 1, "parent_connector": 1}]})";
  const CliRun own = run({"generate", "--tree", (dir_ / "tree.json").string(), "--module-db", kOwn, "--module-db", kPublic, "--out",
                       (dir_ / "own").string()});
  ASSERT_EQ(own.code, 0) << own.err;
  EXPECT_THAT(own.out, HasSubstr("end-effector gripper_A (gripper) at tcp_A (concert_passive_gripper_panel)"));
}

TEST_F(CliTest, ErrorsAreOneLineAndNonZero) {
  const std::string out = (dir_ / "bundle").string();
  CliRun r = run({"generate", "--assembly", kPaperRobot, "--out", out});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(
      r.err,
      "concert model generate: --module-db is required (see `concert model generate --help`)\n");
  r = run({"generate", "--assembly", kPaperRobot, "--tree", "x.json", "--module-db", kPublic, "--out", out});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--tree excludes --assembly"));
  r = run({"generate", "--module-db", kPublic, "--out", out});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("give exactly one of --scan, --tree, --assembly"));
  r = run({"generate", "--assembly", kPaperRobot, "--module-db", kPublic, "--out", out, "--home", "J1_E=abc"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--home: 'J1_E=abc': 'abc' is not a number"));
  r = run({"frobnicate"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("unknown verb 'frobnicate' (one of: generate, show)"));
  r = run({"generate", "--assembly", kPaperRobot, "--module-db", (dir_ / "nowhere").string(), "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("module database folder does not exist"));
  // A tree the database cannot model: clear error, no bundle written, previous bundle kept.
  ASSERT_EQ(run({"generate", "--assembly", kPaperRobot, "--module-db", kPublic, "--out", out}).code, 0);
  std::ofstream(dir_ / "bad.json") << R"({"modules": [{"index": 0, "key": "mobile_platform_concert", "parent_module": -1},
    {"index": 1, "key": "warp_drive", "parent_module": 0, "parent_connector": 5}]})";
  r = run({"generate", "--tree", (dir_ / "bad.json").string(), "--module-db", kPublic, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err, "concert model generate: module 1 ('warp_drive'): no module description with key 'warp_drive' in the module database\n");
  EXPECT_EQ(modelgen::read_bundle_version(out).first, 1u);
  std::ofstream(dir_ / "broken.json") << R"({"modules": [{"index": 0, "key": "x"}]})";
  r = run({"generate", "--tree", (dir_ / "broken.json").string(), "--module-db", kPublic, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("broken.json: modules[0].parent_module: missing"));
}

TEST_F(CliTest, RealScanGivesAModelAndBlankBoardsAreNamed) {
  const std::string real =
      (fs::path(CONCERT_SHARED_DATA) / "ethercat" / "concert_robot_18slaves.yaml").string();
  for (const std::string& db : {kPublic, kOwn}) {
    const std::string out = (dir_ / fs::path(db).filename()).string();
    const CliRun r = run({"generate", "--scan", real, "--module-db", db, "--out", out});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.out, HasSubstr("17 modules, "));
    EXPECT_THAT(r.out, HasSubstr("14 moving joints"));
    EXPECT_THAT(r.out, HasSubstr("chain E (arm)"));
  }
  // The same scan with the link board at ring position 14 unprogrammed: refused, naming it.
  topology::EscScan scan = topology::load_scan(real);
  scan.slaves[13].identity = {};
  const fs::path blank = dir_ / "blank.yaml";
  std::ofstream(blank) << topology::scan_to_yaml(scan);
  const CliRun r = run({"generate", "--scan", blank.string(), "--module-db", kPublic, "--out",
                        (dir_ / "b").string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("1 unknown module, not in the ESC catalogue of the module database: slave "
                       "14 (mod_type 0, "
                       "mod_id 0, mod_size 0, mod_rev 0)"));
  EXPECT_FALSE(fs::exists(dir_ / "b" / "robot.urdf"));
}
