#include "concert/bim/storey_world.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "bim_test_models.hpp"

namespace concert::bim {
namespace {

using namespace concert::bim::test_models;

TEST(StoreyWorld, BoxesStandOnTheFloorWhereTheMapIsOccupied) {
  const BimModel& m = shared_model("duplex.ifc");
  const Storey& s = m.storey("Level 2");
  const OccupancyGrid grid = storey_map(m, s);
  const world::World w = storey_world(m, s);
  EXPECT_TRUE(w.floor);
  EXPECT_DOUBLE_EQ(w.floor_height, 0.0);
  EXPECT_GT(w.walls.size(), 20u);
  EXPECT_FALSE(w.obstacles.empty());
  std::size_t cells = 0;
  for (const auto* list : {&w.walls, &w.obstacles}) {
    for (const auto& b : *list) {
      EXPECT_EQ(b.type, world::WorldShape::Type::kBox);
      EXPECT_NEAR(b.position.z(), b.size.z() / 2, 1e-9) << b.name;  // on the floor, z = 0
      EXPECT_LE(b.size.z(), 3.0 + 1e-9) << b.name;
      EXPECT_GT(b.size.z(), 0.0) << b.name;
      EXPECT_EQ(b.name.rfind("door_", 0), std::string::npos) << b.name;
      EXPECT_TRUE(grid.occupied(b.position.head<2>())) << b.name;
      cells += static_cast<std::size_t>(
          std::lround(b.size.x() / grid.resolution * b.size.y() / grid.resolution));
    }
  }
  // Every occupied cell is under some box (boxes of different elements may overlap).
  std::size_t occupied = 0;
  for (const auto c : grid.cells) occupied += c == OccupancyGrid::kOccupied ? 1 : 0;
  EXPECT_GE(cells, occupied);
  EXPECT_NO_THROW(world::validate_world(w, "duplex Level 2"));
}

TEST(StoreyWorld, YamlRoundTripThroughTheWorldParser) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  const world::World w = storey_world(m, m.storey("Erdgeschoss"));
  const std::string text = world_yaml(w);
  const world::World back = world::parse_world_yaml(text, "fzk.yaml");
  ASSERT_EQ(back.walls.size(), w.walls.size());
  ASSERT_EQ(back.obstacles.size(), w.obstacles.size());
  for (std::size_t i = 0; i < w.walls.size(); ++i) {
    EXPECT_EQ(back.walls[i].name, w.walls[i].name);
    EXPECT_NEAR((back.walls[i].size - w.walls[i].size).norm(), 0, 1e-9);
    EXPECT_NEAR((back.walls[i].position - w.walls[i].position).norm(), 0, 1e-9);
  }
}

TEST(StoreyWorld, YamlRefusesWhatItDoesNotWrite) {
  world::World w;
  world::WorldShape c;
  c.name = "pillar";
  c.type = world::WorldShape::Type::kCylinder;
  w.obstacles.push_back(c);
  EXPECT_THAT([&] { (void)world_yaml(w); },
              ::testing::ThrowsMessage<BimError>(::testing::HasSubstr("pillar")));
}

}  // namespace
}  // namespace concert::bim
