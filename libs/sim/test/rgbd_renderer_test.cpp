// The RGB-D renderer against small hand-built MuJoCo models whose geometry is known exactly:
// depth of walls, the projection of known points, image orientation, the depth range, noise
// statistics, several models on one headless context, and an ArUco marker detected by OpenCV.
#include "concert/sim/rgbd_renderer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <opencv2/aruco.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "concert/hardware/hardware.hpp"

namespace concert::sim {
namespace {

using hardware::HardwareError;
using hardware::RgbdFrame;
using ::testing::HasSubstr;

// Every test runs without a display: the renderer must not need one.
[[maybe_unused]] const bool kHeadless = [] {
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  return true;
}();

CameraParams clean_params() {
  CameraParams p;
  p.noise = false;
  return p;
}

/// A MuJoCo model loaded from MJCF text and extra files (textures) through a virtual file
/// system, with its data after mj_forward.
struct Model {
  Model(const std::string& xml, const std::map<std::string, std::string>& files = {}) {
    mjVFS vfs;
    mj_defaultVFS(&vfs);
    auto add = [&](const std::string& name, const std::string& bytes) {
      ASSERT_EQ(mj_makeEmptyFileVFS(&vfs, name.c_str(), static_cast<int>(bytes.size())), 0) << name;
      std::memcpy(vfs.filedata[vfs.nfile - 1], bytes.data(), bytes.size());
    };
    add("model.xml", xml);
    for (const auto& [name, bytes] : files) {
      add(name, bytes);
    }
    char error[1000] = "";
    m = mj_loadXML("model.xml", &vfs, error, sizeof(error));
    mj_deleteVFS(&vfs);
    if (m == nullptr) {
      throw std::runtime_error(std::string("MuJoCo rejected the test model: ") + error + "\n" +
                               xml);
    }
    d = mj_makeData(m);
    mj_forward(m, d);
  }
  ~Model() {
    mj_deleteData(d);
    mj_deleteModel(m);
  }
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;
  /// Moves mocap body `index` to `pose` (world) and updates the kinematics.
  void place(int index, const Eigen::Isometry3d& pose) const {
    const Eigen::Quaterniond q(pose.rotation());
    for (int i = 0; i < 3; ++i) {
      d->mocap_pos[3 * index + i] = pose.translation()[i];
    }
    d->mocap_quat[4 * index] = q.w();
    d->mocap_quat[4 * index + 1] = q.x();
    d->mocap_quat[4 * index + 2] = q.y();
    d->mocap_quat[4 * index + 3] = q.z();
    mj_kinematics(m, d);
  }
  mjModel* m{nullptr};
  mjData* d{nullptr};
};

std::string mjcf(const std::string& assets, const std::string& worldbody,
                 const CameraParams& params = clean_params()) {
  return "<mujoco>\n" + visual_mjcf(params) + "<asset>\n" + assets + "</asset>\n<worldbody>\n" +
         worldbody + "</worldbody>\n</mujoco>\n";
}

/// A camera looking at a model: its own headless context, the model and a renderer.
struct Camera {
  explicit Camera(const std::string& xml, const CameraParams& params = clean_params(),
                  const std::map<std::string, std::string>& files = {})
      : model(xml, files), renderer(gl, model.m, params) {}
  /// The model as seen from `world_T_optical`.
  RgbdFrame& render(const Eigen::Isometry3d& world_T_optical) {
    renderer.render(model.d, world_T_optical, frame);
    return frame;
  }
  EglContext gl;
  Model model;
  RgbdRenderer renderer;
  RgbdFrame frame;
};

/// A 10 m x 10 m grey wall whose face (at world x = `face`) looks down -x.
std::string wall_at(double face) {
  return "<geom type=\"box\" size=\"0.05 5 5\" pos=\"" + std::to_string(face + 0.05) +
         " 0 0\" rgba=\"0.5 0.5 0.5 1\"/>\n";
}

/// Flat colours (emission, no specular): a pixel's colour is the geom's, whatever the light.
const char* const kFlatMaterials =
    "<material name=\"red\" rgba=\"1 0 0 1\" emission=\"1\" specular=\"0\"/>\n"
    "<material name=\"green\" rgba=\"0 1 0 1\" emission=\"1\" specular=\"0\"/>\n";

/// The optical frame at `position` looking along world +x, level: image right = world -y,
/// image down = world -z.
Eigen::Isometry3d looking_along_x(const Eigen::Vector3d& position) {
  Eigen::Matrix3d r;
  r.col(0) = -Eigen::Vector3d::UnitY();
  r.col(1) = -Eigen::Vector3d::UnitZ();
  r.col(2) = Eigen::Vector3d::UnitX();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() = position;
  return t;
}

Eigen::Vector2d project(const hardware::CameraIntrinsics& k, const Eigen::Vector3d& p) {
  return {k.fx * p.x() / p.z() + k.cx, k.fy * p.y() / p.z() + k.cy};
}

std::uint16_t depth_at(const RgbdFrame& f, int u, int v) {
  return f.depth[static_cast<std::size_t>(v) * f.intrinsics.width + static_cast<std::size_t>(u)];
}
const std::uint8_t* rgb_at(const RgbdFrame& f, int u, int v) {
  return &f.rgb[3 *
                (static_cast<std::size_t>(v) * f.intrinsics.width + static_cast<std::size_t>(u))];
}

/// Centroid [px] of the pixels where `is_colour(r, g, b)`, and how many there are.
template <class Pred>
std::pair<Eigen::Vector2d, int> centroid(const RgbdFrame& f, Pred is_colour) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int n = 0;
  for (int v = 0; v < static_cast<int>(f.intrinsics.height); ++v) {
    for (int u = 0; u < static_cast<int>(f.intrinsics.width); ++u) {
      const std::uint8_t* c = rgb_at(f, u, v);
      if (is_colour(c[0], c[1], c[2])) {
        sum += Eigen::Vector2d(u, v);
        ++n;
      }
    }
  }
  return {n > 0 ? Eigen::Vector2d(sum / n) : sum, n};
}

/// Where the image of a sphere (centre `c` in the optical frame, radius `r`) is centred [px]:
/// its outline is the conic of normalised image points m = (x, y, 1) with
/// (m . c)^2 = (|c|^2 - r^2) |m|^2, an ellipse whose centre (= the centroid of its area) lies
/// slightly outward of the projection of c (by ~f (r/z)^2 tan(angle off axis): 0.3 px at the
/// edge of the image for a 2 cm sphere at 0.6 m).
Eigen::Vector2d sphere_image_centre(const hardware::CameraIntrinsics& k, const Eigen::Vector3d& c,
                                    double r) {
  const Eigen::Matrix3d conic =
      c * c.transpose() - (c.squaredNorm() - r * r) * Eigen::Matrix3d::Identity();
  const Eigen::Vector2d centre =
      conic.topLeftCorner<2, 2>().ldlt().solve(-conic.topRightCorner<2, 1>());
  return {k.fx * centre.x() + k.cx, k.fy * centre.y() + k.cy};
}

bool red(std::uint8_t r, std::uint8_t g, std::uint8_t b) { return r > 200 && g < 50 && b < 50; }
bool green(std::uint8_t r, std::uint8_t g, std::uint8_t b) { return g > 200 && r < 50 && b < 50; }

/// A seeded random optical pose: any orientation, within a metre of the origin.
Eigen::Isometry3d random_pose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::Vector4d q(unit(rng), unit(rng), unit(rng), unit(rng));
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(q.normalized()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
  return t;
}

TEST(RgbdRenderer, IntrinsicsArePinholeWithPixelCentresAtIntegers) {
  const CameraParams p = clean_params();
  const auto k = camera_intrinsics(p);
  EXPECT_EQ(k.width, 640U);
  EXPECT_EQ(k.height, 480U);
  EXPECT_DOUBLE_EQ(k.fx, 615.0);
  EXPECT_DOUBLE_EQ(k.fy, 615.0);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);

  Camera cam(mjcf("", wall_at(0.6)), p);
  EXPECT_EQ(cam.renderer.intrinsics(), k);
  EXPECT_LE(cam.renderer.near_plane(), p.depth_min);
  EXPECT_GE(cam.renderer.far_plane(), p.depth_max);
  cam.frame.sensor = "camera_E";
  const RgbdFrame& frame = cam.render(looking_along_x(Eigen::Vector3d::Zero()));
  EXPECT_EQ(frame.intrinsics, k);
  EXPECT_EQ(frame.sensor, "camera_E");
  EXPECT_EQ(frame.rgb.size(), 640U * 480U * 3U);
  EXPECT_EQ(frame.depth.size(), 640U * 480U);
  EXPECT_FLOAT_EQ(frame.depth_min, static_cast<float>(p.depth_min));
  EXPECT_FLOAT_EQ(frame.depth_max, static_cast<float>(p.depth_max));
  EXPECT_DOUBLE_EQ(frame.depth_scale, 0.001);
}

TEST(RgbdRenderer, WallAtSixtyCentimetresReadsSixHundredMillimetresInEveryPixel) {
  Camera cam(mjcf("", wall_at(0.6)));
  // The wall is perpendicular to the optical axis: z (not the range) is 0.6 m everywhere,
  // also in the corners, whatever the camera's position along the wall.
  const RgbdFrame& frame = cam.render(looking_along_x(Eigen::Vector3d(0.0, 0.3, -0.2)));
  int off = 0;
  for (const auto z : frame.depth) {
    off += std::abs(static_cast<int>(z) - 600) > 1 ? 1 : 0;
  }
  EXPECT_EQ(off, 0);
  EXPECT_NEAR(depth_at(frame, 0, 0), 600, 1);
  EXPECT_NEAR(depth_at(frame, 639, 479), 600, 1);
  // Grey 0.5 facing the headlight is mid grey.
  const std::uint8_t* c = rgb_at(frame, 320, 240);
  EXPECT_NEAR(c[0], 128, 4);
  EXPECT_EQ(c[0], c[1]);
  EXPECT_EQ(c[1], c[2]);
  // Rendering again reuses the frame's buffers.
  const auto* rgb_data = frame.rgb.data();
  const auto* depth_data = frame.depth.data();
  cam.render(looking_along_x(Eigen::Vector3d(0.1, 0.0, 0.0)));
  EXPECT_EQ(frame.rgb.data(), rgb_data);
  EXPECT_EQ(frame.depth.data(), depth_data);
  EXPECT_NEAR(depth_at(frame, 320, 240), 500, 1);
}

TEST(RgbdRenderer, WhiteIsWhite) {
  Camera cam(
      mjcf("", "<geom type=\"box\" size=\"0.05 5 5\" pos=\"1.05 0 0\" rgba=\"1 1 1 1\"/>\n"));
  const std::uint8_t* c = rgb_at(cam.render(looking_along_x(Eigen::Vector3d::Zero())), 320, 240);
  EXPECT_GE(c[0], 250);
  EXPECT_GE(c[1], 250);
  EXPECT_GE(c[2], 250);
}

/// Std-dev of (noisy - clean) over the valid pixels of both.
template <class T>
double noise_std(const std::vector<T>& clean, const std::vector<T>& noisy, bool skip_zero) {
  double sum = 0.0;
  double sum2 = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    if (skip_zero && (clean[i] == 0 || noisy[i] == 0)) {
      continue;
    }
    const double e = static_cast<double>(noisy[i]) - static_cast<double>(clean[i]);
    sum += e;
    sum2 += e * e;
    ++n;
  }
  const double mean = sum / n;
  return std::sqrt(sum2 / n - mean * mean);
}

TEST(RgbdNoise, DepthNoiseFollowsTheD400RmsModelAndColourNoiseItsStdDev) {
  const CameraParams p;  // noise on, the D435i's values
  ASSERT_TRUE(p.noise);
  Camera cam(mjcf("", wall_at(0.6)), p);
  std::mt19937_64 rng(7);
  for (const double z : {0.6, 2.0}) {
    const RgbdFrame clean = cam.render(looking_along_x(Eigen::Vector3d(0.6 - z, 0.0, 0.0)));
    ASSERT_NEAR(depth_at(clean, 320, 240), z * 1000.0, 1.0);
    RgbdFrame noisy = clean;
    add_rgbd_noise(noisy, p, rng);
    const double rms_mm = 1000.0 * z * z * p.depth_subpixel / (p.depth_focal * p.depth_baseline);
    const double measured = noise_std(clean.depth, noisy.depth, true);
    EXPECT_NEAR(measured, rms_mm, 0.15 * rms_mm) << "at " << z << " m";
    EXPECT_NEAR(noise_std(clean.rgb, noisy.rgb, false), p.rgb_noise, 0.15 * p.rgb_noise);
  }
  // 1.4 mm at 0.6 m, 15 mm at 2 m, as sensor_params.hpp says.
  EXPECT_NEAR(600.0 * 600.0 * p.depth_subpixel / (p.depth_focal * p.depth_baseline * 1000.0), 1.36,
              0.05);
}

TEST(RgbdNoise, IsSeededAndOffWhenDisabled) {
  CameraParams p;
  Camera cam(mjcf("", wall_at(0.6)), p);
  const RgbdFrame clean = cam.render(looking_along_x(Eigen::Vector3d::Zero()));
  RgbdFrame a = clean;
  RgbdFrame b = clean;
  RgbdFrame c = clean;
  std::mt19937_64 rng_a(3);
  std::mt19937_64 rng_b(3);
  std::mt19937_64 rng_c(4);
  add_rgbd_noise(a, p, rng_a);
  add_rgbd_noise(b, p, rng_b);
  add_rgbd_noise(c, p, rng_c);
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_NE(a.depth, c.depth);
  EXPECT_NE(a.depth, clean.depth);
  // Two successive frames of one stream differ.
  RgbdFrame next = clean;
  add_rgbd_noise(next, p, rng_a);
  EXPECT_NE(next.depth, a.depth);

  p.noise = false;
  RgbdFrame quiet = clean;
  add_rgbd_noise(quiet, p, rng_a);
  EXPECT_EQ(quiet.depth, clean.depth);
  EXPECT_EQ(quiet.rgb, clean.rgb);
}

TEST(RgbdNoise, KeepsNoDataPixelsAtZeroAndClampsColour) {
  RgbdFrame f;
  f.intrinsics = camera_intrinsics(CameraParams{});
  f.depth.assign(640 * 480, 0);
  f.rgb.assign(640 * 480 * 3, 255);
  CameraParams p;
  p.rgb_noise = 50.0;
  std::mt19937_64 rng(1);
  add_rgbd_noise(f, p, rng);
  EXPECT_EQ(std::count(f.depth.begin(), f.depth.end(), 0), 640 * 480);
  EXPECT_GT(std::count(f.rgb.begin(), f.rgb.end(), 255), 640 * 480);  // clamped, not wrapped
  EXPECT_GT(std::count_if(f.rgb.begin(), f.rgb.end(), [](std::uint8_t v) { return v < 200; }),
            1000);
  f.depth.resize(10);
  EXPECT_THROW(add_rgbd_noise(f, p, rng), HardwareError);
}

TEST(RgbdRenderer, SphereCentreProjectsWhereThePublishedIntrinsicsSay) {
  const double radius = 0.02;
  Camera cam(mjcf(kFlatMaterials, "<body mocap=\"true\"><geom type=\"sphere\" size=\"" +
                                      std::to_string(radius) + "\" material=\"red\"/></body>\n"));
  const auto& k = cam.renderer.intrinsics();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 8; ++trial) {
    const Eigen::Isometry3d world_T_optical = random_pose(rng);
    // A point in the field of view, 0.5..1.5 m away, within 80 % of the image.
    const double z = 1.0 + 0.5 * unit(rng);
    const Eigen::Vector3d p_optical(0.8 * unit(rng) * z * k.cx / k.fx,
                                    0.8 * unit(rng) * z * k.cy / k.fy, z);
    Eigen::Isometry3d sphere = Eigen::Isometry3d::Identity();
    sphere.translation() = world_T_optical * p_optical;
    cam.model.place(0, sphere);
    const RgbdFrame& frame = cam.render(world_T_optical);
    const Eigen::Vector2d expected = project(k, p_optical);
    const Eigen::Vector2d outline_centre = sphere_image_centre(k, p_optical, radius);
    const auto [seen, pixels] = centroid(frame, red);
    ASSERT_GT(pixels, 100) << "trial " << trial;
    EXPECT_LT((seen - outline_centre).norm(), 0.15)
        << "trial " << trial << ": seen " << seen.transpose() << ", sphere's image centred at "
        << outline_centre.transpose() << ", centre projected at " << expected.transpose();
    // Depth on the ray through the centre: the sphere's near surface, z of it.
    const double range = p_optical.norm() - radius;
    const double z_surface_mm = 1000.0 * range * p_optical.z() / p_optical.norm();
    const int u = static_cast<int>(std::lround(expected.x()));
    const int v = static_cast<int>(std::lround(expected.y()));
    EXPECT_NEAR(depth_at(frame, u, v), z_surface_mm, 1.5) << "trial " << trial;
  }
}

TEST(RgbdRenderer, ImageIsUprightAndNotMirrored) {
  Camera cam(mjcf(
      kFlatMaterials,
      "<body mocap=\"true\"><geom type=\"sphere\" size=\"0.03\" material=\"red\"/></body>\n"
      "<body mocap=\"true\"><geom type=\"sphere\" size=\"0.03\" material=\"green\"/></body>\n"));
  std::mt19937_64 rng(5);
  const Eigen::Isometry3d world_T_optical = random_pose(rng);
  Eigen::Isometry3d above = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d right = Eigen::Isometry3d::Identity();
  above.translation() = world_T_optical * Eigen::Vector3d(0.0, -0.25, 1.0);  // -y optical
  right.translation() = world_T_optical * Eigen::Vector3d(0.3, 0.0, 1.0);    // +x optical
  cam.model.place(0, above);
  cam.model.place(1, right);
  const RgbdFrame& frame = cam.render(world_T_optical);
  const auto [red_at, red_pixels] = centroid(frame, red);
  const auto [green_at, green_pixels] = centroid(frame, green);
  ASSERT_GT(red_pixels, 100);
  ASSERT_GT(green_pixels, 100);
  EXPECT_LT(red_at.y(), 120.0);  // top rows
  EXPECT_NEAR(red_at.x(), 319.5, 1.0);
  EXPECT_GT(green_at.x(), 500.0);  // right columns
  EXPECT_NEAR(green_at.y(), 239.5, 1.0);
}

TEST(RgbdRenderer, DepthIsZeroOutsideTheDepthRangeWhileColourStillSees) {
  const CameraParams p = clean_params();
  Camera cam(mjcf("", wall_at(0.0)), p);
  const RgbdFrame& frame = cam.frame;
  auto at = [&](double distance) {
    cam.render(looking_along_x(Eigen::Vector3d(-distance, 0.0, 0.0)));
  };
  auto all_zero = [&] {
    return std::count(frame.depth.begin(), frame.depth.end(), 0) == 640 * 480;
  };
  auto grey = [&] { return rgb_at(frame, 320, 240)[0] > 60; };

  at(p.depth_max + 2.0);  // beyond depth_max
  EXPECT_TRUE(all_zero());
  EXPECT_TRUE(grey());
  at(0.08);  // nearer than depth_min (0.105 m), beyond the near plane
  EXPECT_TRUE(all_zero());
  EXPECT_TRUE(grey());
  at(p.depth_max - 0.5);  // within range, far
  EXPECT_NEAR(depth_at(frame, 320, 240), 9500, 2);
  EXPECT_NEAR(depth_at(frame, 0, 479), 9500, 2);
  at(0.12);  // within range, near
  EXPECT_NEAR(depth_at(frame, 320, 240), 120, 1);

  // Nothing in view: no data, black.
  cam.render(looking_along_x(Eigen::Vector3d(1.0, 0.0, 0.0)));
  EXPECT_TRUE(all_zero());
  EXPECT_EQ(rgb_at(frame, 320, 240)[0], 0);
}

TEST(RgbdRenderer, SeveralModelsShareOneHeadlessContext) {
  ASSERT_EQ(std::getenv("DISPLAY"), nullptr);
  EglContext gl;
  const CameraParams p = clean_params();
  const Model near(mjcf("", wall_at(0.6)));
  const Model far(mjcf("", wall_at(1.3)));
  RgbdRenderer a(gl, near.m, p);
  RgbdRenderer b(gl, far.m, p);
  RgbdFrame fa;
  RgbdFrame fb;
  const auto pose = looking_along_x(Eigen::Vector3d::Zero());
  for (int i = 0; i < 3; ++i) {
    a.render(near.d, pose, fa);
    b.render(far.d, pose, fb);
    EXPECT_NEAR(depth_at(fa, 100, 100), 600, 1);
    EXPECT_NEAR(depth_at(fb, 100, 100), 1300, 1);
  }
  // A hot swap: the old renderer goes, a new one for another model comes, the other stays.
  {
    const Model swapped(mjcf("", wall_at(2.0)));
    RgbdRenderer c(gl, swapped.m, p);
    c.render(swapped.d, pose, fa);
    EXPECT_NEAR(depth_at(fa, 100, 100), 2000, 1);
  }
  b.render(far.d, pose, fb);
  EXPECT_NEAR(depth_at(fb, 100, 100), 1300, 1);
}

TEST(RgbdRenderer, RefusesAnotherThread) {
  Camera cam(mjcf("", wall_at(0.6)));
  std::string error;
  std::thread other([&] {
    try {
      cam.render(looking_along_x(Eigen::Vector3d::Zero()));
    } catch (const HardwareError& e) {
      error = e.what();
    }
  });
  other.join();
  EXPECT_THAT(error, HasSubstr("eglMakeCurrent"));
  EXPECT_THAT(error, HasSubstr("one thread"));
}

TEST(RgbdRenderer, RefusesAModelWithoutTheOffscreenBuffer) {
  EglContext gl;
  const Model model(
      "<mujoco><visual><global offwidth=\"320\" offheight=\"240\"/></visual><worldbody>" +
      wall_at(0.6) + "</worldbody></mujoco>");
  try {
    RgbdRenderer renderer(gl, model.m, clean_params());
    FAIL() << "a 320x240 offscreen buffer was accepted for a 640x480 camera";
  } catch (const HardwareError& e) {
    EXPECT_THAT(e.what(), HasSubstr("320x240"));
    EXPECT_THAT(e.what(), HasSubstr("visual_mjcf"));
  }
}

/// An ArUco DICT_4X4_50 marker `id` of `marker_px` pixels with a white margin of `margin_px`
/// on every side, as PNG bytes.
std::string aruco_png(int id, int marker_px, int margin_px) {
  const auto dictionary = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
  cv::Mat marker;
  cv::aruco::drawMarker(dictionary, id, marker_px, marker, 1);
  cv::Mat padded(marker_px + 2 * margin_px, marker_px + 2 * margin_px, CV_8UC1, cv::Scalar(255));
  marker.copyTo(padded(cv::Rect(margin_px, margin_px, marker_px, marker_px)));
  cv::Mat bgr;
  cv::cvtColor(padded, bgr, cv::COLOR_GRAY2BGR);
  std::vector<unsigned char> png;
  cv::imencode(".png", bgr, png);
  return {png.begin(), png.end()};
}

TEST(RgbdRenderer, ArucoCornersDetectedByOpenCvMatchTheProjectionOfTheirPositions) {
  // A square plane of half-size 0.1 m with the marker (200 of 300 texture pixels) in its middle:
  // the marker's corners are at +-2/3 of the half-size in the plane's x and y, its top edge
  // along +y (MuJoCo maps the texture's top row to the plane's +y side).
  const double half = 0.1;
  const double corner = half * 200.0 / 300.0;
  Camera cam(
      mjcf("<texture name=\"marker\" type=\"2d\" file=\"marker.png\"/>\n"
           "<material name=\"marker\" texture=\"marker\" texrepeat=\"1 1\" texuniform=\"false\" "
           "specular=\"0\"/>\n",
           "<body mocap=\"true\"><geom type=\"plane\" size=\"" + std::to_string(half) + " " +
               std::to_string(half) + " 0.01\" material=\"marker\"/></body>\n"),
      clean_params(), {{"marker.png", aruco_png(7, 200, 50)}});
  const auto& k = cam.renderer.intrinsics();
  // The marker's corners in the plane's frame, in ArUco's order: top-left, top-right,
  // bottom-right, bottom-left.
  const std::vector<Eigen::Vector3d> corners = {{-corner, corner, 0.0},
                                                {corner, corner, 0.0},
                                                {corner, -corner, 0.0},
                                                {-corner, -corner, 0.0}};
  const auto dictionary = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
  auto detector = cv::aruco::DetectorParameters::create();
  detector->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Isometry3d world_T_optical = random_pose(rng);
    // The plane 0.5..0.8 m ahead, its normal towards the camera, tilted up to ~25 degrees,
    // its +y up in the image (optical -y).
    Eigen::Matrix3d facing;
    facing.col(0) = Eigen::Vector3d::UnitX();
    facing.col(1) = -Eigen::Vector3d::UnitY();
    facing.col(2) = -Eigen::Vector3d::UnitZ();
    Eigen::Isometry3d optical_T_plane = Eigen::Isometry3d::Identity();
    optical_T_plane.linear() = facing *
                               Eigen::AngleAxisd(0.4 * unit(rng), Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(0.4 * unit(rng), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(0.3 * unit(rng), Eigen::Vector3d::UnitZ());
    optical_T_plane.translation() =
        Eigen::Vector3d(0.08 * unit(rng), 0.06 * unit(rng), 0.65 + 0.15 * unit(rng));
    cam.model.place(0, world_T_optical * optical_T_plane);
    RgbdFrame& frame = cam.render(world_T_optical);

    cv::Mat rgb(static_cast<int>(k.height), static_cast<int>(k.width), CV_8UC3, frame.rgb.data());
    cv::Mat grey;
    cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
    std::vector<int> ids;
    std::vector<std::vector<cv::Point2f>> found;
    cv::aruco::detectMarkers(grey, dictionary, found, ids, detector);
    ASSERT_EQ(ids.size(), 1U) << "trial " << trial;
    EXPECT_EQ(ids[0], 7);
    for (std::size_t i = 0; i < 4; ++i) {
      const Eigen::Vector2d expected = project(k, optical_T_plane * corners[i]);
      const Eigen::Vector2d seen(found[0][i].x, found[0][i].y);
      EXPECT_LT((seen - expected).norm(), 0.5)
          << "trial " << trial << " corner " << i << ": seen " << seen.transpose() << ", projected "
          << expected.transpose();
    }
  }
}

}  // namespace
}  // namespace concert::sim
