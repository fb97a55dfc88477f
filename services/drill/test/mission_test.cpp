// Mission files: a good file read field by field (relative paths resolved against the file's
// folder, defaults filled in), and each class of bad input refused with a message that names the
// mission, the field and why.
#include "drill/mission.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "concert/common/error_text.hpp"

namespace concert::drill {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kFixtures = fs::path(CONCERT_SOURCE_DIR) / "services/drill/test/fixtures/missions";

std::string parse_error(const std::string& yaml) {
  return error_text<DrillError>([&] { parse_mission(yaml, "m.yaml"); });
}

TEST(MissionFile, ReadsEveryFieldAndResolvesPathsAgainstTheFile) {
  const Mission m = load_mission(kFixtures / "site.yaml");
  EXPECT_EQ(m.name, "east wall");
  EXPECT_EQ(m.ifc, (kFixtures / "../bim/house.ifc").lexically_normal());
  EXPECT_EQ(m.patterns, kFixtures / "patterns.yaml");
  EXPECT_EQ(m.storey, "Erdgeschoss");
  EXPECT_DOUBLE_EQ(m.depth, 0.04);
  ASSERT_EQ(m.areas.size(), 3u);

  const AreaSpec& wall = m.areas[0];
  EXPECT_EQ(wall.name, "a1");
  EXPECT_EQ(wall.marks, MarkKind::kBlobs);
  EXPECT_EQ(wall.wall, "1$wmdwWPjDYuku_ghVkynE");
  EXPECT_TRUE(wall.at.isApprox(Eigen::Vector2d(1.2, 1.1)));
  EXPECT_EQ(wall.face, "right");
  EXPECT_FALSE(wall.point);
  EXPECT_FALSE(wall.pixel);
  EXPECT_EQ(wall.expected, 0);

  const AreaSpec& point = m.areas[1];
  EXPECT_EQ(point.marks, MarkKind::kAruco);
  EXPECT_TRUE(point.wall.empty());
  EXPECT_EQ(point.face, "auto");
  ASSERT_TRUE(point.point);
  EXPECT_TRUE(point.point->isApprox(Eigen::Vector3d(2.0, 0.3, 1.2)));

  const AreaSpec& pixel = m.areas[2];
  EXPECT_EQ(pixel.name, "area 3") << "an unnamed area is named by its place in the list";
  ASSERT_TRUE(pixel.pixel);
  EXPECT_TRUE(pixel.pixel->isApprox(Eigen::Vector2d(320, 240)));
  EXPECT_EQ(pixel.expected, 2);
}

TEST(MissionFile, DefaultsAndPathsWithoutAFolder) {
  const Mission m = parse_mission(
      "ifc: /data/house.ifc\npatterns: tables/p.yaml\nareas: [{point: [1, 2, 3]}]\n", "site.yaml");
  EXPECT_EQ(m.name, "site") << "a mission without a name is named after its source";
  EXPECT_DOUBLE_EQ(m.depth, 0.05);
  EXPECT_EQ(m.ifc, "/data/house.ifc");
  EXPECT_EQ(m.patterns, "tables/p.yaml") << "no folder given: the path stays as written";
  EXPECT_TRUE(m.storey.empty());
  ASSERT_EQ(m.areas.size(), 1u);
  EXPECT_EQ(m.areas[0].name, "area 1");
  EXPECT_EQ(m.areas[0].marks, MarkKind::kBlobs);

  const Mission absolute = parse_mission("ifc: /data/house.ifc\nareas: [{point: [1, 2, 3]}]\n",
                                         "site.yaml", "/missions");
  EXPECT_EQ(absolute.ifc, "/data/house.ifc") << "an absolute path is kept";
}

struct BadMission {
  const char* what;
  const char* yaml;
  const char* error;  // the whole message
};

class MissionFileErrors : public ::testing::TestWithParam<BadMission> {};

TEST_P(MissionFileErrors, NameTheFieldAndWhy) {
  EXPECT_EQ(parse_error(GetParam().yaml), GetParam().error) << GetParam().what;
}

INSTANTIATE_TEST_SUITE_P(
    EachClass, MissionFileErrors,
    ::testing::Values(
        BadMission{"two locations",
                   "areas: [{name: a1, point: [1, 2, 3]}, {point: [1, 2, 3], pixel: [1, 2]}]",
                   "mission 'm.yaml': areas[1]: needs exactly one of wall, point, pixel (has point "
                   "and pixel)"},
        BadMission{
            "no location", "areas: [{name: a1, marks: blobs}]",
            "mission 'm.yaml': areas[0]: needs exactly one of wall, point, pixel (has none)"},
        BadMission{"a typo at the top", "dpeth: 0.05\nareas: [{point: [1, 2, 3]}]",
                   "mission 'm.yaml': dpeth: unknown key (expected name, ifc, storey, patterns, "
                   "depth, areas)"},
        BadMission{"a key given twice", "depth: 0.1\ndepth: 0.2\nareas: [{point: [1, 2, 3]}]",
                   "mission 'm.yaml': depth: given twice"},
        BadMission{"a key given twice in an area", "areas: [{point: [1, 2, 3], name: a, name: b}]",
                   "mission 'm.yaml': areas[0].name: given twice"},
        BadMission{"a typo in an area", "areas: [{pont: [1, 2, 3]}]",
                   "mission 'm.yaml': areas[0].pont: unknown key (expected name, marks, wall, at, "
                   "face, point, pixel, expected)"},
        BadMission{"a face without a wall", "areas: [{point: [1, 2, 3], face: left}]",
                   "mission 'm.yaml': areas[0].face: goes with wall (the face of a wall area)"},
        BadMission{"an unknown face", "ifc: h.ifc\nareas: [{wall: abc, at: [1, 1], face: north}]",
                   "mission 'm.yaml': areas[0].face: expected auto, left or right, got 'north'"},
        BadMission{"a wall without the building", "areas: [{wall: abc, at: [1, 1]}]",
                   "mission 'm.yaml': areas[0].wall: a wall area needs the building model: set "
                   "ifc at the top level"},
        BadMission{"a wall without its centre", "ifc: h.ifc\nareas: [{wall: abc}]",
                   "mission 'm.yaml': areas[0].at: missing: a wall area needs its centre [s, h] "
                   "on the wall (m along the wall from its start, m above the storey)"},
        BadMission{"a centre without a wall", "areas: [{point: [1, 2, 3], at: [1, 1]}]",
                   "mission 'm.yaml': areas[0].at: goes with wall (the centre of a wall area)"},
        BadMission{"a centre below the floor", "ifc: h.ifc\nareas: [{wall: abc, at: [1, -0.5]}]",
                   "mission 'm.yaml': areas[0].at[1]: expected a number >= 0, got '-0.5'"},
        BadMission{"not a number", "areas: [{point: [1, x, 3]}]",
                   "mission 'm.yaml': areas[0].point[1]: expected a number, got 'x'"},
        BadMission{"not finite", "areas: [{point: [.nan, 2, 3]}]",
                   "mission 'm.yaml': areas[0].point[0]: expected a finite number, got '.nan'"},
        BadMission{"a point of two numbers", "areas: [{point: [1, 2]}]",
                   "mission 'm.yaml': areas[0].point: expected [x, y, z] in the map frame [m]"},
        BadMission{"a negative pixel", "areas: [{pixel: [-1, 2]}]",
                   "mission 'm.yaml': areas[0].pixel[0]: expected a number >= 0, got '-1'"},
        BadMission{"duplicate names",
                   "areas: [{name: a1, point: [1, 2, 3]}, {name: a2, point: [1, 2, 3]}, "
                   "{name: a1, pixel: [1, 2]}]",
                   "mission 'm.yaml': areas[2].name: 'a1' is also the name of areas[0]"},
        BadMission{"a name that is another's default",
                   "areas: [{name: area 2, point: [1, 2, 3]}, {point: [1, 2, 3]}]",
                   "mission 'm.yaml': areas[1].name: 'area 2' is also the name of areas[0]"},
        BadMission{"an empty name", "areas: [{name: '', point: [1, 2, 3]}]",
                   "mission 'm.yaml': areas[0].name: expected a non-empty string"},
        BadMission{"no areas", "name: x\nareas: []",
                   "mission 'm.yaml': areas: expected a list of at least one area"},
        BadMission{"no areas key", "name: x",
                   "mission 'm.yaml': areas: missing: a mission needs at least one area"},
        BadMission{"an empty file", "",
                   "mission 'm.yaml': areas: missing: a mission needs at least one area"},
        BadMission{"an area that is not a map", "areas: [3]",
                   "mission 'm.yaml': areas[0]: expected a map with name, marks, wall, at, face, "
                   "point, pixel, expected"},
        BadMission{"a list at the top", "- a\n- b",
                   "mission 'm.yaml': expected a map with name, ifc, storey, patterns, depth, "
                   "areas"},
        BadMission{"a depth of zero", "depth: 0\nareas: [{point: [1, 2, 3]}]",
                   "mission 'm.yaml': depth: expected a depth in (0, 0.3] m, got 0"},
        BadMission{"too deep", "depth: 0.31\nareas: [{point: [1, 2, 3]}]",
                   "mission 'm.yaml': depth: expected a depth in (0, 0.3] m, got 0.31"},
        BadMission{"unknown marks", "areas: [{marks: dots, point: [1, 2, 3]}]",
                   "mission 'm.yaml': areas[0].marks: expected blobs or aruco, got 'dots'"},
        BadMission{"a negative count", "areas: [{point: [1, 2, 3], expected: -1}]",
                   "mission 'm.yaml': areas[0].expected: expected a whole number >= 0, got '-1'"},
        BadMission{"a fractional count", "areas: [{point: [1, 2, 3], expected: 1.5}]",
                   "mission 'm.yaml': areas[0].expected: expected a whole number >= 0, got "
                   "'1.5'"}));

TEST(MissionFile, RefusesTextThatIsNotYaml) {
  EXPECT_THAT(parse_error("areas: [{point: [1, 2, 3]}"),
              HasSubstr("mission 'm.yaml': not valid YAML: "));
}

TEST(MissionFile, LoadErrorsNameTheFile) {
  const fs::path bad = kFixtures / "two_locations.yaml";
  EXPECT_EQ(error_text<DrillError>([&] { load_mission(bad); }),
            "mission '" + bad.string() +
                "': areas[1]: needs exactly one of wall, point, pixel (has point and pixel)");
  const fs::path missing = kFixtures / "no_such_mission.yaml";
  EXPECT_EQ(error_text<DrillError>([&] { load_mission(missing); }),
            missing.string() + ": cannot open the mission file");
}

}  // namespace
}  // namespace concert::drill
