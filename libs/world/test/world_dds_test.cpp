#include "concert/world/world_dds.hpp"

#include <gtest/gtest.h>

namespace concert::world {
namespace {

TEST(WorldDds, RoundTripKeepsEveryField) {
  const World w = load_world_file(std::string(WORLD_FIXTURES) + "/world_wall.yaml");
  const msg::World m = to_msg(w, 4, "world_wall.yaml");
  EXPECT_EQ(m.version(), 4u);
  EXPECT_EQ(m.source(), "world_wall.yaml");
  const World back = from_msg(m);
  ASSERT_EQ(back.walls.size(), 1u);
  ASSERT_EQ(back.obstacles.size(), 1u);
  EXPECT_EQ(back.walls[0].name, "wall_front");
  EXPECT_TRUE(back.walls[0].size.isApprox(w.walls[0].size));
  EXPECT_TRUE(back.walls[0].position.isApprox(w.walls[0].position));
  EXPECT_EQ(back.obstacles[0].type, WorldShape::Type::kCylinder);
  EXPECT_DOUBLE_EQ(back.obstacles[0].size.x(), 0.2);
  EXPECT_EQ(back.floor, w.floor);
}

TEST(WorldDds, BadShapeInAMessageIsNamed) {
  World w;
  WorldShape box;
  box.name = "crate";
  w.obstacles.push_back(box);
  msg::World m = to_msg(w, 1, "test");
  m.obstacles()[0].size({0.0, 1.0, 1.0});
  try {
    (void)from_msg(m);
    FAIL() << "accepted a zero-size box";
  } catch (const WorldError& e) {
    EXPECT_NE(std::string(e.what()).find("obstacles[0] 'crate'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace concert::world
