#include "concert/sim/ray_sensors.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "allocation_counter.hpp"
#include "concert/sim/imu_simulator.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "mujoco_scene.hpp"

namespace concert::sim {
namespace {

using hardware::LaserScan2d;
using hardware::LidarScan;
using test::mjcf_document;
using test::MujocoScene;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

Eigen::Isometry3d pose(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = xyz;
  t.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return t;
}

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string v3(const Eigen::Vector3d& v) {
  return num(v.x()) + " " + num(v.y()) + " " + num(v.z());
}

/// A box geom with centre `c`, half sizes `h`, yaw about z.
std::string box(const Eigen::Vector3d& c, const Eigen::Vector3d& h, double yaw = 0.0,
                int group = kWorldGeomGroup) {
  return "<geom type=\"box\" pos=\"" + v3(c) + "\" size=\"" + v3(h) + "\" euler=\"0 0 " + num(yaw) +
         "\" group=\"" + std::to_string(group) + "\"/>\n";
}

std::string floor_plane(double z) {
  return "<geom type=\"plane\" size=\"50 50 0.1\" pos=\"0 0 " + num(z) + "\"/>\n";
}

/// Sensor mounts of the real mobile platform (xyz, rpy, then then_rpy when given), in its body
/// frame.
Eigen::Isometry3d platform_mount(const std::string& name) {
  const YAML::Node root = YAML::LoadFile(std::string(CONCERT_SHARED_DATA) +
                                         "/concert_resources/sensors/mobile_platform_sensors.yaml");
  for (const auto& s : root["sensors"]) {
    if (s["name"].as<std::string>() != name) {
      continue;
    }
    auto vec = [](const YAML::Node& n) {
      return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
    };
    Eigen::Isometry3d t = pose(vec(s["xyz"]), vec(s["rpy"]));
    if (s["then_rpy"]) {
      t = t * pose(Eigen::Vector3d::Zero(), vec(s["then_rpy"]));
    }
    return t;
  }
  throw std::runtime_error("no sensor '" + name + "' in mobile_platform_sensors.yaml");
}

/// The point a lidar return stands for, in the sensor frame.
Eigen::Vector3d lidar_point(const LidarScan& scan, std::size_t ring, std::size_t column) {
  const double r = scan.ranges[ring * scan.columns + column];
  const double e = scan.elevations[ring];
  const double a = scan.azimuth_min + static_cast<double>(column) * scan.azimuth_increment;
  return r * Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
}

double azimuth_of(const LidarScan& scan, std::size_t column) {
  return scan.azimuth_min + static_cast<double>(column) * scan.azimuth_increment;
}

struct Stats {
  double mean{0.0};
  double std{0.0};
  std::size_t n{0};
};

Stats stats(const std::vector<double>& v) {
  Stats s;
  s.n = v.size();
  for (double x : v) {
    s.mean += x;
  }
  s.mean /= static_cast<double>(v.size());
  for (double x : v) {
    s.std += (x - s.mean) * (x - s.mean);
  }
  s.std = std::sqrt(s.std / static_cast<double>(v.size() - 1));
  return s;
}

// ------------------------------------------------------------------------------------------------
// Lidar

constexpr std::size_t kRingMinus1 = 7;  // VLP-16 rings: -15° + 2° r
constexpr std::size_t kRingPlus1 = 8;
constexpr std::size_t kColumnAzimuth0 = 450;  // -180° + 0.4° c

TEST(LidarSimulator, BeamLayoutIsTheVlp16s) {
  const LidarSimulator lidar(LidarParams{});
  ASSERT_EQ(lidar.elevations().size(), 16u);
  EXPECT_NEAR(lidar.elevations().front(), -15.0 * kDeg, 1e-6);
  EXPECT_NEAR(lidar.elevations()[kRingMinus1], -1.0 * kDeg, 1e-6);
  EXPECT_NEAR(lidar.elevations()[kRingPlus1], 1.0 * kDeg, 1e-6);
  EXPECT_NEAR(lidar.elevations().back(), 15.0 * kDeg, 1e-6);
  const MujocoScene scene(mjcf_document(""));
  std::mt19937_64 rng(1);
  LidarScan scan;
  lidar.scan(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng, scan);
  EXPECT_EQ(scan.columns, 900u);
  EXPECT_EQ(scan.ranges.size(), 16u * 900u);
  EXPECT_DOUBLE_EQ(scan.azimuth_min, -kPi);
  EXPECT_NEAR(azimuth_of(scan, kColumnAzimuth0), 0.0, 1e-12);
  EXPECT_FLOAT_EQ(scan.range_max, 100.0f);
  // Nothing in the world: no return anywhere.
  EXPECT_EQ(std::count(scan.ranges.begin(), scan.ranges.end(), 0.0f),
            static_cast<long>(scan.ranges.size()));
}

TEST(LidarSimulator, BadParametersAreRefusedByName) {
  LidarParams p;
  p.rings = 0;
  EXPECT_THROW(LidarSimulator{p}, std::invalid_argument);
  p = {};
  p.range_max = p.range_min;
  EXPECT_THROW(LidarSimulator{p}, std::invalid_argument);
  p = {};
  p.elevation_max = 2.0;
  try {
    LidarSimulator{p};
    FAIL() << "an elevation above 90° was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("elevation"), std::string::npos) << e.what();
  }
}

TEST(LidarSimulator, WallAheadReadsItsDistanceWithTheNoiseModel) {
  const double d = 5.0;
  const MujocoScene scene(mjcf_document(box({d + 0.1, 0, 0}, {0.1, 20, 20})));
  const LidarParams params;
  const LidarSimulator lidar(params);
  std::mt19937_64 rng(42);
  LidarScan scan;
  lidar.scan(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng, scan);
  const double sigma = params.range_noise;
  for (std::size_t ring : {kRingMinus1, kRingPlus1}) {
    EXPECT_NEAR(scan.ranges[ring * scan.columns + kColumnAzimuth0], d / std::cos(1.0 * kDeg),
                4 * sigma)
        << "ring " << ring;
  }
  std::vector<double> errors;
  for (std::size_t ring = 0; ring < scan.elevations.size(); ++ring) {
    for (std::size_t c = 0; c < scan.columns; ++c) {
      const double a = azimuth_of(scan, c);
      const float r = scan.ranges[ring * scan.columns + c];
      if (std::abs(a) < 70.0 * kDeg) {  // the wall spans ±76° at the sensor's height
        ASSERT_GT(r, 0.0f) << "ring " << ring << " column " << c;
        errors.push_back(r - d / (std::cos(scan.elevations[ring]) * std::cos(a)));
      } else if (std::abs(a) > 80.0 * kDeg) {
        EXPECT_EQ(r, 0.0f) << "ring " << ring << " column " << c << " sees something behind";
      }
    }
  }
  const Stats s = stats(errors);
  EXPECT_GT(s.n, 5000u);
  EXPECT_NEAR(s.mean, 0.0, 4 * sigma / std::sqrt(static_cast<double>(s.n)));
  EXPECT_NEAR(s.std, sigma, 0.15 * sigma);
}

TEST(LidarSimulator, UpsideDownLidarSeesTheWallAtTheRightBearing) {
  // The platform's lidars: rpy (π, 0, ±π/2). A wall at world x = 5; the lidar at the front mount.
  const double wall = 5.0;
  const MujocoScene scene(mjcf_document(box({wall + 0.1, 0, 0}, {0.1, 20, 20})));
  const LidarParams params;
  const LidarSimulator lidar(params);
  for (const double yaw : {kPi / 2, -kPi / 2}) {
    const Eigen::Isometry3d world_T_sensor = pose({0.5305, 0.315, 0.0}, {kPi, 0.0, yaw});
    // Sensor y = world ∓x... world +x is at sensor azimuth +π/2 for yaw +π/2 and -π/2 for yaw -π/2.
    const double bearing = yaw > 0 ? kPi / 2 : -kPi / 2;
    std::mt19937_64 rng(7);
    LidarScan scan;
    lidar.scan(scene.m(), scene.d(), world_T_sensor, rng, scan);
    const auto column = static_cast<std::size_t>(
        std::lround((bearing - scan.azimuth_min) / scan.azimuth_increment));
    const double d = wall - 0.5305;
    for (std::size_t ring = 0; ring < scan.elevations.size(); ++ring) {
      EXPECT_NEAR(scan.ranges[ring * scan.columns + column], d / std::cos(scan.elevations[ring]),
                  4 * params.range_noise)
          << "yaw " << yaw << " ring " << ring;
    }
    // Every return lies on the wall's face; every beam within ±70° of the bearing returns.
    std::size_t hits = 0;
    for (std::size_t ring = 0; ring < scan.elevations.size(); ++ring) {
      for (std::size_t c = 0; c < scan.columns; ++c) {
        double off = azimuth_of(scan, c) - bearing;
        off = std::atan2(std::sin(off), std::cos(off));
        if (scan.ranges[ring * scan.columns + c] == 0.0f) {
          EXPECT_GT(std::abs(off), 70.0 * kDeg)
              << "yaw " << yaw << " ring " << ring << " column " << c;
          continue;
        }
        ++hits;
        const Eigen::Vector3d p = world_T_sensor * lidar_point(scan, ring, c);
        ASSERT_NEAR(p.x(), wall, 5 * params.range_noise)
            << "yaw " << yaw << " ring " << ring << " column " << c;
        EXPECT_LT(std::abs(off), 80.0 * kDeg);
      }
    }
    EXPECT_GT(hits, 16u * 350u);
  }
}

TEST(LidarSimulator, CylinderAppearsAtItsBearingAndDistance) {
  const double bearing = 30.0 * kDeg;
  const double centre = 4.0;
  const double radius = 0.3;
  const Eigen::Vector3d axis(centre * std::cos(bearing), centre * std::sin(bearing), 0.0);
  const MujocoScene scene(mjcf_document("<geom type=\"cylinder\" size=\"" + num(radius) +
                                        " 1\" pos=\"" + v3(axis) + "\"/>\n"));
  const LidarParams params;
  const LidarSimulator lidar(params);
  std::mt19937_64 rng(3);
  LidarScan scan;
  lidar.scan(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng, scan);
  const auto column =
      static_cast<std::size_t>(std::lround((bearing - scan.azimuth_min) / scan.azimuth_increment));
  for (std::size_t ring : {kRingMinus1, kRingPlus1}) {
    EXPECT_NEAR(scan.ranges[ring * scan.columns + column], (centre - radius) / std::cos(1.0 * kDeg),
                4 * params.range_noise);
  }
  const double half_width = std::asin(radius / centre);
  std::size_t columns_hit = 0;
  for (std::size_t ring = 0; ring < scan.elevations.size(); ++ring) {
    for (std::size_t c = 0; c < scan.columns; ++c) {
      if (scan.ranges[ring * scan.columns + c] == 0.0f) {
        continue;
      }
      columns_hit += ring == kRingPlus1 ? 1 : 0;
      EXPECT_LE(std::abs(azimuth_of(scan, c) - bearing), half_width + 1e-9)
          << "ring " << ring << " column " << c;
      const Eigen::Vector3d p = lidar_point(scan, ring, c);
      EXPECT_NEAR((p - axis).head<2>().norm(), radius, 5 * params.range_noise)
          << "ring " << ring << " column " << c;
    }
  }
  EXPECT_GE(columns_hit, static_cast<std::size_t>(2 * half_width / scan.azimuth_increment) - 1);
}

TEST(LidarSimulator, RobotGeomsAreInvisible) {
  const std::string wall = box({4.1, 0, 0}, {0.1, 10, 10});
  // A chassis box around the sensor and an arm link between it and the wall, in the robot's group.
  const std::string robot = box({0, 0, 0}, {0.6, 0.4, 0.3}, 0.0, kRobotGeomGroup) +
                            "<geom type=\"cylinder\" size=\"0.1 0.5\" pos=\"1.5 0 0\" group=\"" +
                            std::to_string(kRobotGeomGroup) + "\"/>\n";
  const MujocoScene bare(mjcf_document(wall));
  const MujocoScene with_robot(mjcf_document(wall + robot));
  const LidarSimulator lidar(LidarParams{});
  LidarScan expected;
  LidarScan seen;
  std::mt19937_64 rng_a(11);
  std::mt19937_64 rng_b(11);
  lidar.scan(bare.m(), bare.d(), Eigen::Isometry3d::Identity(), rng_a, expected);
  lidar.scan(with_robot.m(), with_robot.d(), Eigen::Isometry3d::Identity(), rng_b, seen);
  EXPECT_EQ(seen.ranges, expected.ranges);
  EXPECT_GT(std::count_if(seen.ranges.begin(), seen.ranges.end(), [](float r) { return r > 0.0f; }),
            5000);
}

TEST(LidarSimulator, PaperRobotsLidarSeesOnlyTheWorld) {
  // The simulator's own MJCF for the drill robot (robot geoms in kRobotGeomGroup), a wall ahead.
  std::ifstream in(std::string(ROBOT_FIXTURES) + "/mobile_drill.urdf");
  std::stringstream urdf;
  urdf << in.rdbuf();
  World world;
  world::WorldShape wall;
  wall.name = "wall";
  wall.size = {0.2, 8.0, 3.0};
  wall.position = {4.1, 0.0, 1.5};
  world.walls.push_back(wall);
  const std::string mjcf = urdf_to_mjcf(urdf.str(), world, {});
  ASSERT_NE(mjcf.find("group=\"1\""), std::string::npos);
  const MujocoScene scene(mjcf);
  const int base = mj_name2id(scene.m(), mjOBJ_BODY, "mobile_base");
  ASSERT_GE(base, 0);
  Eigen::Isometry3d world_T_base = Eigen::Isometry3d::Identity();
  world_T_base.translation() = Eigen::Map<const Eigen::Vector3d>(scene.d()->xpos + 3 * base);
  world_T_base.linear() =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(scene.d()->xmat + 9 * base);
  const LidarParams params;
  const LidarSimulator lidar(params);
  for (const std::string name : {"lidar_front", "lidar_back"}) {
    const Eigen::Isometry3d world_T_sensor = world_T_base * platform_mount(name);
    std::mt19937_64 rng(5);
    LidarScan scan;
    lidar.scan(scene.m(), scene.d(), world_T_sensor, rng, scan);
    std::size_t on_wall = 0;
    std::size_t on_floor = 0;
    for (std::size_t ring = 0; ring < scan.elevations.size(); ++ring) {
      for (std::size_t c = 0; c < scan.columns; ++c) {
        if (scan.ranges[ring * scan.columns + c] == 0.0f) {
          continue;
        }
        const Eigen::Vector3d p = world_T_sensor * lidar_point(scan, ring, c);
        const bool wall_hit = std::abs(p.x() - 4.0) < 5 * params.range_noise;
        const bool floor_hit = std::abs(p.z()) < 5 * params.range_noise;
        ASSERT_TRUE(wall_hit || floor_hit)
            << name << " ring " << ring << " column " << c << " sees " << p.transpose();
        on_wall += wall_hit ? 1 : 0;
        on_floor += floor_hit ? 1 : 0;
      }
    }
    EXPECT_GT(on_wall, 1000u) << name;
    EXPECT_GT(on_floor, 3000u) << name;
  }
}

TEST(LidarSimulator, FloorAppearsOnTheLowRings) {
  const double height = 0.684;  // the platform's lidars above the floor
  const MujocoScene scene(mjcf_document(floor_plane(-height)));
  const LidarParams params;
  const LidarSimulator lidar(params);
  std::mt19937_64 rng(9);
  LidarScan scan;
  lidar.scan(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng, scan);
  for (std::size_t ring = 0; ring < scan.elevations.size(); ++ring) {
    const double e = scan.elevations[ring];
    for (std::size_t c = 0; c < scan.columns; ++c) {
      const float r = scan.ranges[ring * scan.columns + c];
      if (e < 0.0) {
        ASSERT_NEAR(r, height / std::sin(-e), 5 * params.range_noise)
            << "ring " << ring << " column " << c;
      } else {
        ASSERT_EQ(r, 0.0f) << "ring " << ring << " column " << c;
      }
    }
  }
  EXPECT_NEAR(height / std::sin(15.0 * kDeg), 2.643, 1e-3);  // ring 0, for the reader
}

TEST(LidarSimulator, FastPathEqualsMjRayOnEveryGeomType) {
  const std::string assets =
      "<mesh name=\"tetra\" vertex=\"0 0 0  1 0 0  0 1 0  0 0 1\"/>\n"
      "<hfield name=\"bumps\" nrow=\"3\" ncol=\"3\" size=\"1.5 1.5 0.4 0.1\"/>\n";
  std::string world = floor_plane(-0.7);
  world += "<geom type=\"plane\" size=\"50 50 0.1\" pos=\"0 0 3\" euler=\"" + num(kPi) +
           " 0 0\"/>\n";         // ceiling
  for (int i = 0; i < 4; ++i) {  // a room
    const double yaw = i * kPi / 2;
    world += box({6.0 * std::cos(yaw), 6.0 * std::sin(yaw), 1.0}, {0.1, 6.0, 2.0}, yaw);
  }
  world += box({2.0, 1.0, 0.0}, {0.3, 0.5, 0.7}, 0.4);
  world += "<geom type=\"cylinder\" size=\"0.25 0.8\" pos=\"-2 1.5 0\"/>\n";
  world += "<geom type=\"sphere\" size=\"0.4\" pos=\"-1.5 -2 0.3\"/>\n";
  world += "<geom type=\"capsule\" size=\"0.2 0.6\" pos=\"1 -2.5 0\" euler=\"0.5 0.3 0\"/>\n";
  world += "<geom type=\"ellipsoid\" size=\"0.3 0.5 0.2\" pos=\"3 -1 0.2\"/>\n";
  world += "<geom type=\"mesh\" mesh=\"tetra\" pos=\"-3 -3 -0.5\"/>\n";
  world += "<geom type=\"hfield\" hfield=\"bumps\" pos=\"3 3 -0.7\"/>\n";
  world +=
      "<geom type=\"box\" size=\"0.5 0.5 0.5\" pos=\"0 3 0\" rgba=\"1 1 1 0\"/>\n";  // invisible
                                                                                     // to rays
  world +=
      "<body pos=\"0.5 0 0\"><joint type=\"hinge\"/><geom type=\"box\" size=\"0.2 0.2 0.2\" "
      "group=\"1\"/>"
      "<geom type=\"box\" size=\"0.1 0.1 0.1\" pos=\"0 0 0.5\"/></body>\n";  // a moving world geom
                                                                             // too
  const MujocoScene scene(mjcf_document(world, "", assets));
  // MuJoCo 2.2.2 takes no inline elevation: a file-less height field is zero until set.
  const float bumps[9] = {0, 1, 0, 1, 0, 1, 0, 1, 0};
  std::copy(std::begin(bumps), std::end(bumps), scene.m()->hfield_data);
  LidarParams params;
  params.noise = false;
  const LidarSimulator lidar(params);
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    const Eigen::Isometry3d world_T_sensor =
        pose({2.0 * uniform(rng), 2.0 * uniform(rng), 0.3 * uniform(rng)},
             {0.3 * uniform(rng) + (trial % 2 == 1 ? kPi : 0.0), 0.3 * uniform(rng),
              kPi * uniform(rng)});
    LidarScan fast;
    LidarScan reference;
    lidar.scan(scene.m(), scene.d(), world_T_sensor, rng, fast);
    lidar.scan_reference(scene.m(), scene.d(), world_T_sensor, reference);
    ASSERT_EQ(fast.ranges.size(), reference.ranges.size());
    for (std::size_t i = 0; i < fast.ranges.size(); ++i) {
      ASSERT_NEAR(fast.ranges[i], reference.ranges[i], 1e-5f) << "trial " << trial << " ray " << i;
    }
    EXPECT_EQ(std::count(fast.ranges.begin(), fast.ranges.end(), 0.0f), 0)
        << "trial " << trial << ": a closed room";
  }
}

TEST(RaySensors, NoAllocationPerReadingAfterTheFirst) {
  const MujocoScene scene(mjcf_document(floor_plane(-0.7) + box({4.1, 0, 0}, {0.1, 5, 3})));
  const LidarSimulator lidar(LidarParams{});
  const SonarSimulator sonar(SonarParams{});
  ImuSimulator imu(ImuParams{}, 1);
  std::mt19937_64 rng(1);
  LidarScan scan;
  scan.sensor = "lidar_front";
  LaserScan2d planar;
  hardware::SonarRange echo;
  hardware::ImuSample sample;
  const std::vector<PosedLidarScan> scans{{&scan, Eigen::Isometry3d::Identity()}};
  auto read_all = [&] {
    lidar.scan(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng, scan);
    derive_scan2d(Scan2dParams{}, scans, Eigen::Isometry3d::Identity(), -0.7, "mobile_base",
                  planar);
    sonar.read(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng, echo);
    imu.sample(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.81), 0.005, sample);
  };
  read_all();
  const concert::test::CountAllocations allocations;
  for (int i = 0; i < 3; ++i) {
    read_all();
  }
  EXPECT_EQ(allocations.count(), 0u);
  EXPECT_NEAR(echo.range, 0.7 / std::sin(15.0 * kDeg),
              0.05);  // the floor, by the cone's lowest rays
  EXPECT_NEAR(planar.ranges[Scan2dParams{}.bins / 2], 4.0, 0.1);
}

// ------------------------------------------------------------------------------------------------
// Planar scan

TEST(DeriveScan2d, BoxRoomAroundTheBaseFromBothPlatformLidars) {
  // Floor at world z = 0, the base 0.747 m above it (as on the platform), turned and shifted in a
  // room x in [-5, 6], y in [-4.5, 5] with 3 m high walls.
  const double xmin = -5.0, xmax = 6.0, ymin = -4.5, ymax = 5.0;
  std::string room = floor_plane(0.0);
  room +=
      box({xmin - 0.1, 0.25, 1.5}, {0.1, 5.0, 1.5}) + box({xmax + 0.1, 0.25, 1.5}, {0.1, 5.0, 1.5});
  room +=
      box({0.5, ymin - 0.1, 1.5}, {5.8, 0.1, 1.5}) + box({0.5, ymax + 0.1, 1.5}, {5.8, 0.1, 1.5});
  const MujocoScene scene(mjcf_document(room));
  const double yaw = 0.4;
  const Eigen::Isometry3d world_T_base = pose({0.3, -0.2, 0.747}, {0, 0, yaw});
  const LidarParams lidar_params;
  const LidarSimulator lidar(lidar_params);
  std::mt19937_64 rng(17);
  LidarScan front;
  LidarScan back;
  const Eigen::Isometry3d world_T_front = world_T_base * platform_mount("lidar_front");
  const Eigen::Isometry3d world_T_back = world_T_base * platform_mount("lidar_back");
  lidar.scan(scene.m(), scene.d(), world_T_front, rng, front);
  lidar.scan(scene.m(), scene.d(), world_T_back, rng, back);
  front.stamp = 1.0;
  back.stamp = 1.05;
  const std::vector<PosedLidarScan> scans{{&front, world_T_front}, {&back, world_T_back}};
  const Scan2dParams params;
  LaserScan2d out;
  derive_scan2d(params, scans, world_T_base, 0.0, "mobile_base", out);
  EXPECT_EQ(out.frame, "mobile_base");
  EXPECT_DOUBLE_EQ(out.stamp, 1.05);
  ASSERT_EQ(out.ranges.size(), params.bins);
  EXPECT_DOUBLE_EQ(out.angle_min, -kPi);

  // Distance from the base origin to the room's walls at bearing b (base frame).
  const Eigen::Vector2d o = world_T_base.translation().head<2>();
  auto wall_distance = [&](double b) {
    const Eigen::Vector2d u(std::cos(yaw + b), std::sin(yaw + b));
    double t = std::numeric_limits<double>::infinity();
    t = std::min(t, u.x() > 0 ? (xmax - o.x()) / u.x() : (xmin - o.x()) / u.x());
    t = std::min(t, u.y() > 0 ? (ymax - o.y()) / u.y() : (ymin - o.y()) / u.y());
    return t;
  };
  const double tolerance = 5 * lidar_params.range_noise;
  std::size_t empty = 0;
  for (std::size_t i = 0; i < out.ranges.size(); ++i) {
    if (!std::isfinite(out.ranges[i])) {
      ++empty;
      continue;
    }
    double lo = std::numeric_limits<double>::infinity();
    double hi = 0.0;
    for (int k = 0; k <= 20; ++k) {
      const double d =
          wall_distance(out.angle_min + (static_cast<double>(i) + k / 20.0) * out.angle_increment);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    EXPECT_GE(out.ranges[i], lo - tolerance) << "bin " << i;
    EXPECT_LE(out.ranges[i], hi + tolerance) << "bin " << i;
  }
  EXPECT_LE(empty, params.bins / 100) << "bins without a return";

  // The scans do have floor returns nearer than the walls: keeping them changes many bins.
  Scan2dParams with_floor = params;
  with_floor.height_min = -1.0;
  LaserScan2d floor_scan;
  derive_scan2d(with_floor, scans, world_T_base, 0.0, "mobile_base", floor_scan);
  std::size_t floor_bins = 0;
  for (std::size_t i = 0; i < floor_scan.ranges.size(); ++i) {
    floor_bins +=
        floor_scan.ranges[i] < wall_distance(out.angle_min +
                                             (static_cast<double>(i) + 0.5) * out.angle_increment) -
                                   0.5
            ? 1
            : 0;
  }
  EXPECT_GT(floor_bins, params.bins / 2);
}

TEST(DeriveScan2d, RefusesAScanWhoseShapeIsWrong) {
  LidarScan bad;
  bad.sensor = "lidar_front";
  bad.elevations = {0.0f, 0.1f};
  bad.columns = 10;
  bad.ranges.assign(15, 1.0f);
  const std::vector<PosedLidarScan> scans{{&bad, Eigen::Isometry3d::Identity()}};
  LaserScan2d out;
  try {
    derive_scan2d(Scan2dParams{}, scans, Eigen::Isometry3d::Identity(), 0.0, "base", out);
    FAIL() << "a malformed scan was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lidar_front"), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------------------------------------------
// Sonar

TEST(SonarSimulator, RaysCoverTheConeAxisAndRings) {
  const SonarParams params;
  const SonarSimulator sonar(params);
  ASSERT_EQ(sonar.directions().size(), params.rays);
  EXPECT_EQ(sonar.directions().front(), Eigen::Vector3d::UnitX());
  double widest = 0.0;
  for (const auto& d : sonar.directions()) {
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    widest = std::max(widest, std::acos(std::clamp(d.x(), -1.0, 1.0)));
  }
  EXPECT_NEAR(widest, params.field_of_view / 2, 1e-9);
  SonarParams bad;
  bad.rays = 0;
  EXPECT_THROW(SonarSimulator{bad}, std::invalid_argument);
}

TEST(SonarSimulator, PerpendicularWallReadsItsDistance) {
  const MujocoScene scene(mjcf_document(box({2.1, 0, 0}, {0.1, 3, 3})));
  const SonarParams params;
  const SonarSimulator sonar(params);
  std::mt19937_64 rng(1);
  std::vector<double> readings;
  for (int i = 0; i < 200; ++i) {
    readings.push_back(sonar.range(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng));
    ASSERT_NEAR(readings.back(), 2.0, 5 * params.range_noise);
  }
  const Stats s = stats(readings);
  EXPECT_NEAR(s.mean, 2.0, 4 * params.range_noise / std::sqrt(200.0));
  EXPECT_NEAR(s.std, params.range_noise, 0.15 * params.range_noise);
}

TEST(SonarSimulator, WallAt45DegreesReadsTheNearestPointInTheCone) {
  // The wall's face passes through (d, 0, 0) with its normal 45° from the cone's axis: the nearest
  // point within a 30° cone lies along the edge ray 15° towards the normal, at
  // d cos 45° / cos(45° - 15°) (that ray is sampled: outer ring, φ = 0).
  const double d = 2.0;
  const Eigen::Vector3d normal(std::cos(kPi / 4), std::sin(kPi / 4), 0.0);
  const MujocoScene scene(
      mjcf_document(box(Eigen::Vector3d(d, 0, 0) + 0.1 * normal, {0.1, 5, 3}, kPi / 4)));
  SonarParams params;
  params.noise = false;
  const double expected = d * std::cos(kPi / 4) / std::cos(kPi / 4 - params.field_of_view / 2);
  std::mt19937_64 rng(1);
  EXPECT_NEAR(
      SonarSimulator(params).range(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng),
      expected, 1e-6);
  params.noise = true;
  EXPECT_NEAR(
      SonarSimulator(params).range(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng),
      expected, 4 * params.range_noise);
  // The axis alone would read d: the cone matters.
  EXPECT_LT(expected, d - 0.3);
}

TEST(SonarSimulator, NothingWithinRangeReadsInfinity) {
  const MujocoScene scene(
      mjcf_document(box({6.1, 0, 0}, {0.1, 3, 3}) + box({0, 2, 0}, {0.3, 0.3, 0.3})));
  const SonarSimulator sonar(SonarParams{});
  std::mt19937_64 rng(1);
  EXPECT_EQ(sonar.range(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng),
            std::numeric_limits<float>::infinity());
  hardware::SonarRange reading;
  sonar.read(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng, reading);
  EXPECT_TRUE(std::isinf(reading.range));
  EXPECT_FLOAT_EQ(reading.range_max, 4.0f);
  EXPECT_FLOAT_EQ(reading.field_of_view, static_cast<float>(SonarParams{}.field_of_view));
}

TEST(SonarSimulator, VeryCloseEchoSaturatesAtRangeMin) {
  const MujocoScene scene(
      mjcf_document(box({0.15, 0, 0}, {0.05, 1, 1}) +
                    box({0.0, 0.0, 0.0}, {0.1, 0.1, 0.1}, 0.0, kRobotGeomGroup)));
  const SonarParams params;
  const SonarSimulator sonar(params);
  std::mt19937_64 rng(1);
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(sonar.range(scene.m(), scene.d(), Eigen::Isometry3d::Identity(), rng),
              static_cast<float>(params.range_min));
  }
}

TEST(SonarSimulator, PlatformsFrontLeftSagittalSonarSeesFloorAndWall) {
  // Base frame = world; floor at z = -0.747 as on the platform. The sonar looks forward and 22.5°
  // down: with the cone's 15° half angle its rays span 7.5° .. 37.5° below the horizon (the rays at
  // φ = ±π/2 of the outer ring lie in that vertical plane).
  const Eigen::Isometry3d world_T_sonar = platform_mount("ultrasound_fl_sag");
  const Eigen::Vector3d axis = world_T_sonar.linear().col(0);
  const double down = std::asin(-axis.z());
  ASSERT_NEAR(down, 22.5 * kDeg, 0.1 * kDeg);
  EXPECT_NEAR(axis.y(), 0.0, 1e-6);
  const SonarParams params;
  const double half = params.field_of_view / 2;
  const double height = world_T_sonar.translation().z() + 0.747;
  const SonarSimulator sonar(params);
  std::mt19937_64 rng(21);
  {
    const MujocoScene scene(mjcf_document(floor_plane(-0.747)));
    EXPECT_NEAR(sonar.range(scene.m(), scene.d(), world_T_sonar, rng),
                height / std::sin(down + half), 4 * params.range_noise);
  }
  {
    const double wall = 1.2;
    const MujocoScene scene(
        mjcf_document(floor_plane(-0.747) + box({wall + 0.1, 0, 0}, {0.1, 3, 3})));
    const double expected = (wall - world_T_sonar.translation().x()) / std::cos(down - half);
    ASSERT_LT(expected, height / std::sin(down + half));  // the wall is nearer than the floor
    EXPECT_NEAR(sonar.range(scene.m(), scene.d(), world_T_sonar, rng), expected,
                4 * params.range_noise);
  }
}

// ------------------------------------------------------------------------------------------------
// IMU

std::string quat_attr(const Eigen::Matrix3d& r) {
  const Eigen::Quaterniond q(r);
  return "quat=\"" + num(q.w()) + " " + num(q.x()) + " " + num(q.y()) + " " + num(q.z()) + "\"";
}

TEST(ImuMjcf, MuJoCosAccelerometerReadsSpecificForce) {
  const ImuMjcf imu = imu_mjcf("imu");
  const Eigen::Matrix3d turned = pose({0, 0, 0}, {0.3, -0.5, 1.0}).linear();
  // A static body turned in space, a free body falling, a free body resting on the floor.
  const std::string world = floor_plane(0.0) + "<body name=\"fixed\" pos=\"0 0 2\" " +
                            quat_attr(turned) + ">" + imu.site + "</body>\n";
  const MujocoScene scene(mjcf_document(world, imu.sensors));
  const ImuTruth still = ImuTruthReader(scene.m(), "imu").read(scene.d());
  const Eigen::Vector3d up_in_sensor = turned.transpose() * Eigen::Vector3d(0, 0, 9.81);
  EXPECT_LT((still.specific_force - up_in_sensor).norm(), 1e-9) << still.specific_force.transpose();
  EXPECT_LT(still.angular_velocity.norm(), 1e-12);

  const ImuMjcf falling = imu_mjcf("drop");
  const std::string free_body =
      "<body name=\"box\" pos=\"0 0 5\"><freejoint/><geom type=\"box\" size=\"0.1 0.1 0.1\" "
      "mass=\"1\"/>" +
      falling.site + "</body>\n";
  const MujocoScene fall(mjcf_document(floor_plane(0.0) + free_body, falling.sensors));
  EXPECT_LT(ImuTruthReader(fall.m(), "drop").read(fall.d()).specific_force.norm(), 1e-9)
      << "free fall reads 0";
  for (int i = 0; i < 3000; ++i) {  // 5 m drop, then settle on the floor
    mj_step(fall.m(), fall.d());
  }
  const ImuTruth resting = ImuTruthReader(fall.m(), "drop").read(fall.d());
  EXPECT_NEAR(fall.d()->qpos[2], 0.1, 0.01) << "the box rests on the floor";
  EXPECT_LT((resting.specific_force - Eigen::Vector3d(0, 0, 9.81)).norm(), 0.05)
      << resting.specific_force.transpose();

  EXPECT_THROW(ImuTruthReader(scene.m(), "nope"), std::invalid_argument);
}

TEST(ImuMjcf, SpinningBodyReadsItsRateAndCentripetalForce) {
  const double omega = 2.0;
  const double radius = 0.5;
  Eigen::Isometry3d body_T_imu = Eigen::Isometry3d::Identity();
  body_T_imu.translation() = Eigen::Vector3d(radius, 0, 0);
  const ImuMjcf imu = imu_mjcf("imu", body_T_imu);
  const std::string world =
      "<body name=\"rotor\"><joint type=\"hinge\" axis=\"0 0 1\"/><geom type=\"cylinder\" "
      "size=\"0.6 0.05\" mass=\"2\"/>" +
      imu.site + "</body>\n";
  const MujocoScene scene(mjcf_document(world, imu.sensors));
  scene.d()->qvel[0] = omega;
  const ImuTruthReader reader(scene.m(), "imu");
  ImuSimulator quiet(
      [] {
        ImuParams p;
        p.noise = false;
        return p;
      }(),
      1);
  for (int i = 0; i < 5; ++i) {
    mj_forward(scene.m(), scene.d());
    const ImuTruth t = reader.read(scene.d());
    EXPECT_LT((t.angular_velocity - Eigen::Vector3d(0, 0, omega)).norm(), 1e-9)
        << t.angular_velocity.transpose();
    // Towards the axis (-x in the sensor frame): ω² r; and gravity's reaction up.
    EXPECT_LT((t.specific_force - Eigen::Vector3d(-omega * omega * radius, 0, 9.81)).norm(), 1e-6)
        << t.specific_force.transpose();
    hardware::ImuSample sample;
    quiet.sample(t.angular_velocity, t.specific_force, 0.005, sample);
    EXPECT_EQ(sample.angular_velocity, t.angular_velocity);
    EXPECT_EQ(sample.angular_velocity_variance, 0.0);
    for (int k = 0; k < 137; ++k) {
      mj_step(scene.m(), scene.d());
    }
  }
  EXPECT_NEAR(scene.d()->qvel[0], omega, 1e-9);
  EXPECT_GT(std::abs(scene.d()->qpos[0]), 1.0) << "it turned";
}

TEST(ImuSimulator, WhiteNoiseBiasAndVariancesFollowTheModel) {
  ImuParams params;
  params.gyro_bias_walk = 0.0;
  params.accel_bias_walk = 0.0;
  const Eigen::Vector3d gyro_true(0.1, -0.2, 0.3);
  const Eigen::Vector3d accel_true(1.0, -2.0, 9.5);
  ImuSimulator imu(params, 7);
  const Eigen::Vector3d gyro_bias = imu.gyro_bias();
  const Eigen::Vector3d accel_bias = imu.accel_bias();
  const double gyro_sigma = params.gyro_noise_density * std::sqrt(params.rate);
  const double accel_sigma = params.accel_noise_density * std::sqrt(params.rate);
  EXPECT_DOUBLE_EQ(imu.gyro_sigma(), gyro_sigma);
  const int n = 20000;
  std::vector<std::vector<double>> g(3), a(3);
  hardware::ImuSample s;
  for (int i = 0; i < n; ++i) {
    imu.sample(gyro_true, accel_true, 1.0 / params.rate, s);
    for (int k = 0; k < 3; ++k) {
      g[k].push_back(s.angular_velocity[k]);
      a[k].push_back(s.linear_acceleration[k]);
    }
  }
  EXPECT_DOUBLE_EQ(s.angular_velocity_variance, gyro_sigma * gyro_sigma);
  EXPECT_DOUBLE_EQ(s.linear_acceleration_variance, accel_sigma * accel_sigma);
  EXPECT_EQ(imu.gyro_bias(), gyro_bias) << "no walk: the bias is constant";
  EXPECT_EQ(imu.accel_bias(), accel_bias);
  for (int k = 0; k < 3; ++k) {
    const Stats gs = stats(g[k]);
    const Stats as = stats(a[k]);
    EXPECT_NEAR(gs.mean, gyro_true[k] + gyro_bias[k], 4 * gyro_sigma / std::sqrt(n))
        << "axis " << k;
    EXPECT_NEAR(as.mean, accel_true[k] + accel_bias[k], 4 * accel_sigma / std::sqrt(n))
        << "axis " << k;
    EXPECT_NEAR(gs.std, gyro_sigma, 0.15 * gyro_sigma) << "axis " << k;
    EXPECT_NEAR(as.std, accel_sigma, 0.15 * accel_sigma) << "axis " << k;
  }
  // The bias is drawn per seed, at the datasheet's scale.
  const ImuSimulator other(params, 8);
  EXPECT_GT((other.gyro_bias() - gyro_bias).norm(), 1e-6);
  EXPECT_GT((other.accel_bias() - accel_bias).norm(), 1e-6);
  EXPECT_LT(gyro_bias.cwiseAbs().maxCoeff(), 5 * params.gyro_bias_sigma);
  EXPECT_LT(accel_bias.cwiseAbs().maxCoeff(), 5 * params.accel_bias_sigma);
}

TEST(ImuSimulator, BiasWalksWithTheStatedDensity) {
  ImuParams params;
  params.gyro_bias_walk = 1e-3;
  ImuSimulator imu(params, 3);
  const double dt = 1.0 / params.rate;
  std::vector<double> steps;
  hardware::ImuSample s;
  for (int i = 0; i < 10000; ++i) {
    const double before = imu.gyro_bias().x();
    imu.sample(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), dt, s);
    steps.push_back(imu.gyro_bias().x() - before);
  }
  const Stats st = stats(steps);
  EXPECT_NEAR(st.std, params.gyro_bias_walk * std::sqrt(dt),
              0.15 * params.gyro_bias_walk * std::sqrt(dt));
  EXPECT_THROW(imu.sample(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), -1.0, s),
               std::invalid_argument);
}

}  // namespace
}  // namespace concert::sim
