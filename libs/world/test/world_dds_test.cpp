#include "concert/world/world_dds.hpp"

#include <gtest/gtest.h>

namespace concert::world {
namespace {

void expect_same(const WorldShape& a, const WorldShape& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.type, b.type);
  EXPECT_EQ(a.size, b.size);
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.yaw, b.yaw);
  EXPECT_EQ(a.friction, b.friction);
  ASSERT_EQ(a.path.has_value(), b.path.has_value()) << a.name;
  if (a.path) {
    EXPECT_EQ(a.path->waypoints, b.path->waypoints);
    EXPECT_EQ(a.path->speed, b.path->speed);
    EXPECT_EQ(a.path->mode, b.path->mode);
  }
}

void expect_same(const std::vector<SurfaceFeature>& a, const std::vector<SurfaceFeature>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].at, b[i].at);
    EXPECT_EQ(a[i].radius, b[i].radius);
    EXPECT_EQ(a[i].height, b[i].height);
  }
}

TEST(WorldDds, RoundTripKeepsEveryField) {
  World w = load_world_file(std::string(WORLD_FIXTURES) + "/marks_world.yaml");
  w.marks[0].rgba = {0.1, 0.2, 0.7, 0.9};
  w.marks[2].angle = 0.25;
  w.walls[0].yaw = 0.1;
  w.floor_height = 0.05;
  const msg::World m = to_msg(w, 4, "marks_world.yaml");
  EXPECT_EQ(m.version(), 4u);
  EXPECT_EQ(m.source(), "marks_world.yaml");
  const World back = from_msg(m);
  EXPECT_EQ(back.floor, w.floor);
  EXPECT_EQ(back.floor_height, w.floor_height);
  EXPECT_EQ(back.floor_friction, w.floor_friction);
  ASSERT_EQ(back.walls.size(), w.walls.size());
  ASSERT_EQ(back.obstacles.size(), w.obstacles.size());
  for (std::size_t i = 0; i < w.walls.size(); ++i) {
    expect_same(back.walls[i], w.walls[i]);
  }
  for (std::size_t i = 0; i < w.obstacles.size(); ++i) {
    expect_same(back.obstacles[i], w.obstacles[i]);
  }
  ASSERT_EQ(back.marks.size(), w.marks.size());
  for (std::size_t i = 0; i < w.marks.size(); ++i) {
    const Mark &a = back.marks[i], &b = w.marks[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.wall, b.wall);
    EXPECT_EQ(a.face, b.face);
    EXPECT_EQ(a.at, b.at);
    EXPECT_EQ(a.diameter, b.diameter);
    EXPECT_EQ(a.rgba, b.rgba);
    EXPECT_EQ(a.size, b.size);
    EXPECT_EQ(a.dictionary, b.dictionary);
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.angle, b.angle);
  }
  ASSERT_EQ(back.surfaces.size(), w.surfaces.size());
  for (std::size_t i = 0; i < w.surfaces.size(); ++i) {
    const Surface &a = back.surfaces[i], &b = w.surfaces[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.wall, b.wall);
    EXPECT_EQ(a.face, b.face);
    EXPECT_EQ(a.at, b.at);
    EXPECT_EQ(a.size, b.size);
    EXPECT_EQ(a.thickness, b.thickness);
    EXPECT_EQ(a.resolution, b.resolution);
    expect_same(a.bumps, b.bumps);
    expect_same(a.holes, b.holes);
  }
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
    EXPECT_NE(std::string(e.what()).find("world message 'test': obstacles[0].size"),
              std::string::npos)
        << e.what();
  }
}

TEST(WorldDds, BadMarkInAMessageIsRefusedAsInAFile) {
  const World w = load_world_file(std::string(WORLD_FIXTURES) + "/marks_world.yaml");
  msg::World m = to_msg(w, 1, "test");
  m.marks()[2].dictionary("DICT_3X3_9");
  EXPECT_THROW((void)from_msg(m), WorldError);
  m = to_msg(w, 1, "test");
  m.surfaces()[0].holes()[0].height(0.02);
  try {
    (void)from_msg(m);
    FAIL() << "accepted a hole deeper than its layer";
  } catch (const WorldError& e) {
    EXPECT_NE(std::string(e.what()).find("surfaces[0].holes[0].depth"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace concert::world
