#include "world_mjcf.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "concert/sim/sim_hardware.hpp"
#include "concert/world/aruco.hpp"
#include "concert/world/geometry.hpp"

namespace concert::sim {
namespace {

using world::load_world_file;

World marks_world() { return load_world_file(std::string(WORLD_FIXTURES) + "/marks_world.yaml"); }

/// The world alone, compiled by MuJoCo, height fields filled.
struct Compiled {
  mjModel* m{nullptr};
  mjData* d{nullptr};
  explicit Compiled(const World& world) {
    const WorldMjcf w = world_mjcf(world);
    const std::string xml = "<mujoco>\n<asset>\n" + w.assets + "</asset>\n<worldbody>\n" +
                            w.worldbody + "</worldbody>\n</mujoco>\n";
    mjVFS vfs;
    mj_defaultVFS(&vfs);
    EXPECT_EQ(mj_makeEmptyFileVFS(&vfs, "world.xml", static_cast<int>(xml.size())), 0);
    std::memcpy(vfs.filedata[0], xml.data(), xml.size());
    char error[1000] = "";
    m = mj_loadXML("world.xml", &vfs, error, sizeof(error));
    mj_deleteVFS(&vfs);
    if (m == nullptr) {
      ADD_FAILURE() << "MuJoCo rejected the world: " << error << "\n" << xml;
      return;
    }
    fill_world_hfields(world, m);
    d = mj_makeData(m);
    mj_forward(m, d);
  }
  ~Compiled() {
    if (d != nullptr) {
      mj_deleteData(d);
    }
    if (m != nullptr) {
      mj_deleteModel(m);
    }
  }
  Compiled(const Compiled&) = delete;
  Compiled& operator=(const Compiled&) = delete;

  /// Distance to the first geom hit from `from` along unit `dir`, and that geom's name.
  std::pair<double, std::string> ray(const Eigen::Vector3d& from,
                                     const Eigen::Vector3d& dir) const {
    int geom = -1;
    const double dist = mj_ray(m, d, from.data(), dir.data(), nullptr, 1, -1, &geom);
    return {dist, geom >= 0 ? mj_id2name(m, mjOBJ_GEOM, geom) : ""};
  }
};

TEST(WorldMjcf, EveryFeatureCompilesInGroupZeroNamedAfterItsElement) {
  const World world = marks_world();
  Compiled c(world);
  ASSERT_NE(c.m, nullptr);
  const std::vector<std::string> elements{"floor",  "wall_front", "pillar",   "cart",
                                          "blob_a", "blob_b",     "marker_7", "plaster"};
  int aruco_white = 0;
  for (int g = 0; g < c.m->ngeom; ++g) {
    const std::string name = mj_id2name(c.m, mjOBJ_GEOM, g);
    EXPECT_EQ(c.m->geom_group[g], 0) << name;
    const bool named = std::any_of(elements.begin(), elements.end(),
                                   [&](const std::string& e) { return name.rfind(e, 0) == 0; });
    EXPECT_TRUE(named) << name;
    const bool mark = name.rfind("blob_", 0) == 0 || name.rfind("marker_7", 0) == 0;
    EXPECT_EQ(c.m->geom_contype[g], 0) << name;
    EXPECT_EQ(c.m->geom_conaffinity[g], mark ? 0 : 1) << name;
    aruco_white += name.rfind("marker_7_white_", 0) == 0 ? 1 : 0;
  }
  EXPECT_GT(aruco_white, 0);
  EXPECT_EQ(c.m->nhfield, 1);
  EXPECT_EQ(c.m->nmocap, 1);
  // Blobs are blue, the wall mid grey.
  const int blob = mj_name2id(c.m, mjOBJ_GEOM, "blob_a");
  EXPECT_NEAR(c.m->geom_rgba[4 * blob + 2], 0.9f, 1e-6);
  EXPECT_NEAR(c.m->geom_rgba[4 * mj_name2id(c.m, mjOBJ_GEOM, "wall_front")], 0.5f, 1e-6);
}

TEST(WorldMjcf, RaysSeeBlobsAtTheirTrueCentres) {
  const World world = marks_world();
  Compiled c(world);
  ASSERT_NE(c.m, nullptr);
  for (const auto& t : world::mark_truth(world)) {
    if (t.type != world::Mark::Type::kBlob) {
      continue;
    }
    // Just inside the rim hits the blob's front surface; just outside hits the wall.
    const Eigen::Vector3d from = t.centre + 0.2 * t.normal;
    const auto inside = c.ray(from + 0.49 * t.diameter * t.right, -t.normal);
    EXPECT_EQ(inside.second, t.name);
    EXPECT_NEAR(inside.first, 0.2, 1e-9);
    EXPECT_EQ(c.ray(from + 0.51 * t.diameter * t.right, -t.normal).second, "wall_front");
  }
}

TEST(WorldMjcf, ArucoCellsSitWhereTheTruthCornersSayInEveryRotation) {
  for (const double angle : {0.0, 0.6, M_PI}) {
    World world = marks_world();
    world.marks[2].angle = angle;
    Compiled c(world);
    ASSERT_NE(c.m, nullptr);
    const world::MarkTruth t = world::mark_truth(world)[2];
    const world::ArucoCells cells = world::aruco_cells(t.dictionary, t.id);
    const Eigen::Vector3d right = (t.corners[1] - t.corners[0]) / cells.side;
    const Eigen::Vector3d down = (t.corners[3] - t.corners[0]) / cells.side;
    for (int r = 0; r < cells.side; ++r) {
      for (int col = 0; col < cells.side; ++col) {
        const Eigen::Vector3d p = t.corners[0] + (col + 0.5) * right + (r + 0.5) * down;
        const auto hit = c.ray(p + 0.1 * t.normal, -t.normal);
        const bool white = hit.second.rfind("marker_7_white_", 0) == 0;
        EXPECT_EQ(white, cells.at(r, col)) << "cell " << r << "," << col << " angle " << angle;
        EXPECT_EQ(hit.second.rfind("marker_7", 0), 0u) << hit.second;
        // Black at the front surface, white 0.1 mm proud of it.
        EXPECT_NEAR(hit.first, white ? 0.0999 : 0.1, 1e-9);
      }
    }
  }
}

TEST(WorldMjcf, HeightFieldIsTheTrueSurfaceAtTheGridPoints) {
  const World world = marks_world();
  Compiled c(world);
  ASSERT_NE(c.m, nullptr);
  const world::Surface& s = world.surfaces[0];
  const world::WorldShape& wall = world::find_wall(world, s.wall);
  const Eigen::Vector3d n = world::face_frame(wall, s.face).linear().col(2);
  // Bump top, hole bottom, flat plaster, and the places the bump would be if the grid were
  // mirrored along u or z.
  for (const Eigen::Vector2d& at :
       {Eigen::Vector2d(-0.8, 1.1), Eigen::Vector2d(-0.55, 0.9), Eigen::Vector2d(-0.6, 1.1),
        Eigen::Vector2d(-0.8, 0.9), Eigen::Vector2d(-0.85, 1.1), Eigen::Vector2d(-0.4, 1.2)}) {
    const Eigen::Vector3d truth = world::surface_point(world, s, at.x(), at.y());
    const auto hit = c.ray(truth + 0.3 * n, -n);
    EXPECT_EQ(hit.second, "plaster");
    // At a grid point the piecewise linear height field is exact (float data).
    EXPECT_NEAR(hit.first, 0.3, 1e-6) << "at " << at.transpose();
  }
  // Between grid points: within what a grid cell can change the profile.
  const Eigen::Vector3d between = world::surface_point(world, s, -0.8 + 0.0127, 1.1 + 0.0031);
  EXPECT_NEAR(c.ray(between + 0.3 * n, -n).first, 0.3, 0.003 * M_PI * s.resolution / 0.05);
}

TEST(WorldMjcf, MovingObstacleFollowsItsPathInTheSimulator) {
  const World world = marks_world();
  std::ifstream in(std::string(ROBOT_FIXTURES) + "/arm_drill.urdf");
  std::stringstream urdf;
  urdf << in.rdbuf();
  SimHardware sim(urdf.str(), world, {});
  const world::WorldShape& cart = world.obstacles[1];
  EXPECT_TRUE(sim.link_pose("cart").translation().isApprox(cart.position));
  // 9 s at 0.5 m/s: 4 m out to the waypoint and 0.5 m back (pingpong).
  for (int i = 0; i < 9000; ++i) {
    sim.step(0.001);
  }
  // Each physics step moves the mocap body to where the path is at the step's start.
  const Eigen::Vector3d expected = world::obstacle_position(cart, sim.time() - 0.001);
  EXPECT_TRUE(sim.link_pose("cart").translation().isApprox(expected, 1e-9))
      << sim.link_pose("cart").translation();
  EXPECT_NEAR(sim.link_pose("cart").translation().y(), 1.5, 0.5 * 0.001 + 1e-9);
  // A new world keeps the time: the cart continues where it is.
  sim.set_world(world);
  EXPECT_TRUE(sim.switch_prepared());
  EXPECT_TRUE(sim.link_pose("cart").translation().isApprox(
      world::obstacle_position(cart, sim.time()), 1e-9));
}

TEST(WorldMjcf, AnInvalidWorldIsRefusedAndTheOldOneKept) {
  std::ifstream in(std::string(ROBOT_FIXTURES) + "/arm_drill.urdf");
  std::stringstream urdf;
  urdf << in.rdbuf();
  const World world = marks_world();
  SimHardware sim(urdf.str(), world, {});
  World bad = world;
  bad.marks[2].id = 50;
  try {
    sim.set_world(bad);
    FAIL() << "accepted id 50 in DICT_4X4_50";
  } catch (const world::WorldError& e) {
    EXPECT_NE(std::string(e.what()).find("marks[2].id"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(sim.switch_prepared());
  EXPECT_EQ(sim.world().marks[2].id, 7);
  EXPECT_NE(sim.mjcf().find("name=\"marker_7\""), std::string::npos);
}

}  // namespace
}  // namespace concert::sim
