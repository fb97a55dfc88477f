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
  expect_error("obstacles:\n  - name: a\n    shape: cone\n    position: [0, 0, 0]\n",
               "obstacles[0].shape");
  expect_error(
      "walls:\n  - name: a\n    shape: cylinder\n    radius: 1\n    height: 1\n    position: [0, "
      "0, 0]\n",
      "walls[0].shape");
  expect_error("roof: {}\n", "roof");
  expect_error(
      "walls:\n  - name: a\n    size: [1, 1, 1]\n    position: [0, 0, 0]\n"
      "  - name: a\n    size: [1, 1, 1]\n    position: [0, 0, 0]\n",
      "duplicate");
  expect_error("walls: [\n", "YAML error");
  expect_error("walls:\n  - name: a\n    size: [1, x, 1]\n    position: [0, 0, 0]\n",
               "walls[0].size[1]");
  // Found by tests/fuzz: yaml-cpp's conversion errors escaped the parser.
  expect_error("floor: f\n", "floor: expected true or false");
  expect_error("floor: {enabled: 3}\n", "floor.enabled: expected true or false");
  expect_error("{[a]: 1}\n", "top level: a key that is not a name");
  expect_error("walls:\n  - {[a]: 1}\n", "walls[0]: a key that is not a name");
}

// A wall 4 m wide (along y), 2 m high, whose -x face is at x = 0.9: u = -y on that face.
const std::string kWall =
    "walls:\n  - {name: w, size: [0.2, 4.0, 2.0], position: [1.0, 0.0, 1.0]}\n";

std::string with(const std::string& items) { return kWall + items; }

TEST(World, ParsesMarksSurfacesAndPaths) {
  const World w = load_world_file(std::string(WORLD_FIXTURES) + "/marks_world.yaml");
  ASSERT_EQ(w.marks.size(), 3u);
  EXPECT_EQ(w.marks[0].type, Mark::Type::kBlob);
  EXPECT_EQ(w.marks[0].face, Face::kMinusX);
  EXPECT_TRUE(w.marks[0].at.isApprox(Eigen::Vector2d(0.25, 1.0)));
  EXPECT_DOUBLE_EQ(w.marks[0].diameter, 0.08);
  EXPECT_TRUE(w.marks[0].rgba.isApprox(Eigen::Vector4d(0.05, 0.1, 0.9, 1.0)));
  EXPECT_EQ(w.marks[2].type, Mark::Type::kAruco);
  EXPECT_EQ(w.marks[2].dictionary, "DICT_4X4_50");
  EXPECT_EQ(w.marks[2].id, 7);
  EXPECT_DOUBLE_EQ(w.marks[2].size, 0.15);
  ASSERT_EQ(w.surfaces.size(), 1u);
  EXPECT_TRUE(w.surfaces[0].size.isApprox(Eigen::Vector2d(0.8, 0.6)));
  ASSERT_EQ(w.surfaces[0].bumps.size(), 1u);
  ASSERT_EQ(w.surfaces[0].holes.size(), 1u);
  EXPECT_DOUBLE_EQ(w.surfaces[0].holes[0].height, 0.004);
  ASSERT_EQ(w.obstacles.size(), 2u);
  EXPECT_FALSE(w.obstacles[0].path);
  ASSERT_TRUE(w.obstacles[1].path);
  EXPECT_EQ(w.obstacles[1].path->mode, ObstaclePath::Mode::kPingPong);
  EXPECT_DOUBLE_EQ(w.obstacles[1].path->speed, 0.5);
  const World defaults = parse_world_yaml(with(
      "marks:\n  - {type: aruco, name: m, wall: w, face: -x, at: [0, 1], size: 0.1, dictionary: "
      "DICT_ARUCO_ORIGINAL, id: 1023}\n"
      "surfaces:\n  - {name: s, wall: w, face: +x, at: [0, 1], size: [1, 1]}\n"
      "obstacles:\n  - {name: o, size: [1, 1, 1], position: [0, 0, 0.5], path: {waypoints: [[1, "
      "1]], speed: 1}}\n"));
  EXPECT_DOUBLE_EQ(defaults.marks[0].angle, 0.0);
  EXPECT_DOUBLE_EQ(defaults.surfaces[0].thickness, 0.01);
  EXPECT_DOUBLE_EQ(defaults.surfaces[0].resolution, 0.005);
  EXPECT_EQ(defaults.obstacles[0].path->mode, ObstaclePath::Mode::kLoop);
}

TEST(World, BadDictionaryFixtureIsRefusedListingTheAcceptedOnes) {
  try {
    (void)load_world_file(std::string(WORLD_FIXTURES) + "/marks_bad_dictionary.yaml");
    FAIL() << "accepted DICT_3X3_9";
  } catch (const WorldError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("marks_bad_dictionary.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("marks[0].dictionary: unknown ArUco dictionary 'DICT_3X3_9'"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("DICT_4X4_50"), std::string::npos) << what;
    EXPECT_NE(what.find("DICT_APRILTAG_36h11"), std::string::npos) << what;
  }
}

TEST(World, MarkErrorsNameTheFieldAndWhy) {
  const std::string blob = "marks:\n  - {type: blob, name: b, wall: w, face: -x, diameter: 0.1, ";
  const std::string aruco =
      "marks:\n  - {type: aruco, name: m, wall: w, face: -x, at: [0, 1], size: 0.1, ";
  expect_error(with(aruco + "dictionary: DICT_4X4_50, id: 50}\n"),
               "marks[0].id: id 50 is not in DICT_4X4_50 (ids 0..49)");
  expect_error(with(aruco + "dictionary: DICT_4X4_50, id: -1}\n"), "marks[0].id");
  expect_error(with(aruco + "dictionary: DICT_4X4_50}\n"), "marks[0].id: missing");
  expect_error(with(aruco + "dictionary: DICT_5X5_50, id: 1, diameter: 3}\n"),
               "marks[0].diameter: unknown key");
  expect_error(with(blob + "at: [0, 1], wall2: x}\n"), "marks[0].wall2: unknown key");
  expect_error(
      with("marks:\n  - {type: blob, name: b, wall: nope, face: -x, at: [0, 1], diameter: 0.1}\n"),
      "marks[0].wall: no wall named 'nope' (walls: w)");
  expect_error(
      with("marks:\n  - {type: blob, name: b, wall: w, face: +z, at: [0, 1], diameter: 0.1}\n"),
      "marks[0].face: unknown face '+z'");
  expect_error(with("marks:\n  - {type: disc, name: b, wall: w, face: -x, at: [0, 1]}\n"),
               "marks[0].type");
  // Off the face: sideways (its radius included), above the top, below the bottom.
  expect_error(with(blob + "at: [1.96, 1]}\n"),
               "marks[0].at: 'b' is not entirely on face -x of wall 'w'");
  expect_error(with(blob + "at: [0, 1.96]}\n"), "marks[0].at");
  expect_error(with(blob + "at: [0, 0.04]}\n"), "not entirely on face");
  EXPECT_NO_THROW((void)parse_world_yaml(with(blob + "at: [1.95, 1.95]}\n")));
  // A marker rotated by 45 degrees needs sqrt(2) times the room.
  EXPECT_NO_THROW((void)parse_world_yaml(with(aruco + "dictionary: DICT_4X4_50, id: 1}\n")));
  expect_error(
      with("marks:\n  - {type: aruco, name: m, wall: w, face: -x, at: [1.94, 1], size: 0.1, "
           "dictionary: DICT_4X4_50, id: 1, angle: 0.785398}\n"),
      "not entirely on face");
  expect_error(
      with("marks:\n  - {type: blob, name: b, wall: w, face: -x, at: [0, 1], diameter: 0}\n"),
      "marks[0].diameter: must be positive");
  expect_error(with("marks:\n  - {type: aruco, name: m, wall: w, face: -x, at: [0, 1], size: -0.1, "
                    "dictionary: DICT_4X4_50, id: 1}\n"),
               "marks[0].size: must be positive");
  expect_error(with(blob + "at: [0, 1], rgba: [0, 0, 2, 1]}\n"), "marks[0].rgba");
  // Overlaps on the same face; the same place on the other face is fine.
  expect_error(with(blob + "at: [0, 1]}\n  - {type: blob, name: c, wall: w, face: -x, at: [0.09, "
                           "1], diameter: 0.1}\n"),
               "marks[1].at: 'c' overlaps marks[0] 'b' on face -x of wall 'w'");
  EXPECT_NO_THROW((void)parse_world_yaml(with(
      blob +
      "at: [0, 1]}\n  - {type: blob, name: c, wall: w, face: +x, at: [0, 1], diameter: 0.1}\n")));
  expect_error(
      with(
          blob +
          "at: [0, 1]}\n  - {type: blob, name: b, wall: w, face: +x, at: [0, 1], diameter: 0.1}\n"),
      "marks[1].name: duplicate name 'b' (also marks[0])");
  expect_error(
      with(
          blob +
          "at: [0, 1]}\n  - {type: blob, name: w, wall: w, face: +x, at: [0, 1], diameter: 0.1}\n"),
      "marks[1].name: duplicate name 'w' (also walls[0])");
}

TEST(World, SurfaceErrorsNameTheFieldAndWhy) {
  const std::string s = "surfaces:\n  - {name: s, wall: w, face: -x, at: [0, 1], size: [1, 1], ";
  EXPECT_NO_THROW(
      (void)parse_world_yaml(with(s + "bumps: [{at: [0.2, 1.2], radius: 0.1, height: 0.002}]}\n")));
  expect_error(with(s + "holes: [{at: [0, 1], radius: 0.1, depth: 0.01}]}\n"),
               "surfaces[0].holes[0].depth: a hole must be shallower than the layer");
  expect_error(with(s + "holes: [{at: [0, 1], radius: 0.1, height: 0.001}]}\n"),
               "surfaces[0].holes[0].height: unknown key");
  expect_error(with(s + "bumps: [{at: [0.45, 1], radius: 0.1, height: 0.002}]}\n"),
               "surfaces[0].bumps[0].at: not entirely on the panel 's'");
  expect_error(
      with(s +
           "bumps: [{at: [0, 1], radius: 0.1, height: 0.002}], holes: [{at: [0.1, 1], radius: 0.1, "
           "depth: 0.002}]}\n"),
      "surfaces[0].holes[0].at: overlaps surfaces[0].bumps[0]");
  expect_error(with(s + "bumps: [{at: [0, 1], radius: 0, height: 0.002}]}\n"),
               "surfaces[0].bumps[0].radius: must be positive");
  expect_error(with(s + "thickness: 0}\n"), "surfaces[0].thickness: must be positive");
  expect_error(with(s + "resolution: -1}\n"), "surfaces[0].resolution: must be positive");
  expect_error(with(s + "resolution: 0.0001}\n"), "surfaces[0].resolution: too fine");
  expect_error(with("surfaces:\n  - {name: s, wall: w, face: -x, at: [0, 1], size: [0, 1]}\n"),
               "surfaces[0].size[0]: must be positive");
  expect_error(with("surfaces:\n  - {name: s, wall: w, face: -x, at: [1.6, 1], size: [1, 1]}\n"),
               "surfaces[0].at: 's' is not entirely on face -x");
  expect_error(with("surfaces:\n  - {name: s, wall: x, face: -x, at: [0, 1], size: [1, 1]}\n"),
               "surfaces[0].wall: no wall named 'x'");
  expect_error(with(s + "}\nmarks:\n  - {type: blob, name: b, wall: w, face: -x, at: [0.4, 1.4], "
                        "diameter: 0.1}\n"),
               "surfaces[0].at: 's' overlaps marks[0] 'b'");
}

TEST(World, PathErrorsNameTheFieldAndWhy) {
  const std::string o = "obstacles:\n  - {name: o, size: [1, 1, 1], position: [0, 0, 0.5], path: ";
  expect_error(o + "{waypoints: [], speed: 1}}\n",
               "obstacles[0].path.waypoints: needs at least one waypoint");
  expect_error(o + "{waypoints: [[1, 1]], speed: 0}}\n",
               "obstacles[0].path.speed: must be positive");
  expect_error(o + "{waypoints: [[1, 1]]}}\n", "obstacles[0].path.speed: missing");
  expect_error(o + "{waypoints: [[1, 1, 1]], speed: 1}}\n",
               "obstacles[0].path.waypoints[0]: expected a list of 2");
  expect_error(o + "{waypoints: [[1, 1]], speed: 1, mode: bounce}}\n",
               "obstacles[0].path.mode: unknown mode 'bounce'");
  expect_error(
      "walls:\n  - {name: w, size: [1, 1, 1], position: [0, 0, 0.5], path: {waypoints: [[1, 1]], "
      "speed: 1}}\n",
      "walls[0].path: unknown key");
}

}  // namespace
}  // namespace concert::world
