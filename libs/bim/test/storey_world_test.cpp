#include "concert/bim/storey_world.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "bim_test_models.hpp"
#include "concert/bim/wall_goal.hpp"
#include "concert/world/geometry.hpp"

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

TEST(StoreyWorld, MarksGoOnTheSimulatedFaceOfTheWallABimGoalNames) {
  // The FZK house's interior wall north of the living room (Wand-Int-ERDG-5: y = 4.13 m, 0.24 m
  // thick): an area 1.75 m along its axis, 1.2 m high, on the face wall_goal picks.
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  const Storey& storey = m.storey("Erdgeschoss");
  world::World w = storey_world(m, storey);
  const OccupancyGrid grid = storey_map(m, storey);
  const std::string wall = "1$wmdwWPjDYuku_ghVkynE";
  const WallGoal goal = wall_goal(m, grid, wall, 1.75, 1.2, 0.8, 0.4);
  const Eigen::Vector3d normal = goal.area_frame.linear().col(2);
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(normal);
  w.marks.push_back(mark_on_wall(w, wall, goal.area_frame.translation() - 0.05 * right, normal,
                                 "left", 0.025));
  w.marks.push_back(mark_on_wall(w, wall, goal.area_frame.translation() + 0.05 * right, normal,
                                 "right", 0.025));
  const world::World back = world::parse_world_yaml(world_yaml(w), "fzk_marks.yaml");
  ASSERT_EQ(back.marks.size(), 2u);
  const auto truth = world::mark_truth(back);
  ASSERT_EQ(truth.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d asked =
        goal.area_frame.translation() + (i == 0 ? -0.05 : 0.05) * right;
    SCOPED_TRACE(truth[i].name);
    EXPECT_LT((truth[i].normal - normal).norm(), 1e-9);  // the face the area looks out of
    // Along the face: where asked; along the normal: on the simulator's face, within a map cell
    // of the IFC's face.
    const Eigen::Vector3d d = truth[i].centre - asked;
    EXPECT_NEAR(d.dot(right), 0.0, 1e-9);
    EXPECT_NEAR(d.z(), 0.0, 1e-9);
    EXPECT_LE(std::abs(d.dot(normal)), grid.resolution + 0.002);
  }
  EXPECT_NEAR((truth[1].centre - truth[0].centre).dot(right), 0.1, 1e-9);
  // A point on another wall's face, and a wall not in the storey, are refused by name.
  EXPECT_THAT([&] { (void)mark_on_wall(w, wall, {2.05, 0.0, 1.2}, normal, "far", 0.025); },
              ::testing::ThrowsMessage<BimError>(::testing::HasSubstr("holds it")));
  EXPECT_THAT([&] { (void)mark_on_wall(w, "nope", {2.05, 4.0, 1.2}, normal, "x", 0.025); },
              ::testing::ThrowsMessage<BimError>(::testing::HasSubstr("not in this storey")));
}

// A plaster panel on the FZK house's interior wall east of the stair (Wand-Int-ERDG-4, its south
// face at y = 4.01 m, x 7.41 .. 11.7 m): placed on the simulator's face, written and read back.
TEST(StoreyWorld, APlasterPanelGoesOnTheFaceThatHoldsItWhole) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  world::World w = storey_world(m, m.storey("Erdgeschoss"));
  const std::string wall = "2XPyKWY018sA1ygZKgQPtU";
  const Eigen::Vector3d south(0.0, -1.0, 0.0);
  const WallSpot spot = place_on_wall(w, wall, {10.6, 4.0, 2.175}, south, {0.8, 0.3}, "plaster");
  EXPECT_LT((spot.frame.linear().col(2) - south).norm(), 1e-9);
  EXPECT_NEAR(spot.frame.translation().x(), 10.6, 1e-9);
  EXPECT_NEAR(spot.frame.translation().y(), 4.01, 0.05 + 1e-3);  // a map cell of the IFC's face
  EXPECT_NEAR(spot.at.y(), 2.175, 1e-12);
  world::Surface plaster;
  plaster.name = "plaster";
  plaster.wall = spot.wall;
  plaster.face = spot.face;
  plaster.at = spot.at;
  plaster.size = {1.6, 0.6};
  plaster.bumps.push_back({spot.at + Eigen::Vector2d(0.2, -0.1), 0.05, 0.003});
  plaster.holes.push_back({spot.at + Eigen::Vector2d(-0.2, 0.1), 0.04, 0.004});
  w.surfaces.push_back(plaster);
  const world::World back = world::parse_world_yaml(world_yaml(w), "fzk_plaster.yaml");
  ASSERT_EQ(back.surfaces.size(), 1u);
  EXPECT_EQ(back.surfaces[0].wall, spot.wall);
  EXPECT_EQ(back.surfaces[0].face, spot.face);
  EXPECT_TRUE(back.surfaces[0].at.isApprox(spot.at, 1e-9));
  EXPECT_TRUE(back.surfaces[0].size.isApprox(plaster.size, 1e-9));
  ASSERT_EQ(back.surfaces[0].bumps.size(), 1u);
  ASSERT_EQ(back.surfaces[0].holes.size(), 1u);
  EXPECT_DOUBLE_EQ(back.surfaces[0].holes[0].height, 0.004);
  // 1.6 m wide centred 0.5 m from the wall's east end: no face holds it whole.
  EXPECT_THAT([&] { (void)place_on_wall(w, wall, {11.2, 4.0, 2.175}, south, {0.8, 0.3}, "plaster"); },
              ::testing::ThrowsMessage<BimError>(::testing::HasSubstr("plaster: wall 2XPyKWY018sA1ygZKgQPtU")));
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
