// The simulated robot's sensors end to end: mounted from the module database (the demo robots
// of deploy/demo), run by SimHardware's sensor threads, delivered to a SensorSink, measured
// against the world's ground truth (libs/world geometry) and, for the camera, against OpenCV's
// ArUco detector.
#include <gtest/gtest.h>

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <numeric>
#include <set>
#include <thread>

#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/world/geometry.hpp"
#include "test_data.hpp"

namespace concert::sim {
namespace {

using hardware::SensorType;

SimulatedRobot demo_robot(const std::string& file) {
  const AssemblyBuilder builder({test_data::kProjectDb});
  return builder.build(std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/" + file);
}

/// Everything the sensors deliver (called from the sensor threads).
class Collector : public hardware::SensorSink {
 public:
  void on_sensors(const std::vector<hardware::SensorInfo>& sensors) override {
    std::lock_guard lock(mutex);
    mounted = sensors;
    ++announcements;
  }
  void on_rgbd(const hardware::RgbdFrame& frame) override {
    std::lock_guard lock(mutex);
    rgbd[frame.sensor] = frame;
    ++rgbd_count[frame.sensor];
  }
  void on_lidar(const hardware::LidarScan& scan) override {
    std::lock_guard lock(mutex);
    lidar[scan.sensor] = scan;
  }
  void on_scan2d(const hardware::LaserScan2d& scan) override {
    std::lock_guard lock(mutex);
    scan2d = scan;
    ++scan2d_count;
  }
  void on_sonars(const hardware::SonarRanges& ranges) override {
    std::lock_guard lock(mutex);
    sonars = ranges;
    ++sonar_count;
  }
  void on_imu(const hardware::ImuSample& sample) override {
    std::lock_guard lock(mutex);
    imu.push_back(sample);
  }
  [[nodiscard]] std::set<std::string> mounted_names() const {
    std::set<std::string> out;
    for (const auto& m : mounted) out.insert(m.name);
    return out;
  }

  mutable std::mutex mutex;
  std::vector<hardware::SensorInfo> mounted;
  int announcements{0};
  std::map<std::string, hardware::RgbdFrame> rgbd;
  std::map<std::string, int> rgbd_count;
  std::map<std::string, hardware::LidarScan> lidar;
  hardware::LaserScan2d scan2d;
  int scan2d_count{0};
  hardware::SonarRanges sonars;
  int sonar_count{0};
  std::vector<hardware::ImuSample> imu;
};

/// Runs the simulation as the control thread does (switch at the cycle boundary, 1 ms steps),
/// paced so the sensor threads keep up, until `done` holds (checked under the collector's
/// lock) or `max_steps` steps (a bound, not a timing assertion).
bool run_until(SimHardware& sim, Collector& c, const std::function<bool()>& done, int max_steps = 20000) {
  for (int i = 0; i < max_steps; ++i) {
    sim.switch_prepared();
    sim.step(0.001);
    if (i % 10 == 0) {
      std::lock_guard lock(c.mutex);
      if (done()) return true;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(300));
  }
  return false;
}

/// The drill robot with its base fixed level at its standing height, arm upright (q = 0): the
/// drill camera looks horizontally along world +x (checked).
SimParams fixed_base_params(bool noise) {
  SimParams p;
  p.floating_base = false;
  p.base_position = {0.0, 0.0, 0.86};  // wheel bottoms 1 cm above the floor
  p.sensors.camera.noise = noise;
  p.sensors.lidar.noise = noise;
  p.sensors.sonar.noise = noise;
  p.sensors.imu.noise = noise;
  p.sensors.seed = 7;
  return p;
}

TEST(SimSensors, EveryMountedSensorOfTheDemoRobotDelivers) {
  const SimulatedRobot robot = demo_robot("drill_robot.yaml");
  ASSERT_EQ(robot.sensors.size(), 14u);  // 2 lidars, 8 sonars, 2 + 1 cameras, 1 IMU
  world::World world = world::load_world_file(std::string(WORLD_FIXTURES) + "/marks_world.yaml");
  SimHardware sim(robot.urdf, world, fixed_base_params(true), robot.sensors);
  ASSERT_EQ(sim.sensors().size(), 14u);
  Collector c;
  sim.set_sensor_sink(&c);
  ASSERT_TRUE(run_until(sim, c, [&] {
    return c.mounted.size() == 14u && c.rgbd_count.size() == 3u && c.lidar.size() == 2u && c.scan2d_count > 0 &&
           c.sonar_count > 0 && c.imu.size() >= 50u;
  })) << "cameras " << c.rgbd_count.size() << " lidars " << c.lidar.size() << " imu " << c.imu.size();
  sim.set_sensor_sink(nullptr);
  std::lock_guard lock(c.mutex);
  EXPECT_EQ(c.mounted_names(), (std::set<std::string>{"lidar_front", "lidar_back", "ultrasound_fl_sag",
                                                      "ultrasound_fr_sag", "ultrasound_rl_sag", "ultrasound_rr_sag",
                                                      "ultrasound_fl_lat", "ultrasound_rl_lat", "ultrasound_fr_lat",
                                                      "ultrasound_rr_lat", "d435i_front", "d435i_back", "imu",
                                                      "camera_E"}));
  for (const auto& [name, frame] : c.rgbd) {
    EXPECT_EQ(frame.intrinsics.width, 640u) << name;
    EXPECT_EQ(frame.rgb.size(), 640u * 480u * 3u) << name;
    EXPECT_EQ(frame.depth.size(), 640u * 480u) << name;
  }
  // The lidars see the wall ahead (its face at x = 0.75 m): the planar scan's bin straight
  // ahead reads the face's distance from the root link.
  const hardware::LaserScan2d& s = c.scan2d;
  ASSERT_EQ(s.ranges.size(), 720u);
  const auto ahead = static_cast<std::size_t>(std::lround((0.0 - s.angle_min) / s.angle_increment));
  EXPECT_EQ(s.frame, "base_link");  // the robot's root link, not a world body
  // The nearest of a bin's returns: the face's distance, biased low by the noise (4 sigma).
  EXPECT_NEAR(s.ranges[ahead], 0.75, 0.06);
  EXPECT_EQ(c.sonars.sonars.size(), 8u);
  // IMU at rest on the level base: specific force +g up, no rotation (bias within 4 sigma).
  Eigen::Vector3d acc = Eigen::Vector3d::Zero(), gyro = Eigen::Vector3d::Zero();
  for (const auto& sample : c.imu) {
    acc += sample.linear_acceleration;
    gyro += sample.angular_velocity;
  }
  acc /= static_cast<double>(c.imu.size());
  gyro /= static_cast<double>(c.imu.size());
  EXPECT_NEAR(acc.z(), 9.81, 4 * 0.23);
  EXPECT_NEAR(acc.head<2>().norm(), 0.0, 4 * 0.23 * std::sqrt(2.0));
  EXPECT_LT(gyro.norm(), 4 * 5.8e-3 * std::sqrt(3.0));
  // Stamps are simulated time and increase.
  for (std::size_t i = 1; i < c.imu.size(); ++i) {
    EXPECT_GT(c.imu[i].stamp, c.imu[i - 1].stamp);
  }
}

TEST(SimSensors, AfterAHotSwapTheCameraFollowsTheTool) {
  const SimulatedRobot drill = demo_robot("drill_robot.yaml");
  const SimulatedRobot sander = demo_robot("sanding_robot.yaml");
  SimHardware sim(drill.urdf, {}, fixed_base_params(false), drill.sensors);
  Collector c;
  sim.set_sensor_sink(&c);
  ASSERT_TRUE(run_until(sim, c, [&] { return c.rgbd_count.count("camera_E") > 0; }));
  // Drill -> sanding tool: the drill's camera goes, the platform's cameras stay.
  ASSERT_TRUE(sim.swap_model(sander.urdf, sander.sensors));
  ASSERT_TRUE(run_until(sim, c, [&] { return c.mounted_names().count("camera_E") == 0 && !c.mounted.empty(); }));
  EXPECT_EQ(c.mounted.size(), 13u);
  run_until(sim, c, [] { return false; }, 100);  // frames rendered before the switch drain
  {
    std::lock_guard lock(c.mutex);
    c.rgbd_count.clear();
  }
  ASSERT_TRUE(run_until(sim, c, [&] { return c.rgbd_count["d435i_front"] >= 3; }));
  {
    std::lock_guard lock(c.mutex);
    EXPECT_EQ(c.rgbd_count.count("camera_E"), 0u) << "the old tool's camera still delivers";
  }
  // Sanding tool -> drill: its camera is back, at the new tool's pose.
  ASSERT_TRUE(sim.swap_model(drill.urdf, drill.sensors));
  ASSERT_TRUE(run_until(sim, c, [&] { return c.mounted_names().count("camera_E") == 1; }));
  ASSERT_TRUE(run_until(sim, c, [&] { return c.rgbd_count["camera_E"] >= 2; }));
  sim.set_sensor_sink(nullptr);
}

/// Pixel of a world point seen by a camera at world_T_optical with intrinsics k.
Eigen::Vector2d project(const hardware::CameraIntrinsics& k, const Eigen::Isometry3d& world_T_optical,
                        const Eigen::Vector3d& p_world) {
  const Eigen::Vector3d p = world_T_optical.inverse() * p_world;
  return {k.fx * p.x() / p.z() + k.cx, k.fy * p.y() / p.z() + k.cy};
}

/// A wall facing -x that the drill camera's optical axis meets `distance` in front of it (the
/// camera is pitched towards the bit, so it sees the wall at a slant), with an ArUco marker
/// where the axis meets it and a blue blob beside it.
struct WallInFront {
  world::World world;
  double distance{0.6};
  Eigen::Vector3d on_axis{Eigen::Vector3d::Zero()};  ///< where the optical axis meets the face
};

WallInFront wall_in_front(const Eigen::Isometry3d& camera, double distance) {
  const Eigen::Vector3d axis = camera.linear().col(2);
  WallInFront w;
  w.distance = distance;
  w.on_axis = camera.translation() + distance * axis;
  world::WorldShape wall;
  wall.name = "wall";
  wall.size = {0.2, 3.0, 4.0};
  const double face_x = w.on_axis.x();
  wall.position = {face_x + 0.1, w.on_axis.y(), 2.0};
  EXPECT_GT(axis.x(), 0.5) << "the drill camera should face +x";
  w.world.walls.push_back(wall);
  // On the wall's -x face, u = +y (the viewer's right), at = [u from the face centre, height].
  world::Mark marker;
  marker.name = "marker";
  marker.type = world::Mark::Type::kAruco;
  marker.wall = "wall";
  marker.face = world::Face::kMinusX;
  marker.at = {0.0, w.on_axis.z()};
  marker.size = 0.15;
  marker.dictionary = "DICT_4X4_50";
  marker.id = 7;
  w.world.marks.push_back(marker);
  world::Mark blob;
  blob.name = "blob";
  blob.type = world::Mark::Type::kBlob;
  blob.wall = "wall";
  blob.face = world::Face::kMinusX;
  blob.at = {0.14, w.on_axis.z() + 0.16};
  blob.diameter = 0.05;
  w.world.marks.push_back(blob);
  return w;
}

TEST(SimSensors, DrillCameraSeesTheMarksWhereTheWorldPutsThem) {
  const SimulatedRobot robot = demo_robot("drill_robot.yaml");
  SimHardware sim(robot.urdf, {}, fixed_base_params(false), robot.sensors);
  for (int i = 0; i < 500; ++i) sim.step(0.001);  // settle the arm under its drives
  const Eigen::Isometry3d camera = sim.link_pose("camera_E");
  const WallInFront scene = wall_in_front(camera, 0.6);
  sim.set_world(scene.world);
  Collector c;
  sim.set_sensor_sink(&c);
  ASSERT_TRUE(run_until(sim, c, [&] { return c.rgbd_count["camera_E"] >= 3; }));
  sim.set_sensor_sink(nullptr);
  hardware::RgbdFrame frame;
  {
    std::lock_guard lock(c.mutex);
    frame = c.rgbd.at("camera_E");
  }
  const Eigen::Isometry3d optical = sim.link_pose("camera_E");
  EXPECT_LT((optical.translation() - camera.translation()).norm(), 1e-4) << "the arm moved";
  const auto& k = frame.intrinsics;
  const auto truth = world::mark_truth(scene.world);
  ASSERT_EQ(truth.size(), 2u);

  // Depth: wall pixels (away from the marks) read the point's distance along the optical axis.
  const Eigen::Vector3d wall_point = world::face_point(scene.world.walls[0], world::Face::kMinusX,
                                                       {-0.15, scene.on_axis.z() - 0.1});
  const Eigen::Vector2d wall_px = project(k, optical, wall_point);
  const auto at = [&](const Eigen::Vector2d& px) {
    return frame.depth[static_cast<std::size_t>(std::lround(px.y())) * k.width +
                       static_cast<std::size_t>(std::lround(px.x()))];
  };
  const auto z_of = [&](const Eigen::Vector3d& p) { return (optical.inverse() * p).z(); };
  EXPECT_NEAR(at(wall_px) * frame.depth_scale, z_of(wall_point), 0.0011);
  // The marker's centre is 1 mm in front of the face.
  EXPECT_NEAR(at(project(k, optical, truth[0].centre)) * frame.depth_scale, z_of(truth[0].centre),
              0.0011);

  // ArUco: OpenCV finds marker 7 with each corner where the world's truth projects.
  cv::Mat rgb(static_cast<int>(k.height), static_cast<int>(k.width), CV_8UC3, frame.rgb.data());
  cv::Mat gray;
  cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  cv::aruco::detectMarkers(gray, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50), corners, ids, params);
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(ids[0], 7);
  double worst = 0.0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d expected = project(k, optical, truth[0].corners[static_cast<std::size_t>(i)]);
    const double error = std::hypot(corners[0][static_cast<std::size_t>(i)].x - expected.x(),
                                    corners[0][static_cast<std::size_t>(i)].y - expected.y());
    worst = std::max(worst, error);
  }
  EXPECT_LE(worst, 1.0) << "corner error [px]";
  std::cout << "[ measured ] ArUco corner error " << worst << " px\n";

  // Blue blob: segmented (HSV hue of blue, saturated) and its centroid at the projected centre.
  cv::Mat hsv, mask;
  cv::cvtColor(rgb, hsv, cv::COLOR_RGB2HSV);
  cv::inRange(hsv, cv::Scalar(100, 120, 40), cv::Scalar(130, 255, 255), mask);
  const cv::Moments m = cv::moments(mask, true);
  ASSERT_GT(m.m00, 100.0) << "no blue blob in the image";
  const Eigen::Vector2d centroid(m.m10 / m.m00, m.m01 / m.m00);
  const Eigen::Vector2d expected = project(k, optical, truth[1].centre);
  EXPECT_LT((centroid - expected).norm(), 1.0) << "blob centroid [px]";
  // The disc's apparent area matches the area its outline projects to (within 10 %).
  double area = 0.0;
  Eigen::Vector2d last = Eigen::Vector2d::Zero();
  for (int i = 0; i <= 64; ++i) {
    const double t = 2.0 * M_PI * i / 64;
    const Eigen::Vector3d rim =
        truth[1].centre + truth[1].diameter / 2 * Eigen::Vector3d(0.0, std::cos(t), std::sin(t));
    const Eigen::Vector2d px = project(k, optical, rim);
    if (i > 0) area += 0.5 * (last.x() * px.y() - px.x() * last.y());
    last = px;
  }
  EXPECT_NEAR(m.m00, std::abs(area), 0.1 * std::abs(area));
}

}  // namespace
}  // namespace concert::sim

namespace concert::sim {
namespace {

// The simulated base stands on the wheels its model names by role (its chains of role leg), not
// on wheels guessed from the URDF's axes: the demo robot and the paper's robot from the public
// CONCERT database each have four steering legs; the same URDF with no legs named is a fixed robot,
// and bare (no roles at all) is put on the wheels its axes show.
TEST(SimAssembly, TheBaseStandsOnTheLegsTheModelNamesByRole) {
  SimParams params;
  params.sensors.enabled = false;
  const SimulatedRobot paper = AssemblyBuilder({test_data::kPublicDb})
                                   .build(test_data::kExamples + "/concert_paper_robot.yaml");
  for (const SimulatedRobot& robot : {demo_robot("drill_robot.yaml"), paper}) {
    SCOPED_TRACE(robot.source);
    ASSERT_TRUE(robot.legs.has_value());
    ASSERT_EQ(robot.legs->size(), 4u);
    for (const SimLeg& leg : *robot.legs) {
      EXPECT_GT(leg.wheel_radius, 0.05) << leg.wheel_joint;
      EXPECT_NE(leg.steering_joint, leg.wheel_joint);
    }
    const SimHardware sim(robot, World{}, params);
    EXPECT_NE(sim.mjcf().find("__floating_base"), std::string::npos);
    // Standing on its wheels: the base frame as high as a wheel radius above the wheel centres.
    EXPECT_GT(sim.base_pose().translation().z(), 0.05);

    SimulatedRobot none = robot;
    none.legs = std::vector<SimLeg>{};
    const SimHardware fixed(none, World{}, params);
    EXPECT_EQ(fixed.mjcf().find("__floating_base"), std::string::npos);
    EXPECT_EQ(fixed.base_pose().translation().z(), 0.0);

    const SimHardware bare(robot.urdf, World{}, params);
    EXPECT_NE(bare.mjcf().find("__floating_base"), std::string::npos);

    // A leg whose joints are no steering axis over a wheel is refused, named.
    SimulatedRobot wrong = robot;
    (*wrong.legs)[0].steering_joint = (*wrong.legs)[0].wheel_joint;
    try {
      const SimHardware hw(wrong, World{}, params);
      FAIL() << "a leg without a steering axis was taken";
    } catch (const hardware::HardwareError& e) {
      EXPECT_NE(std::string(e.what()).find("sim: leg " + (*wrong.legs)[0].wheel_joint), std::string::npos)
          << e.what();
    }
  }
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("no '" + from + "' in the assembly");
  return text.replace(at, from.size(), to);
}

// A hot swap carries a joint's state by its module, as a drive's encoder does, never by the
// joint's name (the paper's naming numbers joints along a chain, so another morphology gives a
// kept name to another module's joint and a kept module's joint another name).
TEST(SimAssembly, AHotSwapCarriesAJointsStateByItsModuleNeverByItsName) {
  const AssemblyBuilder builder({test_data::kPublicDb});
  std::ifstream in(test_data::kExamples + "/concert_paper_robot.yaml");
  const std::string paper{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const auto joint_of = [](const SimulatedRobot& r, const std::string& module) {
    for (const auto& [joint, m] : r.joint_modules)
      if (m == module) return joint;
    return std::string();
  };
  const auto position = [](SimHardware& sim, const std::string& joint) {
    hardware::HardwareState s;
    sim.read(s);
    const auto& names = sim.joint_names();
    const auto at = std::find(names.begin(), names.end(), joint);
    if (at == names.end()) throw std::runtime_error("no joint " + joint);
    return s.position[static_cast<std::size_t>(at - names.begin())];
  };
  const std::string kElbow3 = "module_joint_elbow_B_concert robot_id 55";
  const std::string kYaw2 = "module_joint_yaw_B_concert robot_id 54";
  const SimulatedRobot a = builder.build_from_text(paper, "paper.yaml");
  const std::string elbow3 = joint_of(a, kElbow3);
  const std::string yaw2 = joint_of(a, kYaw2);
  ASSERT_FALSE(elbow3.empty());
  ASSERT_FALSE(yaw2.empty());
  SimParams params;
  params.sensors.enabled = false;
  params.initial_positions = {{elbow3, 0.7}, {yaw2, -0.4}};
  SimHardware sim(a, World{}, params);
  for (int i = 0; i < 10; ++i) sim.step(0.001);
  EXPECT_NEAR(position(sim, elbow3), 0.7, 0.02);

  // Another elbow (another type, another robot_id) where elbow_3 was: the joint keeps its
  // name, not the old module's state; it starts at its homing position.
  const std::string kElbowA = "module_joint_elbow_A_concert robot_id 57";
  const std::string b_text =
      replaced(paper, "{name: elbow_3, key: module_joint_elbow_B_concert, parent: link_2, connector: 1, robot_id: 55}",
               "{name: elbow_3, key: module_joint_elbow_A_concert, parent: link_2, connector: 1, robot_id: 57}");
  const SimulatedRobot b = builder.build_from_text(b_text, "other_elbow.yaml");
  ASSERT_EQ(joint_of(b, kElbowA), elbow3);
  ASSERT_TRUE(sim.swap_model(b));
  ASSERT_TRUE(sim.switch_prepared());
  EXPECT_NEAR(position(sim, elbow3), b.joint_homes.at(elbow3), 1e-9);
  EXPECT_NEAR(position(sim, yaw2), -0.4, 0.02);

  // elbow_2 taken out: the joints after it are numbered one less, and yaw_2's joint, under its
  // new name, keeps yaw_2's state.
  const SimulatedRobot c = builder.build_from_text(
      replaced(replaced(b_text, "  - {name: elbow_2, key: module_joint_elbow_A_concert, parent: link_1, connector: 1, robot_id: 53}\n", ""),
               "{name: yaw_2, key: module_joint_yaw_B_concert, parent: elbow_2,",
               "{name: yaw_2, key: module_joint_yaw_B_concert, parent: link_1,"),
      "no_elbow_2.yaml");
  const std::string yaw2_c = joint_of(c, kYaw2);
  ASSERT_FALSE(yaw2_c.empty());
  EXPECT_NE(yaw2_c, yaw2);
  ASSERT_TRUE(sim.swap_model(c));
  ASSERT_TRUE(sim.switch_prepared());
  EXPECT_NEAR(position(sim, yaw2_c), -0.4, 0.02);
  // The name yaw_2's joint had now is the spare elbow's joint: it keeps the elbow's state, not
  // the -0.4 rad a carry by name would give it.
  EXPECT_EQ(c.joint_modules.at(yaw2), kElbowA);
  EXPECT_NEAR(position(sim, yaw2), b.joint_homes.at(elbow3), 0.02);
}

// The sanding tool's links get the running disc's friction (SimParams::sanding_disc_friction):
// the links moved with it are found from its end-effector, and they are links of the robot
// (a name that is none is refused by the simulator, as below).
TEST(SimAssembly, TheSandingToolsLinksAreFoundForTheDiscFriction) {
  const SimulatedRobot sanding = demo_robot("sanding_robot.yaml");
  ASSERT_FALSE(sanding.sanding_links.empty());
  const SimulatedRobot drill = demo_robot("drill_robot.yaml");
  EXPECT_TRUE(drill.sanding_links.empty());
  SimParams params;
  params.sensors.enabled = false;
  const world::World w =
      world::load_world_file(std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/sand_site.yaml");
  EXPECT_NO_THROW(SimHardware(sanding.urdf, w, params, {}, {}, sanding.sanding_links));
  try {
    SimHardware hw(sanding.urdf, w, params, {}, {}, {"no_such_link"});
    FAIL() << "a sanding link that is no link was taken";
  } catch (const hardware::HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_link"), std::string::npos) << e.what();
  }
  // A hot swap drill -> sanding tool -> drill: each robot's own links (the drill has none).
  SimHardware swapped(drill.urdf, w, params, {}, {}, drill.sanding_links);
  EXPECT_TRUE(swapped.swap_model(sanding.urdf, {}, {}, sanding.sanding_links));
  EXPECT_TRUE(swapped.swap_model(drill.urdf, {}, {}, drill.sanding_links));
  // The tool's TCP link is among them (the subtree of the last joint moving it).
  bool tcp = false;
  for (const std::string& l : sanding.sanding_links)
    tcp = tcp || l.find("tcp") != std::string::npos;
  std::string all;
  for (const std::string& l : sanding.sanding_links) all += l + " ";
  EXPECT_TRUE(tcp) << all;
}

}  // namespace
}  // namespace concert::sim
