// The map from the sensors (SensorMapper): synthetic lidar revolutions and depth frames of a
// known wall, beams that hit the robot's own arm, and bad input. Seeded noise.

#include "planner/sensor_map.hpp"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <numbers>
#include <random>

#include "planner/fixtures.hpp"
#include "planner/state_checker.hpp"

using namespace concert::planner;
using concert::hardware::LidarScan;
using concert::hardware::RgbdFrame;

namespace {

constexpr double kWallX = 2.0;  // front face of the wall (normal -x)
constexpr double kRes = 0.05;
constexpr double kPitch = -0.6;  // [rad] of the arm's second joint in the self-filter test: leaning
                                 // back towards the lidar

std::shared_ptr<const PlanningModel> model_a(const Params& p) {
  return PlanningModel::build(
      fixtures::model_from_assembly(fixtures::data_dir() / "morphology_a.yaml", 3), p);
}

Eigen::Isometry3d at(const Eigen::Vector3d& xyz, double yaw = 0.0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = xyz;
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

// The wall's scan with the test's sensor names.
LidarScan wall_scan(const Eigen::Isometry3d& map_T_sensor, double sigma, std::mt19937& rng,
                    std::uint32_t columns = 900) {
  LidarScan s = fixtures::wall_scan(map_T_sensor, kWallX, sigma, rng, columns);
  s.sensor = "test_lidar";
  s.frame = "test_lidar_frame";
  return s;
}

using fixtures::beam;

std::vector<Eigen::Vector3d> occupied_centres(const Environment& env) {
  std::vector<Eigen::Vector3d> out;
  const octomap::OcTree& t = *env.octree();
  for (auto it = t.begin_leafs(); it != t.end_leafs(); ++it) {
    if (t.isNodeOccupied(*it)) out.emplace_back(it.getX(), it.getY(), it.getZ());
  }
  return out;
}

// Known free: the voxel exists in the tree and is not occupied.
bool known_free(const Environment& env, const Eigen::Vector3d& p) {
  const octomap::OcTreeNode* n = env.octree()->search(p.x(), p.y(), p.z());
  return n != nullptr && !env.octree()->isNodeOccupied(n);
}

}  // namespace

TEST(SensorMap, LidarScanOfAWallMarksTheWallFreesTheSpaceBeforeItAndNothingBehind) {
  Params p;
  const auto model = model_a(p);
  const SensorMapper mapper(model, p);
  Environment env(kRes);
  std::mt19937 rng(5u);
  const Eigen::Isometry3d sensor = at({-1.5, 0.2, 1.1}, 0.15);  // behind the robot, clear of it
  const LidarScan scan = wall_scan(sensor, 0.01, rng);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model->full_dof());
  const SensorMapStats stats = mapper.insert_lidar(env, scan, sensor, q);
  EXPECT_GT(stats.occupied, 1000u);
  EXPECT_GT(stats.floor, 1000u);      // the lower rings reach the floor
  EXPECT_GT(stats.no_return, 1000u);  // the rear half sees nothing

  const auto cells = occupied_centres(env);
  ASSERT_GT(cells.size(), 100u);
  std::size_t on_wall = 0;
  for (const Eigen::Vector3d& c : cells) {
    // Every occupied voxel is on the wall's face within one voxel (nothing of the floor, of the
    // robot, or behind the wall).
    EXPECT_NEAR(c.x(), kWallX, kRes) << "occupied voxel at " << c.transpose();
    EXPECT_GT(c.z(), p.floor_height + p.sensor_floor_band - kRes);
    on_wall += std::abs(c.x() - kWallX) <= kRes ? 1 : 0;
  }
  EXPECT_EQ(on_wall, cells.size());
  // Every wall return has an occupied voxel within one voxel of it (x-direction neighbours).
  std::size_t hits = 0, found = 0;
  for (std::size_t r = 0; r < scan.elevations.size(); ++r) {
    for (std::uint32_t c = 0; c < scan.columns; ++c) {
      const float range = scan.ranges[r * scan.columns + c];
      if (range <= 0.0F) continue;
      const Eigen::Vector3d pt = sensor * (range * beam(scan, r, c));
      if (pt.z() < 0.1 || std::abs(pt.x() - kWallX) > 0.05) continue;
      hits += 1;
      bool any = false;
      for (double dx : {-kRes, 0.0, kRes})
        any = any || env.occupied(pt + Eigen::Vector3d(dx, 0.0, 0.0));
      found += any ? 1 : 0;
      // Free before the wall along the beam (up to two voxels short of it), unknown behind.
      for (double s = 0.5; s < range - 2.0 * kRes; s += 0.25) {
        EXPECT_TRUE(known_free(env, sensor * (s * beam(scan, r, c))))
            << "not free at " << s << " m along beam " << r << "," << c;
      }
      const Eigen::Vector3d behind = sensor * ((range + 0.3) * beam(scan, r, c));
      if (std::abs(behind.y()) > 2.5)
        continue;  // beams past the wall's edge reach the floor behind it
      EXPECT_EQ(env.octree()->search(behind.x(), behind.y(), behind.z()), nullptr)
          << "known behind the wall at " << behind.transpose();
    }
  }
  EXPECT_GT(hits, 1000u);
  EXPECT_EQ(found, hits);
}

TEST(SensorMap, ReturnsFartherThanTheMaximumRangeClearTheirRayAndMarkNothing) {
  Params p;
  p.sensor_max_range = 2.0;  // the wall is 3.5 m away
  const auto model = model_a(p);
  Environment env(kRes);
  std::mt19937 rng(6u);
  const Eigen::Isometry3d sensor = at({-1.5, 0.0, 1.6});
  const SensorMapStats stats = SensorMapper(model, p).insert_lidar(
      env, wall_scan(sensor, 0.0, rng), sensor, Eigen::VectorXd::Zero(model->full_dof()));
  EXPECT_GT(stats.cut, 1000u);
  EXPECT_EQ(env.occupied_cells(), 0u);
  EXPECT_TRUE(known_free(env, sensor * Eigen::Vector3d(1.8, 0.0, 0.0)));
  EXPECT_FALSE(known_free(env, sensor * Eigen::Vector3d(2.3, 0.0, 0.0)));
}

namespace {

// Independent of the mapper: whether p lies in one of the robot's unpadded shapes at q.
bool in_robot(const PlanningModel& m, const std::vector<Eigen::Isometry3d>& poses,
              const Eigen::Vector3d& p) {
  for (std::size_t i = 0; i < m.links().size(); ++i) {
    for (const LinkShape& s : m.links()[i].shapes) {
      const Eigen::Vector3d l = (poses[i] * s.origin).inverse() * p;
      const bool in = s.type == LinkShape::Type::kBox
                          ? (l.cwiseAbs().array() <= 0.5 * s.size.array()).all()
                      : s.type == LinkShape::Type::kCylinder
                          ? l.head<2>().norm() <= s.size.x() && std::abs(l.z()) <= 0.5 * s.size.z()
                          : l.norm() <= s.size.x();
      if (in) return true;
    }
  }
  return false;
}

// The wall scan with the robot at q in front of it: each beam stops at the robot's first
// shape it meets (marched in 5 mm steps).
LidarScan scan_with_robot(const PlanningModel& m, const Eigen::VectorXd& q,
                          const Eigen::Isometry3d& sensor, std::size_t& on_robot) {
  std::mt19937 rng(7u);
  LidarScan s = wall_scan(sensor, 0.0, rng, 360);
  std::vector<Eigen::Isometry3d> poses;
  m.link_poses(q, poses);
  on_robot = 0;
  for (std::size_t r = 0; r < s.elevations.size(); ++r) {
    for (std::uint32_t c = 0; c < s.columns; ++c) {
      float& range = s.ranges[r * s.columns + c];
      const double end = std::min(range > 0.0F ? static_cast<double>(range) : 4.0, 2.5);
      const Eigen::Vector3d d = sensor.linear() * beam(s, r, c);
      for (double t = 0.2; t < end; t += 0.005) {
        if (in_robot(m, poses, sensor.translation() + t * d)) {
          range = static_cast<float>(t);
          on_robot += 1;
          break;
        }
      }
    }
  }
  return s;
}

}  // namespace

TEST(SensorMap, BeamsThatHitTheRobotsOwnArmMarkNothingOnIt) {
  Params p;
  p.contact_force = 0.0;
  const auto model = model_a(p);
  const SensorMapper mapper(model, p);
  // The arm reaching forward at shoulder height, a lidar behind the robot looking at it.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model->full_dof());
  const auto& names = model->kinematics().joint_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == model->joint_names()[4]) q[static_cast<Eigen::Index>(i)] = kPitch;
  }
  const Eigen::Isometry3d sensor = at({-1.2, 0.05, 1.0});
  ASSERT_TRUE(StateChecker(model, Environment(kRes), p, 0.0).check(q).valid())
      << "the posture itself must be valid";
  std::size_t on_robot = 0;
  const LidarScan scan = scan_with_robot(*model, q, sensor, on_robot);
  ASSERT_GT(on_robot, 100u) << "the test's beams must hit the robot";

  Environment env(kRes);
  const SensorMapStats stats = mapper.insert_lidar(env, scan, sensor, q);
  EXPECT_GE(stats.self, on_robot);  // and floor returns within the padding of the wheels
  EXPECT_GT(stats.occupied, 500u);  // the wall around the robot's shadow
  // No occupied voxel on the robot: FCL (the state checker) finds the robot clear of the map.
  StateChecker exact(model, env, p, 0.0);
  const Validity v = exact.check(q);
  EXPECT_TRUE(v.valid()) << to_string(v.constraint) << ": " << v.detail;
  for (const Eigen::Vector3d& c : occupied_centres(env))
    EXPECT_NEAR(c.x(), kWallX, kRes) << c.transpose();

  // The same scan filtered with a stale joint state (the arm elsewhere) leaves the arm in the map:
  // the filter follows the joints.
  Environment stale(kRes);
  (void)mapper.insert_lidar(stale, scan, sensor, Eigen::VectorXd::Zero(model->full_dof()));
  StateChecker stale_check(model, stale, p, 0.0);
  EXPECT_EQ(stale_check.check(q).constraint, Constraint::kEnvironmentCollision);
}

TEST(SensorMap, BadInputIsRefusedNamingTheFieldAndTheMapIsUnchanged) {
  Params p;
  const auto model = model_a(p);
  const SensorMapper mapper(model, p);
  Environment env(kRes);
  std::mt19937 rng(8u);
  const Eigen::Isometry3d sensor = at({-1.5, 0.0, 1.0});
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model->full_dof());
  (void)mapper.insert_lidar(env, wall_scan(sensor, 0.01, rng), sensor, q);
  const auto before = env.octree();
  const std::size_t cells = env.occupied_cells();
  ASSERT_GT(cells, 0u);
  auto refused = [&](const LidarScan& s, const Eigen::Isometry3d& pose, const Eigen::VectorXd& qq) {
    try {
      (void)mapper.insert_lidar(env, s, pose, qq);
    } catch (const PlannerError& e) {
      EXPECT_EQ(env.octree(), before);
      EXPECT_EQ(env.occupied_cells(), cells);
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  // A scan that clears everything the map had, if accepted.
  LidarScan good = wall_scan(sensor, 0.0, rng);
  for (float& r : good.ranges) r = 10.0F;
  LidarScan short_ranges = good;
  short_ranges.ranges.pop_back();
  EXPECT_EQ(refused(short_ranges, sensor, q),
            "lidar 'test_lidar' (frame 'test_lidar_frame'): ranges has 14399 values, rings x "
            "columns = 16 x 900 = 14400");
  LidarScan nan_range = good;
  nan_range.ranges[905] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(refused(nan_range, sensor, q).find("range 905 (ring 1, column 5) is nan"),
            std::string::npos);
  LidarScan negative = good;
  negative.ranges[3] = -1.0F;
  EXPECT_NE(refused(negative, sensor, q).find("range 3 (ring 0, column 3) is -1"),
            std::string::npos);
  LidarScan no_rings = good;
  no_rings.elevations.clear();
  EXPECT_NE(refused(no_rings, sensor, q).find("elevations: no rings"), std::string::npos);
  LidarScan no_columns = good;
  no_columns.columns = 0;
  EXPECT_NE(refused(no_columns, sensor, q).find("columns: 0"), std::string::npos);
  Eigen::Isometry3d bad_pose = sensor;
  bad_pose.translation().x() = std::numeric_limits<double>::infinity();
  EXPECT_NE(refused(good, bad_pose, q).find("sensor pose is not finite"), std::string::npos);
  EXPECT_NE(refused(good, sensor, Eigen::VectorXd::Zero(3)).find("joint vector has 3 values"),
            std::string::npos);
  EXPECT_NE(refused(good, sensor, q).find("accepted"),
            std::string::npos);  // the check itself can pass
  EXPECT_NE(env.octree(), before);

  // Depth: wrong size, bad intrinsics, frames of different cameras.
  RgbdFrame f;
  f.sensor = "cam";
  f.frame = "cam_optical";
  f.intrinsics = {64, 48, 50.0, 50.0, 31.5, 23.5};
  f.depth.assign(64 * 48, 1500);
  const auto env_before = env.octree();
  auto depth_refused = [&](const std::vector<RgbdFrame>& frames) {
    try {
      (void)mapper.insert_depth(env, frames, sensor, q);
    } catch (const PlannerError& e) {
      EXPECT_EQ(env.octree(), env_before);
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  RgbdFrame small = f;
  small.depth.resize(10);
  EXPECT_EQ(
      depth_refused({f, small}),
      "camera 'cam' (frame 'cam_optical'): frame 1: depth has 10 values, width x height = 3072");
  RgbdFrame no_focal = f;
  no_focal.intrinsics.fx = 0.0;
  EXPECT_NE(depth_refused({no_focal}).find("intrinsics: fx, fy must be finite and > 0"),
            std::string::npos);
  RgbdFrame other = f;
  other.sensor = "cam2";
  EXPECT_NE(depth_refused({f, other}).find("frame 1: another camera or other intrinsics"),
            std::string::npos);
  EXPECT_EQ(depth_refused({}), "depth: no frames");
}

TEST(SensorMap, AveragedDepthFramesPutTheWallInOneVoxelLayerWhereSingleFramesScatter) {
  Params p;
  p.sensor_depth_stride = 2;
  const auto model = model_a(p);
  const SensorMapper mapper(model, p);
  // A camera 1.2 m before the wall looking at it (optical z along +x, x right = -y, y down = -z).
  Eigen::Isometry3d cam = Eigen::Isometry3d::Identity();
  cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  cam.translation() = Eigen::Vector3d(kWallX - 1.2, 0.0, 1.4);
  RgbdFrame f;
  f.sensor = "cam";
  f.frame = "cam_optical";
  f.intrinsics = {160, 120, 120.0, 120.0, 79.5, 59.5};
  std::mt19937 rng(9u);
  std::normal_distribution<double> noise(0.0, 0.03);  // [m] per frame
  std::vector<RgbdFrame> frames;
  for (int i = 0; i < 8; ++i) {
    f.depth.assign(160 * 120, 0);
    for (auto& d : f.depth)
      d = static_cast<std::uint16_t>(std::lround((1.2 + noise(rng)) * 1000.0));
    frames.push_back(f);
  }
  auto scattered = [&](const std::vector<RgbdFrame>& use) {
    Environment env(kRes);
    const SensorMapStats s =
        mapper.insert_depth(env, use, cam, Eigen::VectorXd::Zero(model->full_dof()));
    EXPECT_EQ(s.returns, 80u * 60u);
    std::size_t off = 0;
    const auto cells = occupied_centres(env);
    EXPECT_GT(cells.size(), 100u);
    for (const Eigen::Vector3d& c : cells) off += std::abs(c.x() - kWallX) > kRes ? 1 : 0;
    return off;
  };
  const std::size_t single = scattered({frames.front()});
  const std::size_t averaged = scattered(frames);
  EXPECT_GT(single, 50u);   // 3 cm noise: some returns land two voxels off the face
  EXPECT_EQ(averaged, 0u);  // 8 frames: 1 cm
}

TEST(SensorMap, TheWorldsMapAndTheSensorsTogetherHoldTheOccupiedCellsOfBoth) {
  Params p;
  const auto model = model_a(p);
  Environment world(kRes);
  World w;
  w.boxes.push_back(
      {"crate", Eigen::Vector3d(0.4, 0.4, 0.4), Eigen::Vector3d(1.0, -1.5, 0.2), 0.0});
  world.add_world(w);  // pruned into 0.1 m and 0.2 m leaves where it can
  Environment sensors(kRes);
  std::mt19937 rng(10u);
  const Eigen::Isometry3d sensor = at({-1.5, 0.0, 1.0});
  (void)SensorMapper(model, p).insert_lidar(sensors, wall_scan(sensor, 0.0, rng), sensor,
                                            Eigen::VectorXd::Zero(model->full_dof()));
  Environment both = world;
  both.add_occupied(sensors);
  for (const Environment* part : {&world, &sensors}) {
    for (const Eigen::Vector3d& c : occupied_centres(*part))
      EXPECT_TRUE(both.occupied(c)) << c.transpose();
  }
  // Every cell of the crate, not only the centres of pruned leaves.
  for (double x = 0.825; x < 1.2; x += kRes)
    EXPECT_TRUE(both.occupied(Eigen::Vector3d(x, -1.325, 0.025))) << x;
  EXPECT_FALSE(both.occupied(Eigen::Vector3d(0.5, 0.0, 1.0)));
  EXPECT_THROW(both.add_occupied(Environment(0.1)), PlannerError);
}

TEST(SensorMap, SeveralSensorsInOneInsertMapWhatEachSees) {
  Params p;
  p.sensor_max_range = 4.0;
  const auto model = model_a(p);
  const SensorMapper mapper(model, p);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model->full_dof());
  std::mt19937 rng(11u);
  // Two lidars on either side of the robot; within 4 m each reaches only its own end of the wall.
  const Eigen::Isometry3d left = at({-1.0, 2.0, 1.0}), right = at({-1.0, -2.0, 1.0});
  LidarScan a = wall_scan(left, 0.0, rng), b = wall_scan(right, 0.0, rng);
  const SensorRays ra = mapper.lidar_rays(a, left, q), rb = mapper.lidar_rays(b, right, q);
  Environment env(kRes);
  env.insert_rays({ra.rays, rb.rays});
  Environment one_by_one(kRes);
  (void)mapper.insert_lidar(one_by_one, a, left, q);
  (void)mapper.insert_lidar(one_by_one, b, right, q);
  // Each end of the wall is in the map (somewhere up its face).
  auto end_seen = [&](double y) {
    for (double z = 0.525; z < 2.0; z += kRes) {
      if (env.occupied({kWallX - 0.025, y, z}) || env.occupied({kWallX + 0.025, y, z})) return true;
    }
    return false;
  };
  EXPECT_TRUE(end_seen(2.825));
  EXPECT_TRUE(end_seen(-2.825));
  // Where only one sensor reaches, one insert and two give the same cells.
  for (const Eigen::Vector3d& c : occupied_centres(one_by_one)) {
    if (std::abs(c.y()) > 1.5) {
      EXPECT_TRUE(env.occupied(c)) << c.transpose();
    }
  }
  // A bad bundle is named and nothing is inserted.
  const auto before = env.octree();
  RayBundle bad = rb.rays;
  bad.hits[3].x() = std::numeric_limits<double>::quiet_NaN();
  try {
    env.insert_rays({ra.rays, bad});
    ADD_FAILURE() << "a non-finite hit was accepted";
  } catch (const PlannerError& e) {
    EXPECT_EQ(std::string(e.what()), "rays of bundle 1: hit 3 is not finite");
  }
  EXPECT_EQ(env.octree(), before);
}
