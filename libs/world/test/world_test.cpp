#include "concert/world/world.hpp"

#include <gtest/gtest.h>

namespace concert::world {
namespace {

TEST(World, ParsesFloorWallsObstacles) {
  const World w = load_world_file(std::string(WORLD_FIXTURES) + "/world_wall.yaml");
  EXPECT_TRUE(w.floor);
  EXPECT_DOUBLE_EQ(w.floor_friction, 1.0);
  ASSERT_EQ(w.walls.size(), 1u);
  EXPECT_EQ(w.walls[0].name, "wall_front");
  EXPECT_TRUE(w.walls[0].size.isApprox(Eigen::Vector3d(0.2, 3.0, 2.5)));
  EXPECT_TRUE(w.walls[0].position.isApprox(Eigen::Vector3d(0.85, 0.0, 1.25)));
  ASSERT_EQ(w.obstacles.size(), 1u);
  EXPECT_EQ(w.obstacles[0].type, WorldShape::Type::kCylinder);
  EXPECT_DOUBLE_EQ(w.obstacles[0].size.x(), 0.2);
  EXPECT_DOUBLE_EQ(w.obstacles[0].size.z(), 2.0);
}

TEST(World, EmptyTextIsJustAFloor) {
  const World w = parse_world_yaml("");
  EXPECT_TRUE(w.floor);
  EXPECT_TRUE(w.walls.empty());
}

void expect_error(const std::string& yaml, const std::string& needle) {
  try {
    (void)parse_world_yaml(yaml, "site.yaml");
    FAIL() << "no error for: " << yaml;
  } catch (const WorldError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("site.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

TEST(World, ClearErrorsNameFileAndField) {
  expect_error("walls:\n  - name: a\n    size: [1, 2]\n    position: [0, 0, 0]\n", "walls[0].size");
  expect_error("walls:\n  - name: a\n    size: [1, 2, 3]\n", "walls[0].position");
  expect_error("walls:\n  - size: [1, 2, 3]\n    position: [0, 0, 0]\n", "walls[0].name");
  expect_error("walls:\n  - name: a\n    size: [1, -2, 3]\n    position: [0, 0, 0]\n", "positive");
  expect_error("obstacles:\n  - name: a\n    shape: cone\n    position: [0, 0, 0]\n", "obstacles[0].shape");
  expect_error("walls:\n  - name: a\n    shape: cylinder\n    radius: 1\n    height: 1\n    position: [0, 0, 0]\n",
               "walls[0].shape");
  expect_error("roof: {}\n", "roof");
  expect_error("walls:\n  - name: a\n    size: [1, 1, 1]\n    position: [0, 0, 0]\n"
               "  - name: a\n    size: [1, 1, 1]\n    position: [0, 0, 0]\n",
               "duplicate");
  expect_error("walls: [\n", "YAML error");
  expect_error("walls:\n  - name: a\n    size: [1, x, 1]\n    position: [0, 0, 0]\n", "walls[0].size[1]");
}

}  // namespace
}  // namespace concert::world
