#include "concert/world/geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/aruco.hpp>

#include "concert/world/aruco.hpp"

namespace concert::world {
namespace {

World fixture() { return load_world_file(std::string(WORLD_FIXTURES) + "/marks_world.yaml"); }

WorldShape wall(double yaw) {
  WorldShape w;
  w.name = "w";
  w.size = {0.2, 4.0, 2.0};
  w.position = {1.0, 2.0, 1.0};
  w.yaw = yaw;
  return w;
}

TEST(WorldGeometry, FaceFrameIsRightHandedWithUToTheViewersRight) {
  for (const double yaw : {0.0, 0.3, -2.0}) {
    for (const Face face : {Face::kPlusX, Face::kMinusX, Face::kPlusY, Face::kMinusY}) {
      const WorldShape w = wall(yaw);
      const Eigen::Isometry3d f = face_frame(w, face);
      const Eigen::Matrix3d r = f.linear();
      EXPECT_TRUE((r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
      EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
      EXPECT_TRUE(r.col(1).isApprox(Eigen::Vector3d::UnitZ()));
      // The face centre is half the wall's depth out from the centre, along n.
      const double half_depth = (face == Face::kPlusX || face == Face::kMinusX) ? 0.1 : 2.0;
      EXPECT_TRUE(f.translation().isApprox(w.position + half_depth * r.col(2), 1e-12));
      // A viewer outside looking at the face (along -n) with z up has its right at
      // forward x up = (-n) x z.
      EXPECT_TRUE(r.col(0).isApprox((-r.col(2)).cross(Eigen::Vector3d::UnitZ()), 1e-12));
    }
  }
  // Yaw 0: +x face normal +x, u = +y; -x face normal -x, u = -y.
  EXPECT_TRUE(
      face_frame(wall(0.0), Face::kPlusX).linear().col(0).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE(
      face_frame(wall(0.0), Face::kMinusX).linear().col(0).isApprox(-Eigen::Vector3d::UnitY()));
  EXPECT_TRUE(
      face_frame(wall(M_PI / 2), Face::kPlusX).linear().col(2).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE(face_size(wall(0.0), Face::kPlusY).isApprox(Eigen::Vector2d(0.2, 2.0)));
  EXPECT_TRUE(face_size(wall(0.0), Face::kMinusX).isApprox(Eigen::Vector2d(4.0, 2.0)));
}

void expect_marker_geometry(const World& w) {
  const auto truth = mark_truth(w);
  ASSERT_EQ(truth.size(), w.marks.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const MarkTruth& t = truth[i];
    const Mark& m = w.marks[i];
    const Eigen::Isometry3d f = face_frame(find_wall(w, m.wall), m.face);
    // The centre is on the front surface, 1 mm in front of the face, at [u, z].
    const Eigen::Vector3d local = f.inverse() * t.centre;
    EXPECT_NEAR(local.z(), kMarkStandoff, 1e-12);
    EXPECT_NEAR(local.x(), m.at.x(), 1e-12);
    EXPECT_NEAR(t.centre.z(), m.at.y(), 1e-12);
    EXPECT_TRUE(t.normal.isApprox(f.linear().col(2)));
    if (m.type == Mark::Type::kBlob) {
      EXPECT_DOUBLE_EQ(t.diameter, m.diameter);
      continue;
    }
    // Corners: a square of side `size` on the front plane, around the centre.
    for (std::size_t k = 0; k < 4; ++k) {
      const Eigen::Vector3d a = t.corners[k], b = t.corners[(k + 1) % 4],
                            c = t.corners[(k + 2) % 4];
      EXPECT_NEAR((b - a).norm(), m.size, 1e-12);
      EXPECT_NEAR((b - a).dot(c - b), 0.0, 1e-12);
      EXPECT_NEAR((f.inverse() * a).z(), kMarkStandoff, 1e-12);
      // Clockwise as seen from the front (OpenCV's order): (b - a) x (c - b) points into the wall.
      EXPECT_LT((b - a).cross(c - b).dot(t.normal), 0.0);
    }
    EXPECT_TRUE(((t.corners[0] + t.corners[2]) / 2).isApprox(t.centre, 1e-12));
    // Top edge direction: u rotated by `angle` counter-clockwise (seen from the front) about n.
    const Eigen::Vector3d top = (t.corners[1] - t.corners[0]).normalized();
    const Eigen::Vector3d expected =
        std::cos(m.angle) * t.right + std::sin(m.angle) * Eigen::Vector3d::UnitZ();
    EXPECT_TRUE(top.isApprox(expected, 1e-12)) << top.transpose() << " vs " << expected.transpose();
  }
}

TEST(WorldGeometry, ArucoCornersAreInOpenCvOrderOnEveryFace) {
  World w = fixture();
  expect_marker_geometry(w);
  const auto t = mark_truth(w)[2];
  EXPECT_EQ(t.name, "marker_7");
  EXPECT_EQ(t.id, 7);
  // Seen from the origin (face -x at x = 0.75 m, u = -y): top-left is at +y and up.
  EXPECT_TRUE(t.centre.isApprox(Eigen::Vector3d(0.749, -0.5, 1.3), 1e-12));
  EXPECT_TRUE(t.corners[0].isApprox(Eigen::Vector3d(0.749, -0.425, 1.375), 1e-12));
  EXPECT_TRUE(t.corners[1].isApprox(Eigen::Vector3d(0.749, -0.575, 1.375), 1e-12));
  EXPECT_TRUE(t.corners[2].isApprox(Eigen::Vector3d(0.749, -0.575, 1.225), 1e-12));
  EXPECT_TRUE(t.corners[3].isApprox(Eigen::Vector3d(0.749, -0.425, 1.225), 1e-12));
  // Every face of a yawed wall, rotated markers.
  World yawed;
  yawed.walls.push_back(wall(0.7));
  int k = 0;
  for (const Face face : {Face::kPlusX, Face::kMinusX, Face::kPlusY, Face::kMinusY}) {
    Mark m;
    m.name = "m" + std::to_string(k);
    m.type = Mark::Type::kAruco;
    m.wall = "w";
    m.face = face;
    m.at = {0.0, 1.0};
    m.size = 0.08;
    m.id = k;
    m.angle = 0.4 * k;
    yawed.marks.push_back(m);
    ++k;
  }
  validate_world(yawed, "test");
  expect_marker_geometry(yawed);
  // Angle pi/2: the top-left corner of the upright marker moves to the bottom-left.
  World turned = w;
  turned.marks[2].angle = M_PI / 2;
  const auto r = mark_truth(turned)[2];
  EXPECT_TRUE(r.corners[0].isApprox(t.corners[3], 1e-12));
  EXPECT_TRUE(r.corners[1].isApprox(t.corners[0], 1e-12));
}

TEST(WorldGeometry, SurfaceHeightHasCosineBumpsAndHoles) {
  const World w = fixture();
  const Surface& s = w.surfaces[0];
  EXPECT_DOUBLE_EQ(surface_height(s, -0.8, 1.1), 0.003);
  EXPECT_NEAR(surface_height(s, -0.8 + 0.025, 1.1), 0.0015,
              1e-12);  // half the radius: half the height
  EXPECT_NEAR(surface_height(s, -0.8, 1.1 - 0.05), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(surface_height(s, -0.55, 0.9), -0.004);
  EXPECT_NEAR(surface_height(s, -0.55 + 0.03, 0.9), -0.004 * 0.5 * (1 + std::cos(M_PI * 0.75)),
              1e-12);
  EXPECT_DOUBLE_EQ(surface_height(s, -0.7, 1.25), 0.0);
  // The bump top is thickness + height in front of the face (x = 0.75, n = -x).
  EXPECT_TRUE(
      surface_point(w, s, -0.8, 1.1).isApprox(Eigen::Vector3d(0.75 - 0.013, 0.8, 1.1), 1e-12));
}

WorldShape mover(ObstaclePath::Mode mode) {
  WorldShape o;
  o.name = "o";
  o.position = {0.0, 0.0, 0.4};
  o.path = ObstaclePath{{{2.0, 0.0}, {2.0, 1.0}}, 0.5, mode};
  return o;
}

TEST(WorldGeometry, ObstaclePositionForEachMode) {
  const WorldShape loop = mover(ObstaclePath::Mode::kLoop);
  EXPECT_NEAR(path_length(loop), 3.0 + std::sqrt(5.0), 1e-12);
  EXPECT_TRUE(obstacle_position(loop, 0.0).isApprox(Eigen::Vector3d(0.0, 0.0, 0.4)));
  EXPECT_TRUE(obstacle_position(loop, 2.0).isApprox(Eigen::Vector3d(1.0, 0.0, 0.4)));
  EXPECT_TRUE(obstacle_position(loop, 5.0).isApprox(Eigen::Vector3d(2.0, 0.5, 0.4)));
  // Back towards the start along the closing segment, then round again.
  const double lap = (3.0 + std::sqrt(5.0)) / 0.5;
  EXPECT_TRUE(
      obstacle_position(loop, 6.0 + std::sqrt(5.0)).isApprox(Eigen::Vector3d(1.0, 0.5, 0.4), 1e-9));
  EXPECT_TRUE(obstacle_position(loop, lap + 2.0).isApprox(Eigen::Vector3d(1.0, 0.0, 0.4), 1e-9));

  const WorldShape ping = mover(ObstaclePath::Mode::kPingPong);
  EXPECT_NEAR(path_length(ping), 3.0, 1e-12);
  EXPECT_TRUE(obstacle_position(ping, 5.0).isApprox(Eigen::Vector3d(2.0, 0.5, 0.4)));
  EXPECT_TRUE(
      obstacle_position(ping, 7.0).isApprox(Eigen::Vector3d(2.0, 0.5, 0.4)));  // on its way back
  EXPECT_TRUE(obstacle_position(ping, 10.0).isApprox(Eigen::Vector3d(1.0, 0.0, 0.4)));
  EXPECT_TRUE(obstacle_position(ping, 14.0).isApprox(Eigen::Vector3d(1.0, 0.0, 0.4)));  // out again

  const WorldShape once = mover(ObstaclePath::Mode::kOnce);
  EXPECT_TRUE(obstacle_position(once, 5.0).isApprox(Eigen::Vector3d(2.0, 0.5, 0.4)));
  EXPECT_TRUE(obstacle_position(once, 60.0).isApprox(Eigen::Vector3d(2.0, 1.0, 0.4)));

  WorldShape still = once;
  still.path.reset();
  EXPECT_TRUE(obstacle_position(still, 10.0).isApprox(still.position));
}

TEST(WorldGeometry, ArucoCellsMatchOpenCvsDictionary) {
  EXPECT_EQ(aruco_dictionary_names().size(), 21u);
  EXPECT_EQ(aruco_dictionary_size("DICT_4X4_50"), 50);
  EXPECT_EQ(aruco_dictionary_size("DICT_ARUCO_ORIGINAL"), 1024);
  const ArucoCells c = aruco_cells("DICT_4X4_50", 7);
  EXPECT_EQ(c.side, 6);
  int white = 0;
  for (int i = 0; i < c.side; ++i) {
    // The border is black.
    EXPECT_FALSE(c.at(0, i));
    EXPECT_FALSE(c.at(i, 0));
    EXPECT_FALSE(c.at(c.side - 1, i));
    EXPECT_FALSE(c.at(i, c.side - 1));
    for (int j = 0; j < c.side; ++j) {
      white += c.at(i, j) ? 1 : 0;
    }
  }
  EXPECT_GT(white, 0);
  EXPECT_LT(white, 16);
  EXPECT_NE(aruco_cells("DICT_4X4_50", 8).white, c.white);
  // OpenCV detects the cells, drawn upright with a white margin, as marker 7 with its first
  // corner at the top-left.
  const int px = 20, margin = 40;
  cv::Mat image(c.side * px + 2 * margin, c.side * px + 2 * margin, CV_8UC1, cv::Scalar(255));
  for (int r = 0; r < c.side; ++r) {
    for (int col = 0; col < c.side; ++col) {
      image(cv::Rect(margin + col * px, margin + r * px, px, px)).setTo(c.at(r, col) ? 255 : 0);
    }
  }
  std::vector<std::vector<cv::Point2f>> found;
  std::vector<int> ids;
  cv::aruco::detectMarkers(image, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50), found,
                           ids);
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(ids[0], 7);
  EXPECT_NEAR(found[0][0].x, margin, 2.0);
  EXPECT_NEAR(found[0][0].y, margin, 2.0);
  EXPECT_NEAR(found[0][1].x, margin + c.side * px, 2.0);
  EXPECT_NEAR(found[0][1].y, margin, 2.0);
  EXPECT_THROW((void)aruco_cells("DICT_4X4_50", 50), WorldError);
  EXPECT_THROW((void)aruco_cells("DICT_3X3_9", 0), WorldError);
}

}  // namespace
}  // namespace concert::world
