// The drilling perception: the hole patterns of ArUco markers.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "drill/mission.hpp"
#include "drill/patterns.hpp"

namespace concert::drill {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// --- Hole patterns
// --------------------------------------------------------------------------------

std::string shipped_patterns() { return std::string(DRILL_CONFIG_DIR) + "/patterns.yaml"; }

TEST(Patterns, ShippedTableHasTheSixtyCentimetreRowsAndAColumn) {
  const PatternTable table = load_patterns(shipped_patterns());
  EXPECT_EQ(table.dictionary(), "DICT_4X4_50");
  EXPECT_DOUBLE_EQ(table.marker_size(), 0.1);
  for (int id = 0; id < 10; ++id) {
    EXPECT_NE(table.find(id), nullptr) << "id " << id;
  }
  EXPECT_EQ(table.find(10), nullptr);
  EXPECT_EQ(table.find(-1), nullptr);
  // Id 0: 4 holes 0.2 m apart, centred 0.15 m below the marker: x -0.3 .. 0.3 at y -0.15.
  const auto row = pattern_holes(Eigen::Isometry3d::Identity(), *table.find(0));
  ASSERT_EQ(row.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_TRUE(row[i].translation().isApprox(
        Eigen::Vector3d(-0.3 + 0.2 * static_cast<double>(i), -0.15, 0.0), 1e-12))
        << i << ": " << row[i].translation().transpose();
    EXPECT_TRUE(row[i].linear().isIdentity(1e-12));
  }
  // Id 6: a column going up, 0.15 m to the right of the marker.
  const auto column = pattern_holes(Eigen::Isometry3d::Identity(), *table.find(6));
  ASSERT_EQ(column.size(), 4u);
  EXPECT_TRUE(column.front().translation().isApprox(Eigen::Vector3d(0.15, -0.3, 0.0), 1e-9));
  EXPECT_TRUE(column.back().translation().isApprox(Eigen::Vector3d(0.15, 0.3, 0.0), 1e-9));
  // Every shipped row is 60 cm long or a single hole.
  for (const HolePattern& p : table.patterns()) {
    EXPECT_TRUE(p.count == 1 || std::abs((p.count - 1) * p.spacing - 0.6) < 1e-9) << "id " << p.id;
  }
}

TEST(Patterns, HolesAreInTheMarkersPlaneWithItsNormal) {
  // A marker on a wall facing -y, turned 90 degrees: its x is world +z, its y world +x.
  Eigen::Isometry3d world_T_marker = Eigen::Isometry3d::Identity();
  world_T_marker.linear().col(0) = Eigen::Vector3d::UnitZ();
  world_T_marker.linear().col(1) = Eigen::Vector3d::UnitX();
  world_T_marker.linear().col(2) = -Eigen::Vector3d::UnitY();
  world_T_marker.translation() = Eigen::Vector3d(1.0, 2.0, 1.5);
  HolePattern p;
  p.centre = {0.0, -0.15};
  p.direction = 0.0;
  p.count = 2;
  p.spacing = 0.6;
  const auto holes = pattern_holes(world_T_marker, p);
  ASSERT_EQ(holes.size(), 2u);
  EXPECT_TRUE(holes[0].translation().isApprox(Eigen::Vector3d(1.0 - 0.15, 2.0, 1.5 - 0.3), 1e-12));
  EXPECT_TRUE(holes[1].translation().isApprox(Eigen::Vector3d(1.0 - 0.15, 2.0, 1.5 + 0.3), 1e-12));
  EXPECT_TRUE(holes[1].linear().col(2).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
}

void expect_pattern_error(const std::string& yaml, const std::vector<std::string>& parts) {
  try {
    parse_patterns(yaml, "table.yaml");
    FAIL() << "accepted:\n" << yaml;
  } catch (const DrillError& e) {
    for (const auto& part : parts) {
      EXPECT_THAT(e.what(), HasSubstr(part)) << yaml;
    }
  }
}

TEST(Patterns, BadTablesNameTheFileTheEntryAndTheField) {
  const std::string head = "dictionary: DICT_4X4_50\nmarker_size: 0.1\npatterns:\n";
  expect_pattern_error(head + "  2: {centre: [0, -0.15], direction: 0, count: 4, spacing: -0.2}\n",
                       {"table.yaml", "patterns.2.spacing", "line 4"});
  expect_pattern_error(head + "  2: {centre: [0, -0.15], direction: 0, count: 4, spacing: 0}\n",
                       {"patterns.2.spacing", "must be > 0 when count > 1"});
  expect_pattern_error(head + "  2: {centre: [0, -0.15], direction: 0, spacing: 0.2}\n",
                       {"patterns.2.count", "missing"});
  expect_pattern_error(head + "  2: {centre: [0], direction: 0, count: 4, spacing: 0.2}\n",
                       {"patterns.2.centre"});
  expect_pattern_error(head + "  2: {centre: [0, 0], direction: 0, count: 0, spacing: 0.2}\n",
                       {"patterns.2.count"});
  expect_pattern_error(head + "  2: {centre: [0, 0], count: 4, spacing: 0.2, spacin: 1}\n",
                       {"patterns.2.spacin", "unknown key"});
  expect_pattern_error(head + "  50: {centre: [0, 0], count: 1, spacing: 0}\n",
                       {"patterns.50", "DICT_4X4_50 (0..49)"});
  expect_pattern_error(head + "  seven: {centre: [0, 0], count: 1, spacing: 0}\n",
                       {"patterns.seven", "marker id"});
  expect_pattern_error(head +
                           "  1: {centre: [0, 0], count: 1, spacing: 0}\n  01: {centre: [0, 0], "
                           "count: 1, spacing: 0}\n",
                       {"patterns.1", "given twice"});
  expect_pattern_error("dictionary: DICT_9X9\npatterns: {}\n", {"dictionary", "DICT_4X4_50"});
  expect_pattern_error("marker_size: -1\npatterns: {}\n", {"marker_size"});
  expect_pattern_error("dictionary: DICT_4X4_50\n", {"patterns", "missing"});
  expect_pattern_error("patterns: [1, 2]\n", {"patterns"});
  expect_pattern_error("patterns: {0: {centre: [0, 0], count: 1}\n", {"table.yaml", "YAML"});
}

TEST(Patterns, BadFilesAreNamed) {
  try {
    load_patterns(std::string(DRILL_FIXTURES) + "/bad_patterns.yaml");
    FAIL() << "accepted a negative spacing";
  } catch (const DrillError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("bad_patterns.yaml"), HasSubstr("patterns.3.spacing")));
  }
  try {
    load_patterns(std::string(DRILL_FIXTURES) + "/no_such_table.yaml");
    FAIL() << "read a missing file";
  } catch (const DrillError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no_such_table.yaml"));
  }
}

}  // namespace
}  // namespace concert::drill
