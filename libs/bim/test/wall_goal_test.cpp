#include "concert/bim/wall_goal.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "bim_test_models.hpp"
#include "concert/bim/geometry.hpp"
#include "concert/bim/storey_map.hpp"

namespace concert::bim {
namespace {

using ::testing::HasSubstr;
using namespace concert::bim::test_models;

constexpr const char* kInteriorWall = "2ptk1k7qn8_Qk22vjh$0DE";  // Wand-Int-ERDG-1, no opening
constexpr const char* kDoorWall = "3PfS__Y_DBAfq5naM6zD2Z";  // Wand-Int-ERDG-2, door Innentuer-1
constexpr const char* kDoor = "1Oms875aH3Wg$9l65H2ZGw";      // Innentuer-1

class WallGoalTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
    grid_ = new OccupancyGrid(storey_map(m, m.storey("Erdgeschoss")));
  }
  static void TearDownTestSuite() { delete grid_; }
  const BimModel& model() const { return shared_model("AC20-FZK-Haus.ifc"); }
  static OccupancyGrid* grid_;
};
OccupancyGrid* WallGoalTest::grid_ = nullptr;

TEST_F(WallGoalTest, FrameOnTheFaceAndBaseAtTheStandoffFacingIt) {
  const WallGeometry g = wall_geometry(model().element(kInteriorWall));
  const double s = g.length() / 2;
  const double standoff = 0.7;
  const double radius = 0.3;
  const WallGoal goal = wall_goal(model(), *grid_, kInteriorWall, s, 1.2, standoff, radius);
  const Eigen::Vector2d n = g.faces[static_cast<std::size_t>(goal.face)].normal;
  const Eigen::Matrix3d r = goal.area_frame.linear();
  // z along the face's outward normal, x horizontal along the face, a proper rotation.
  EXPECT_NEAR((r.col(2) - Eigen::Vector3d(n.x(), n.y(), 0)).norm(), 0, 1e-9);
  EXPECT_NEAR(r.col(0).z(), 0, 1e-9);
  EXPECT_NEAR(std::abs(r.col(0).head<2>().dot(g.direction())), 1, 1e-9);
  EXPECT_NEAR(r.determinant(), 1, 1e-9);
  EXPECT_NEAR((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 0, 1e-9);
  // Origin on the face at s along the axis and h above the storey.
  const Eigen::Vector3d o = goal.area_frame.translation();
  EXPECT_NEAR(o.z(), model().storey("Erdgeschoss").elevation + 1.2, 1e-9);
  EXPECT_NEAR(g.direction().dot(o.head<2>() - g.start), s, 1e-9);
  EXPECT_NEAR(n.dot(o.head<2>() - g.start), g.thickness / 2, 1e-9);
  // Base pose: standoff in front of the face, facing it, in free space.
  const Eigen::Vector2d base = goal.base_pose.head<2>();
  EXPECT_NEAR(n.dot(base - o.head<2>()), standoff, 1e-9);
  EXPECT_NEAR((base - o.head<2>() - standoff * n).norm(), 0, 1e-9);
  EXPECT_NEAR(std::remainder(goal.base_pose.z() - std::atan2(-n.y(), -n.x()), 2 * M_PI), 0, 1e-9);
  for (double a = 0; a < 2 * M_PI; a += 0.1) {
    EXPECT_FALSE(grid_->occupied(base + 0.99 * radius * Eigen::Vector2d(std::cos(a), std::sin(a))));
  }
  EXPECT_GE(goal.free_area, 2.0);
  EXPECT_EQ(goal.storey, "Erdgeschoss");
}

TEST(FaceChoiceName, ReadsTheThreeWordsAndNamesAnyOther) {
  EXPECT_EQ(face_choice("auto"), FaceChoice::kAuto);
  EXPECT_EQ(face_choice("left"), FaceChoice::kLeft);
  EXPECT_EQ(face_choice("right"), FaceChoice::kRight);
  EXPECT_THROW(
      {
        try {
          (void)face_choice("north");
        } catch (const BimError& e) {
          EXPECT_NE(std::string(e.what()).find("'north'"), std::string::npos) << e.what();
          throw;
        }
      },
      BimError);
}

TEST_F(WallGoalTest, BothFacesOfAnInteriorWallCanBeAsked) {
  const WallGeometry g = wall_geometry(model().element(kInteriorWall));
  const WallGoal left =
      wall_goal(model(), *grid_, kInteriorWall, g.length() / 2, 1.0, 0.7, 0.3, {FaceChoice::kLeft});
  const WallGoal right = wall_goal(model(), *grid_, kInteriorWall, g.length() / 2, 1.0, 0.7, 0.3,
                                   {FaceChoice::kRight});
  EXPECT_EQ(left.face, 0);
  EXPECT_EQ(right.face, 1);
  EXPECT_NEAR((left.area_frame.linear().col(2) + right.area_frame.linear().col(2)).norm(), 0, 1e-9);
}

TEST_F(WallGoalTest, PointOnADoorOpeningIsRefusedNamingTheDoor) {
  const Element& door = model().element(kDoor);
  const WallGeometry g = wall_geometry(model().element(kDoorWall));
  const double s = g.direction().dot(door.bounds.center().head<2>() - g.start);
  EXPECT_THAT([&] { (void)wall_goal(model(), *grid_, kDoorWall, s, 1.0, 0.7, 0.3); },
              ::testing::ThrowsMessage<BimError>(::testing::AllOf(
                  HasSubstr("on an opening"), HasSubstr("IfcDoor"), HasSubstr(kDoor))));
}

TEST_F(WallGoalTest, OffTheWallIsRefused) {
  EXPECT_THAT([&] { (void)wall_goal(model(), *grid_, kInteriorWall, -0.5, 1.0, 0.7, 0.3); },
              ::testing::ThrowsMessage<BimError>(HasSubstr("s = -0.500 m is off wall")));
  EXPECT_THAT([&] { (void)wall_goal(model(), *grid_, kInteriorWall, 1.0, 9.0, 0.7, 0.3); },
              ::testing::ThrowsMessage<BimError>(HasSubstr("h = 9.000 m is off wall")));
}

TEST_F(WallGoalTest, UnknownGlobalIdAndNonWallAreRefused) {
  EXPECT_THAT(
      [&] { (void)wall_goal(model(), *grid_, "3xxxxxxxxxxxxxxxxxxxxx", 1.0, 1.0, 0.7, 0.3); },
      ::testing::ThrowsMessage<BimError>(
          HasSubstr("no element with GlobalId '3xxxxxxxxxxxxxxxxxxxxx'")));
  EXPECT_THAT([&] { (void)wall_goal(model(), *grid_, kDoor, 1.0, 1.0, 0.7, 0.3); },
              ::testing::ThrowsMessage<BimError>(HasSubstr("is an IfcDoor, not a wall")));
}

TEST_F(WallGoalTest, NoReachableFaceGivesTheReasonPerFace) {
  const WallGeometry g = wall_geometry(model().element(kInteriorWall));
  // A robot whose disc reaches back into the wall from 5 cm in front of it.
  try {
    (void)wall_goal(model(), *grid_, kInteriorWall, g.length() / 2, 1.0, 0.05, 0.3);
    FAIL() << "no error";
  } catch (const BimError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no face of wall"));
    EXPECT_THAT(e.what(), HasSubstr("left face: the robot (radius 0.30 m)"));
    EXPECT_THAT(e.what(), HasSubstr("right face: the robot"));
    EXPECT_THAT(e.what(), HasSubstr("occupied cell"));
  }
}

}  // namespace
}  // namespace concert::bim
