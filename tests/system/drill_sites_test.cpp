// The generated drilling sites (drill_sites.hpp): the same from the same seed, valid world files
// the world library reads, every hole within the heights and the yaw the issue asks for, the
// boxes clear of the marks and of the robot's start. No DDS, no simulator.
#include "drill_sites.hpp"

#include <gtest/gtest.h>

#include <set>

#include "drill_runner.hpp"

namespace concert::system_test {
namespace {

drill::PatternTable patterns() {
  return drill::load_patterns(std::string(CONCERT_SOURCE_DIR) + "/services/drill/config/patterns.yaml");
}

TEST(DrillSites, TheSameSeedDrawsTheSameSitesWhateverTheCount) {
  const auto table = patterns();
  const auto five = generate_sites(7, 5, table);
  const auto three = generate_sites(7, 3, table);
  ASSERT_EQ(five.size(), 5u);
  for (std::size_t k = 0; k < three.size(); ++k) {
    EXPECT_EQ(three[k].world_yaml, five[k].world_yaml) << k;
    EXPECT_EQ(three[k].mission_yaml, five[k].mission_yaml) << k;
  }
  const auto other = generate_sites(8, 5, table);
  int same = 0;
  for (std::size_t k = 0; k < five.size(); ++k) same += other[k].world_yaml == five[k].world_yaml ? 1 : 0;
  EXPECT_EQ(same, 0);
}

TEST(DrillSites, EverySiteIsAValidWorldWithItsHolesWhereTheIssueAsks) {
  const auto table = patterns();
  std::set<int> ids;
  int blob_sites = 0, c_sites = 0, boxes = 0;
  for (const std::uint64_t seed : {1u, 2u}) {
    for (const GeneratedSite& site : generate_sites(seed, 40, table)) {
      SCOPED_TRACE(site.name + " of seed " + std::to_string(seed) + ": " + site.description);
      const world::World w = world::parse_world_yaml(site.world_yaml, site.name);
      ASSERT_EQ(w.walls.size(), 1u);
      const world::WorldShape& wall = w.walls.front();
      EXPECT_LE(std::abs(wall.yaw), 0.25);
      // The face's distance from the start (the origin) along its normal: 1.6-2.8 m.
      const Eigen::Isometry3d face = world::face_frame(wall, world::Face::kMinusX);
      const double distance = -face.translation().dot(face.linear().col(2));
      EXPECT_GE(distance, 1.6);
      EXPECT_LE(distance, 2.8);

      const std::vector<Target> targets = targets_of(w, table);
      ASSERT_FALSE(targets.empty());
      double highest = 0.0;
      for (const Target& t : targets) {
        EXPECT_GE(t.position.z(), kSiteLowest - 1e-9) << t.name;
        EXPECT_LE(t.position.z(), kSiteHighest + 1e-9) << t.name;
        highest = std::max(highest, t.position.z());
        // On the wall's face, its normal towards the start.
        EXPECT_NEAR((t.position - face.translation()).dot(face.linear().col(2)), world::kMarkStandoff, 1e-6);
        EXPECT_NEAR(t.normal.dot(face.linear().col(2)), 1.0, 1e-9);
      }
      EXPECT_EQ(site.morphology_c, highest > kSiteMorphologyC);
      c_sites += site.morphology_c ? 1 : 0;
      if (w.marks.front().type == world::Mark::Type::kBlob) {
        ++blob_sites;
        EXPECT_EQ(targets.size(), 2u);
        EXPECT_NEAR((targets[0].position - targets[1].position).norm(), 0.1, 1e-6);
        EXPECT_NE(site.mission_yaml.find("expected: 2"), std::string::npos);
      } else {
        ids.insert(w.marks.front().id);
        EXPECT_EQ(static_cast<int>(targets.size()), table.find(w.marks.front().id)->count);
      }
      // Boxes stand against the face, at least 0.5 m beside every hole along the wall, and
      // leave the start free.
      for (const world::WorldShape& box : w.obstacles) {
        const Eigen::Vector3d in_face = face.inverse() * box.position;
        EXPECT_NEAR(in_face.z(), box.size.x() / 2, 1e-6) << box.name;
        for (const Target& t : targets) {
          const double u = (face.inverse() * t.position).x();
          EXPECT_GE(std::abs(u - in_face.x()) - box.size.y() / 2, 0.5 - 1e-6) << box.name << " and " << t.name;
        }
        EXPECT_GT(box.position.head<2>().norm(), 0.75) << box.name;
        ++boxes;
      }
      // The mission's area point is the mark's centre on the face.
      EXPECT_NE(site.mission_yaml.find("name: " + site.name), std::string::npos);
    }
  }
  // 80 sites cover both kinds of marks, every pattern of the table, morphology C, and boxes.
  EXPECT_GT(blob_sites, 20);
  EXPECT_LT(blob_sites, 60);
  EXPECT_EQ(ids.size(), table.patterns().size());
  EXPECT_GT(c_sites, 0);
  EXPECT_GT(boxes, 40);
}

}  // namespace
}  // namespace concert::system_test
