// The map from the sensors against scans the simulator renders: the demo's drilling site
// (deploy/demo/drill_site.yaml) in MuJoCo, the robot's two VLP-16 lidars (libs/sim's
// LidarSimulator: MuJoCo ray casting, 1.5 cm range noise, seeded) at their mounts on morphology
// A's base, the scans ray-cast by SensorMapper. The result is compared with the map the planner
// builds from the world description, and the planner's state check must refuse a posture
// through the wall with either map.

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <octomap/OcTree.h>

#include <iostream>
#include <random>
#include <sstream>

#include "concert/sim/ray_sensors.hpp"
#include "concert/world/world.hpp"
#include "mujoco_scene.hpp"  // libs/sim's test helper: a MuJoCo model + data from MJCF text
#include "planner/fixtures.hpp"
#include "planner/planner.hpp"
#include "planner/sensor_map.hpp"
#include "planner/state_checker.hpp"

using namespace concert;
using namespace concert::planner;

namespace {

// The world's boxes and cylinders as the planner reads them.
World planner_world(const world::World& w) {
  World out;
  for (const auto* list : {&w.walls, &w.obstacles}) {
    for (const world::WorldShape& s : *list) {
      if (s.type == world::WorldShape::Type::kCylinder) {
        out.cylinders.push_back({s.name, s.size.x(), s.size.z(), s.position});
      } else {
        out.boxes.push_back({s.name, s.size, s.position, s.yaw});
      }
    }
  }
  return out;
}

// The floor and the world's boxes and cylinders as MuJoCo geoms (group 0, what the lidars see).
std::string mjcf_of(const world::World& w) {
  std::ostringstream x;
  x.precision(17);
  x << "<geom type=\"plane\" size=\"50 50 0.1\" pos=\"0 0 " << w.floor_height << "\"/>\n";
  for (const auto* list : {&w.walls, &w.obstacles}) {
    for (const world::WorldShape& s : *list) {
      const Eigen::Vector3d& p = s.position;
      if (s.type == world::WorldShape::Type::kCylinder) {
        x << "<geom type=\"cylinder\" size=\"" << s.size.x() << " " << 0.5 * s.size.z()
          << "\" pos=\"" << p.x() << " " << p.y() << " " << p.z() << "\"/>\n";
      } else {
        x << "<geom type=\"box\" size=\"" << 0.5 * s.size.x() << " " << 0.5 * s.size.y() << " "
          << 0.5 * s.size.z() << "\" pos=\"" << p.x() << " " << p.y() << " " << p.z()
          << "\" euler=\"0 0 " << s.yaw << "\"/>\n";
      }
    }
  }
  return sim::test::mjcf_document(x.str());
}

Eigen::VectorXd at_base(const PlanningModel& m, double x, double y, double yaw) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m.full_dof());
  q[0] = x;
  q[1] = y;
  q[2] = yaw;
  return q;
}

}  // namespace

TEST(SensorMapSim, SimulatedLidarScansOfTheDemoSiteMapItsWallLikeTheWorldDescription) {
  const world::World site =
      world::load_world_file(std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_site.yaml");
  ASSERT_FALSE(site.walls.empty());
  Params params;
  const auto model = PlanningModel::build(
      fixtures::model_from_assembly(fixtures::data_dir() / "morphology_a.yaml", 1), params);
  const auto lidars = model->robot().sensor_frames(model::SensorKind::kLidar);
  ASSERT_EQ(lidars.size(), 2u) << "morphology A's base carries two lidars";

  Environment from_world(params.octomap_resolution);
  from_world.add_world(planner_world(site));

  // The robot drives along the wall and stops at five places; both lidars scan at each.
  const sim::test::MujocoScene scene(mjcf_of(site));
  const sim::LidarSimulator lidar{sim::LidarParams{}};
  std::mt19937_64 rng(42);
  const SensorMapper mapper(model, params);
  Environment from_sensors(params.octomap_resolution);
  hardware::LidarScan scan;
  std::size_t scans = 0;
  for (const Eigen::Vector3d& base :
       {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.2, -1.2, 0.3),
        Eigen::Vector3d(0.2, 1.2, -0.3), Eigen::Vector3d(0.8, 0.0, 0.0),
        Eigen::Vector3d(-0.5, 0.5, 0.8)}) {
    const Eigen::VectorXd q = at_base(*model, base.x(), base.y(), base.z());
    for (const model::SensorFrame* s : lidars) {
      const Eigen::Isometry3d pose = mapper.sensor_pose(q, s->frame);
      lidar.scan(scene.m(), scene.d(), pose, rng, scan);
      scan.sensor = s->name;
      scan.frame = s->frame;
      const SensorMapStats stats = mapper.insert_lidar(from_sensors, scan, pose, q);
      EXPECT_EQ(stats.self, 0u) << "the simulator's lidars do not see the robot";
      scans += 1;
    }
  }
  ASSERT_EQ(scans, 10u);

  // Every occupied voxel of the sensor map, against the world map.
  const double r = params.octomap_resolution;
  std::size_t cells = 0, same = 0, within_one = 0;
  const octomap::OcTree& t = *from_sensors.octree();
  for (auto it = t.begin_leafs(); it != t.end_leafs(); ++it) {
    if (!t.isNodeOccupied(*it)) continue;
    const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
    cells += 1;
    same += from_world.occupied(c) ? 1 : 0;
    bool near = false;
    for (int dx = -1; dx <= 1 && !near; ++dx) {
      for (int dy = -1; dy <= 1 && !near; ++dy) {
        for (int dz = -1; dz <= 1 && !near; ++dz)
          near = from_world.occupied(c + r * Eigen::Vector3d(dx, dy, dz));
      }
    }
    within_one += near ? 1 : 0;
  }
  // The world map's voxels in the wall's first layer behind its face that the lidars could
  // see (below the height their upper beams reach); the sensor map has them there or one
  // voxel before (noise).
  const world::WorldShape& wall = site.walls.front();
  const double face = wall.position.x() - 0.5 * wall.size.x();
  std::size_t face_cells = 0, face_seen = 0;
  for (double y = -2.5 + 0.5 * r; y < 2.5; y += r) {
    for (double z = params.sensor_floor_band + 0.5 * r; z < 0.9; z += r) {
      const Eigen::Vector3d p((std::floor((face + 0.25 * r) / r) + 0.5) * r, y, z);
      if (!from_world.occupied(p)) continue;
      face_cells += 1;
      face_seen +=
          from_sensors.occupied(p) || from_sensors.occupied(p - Eigen::Vector3d(r, 0, 0)) ? 1 : 0;
    }
  }
  std::cout << "sensor map: " << cells << " occupied voxels from " << scans
            << " simulated revolutions; " << same << " occupied in the world map ("
            << 100.0 * static_cast<double>(same) / static_cast<double>(cells) << " %), "
            << within_one << " within one voxel ("
            << 100.0 * static_cast<double>(within_one) / static_cast<double>(cells)
            << " %); wall face 0.05-0.9 m, |y| < 2.5 m: " << face_seen << " of " << face_cells
            << " voxels seen" << std::endl;
  ASSERT_GT(cells, 500u);
  EXPECT_GE(static_cast<double>(same) / static_cast<double>(cells), 0.9);
  EXPECT_GE(static_cast<double>(within_one) / static_cast<double>(cells), 0.99);
  EXPECT_GE(static_cast<double>(face_seen) / static_cast<double>(face_cells), 0.8);

  // The planner's check: the robot standing at the origin is clear of both maps; with the base
  // driven into the wall, or the arm stretched through it, both maps refuse it.
  for (const Environment* env : {&from_world, &from_sensors}) {
    const char* which = env == &from_world ? "world map" : "sensor map";
    StateChecker checker(model, *env, params, params.environment_padding);
    const Validity free = checker.check(at_base(*model, 0.0, 0.0, 0.0));
    EXPECT_NE(free.constraint, Constraint::kEnvironmentCollision) << which << ": " << free.detail;
    const Validity in_wall = checker.check(at_base(*model, face - 0.1, 0.0, 0.0));
    EXPECT_EQ(in_wall.constraint, Constraint::kEnvironmentCollision)
        << which << ": " << to_string(in_wall.constraint);
  }

  // The planner itself on the sensor map: a drilling area on the wall's face at 0.8 m (where the
  // lidars saw it) is planned, and every state of its trajectory is clear of the true wall (the
  // world map, no padding).
  const Params plan_params = fixtures::generous(3);
  Planner planner(plan_params);
  planner.set_model(fixtures::model_from_assembly(fixtures::data_dir() / "morphology_a.yaml", 1));
  planner.set_environment(from_sensors);
  const Eigen::VectorXd start = at_base(*planner.model(), 0.0, 0.0, 0.0);
  StateChecker truth(planner.model(), from_world, plan_params, 0.0);
  {
    const Eigen::Isometry3d area = fixtures::drilling_area(face, 0.0, 0.8);
    const PlanResult plan = planner.plan(PlanRequest{1, 1, "", {{area}}}, start);
    ASSERT_EQ(plan.status, Status::kSucceeded) << plan.reason;
    const GoalResult& goal = plan.goals.front();
    std::size_t states = 0;
    for (const TrajectoryPoint& pt : goal.trajectory.points) {
      const Validity v = truth.check(planner.model()->to_full(pt.q, start));
      EXPECT_NE(v.constraint, Constraint::kEnvironmentCollision)
          << "at t = " << pt.time << " s: " << v.detail;
      states += 1;
    }
    EXPECT_GT(states, 10u);
    std::cout << "area at x = " << area.translation().x() << " m planned on the sensor map ("
              << goal.path_method << ", " << goal.trajectory.points.back().time
              << " s of motion, base ends at " << goal.goal_q.head<3>().transpose()
              << "): " << states << " states clear of the true wall" << std::endl;
  }
}
