// The drilling perception against the simulator: worlds with marks rendered by the simulator's
// own renderer and RealSense noise model (libs/sim SceneCamera), measured against the world's
// ground truth (world::mark_truth, face frames). Measured figures are printed as
// "[ measured ] ..." lines and recorded as test properties.
#include "drill/perception.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "concert/sim/scene_camera.hpp"
#include "concert/world/geometry.hpp"
#include "drill/patterns.hpp"

namespace concert::drill {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using world::Face;
using world::Mark;

// Every test renders without a display.
[[maybe_unused]] const bool kHeadless = [] {
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  return true;
}();

constexpr double kHeight = 1.2;  // height of the area the camera looks at [m]
constexpr double kDeg = M_PI / 180.0;

void measured(const std::string& key, double value, const char* unit) {
  ::testing::Test::RecordProperty(key, std::to_string(value));
  std::printf("[ measured ] %s = %.3f %s\n", key.c_str(), value, unit);
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// A 5 m x 3 m wall standing on the floor whose -x face has its centre at (face_x, 0, 1.5),
/// turned by `yaw` about that centre's vertical.
world::World wall_world(double face_x = 2.0, double yaw = 0.0) {
  world::World w;
  world::WorldShape wall;
  wall.name = "wall";
  wall.size = {0.2, 5.0, 3.0};
  wall.yaw = yaw;
  const Eigen::Vector3d face(face_x, 0.0, 1.5);
  wall.position =
      face + Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(0.1, 0, 0);
  w.walls.push_back(wall);
  return w;
}

/// A mark of `type` on the wall's -x face at [u, height].
Mark mark(const std::string& name, Mark::Type type, const Eigen::Vector2d& at) {
  Mark m;
  m.name = name;
  m.type = type;
  m.wall = "wall";
  m.face = Face::kMinusX;
  m.at = at;
  return m;
}

Mark blob(const std::string& name, const Eigen::Vector2d& at, double diameter) {
  Mark m = mark(name, Mark::Type::kBlob, at);
  m.diameter = diameter;
  return m;
}

Mark marker(const std::string& name, const Eigen::Vector2d& at, int id, double size = 0.1,
            double angle = 0.0) {
  Mark m = mark(name, Mark::Type::kAruco, at);
  m.size = size;
  m.dictionary = "DICT_4X4_50";
  m.id = id;
  m.angle = angle;
  return m;
}

/// The wall's -x face frame (x the viewer's right, y up, z the outward normal).
Eigen::Isometry3d face(const world::World& w) {
  return world::face_frame(w.walls[0], Face::kMinusX);
}

/// Added to every camera distance: off the depth's millimetre grid, so that its rounding shows
/// in the errors [m].
constexpr double kOffGrid = 0.00037;

/// The camera `distance` (+ kOffGrid) from face point `at` ([u, height]), looking at it from
/// `from` (unit, from the point towards the camera, world frame; default the face normal), level.
Eigen::Isometry3d camera_at(const world::World& w, const Eigen::Vector2d& at, double distance,
                            std::optional<Eigen::Vector3d> from = std::nullopt) {
  const Eigen::Vector3d target = world::face_point(w.walls[0], Face::kMinusX, at);
  const Eigen::Vector3d dir = from.value_or(face(w).linear().col(2)).normalized();
  return sim::look_at(target + (distance + kOffGrid) * dir, target);
}

sim::CameraParams camera_params(bool noise) {
  sim::CameraParams p;
  p.noise = noise;
  return p;
}

/// world z seen in the optical frame.
Eigen::Vector3d up_in(const Eigen::Isometry3d& world_T_optical) {
  return world_T_optical.linear().transpose() * Eigen::Vector3d::UnitZ();
}

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

// --- Frames, pixels, errors -------------------------------------------------------------------

/// A grey image at a constant depth, made by hand (no renderer).
hardware::RgbdFrame flat_frame(std::uint16_t depth_mm = 600) {
  hardware::RgbdFrame f;
  f.sensor = "camera_E";
  f.stamp = 12.3;
  f.intrinsics = {640, 480, 615.0, 615.0, 319.5, 239.5};
  f.rgb.assign(640u * 480u * 3u, 128);
  f.depth.assign(640u * 480u, depth_mm);
  return f;
}

template <class F>
void expect_drill_error(F&& f, const std::vector<std::string>& parts) {
  try {
    f();
    FAIL() << "no error";
  } catch (const DrillError& e) {
    for (const auto& part : parts) {
      EXPECT_THAT(e.what(), HasSubstr(part));
    }
  }
}

TEST(Frames, BadFramesAreRefusedNamingTheFrameAndWhatIsWrong) {
  hardware::RgbdFrame empty;
  empty.sensor = "camera_E";
  expect_drill_error([&] { detect_blobs(empty); }, {"camera_E", "empty image"});
  hardware::RgbdFrame short_depth = flat_frame();
  short_depth.depth.resize(100);
  expect_drill_error([&] { detect_aruco(short_depth); }, {"rgbd frame 'camera_E' at t = 12.300 s",
                                                          "depth has 100 values, expected 307200"});
  hardware::RgbdFrame short_rgb = flat_frame();
  short_rgb.rgb.resize(640u * 480u);
  expect_drill_error(
      [&] { area_frame_at(short_rgb, Eigen::Vector2d(320, 240), -Eigen::Vector3d::UnitY()); },
      {"camera_E", "rgb has 307200 values, expected 921600"});
  hardware::RgbdFrame no_focal = flat_frame();
  no_focal.intrinsics.fx = 0.0;
  expect_drill_error([&] { point_at_pixel(no_focal, {320, 240}); }, {"camera_E", "intrinsics"});
  expect_drill_error(
      [&] {
        detect_aruco(flat_frame(), ArucoParams{"DICT_9X9_1", 0.1, true, 50});
      },
      {"ArUco detection: unknown ArUco dictionary 'DICT_9X9_1'", "DICT_4X4_50"});
}

TEST(Frames, PixelsWithoutDepthAreErrorsNamingThePixel) {
  hardware::RgbdFrame f = flat_frame();
  // A hole of 20 x 20 px without depth around (100, 100).
  for (int v = 90; v < 110; ++v) {
    for (int u = 90; u < 110; ++u) {
      f.depth[static_cast<std::size_t>(v) * 640 + static_cast<std::size_t>(u)] = 0;
    }
  }
  expect_drill_error(
      [&] {
        point_at_pixel(f, {100, 100});
      },
      {"camera_E", "no depth at pixel (100.0, 100.0)"});
  expect_drill_error(
      [&] { area_frame_at(f, Eigen::Vector2d(100, 100), -Eigen::Vector3d::UnitY()); },
      {"no depth at pixel (100.0, 100.0)"});
  expect_drill_error(
      [&] {
        point_at_pixel(f, {700, 100});
      },
      {"pixel (700.0, 100.0) is outside the 640 x 480 image"});
  // The hole's edge: depth within the radius.
  EXPECT_NEAR(point_at_pixel(f, {92, 100}, 3.0).z(), 0.6, 1e-12);
}

TEST(Frames, PointAtPixelIsWhereTheRenderedWallIs) {
  world::World w = wall_world(2.0);
  const Eigen::Isometry3d cam = camera_at(w, {0.0, kHeight}, 0.6);
  sim::SceneCamera camera(w, camera_params(false));
  const hardware::RgbdFrame f = camera.render(cam);
  for (const Eigen::Vector2d& px :
       {Eigen::Vector2d(319.5, 239.5), Eigen::Vector2d(20, 30), Eigen::Vector2d(600, 400)}) {
    const Eigen::Vector3d p = cam * point_at_pixel(f, px);
    // On the face (x = 2.0) within the depth's 1 mm rounding, on the pixel's ray.
    EXPECT_NEAR(p.x(), 2.0, 0.0006) << px.transpose();
    EXPECT_LT((project(f.intrinsics, cam.inverse() * p) - px).norm(), 1e-9);
  }
}

// A view written for a person (concert_drill --unseen-frames): read back, it is the frame's
// colour image, pixel for pixel, with the cross where the mark was expected; a path that cannot
// be written is an error naming it.
TEST(Frames, AViewWrittenAsPngReadsBackAsTheFrameWithTheMarkCrossed) {
  hardware::RgbdFrame f = flat_frame();
  for (std::size_t i = 0; i < f.rgb.size(); ++i) f.rgb[i] = static_cast<std::uint8_t>((i * 7 + i / 1920) % 251);
  const std::string dir = ::testing::TempDir();
  const std::string path = dir + "/perception_test_view.png";
  write_view_png(f, path, Eigen::Vector2d(100.0, 200.0));
  const cv::Mat back = cv::imread(path, cv::IMREAD_COLOR);
  std::remove(path.c_str());
  ASSERT_FALSE(back.empty());
  ASSERT_EQ(back.cols, 640);
  ASSERT_EQ(back.rows, 480);
  const auto rgb_at = [&](int u, int v) {
    const std::size_t i = (static_cast<std::size_t>(v) * 640u + static_cast<std::size_t>(u)) * 3u;
    return cv::Vec3b(f.rgb[i + 2], f.rgb[i + 1], f.rgb[i]);  // as OpenCV reads it: BGR
  };
  for (const auto& [u, v] : {std::pair{0, 0}, std::pair{639, 479}, std::pair{320, 240}, std::pair{500, 30}})
    EXPECT_EQ(back.at<cv::Vec3b>(v, u), rgb_at(u, v)) << u << ", " << v;
  EXPECT_EQ(back.at<cv::Vec3b>(200, 100), cv::Vec3b(0, 0, 255));  // the cross's centre: red
  EXPECT_EQ(back.at<cv::Vec3b>(200, 116), cv::Vec3b(0, 0, 255));  // on its circle
  expect_drill_error([&] { write_view_png(f, dir + "/no/such/dir/view.png"); },
                     {"cannot write", "no/such/dir/view.png", "camera_E"});
}

// --- Depth averaging (hand-made frames) --------------------------------------------------------

TEST(DepthAverager, AveragesValidReadingsPerPixelInSubMillimetreSteps) {
  DepthAverager avg(3, 0.5);
  hardware::RgbdFrame a = flat_frame(1000), b = flat_frame(0), c = flat_frame(1003);
  b.depth[0] = 1001;  // pixel 0 read in every frame, the others in two of three
  a.stamp = 1.0;
  b.stamp = 2.0;
  c.stamp = 3.0;
  avg.add(a);
  avg.add(b);
  avg.add(c);
  hardware::RgbdFrame out = avg.average();
  EXPECT_DOUBLE_EQ(out.depth_scale, 1e-4);
  EXPECT_EQ(out.stamp, 3.0);
  EXPECT_EQ(out.depth[0], 10013);  // (1000 + 1001 + 1003) / 3 mm, in 0.1 mm
  EXPECT_EQ(out.depth[1], 10015);  // the zero ignored
  // A fourth frame pushes the first out; pixel 1 now has one reading of three: no data.
  avg.add(flat_frame(0));
  out = avg.average();
  EXPECT_EQ(avg.size(), 3u);
  EXPECT_EQ(out.depth[1], 0);
  EXPECT_EQ(out.depth[0], 10020);  // (1001 + 1003) / 2: b and c
  hardware::RgbdFrame other = flat_frame(1000);
  other.intrinsics.fx = 600.0;
  expect_drill_error([&] { avg.add(other); }, {"differ", "clear()"});
  avg.clear();
  EXPECT_NO_THROW(avg.add(other));
  expect_drill_error([] { DepthAverager(0); }, {"window"});
  expect_drill_error([] { (void)DepthAverager().average(); }, {"no frame"});
}

// --- Blue blobs --------------------------------------------------------------------------------

TEST(Blobs, ShapeSizeColourAndBorderFiltersOnADrawnFrame) {
  hardware::RgbdFrame f = flat_frame(600);
  cv::Mat rgb(480, 640, CV_8UC3, f.rgb.data());
  const cv::Scalar blue(20, 30, 220);  // RGB
  cv::circle(rgb, {200, 200}, 12, blue, cv::FILLED, cv::LINE_8);
  cv::line(rgb, {350, 100}, {450, 130}, blue, 8);                        // a pen stroke
  cv::circle(rgb, {100, 400}, 1, blue, cv::FILLED);                      // a speck
  cv::circle(rgb, {400, 350}, 60, blue, cv::FILLED);                     // 0.12 m: too large
  cv::circle(rgb, {634, 240}, 12, blue, cv::FILLED);                     // cut by the border
  cv::circle(rgb, {300, 300}, 12, cv::Scalar(220, 30, 20), cv::FILLED);  // red
  const std::vector<Blob> blobs = detect_blobs(f);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_LT((blobs[0].pixel - Eigen::Vector2d(200, 200)).norm(), 0.01);
  EXPECT_NEAR(blobs[0].radius_px, 12.0, 0.5);
  EXPECT_NEAR(blobs[0].diameter, 2 * 12.0 * 0.6 / 615.0, 0.001);
  EXPECT_TRUE(blobs[0].position.isApprox(deproject(f.intrinsics, {200, 200}, 0.6), 1e-4));
  EXPECT_GT(blobs[0].circularity, 0.85);
  // Allowing larger blobs finds the large disc, first.
  BlobParams large;
  large.max_diameter = 0.2;
  const std::vector<Blob> two = detect_blobs(f, large);
  ASSERT_EQ(two.size(), 2u);
  EXPECT_LT((two[0].pixel - Eigen::Vector2d(400, 350)).norm(), 0.01);
  EXPECT_NEAR(two[0].diameter, 2 * 60.0 * 0.6 / 615.0, 0.002);
  // Without depth behind it a blob is not reported (its size cannot be told).
  for (int v = 180; v <= 220; ++v) {
    for (int u = 180; u <= 220; ++u) {
      f.depth[static_cast<std::size_t>(v) * 640 + static_cast<std::size_t>(u)] = 0;
    }
  }
  EXPECT_TRUE(detect_blobs(f).empty());
}

/// A wall 3 m from the origin seen from `distance`, with 8 blobs of 2-3 cm spread over the
/// image, and what must not be taken for a blob: an ArUco marker, a red disc, an 8 cm blue disc,
/// a blob cut by the image's right border.
struct BlobScene {
  world::World world;
  Eigen::Isometry3d camera;
  std::vector<std::string> blobs;  ///< names of the marks that are blobs to find
};

BlobScene blob_scene(double d) {
  BlobScene s;
  s.world = wall_world(3.0);
  const double diameters[] = {0.02, 0.025, 0.03};
  int i = 0;
  for (const double u : {-0.36, -0.12, 0.12, 0.36}) {
    for (const double z : {-0.22, 0.12}) {
      const std::string name = "blob_" + std::to_string(i);
      s.world.marks.push_back(blob(name, {u * d, kHeight + z * d}, diameters[i % 3]));
      s.blobs.push_back(name);
      ++i;
    }
  }
  s.world.marks.push_back(marker("marker", {0.0, kHeight}, 0));
  Mark red = blob("red", {-0.24 * d, kHeight + 0.3 * d}, 0.025);
  red.rgba = {0.9, 0.1, 0.05, 1.0};
  s.world.marks.push_back(red);
  s.world.marks.push_back(blob("large", {0.24 * d, kHeight + 0.28 * d}, 0.08));
  s.world.marks.push_back(blob("cut", {320.0 / 615.0 * d, kHeight - 0.05 * d}, 0.025));
  s.camera = camera_at(s.world, {0.0, kHeight}, d);
  return s;
}

/// Errors of the detected blobs against the truth (optical frame) [m].
struct BlobErrors {
  double position{0.0};  ///< largest 3D error
  double depth{0.0};     ///< largest error along the optical axis
  double depth_mean{0.0};
  double diameter{0.0};  ///< largest
};

/// Matches every true blob to exactly one detection (nearest, within 2 cm) and measures.
BlobErrors blob_errors(const BlobScene& s, const std::vector<Blob>& found) {
  BlobErrors e;
  const auto truth = world::mark_truth(s.world);
  std::vector<bool> used(found.size(), false);
  for (const auto& t : truth) {
    if (std::find(s.blobs.begin(), s.blobs.end(), t.name) == s.blobs.end()) {
      continue;
    }
    const Eigen::Vector3d p = s.camera.inverse() * t.centre;
    std::size_t best = found.size();
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < found.size(); ++k) {
      const double dist = (found[k].position - p).norm();
      if (dist < nearest) {
        nearest = dist;
        best = k;
      }
    }
    EXPECT_LT(nearest, 0.02) << t.name << " not found";
    if (best == found.size() || nearest >= 0.02) {
      continue;
    }
    EXPECT_FALSE(used[best]) << t.name << " matched twice";
    used[best] = true;
    e.position = std::max(e.position, nearest);
    const double dz = std::abs(found[best].position.z() - p.z());
    e.depth = std::max(e.depth, dz);
    e.depth_mean += dz / static_cast<double>(s.blobs.size());
    e.diameter = std::max(e.diameter, std::abs(found[best].diameter - t.diameter));
  }
  return e;
}

struct BlobCase {
  double distance;
  bool noise;
  double max_position;  ///< [m]
  double max_diameter;  ///< [m]
};

class BlobsAtDistance : public ::testing::TestWithParam<BlobCase> {};

TEST_P(BlobsAtDistance, EveryBlobFoundNoneInventedWithinTheBound) {
  const BlobCase c = GetParam();
  const BlobScene s = blob_scene(c.distance);
  sim::SceneCamera camera(s.world, camera_params(c.noise), 11);
  const hardware::RgbdFrame f = camera.render(s.camera);
  const std::vector<Blob> found = detect_blobs(f);
  EXPECT_EQ(found.size(), s.blobs.size());
  const BlobErrors e = blob_errors(s, found);
  char key[64];
  std::snprintf(key, sizeof(key), "blob at %.1f m%s", c.distance, c.noise ? " noisy" : "");
  measured(std::string(key) + ": position error (max)", 1000 * e.position, "mm");
  measured(std::string(key) + ": depth error (max)", 1000 * e.depth, "mm");
  measured(std::string(key) + ": diameter error (max)", 1000 * e.diameter, "mm");
  double roundest = 1.0;
  for (const Blob& b : found) {
    roundest = std::min(roundest, b.circularity);
  }
  measured(std::string(key) + ": lowest circularity", roundest, "");
  EXPECT_LE(e.position, c.max_position);
  EXPECT_LE(e.diameter, c.max_diameter);
}

INSTANTIATE_TEST_SUITE_P(
    PaperDistances, BlobsAtDistance,
    ::testing::Values(BlobCase{0.6, false, 0.001, 0.001}, BlobCase{0.6, true, 0.001, 0.001},
                      BlobCase{1.0, false, 0.002, 0.002}, BlobCase{1.0, true, 0.002, 0.002},
                      BlobCase{2.0, false, 0.002, 0.003}, BlobCase{2.0, true, 0.010, 0.003},
                      BlobCase{2.5, true, 0.015, 0.003}));

// --- ArUco markers
// --------------------------------------------------------------------------------

/// world_T_marker of a marker's truth, straight from the world's conventions: x the marker's
/// right and y its up turned by its angle about the normal, z the normal.
Eigen::Isometry3d truth_marker_frame(const world::MarkTruth& t) {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear().col(0) = std::cos(t.angle) * t.right + std::sin(t.angle) * up;
  m.linear().col(1) = -std::sin(t.angle) * t.right + std::cos(t.angle) * up;
  m.linear().col(2) = t.normal;
  m.translation() = t.centre;
  return m;
}

double rotation_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

double hole_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const HolePattern& p) {
  const auto ha = pattern_holes(a, p), hb = pattern_holes(b, p);
  double worst = 0.0;
  for (std::size_t i = 0; i < ha.size(); ++i) {
    worst = std::max(worst, (ha[i].translation() - hb[i].translation()).norm());
  }
  return worst;
}

TEST(Aruco, MarkerFrameOfTheTruthCornersIsTheTruthFrame) {
  world::World w = wall_world(3.0, 0.4);
  w.marks.push_back(marker("m", {0.1, kHeight}, 3, 0.12, 0.7));
  const world::MarkTruth t = world::mark_truth(w)[0];
  const Eigen::Isometry3d frame = marker_frame(t.corners);
  EXPECT_TRUE(frame.isApprox(truth_marker_frame(t), 1e-12));
  expect_drill_error(
      [&] {
        marker_frame({t.centre, t.centre, t.centre, t.centre});
      },
      {"collinear"});
}

struct ArucoCase {
  double distance;
  bool noise;
  bool oblique;  ///< wall turned 20 degrees, seen from 15 degrees below, marker turned 0.3 rad
  double max_position;  ///< depth-refined [m]
  double max_angle;     ///< depth-refined [rad]
  double max_hole;      ///< pattern holes [m]
};

class ArucoAtDistance : public ::testing::TestWithParam<ArucoCase> {};

TEST_P(ArucoAtDistance, PoseAndPatternHolesMatchTheTruth) {
  const ArucoCase c = GetParam();
  const PatternTable table = load_patterns(shipped_patterns());
  world::World w = wall_world(3.0, c.oblique ? 20 * kDeg : 0.0);
  w.marks.push_back(
      marker("marker", {0.05, kHeight + 0.02}, 0, table.marker_size(), c.oblique ? 0.3 : 0.0));
  const Eigen::Vector3d n = face(w).linear().col(2);
  const Eigen::Vector3d from =
      c.oblique ? Eigen::Vector3d(std::cos(15 * kDeg) * -Eigen::Vector3d::UnitX() -
                                  std::sin(15 * kDeg) * Eigen::Vector3d::UnitZ())
                : n;
  const Eigen::Isometry3d cam = camera_at(w, {0.0, kHeight}, c.distance, from);
  sim::SceneCamera camera(w, camera_params(c.noise), 5);
  const hardware::RgbdFrame f = camera.render(cam);
  ArucoParams params;
  params.dictionary = table.dictionary();
  params.marker_size = table.marker_size();
  const std::vector<ArucoDetection> found = detect_aruco(f, params);
  ASSERT_EQ(found.size(), 1u);
  const ArucoDetection& det = found[0];
  EXPECT_EQ(det.id, 0);
  EXPECT_EQ(det.dictionary, "DICT_4X4_50");
  EXPECT_TRUE(det.depth_refined);
  const world::MarkTruth t = world::mark_truth(w)[0];
  // Corners where the truth projects, in the truth's order.
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_LT((det.corners[i] - project(f.intrinsics, cam.inverse() * t.corners[i])).norm(), 1.0)
        << "corner " << i;
  }
  const Eigen::Isometry3d truth = truth_marker_frame(t);
  const Eigen::Isometry3d refined = cam * det.optical_T_marker;
  const Eigen::Isometry3d pnp = cam * det.pnp;
  const HolePattern& pattern = *table.find(det.id);
  char key[80];
  std::snprintf(key, sizeof(key), "aruco at %.1f m%s%s", c.distance, c.oblique ? " oblique" : "",
                c.noise ? " noisy" : "");
  const double pnp_position = (pnp.translation() - truth.translation()).norm();
  const double refined_position = (refined.translation() - truth.translation()).norm();
  measured(std::string(key) + ": PnP position error", 1000 * pnp_position, "mm");
  measured(std::string(key) + ": depth-refined position error", 1000 * refined_position, "mm");
  measured(std::string(key) + ": PnP angle error", rotation_error(pnp, truth) / kDeg, "deg");
  measured(std::string(key) + ": depth-refined angle error", rotation_error(refined, truth) / kDeg,
           "deg");
  measured(std::string(key) + ": PnP pattern hole error (max)",
           1000 * hole_error(pnp, truth, pattern), "mm");
  measured(std::string(key) + ": depth-refined pattern hole error (max)",
           1000 * hole_error(refined, truth, pattern), "mm");
  measured(std::string(key) + ": measured marker size", 1000 * det.measured_size, "mm");
  EXPECT_LE(refined_position, c.max_position);
  EXPECT_LT(refined_position, pnp_position) << "the depth should place the marker better than PnP";
  EXPECT_LE(rotation_error(refined, truth), c.max_angle);
  EXPECT_LE(hole_error(refined, truth, pattern), c.max_hole);
  EXPECT_NEAR(det.measured_size, table.marker_size(), 0.003);
}

INSTANTIATE_TEST_SUITE_P(WorkingDistances, ArucoAtDistance,
                         ::testing::Values(ArucoCase{0.6, false, false, 0.001, 0.5 * kDeg, 0.003},
                                           ArucoCase{0.6, true, false, 0.001, 0.5 * kDeg, 0.003},
                                           ArucoCase{0.6, true, true, 0.001, 0.5 * kDeg, 0.003},
                                           ArucoCase{1.0, false, false, 0.001, 0.5 * kDeg, 0.003},
                                           ArucoCase{1.0, true, false, 0.001, 0.5 * kDeg, 0.003},
                                           ArucoCase{1.0, true, true, 0.001, 0.5 * kDeg, 0.003}));

TEST(Aruco, AMarkerOfAnotherSizeShowsInTheMeasuredSizeAndNotInTheRefinedPose) {
  world::World w = wall_world(3.0);
  w.marks.push_back(marker("marker", {0.0, kHeight}, 7, 0.15));
  const Eigen::Isometry3d cam = camera_at(w, {0.0, kHeight}, 0.6);
  sim::SceneCamera camera(w, camera_params(true), 9);
  ArucoParams params;  // 0.1 m: the table's size, not the printed one
  const std::vector<ArucoDetection> found = detect_aruco(camera.render(cam), params);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].id, 7);
  const Eigen::Vector3d truth = world::mark_truth(w)[0].centre;
  EXPECT_NEAR(found[0].measured_size, 0.15, 0.003);
  EXPECT_LT(((cam * found[0].optical_T_marker).translation() - truth).norm(), 0.002);
  // PnP believes the marker is 2/3 as far away as it is.
  EXPECT_GT(((cam * found[0].pnp).translation() - truth).norm(), 0.1);
}

// --- Surface normal and area frame
// ----------------------------------------------------------------

struct NormalCase {
  const char* name;
  double yaw;       ///< wall [rad]
  double below;     ///< camera this far below the normal's horizontal [rad]
  double distance;  ///< [m]
  bool noise;
};

/// The wall and the camera of a case; the camera looks along world +x turned by `below` upwards
/// (a wall turned by `yaw` is seen at that angle).
std::pair<world::World, Eigen::Isometry3d> normal_scene(const NormalCase& c) {
  world::World w = wall_world(3.0, c.yaw);
  const Eigen::Vector3d from =
      std::cos(c.below) * -Eigen::Vector3d::UnitX() - std::sin(c.below) * Eigen::Vector3d::UnitZ();
  return {w, camera_at(w, {0.0, kHeight}, c.distance, from)};
}

struct NormalErrors {
  double normal{0.0};       ///< angle of the frame's z from the face normal [rad]
  double x{0.0};            ///< angle of the frame's x from the face's horizontal [rad]
  double off_surface{0.0};  ///< distance of the origin from the face [m]
};

NormalErrors normal_errors(const world::World& w, const Eigen::Isometry3d& cam,
                           const Eigen::Isometry3d& optical_T_area) {
  const Eigen::Isometry3d area = cam * optical_T_area;
  const Eigen::Isometry3d truth = face(w);
  return {angle_between(area.linear().col(2), truth.linear().col(2)),
          angle_between(area.linear().col(0), truth.linear().col(0)),
          std::abs(truth.linear().col(2).dot(area.translation() - truth.translation()))};
}

class NormalOnTiltedWall : public ::testing::TestWithParam<NormalCase> {};

TEST_P(NormalOnTiltedWall, AreaFrameIsTheFaceFrameAtThePickedPixel) {
  const NormalCase c = GetParam();
  const auto [w, cam] = normal_scene(c);
  sim::SceneCamera camera(w, camera_params(c.noise), 3);
  const hardware::RgbdFrame f = camera.render(cam);
  double worst_normal = 0.0, worst_x = 0.0, worst_off = 0.0;
  for (const Eigen::Vector2d& px :
       {Eigen::Vector2d(319.5, 239.5), Eigen::Vector2d(150, 120), Eigen::Vector2d(500, 380)}) {
    const Eigen::Isometry3d area = area_frame_at(f, px, up_in(cam));
    const NormalErrors e = normal_errors(w, cam, area);
    worst_normal = std::max(worst_normal, e.normal);
    worst_x = std::max(worst_x, e.x);
    worst_off = std::max(worst_off, e.off_surface);
    // On the picked pixel's ray.
    EXPECT_LT((project(f.intrinsics, area.translation()) - px).norm(), 1e-6) << px.transpose();
  }
  measured(std::string(c.name) + ": normal error (max)", worst_normal / kDeg, "deg");
  measured(std::string(c.name) + ": x error (max)", worst_x / kDeg, "deg");
  measured(std::string(c.name) + ": origin off the surface (max)", 1000 * worst_off, "mm");
  // The brief asks for 2 degrees; 0.5 catches a regression (1 cm voxels: 0.5 degrees).
  EXPECT_LE(worst_normal, 0.5 * kDeg);
  EXPECT_LE(worst_x, 0.5 * kDeg);
  EXPECT_LE(worst_off, 0.001);
  // A point 2 cm off the wall (e.g. from the map) goes onto the surface.
  const Eigen::Vector3d off =
      world::face_point(w.walls[0], Face::kMinusX, {0.05, kHeight + 0.05}, 0.02);
  const NormalErrors e =
      normal_errors(w, cam, area_frame_at(f, Eigen::Vector3d(cam.inverse() * off), up_in(cam)));
  EXPECT_LE(e.normal, 0.5 * kDeg);
  EXPECT_LE(e.off_surface, 0.001);
}

INSTANTIATE_TEST_SUITE_P(
    Walls, NormalOnTiltedWall,
    ::testing::Values(NormalCase{"wall turned 25 deg at 0.6 m", 25 * kDeg, 0.0, 0.6, false},
                      NormalCase{"wall turned 25 deg at 0.6 m noisy", 25 * kDeg, 0.0, 0.6, true},
                      NormalCase{"wall turned -30 deg at 1.0 m noisy", -30 * kDeg, 0.0, 1.0, true},
                      NormalCase{"seen 25 deg from below at 0.6 m", 0.0, 25 * kDeg, 0.6, false},
                      NormalCase{"seen 25 deg from below at 0.6 m noisy", 0.0, 25 * kDeg, 0.6,
                                 true},
                      NormalCase{"turned 20 deg, seen 20 deg from below at 1.0 m noisy", 20 * kDeg,
                                 20 * kDeg, 1.0, true}));

TEST(Surface, FloorsAndCeilingsHaveNoHorizontalAxis) {
  SurfacePatch patch;
  patch.normal = {0.0, -1.0, 0.0};  // optical -y: up
  expect_drill_error([&] { area_frame(patch, Eigen::Vector3d(0.0, -1.0, 0.0)); },
                     {"within 1 degree of up"});
}

// --- Depth averaging against single frames
// ----------------------------------------------------------

TEST(DepthAverager, AveragingTenNoisyFramesReducesTheBlobAndNormalErrors) {
  constexpr double kFar = 2.0;
  const BlobScene s = blob_scene(kFar);
  sim::SceneCamera camera(s.world, camera_params(true), 21);
  DepthAverager averager(10);
  hardware::RgbdFrame single;
  for (int i = 0; i < 10; ++i) {
    single = camera.render(s.camera);
    averager.add(single);
  }
  const hardware::RgbdFrame averaged = averager.average();
  const BlobErrors one = blob_errors(s, detect_blobs(single));
  const BlobErrors ten = blob_errors(s, detect_blobs(averaged));
  measured("blob at 2.0 m: mean depth error, one frame", 1000 * one.depth_mean, "mm");
  measured("blob at 2.0 m: mean depth error, 10 frames averaged", 1000 * ten.depth_mean, "mm");
  EXPECT_LT(ten.depth_mean, one.depth_mean);

  const NormalCase c{"", 25 * kDeg, 0.0, 2.0, true};
  const auto [w, cam] = normal_scene(c);
  sim::SceneCamera wall_camera(w, camera_params(true), 22);
  averager.clear();
  for (int i = 0; i < 10; ++i) {
    single = wall_camera.render(cam);
    averager.add(single);
  }
  const hardware::RgbdFrame wall_averaged = averager.average();
  double one_normal = 0.0, ten_normal = 0.0;
  const std::vector<Eigen::Vector2d> pixels{
      {319.5, 239.5}, {150, 120}, {500, 380}, {150, 380}, {500, 120}};
  for (const auto& px : pixels) {
    one_normal += normal_errors(w, cam, area_frame_at(single, px, up_in(cam))).normal /
                  static_cast<double>(pixels.size());
    ten_normal += normal_errors(w, cam, area_frame_at(wall_averaged, px, up_in(cam))).normal /
                  static_cast<double>(pixels.size());
  }
  measured("wall turned 25 deg at 2.0 m: mean normal error, one frame", one_normal / kDeg, "deg");
  measured("wall turned 25 deg at 2.0 m: mean normal error, 10 frames averaged", ten_normal / kDeg,
           "deg");
  EXPECT_LT(ten_normal, one_normal);
}

}  // namespace
}  // namespace concert::drill
