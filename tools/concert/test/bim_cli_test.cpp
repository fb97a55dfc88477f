// `concert bim import|goal` and `concert sim world --ifc` as a user runs them: the real binary
// on a shared IFC file.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using concert::testing::run;
using concert::testing::TempDir;
using ::testing::HasSubstr;
using Json = nlohmann::json;

const std::string kFzk = std::string(CONCERT_SHARED_DATA) + "/bim/AC20-FZK-Haus.ifc";
constexpr auto kTimeout = std::chrono::seconds(120);

TEST(BimCli, ImportWritesMapsAndGeometryPerStoreyThenGoalReadsThem) {
  TempDir dir("bim-cli");
  const auto imported = run(
      {CONCERT_BIN, "bim", "import", kFzk, "--out", dir.path(), "--resolution", "0.1"}, kTimeout);
  ASSERT_EQ(imported.code, 0) << imported.err;
  EXPECT_THAT(imported.out, HasSubstr("storey 'Erdgeschoss' (elevation 0.000 m)"));
  EXPECT_THAT(imported.out, HasSubstr("IfcWallStandardCase 9"));
  EXPECT_THAT(imported.out, HasSubstr("IfcDoor 5"));
  EXPECT_THAT(imported.out, HasSubstr("at 0.10 m"));
  for (const char* storey : {"erdgeschoss", "dachgeschoss"}) {
    for (const char* file : {"map.yaml", "map.pgm", "geometry.json"}) {
      EXPECT_TRUE(fs::is_regular_file(fs::path(dir.path()) / storey / file))
          << storey << "/" << file;
    }
  }
  std::ifstream in(fs::path(dir.path()) / "erdgeschoss" / "geometry.json");
  const Json geometry = Json::parse(in);
  int walls = 0;
  for (const auto& e : geometry.at("elements")) {
    if (e.at("category") != "wall") continue;
    ++walls;
    EXPECT_EQ(e.at("faces").size(), 2u);
    EXPECT_GT(e.at("thickness").get<double>(), 0.05);
  }
  EXPECT_EQ(walls, 9);

  const auto goal =
      run({CONCERT_BIN, "bim", "goal", "--wall", "2ptk1k7qn8_Qk22vjh$0DE", "--at", "2", "1.2",
           "--bim", dir.path(), "--robot-radius", "0.3", "--standoff", "0.7", "--json"},
          kTimeout);
  ASSERT_EQ(goal.code, 0) << goal.err;
  const Json g = Json::parse(goal.out);
  EXPECT_EQ(g.at("storey"), "Erdgeschoss");
  const auto& z = g.at("area_frame").at("z");
  EXPECT_NEAR(z[2].get<double>(), 0.0, 1e-9);  // the face normal is horizontal
  const double nx = z[0].get<double>(), ny = z[1].get<double>();
  const auto& origin = g.at("area_frame").at("position");
  const auto& base = g.at("base_pose");
  EXPECT_NEAR(base.at("x").get<double>(), origin[0].get<double>() + 0.7 * nx, 1e-6);
  EXPECT_NEAR(base.at("y").get<double>(), origin[1].get<double>() + 0.7 * ny, 1e-6);

  const auto refused =
      run({CONCERT_BIN, "bim", "goal", "--wall", "nope", "--at", "2", "1.2", "--bim", dir.path()},
          kTimeout);
  EXPECT_EQ(refused.code, 1);
  EXPECT_THAT(refused.err, HasSubstr("no element with GlobalId 'nope'"));
}

TEST(BimCli, BadInputIsNamed) {
  TempDir dir("bim-cli");
  const auto storey = run(
      {CONCERT_BIN, "bim", "import", kFzk, "--out", dir.path(), "--storey", "Keller"}, kTimeout);
  EXPECT_EQ(storey.code, 1);
  EXPECT_THAT(storey.err, HasSubstr("storey 'Keller' not found"));
  EXPECT_THAT(storey.err, HasSubstr("storeys: Erdgeschoss, Dachgeschoss"));
  const std::string junk = dir.path() + "/junk.ifc";
  std::ofstream(junk) << "not a building\n";
  const auto not_ifc = run({CONCERT_BIN, "bim", "import", junk, "--out", dir.path()}, kTimeout);
  EXPECT_EQ(not_ifc.code, 1);
  EXPECT_THAT(not_ifc.err, HasSubstr("not an IFC file"));
  const auto band = run(
      {CONCERT_BIN, "bim", "import", kFzk, "--out", dir.path(), "--band", "1.5", "0.5"}, kTimeout);
  EXPECT_EQ(band.code, 2);
  EXPECT_THAT(band.err, HasSubstr("--band"));
}

TEST(BimCli, SimWorldFromIfcChecksItsArgumentsBeforeTalkingToTheSimulator) {
  const auto both =
      run({CONCERT_BIN, "sim", "world", "some.yaml", "--ifc", kFzk, "--storey", "Erdgeschoss"},
          kTimeout);
  EXPECT_EQ(both.code, 2);
  EXPECT_THAT(both.err, HasSubstr("one of them"));
  const auto no_storey = run({CONCERT_BIN, "sim", "world", "--ifc", kFzk}, kTimeout);
  EXPECT_EQ(no_storey.code, 2);
  EXPECT_THAT(no_storey.err, HasSubstr("--storey"));
  const auto unknown =
      run({CONCERT_BIN, "sim", "world", "--ifc", kFzk, "--storey", "Keller"}, kTimeout);
  EXPECT_EQ(unknown.code, 1);
  EXPECT_THAT(unknown.err, HasSubstr("world rejected, nothing changed: storey 'Keller' not found"));
}

}  // namespace
