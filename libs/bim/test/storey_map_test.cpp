#include "concert/bim/storey_map.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <deque>

#include "bim_test_models.hpp"
#include "concert/bim/geometry.hpp"

namespace concert::bim {
namespace {

using namespace concert::bim::test_models;

struct Case {
  std::string file;
  std::string storey;
};

const OccupancyGrid& shared_map(const Case& c) {
  static std::map<std::string, OccupancyGrid> maps;
  const std::string key = c.file + "#" + c.storey;
  auto it = maps.find(key);
  if (it == maps.end()) {
    const BimModel& m = shared_model(c.file);
    it = maps.emplace(key, storey_map(m, m.storey(c.storey))).first;
  }
  return it->second;
}

/// True when `p` (at band height) lies inside no obstacle element's box grown by one cell: such a
/// point must be free, whatever the rasterisation's conservatism.
bool clear_of_obstacles(const BimModel& m, const Storey& s, const Eigen::Vector2d& p, double grow) {
  const SliceParams band;
  for (const auto& e : m.elements) {
    if (!is_obstacle(e.category) || e.bounds.isEmpty()) continue;
    if (e.bounds.max().z() < s.elevation + band.band_min ||
        e.bounds.min().z() > s.elevation + band.band_max)
      continue;
    const Eigen::Vector2d lo = e.bounds.min().head<2>().array() - grow;
    const Eigen::Vector2d hi = e.bounds.max().head<2>().array() + grow;
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) return false;
  }
  return true;
}

/// Is `p` on a door of this wall (within its box, grown by `grow`)?
bool on_door(const BimModel& m, const Element& wall, const Eigen::Vector2d& p, double grow) {
  for (const auto& d : m.elements) {
    if (d.category != Category::kDoor || d.host != wall.global_id) continue;
    const Eigen::Vector2d lo = d.bounds.min().head<2>().array() - grow;
    const Eigen::Vector2d hi = d.bounds.max().head<2>().array() + grow;
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) return true;
  }
  return false;
}

class StoreyMaps : public ::testing::TestWithParam<Case> {};

TEST_P(StoreyMaps, WallAxesAreOccupiedAndRoomsBesideThemFree) {
  const BimModel& m = shared_model(GetParam().file);
  const Storey& s = m.storey(GetParam().storey);
  const OccupancyGrid& grid = shared_map(GetParam());
  int occupied_samples = 0;
  int free_samples = 0;
  for (const Element* e : m.elements_of(s)) {
    if (e->category != Category::kWall || e->mesh.triangles.empty()) continue;
    // Walls through the middle of the band (not parapets, knee walls or foundations).
    if (e->bounds.min().z() > s.elevation + 0.5 || e->bounds.max().z() < s.elevation + 1.5)
      continue;
    const WallGeometry g = wall_geometry(*e);
    for (double f = 0.1; f <= 0.9 + 1e-9; f += 0.1) {
      const Eigen::Vector2d p = g.start + f * (g.end - g.start);
      if (on_door(m, *e, p, 0.1)) continue;
      EXPECT_TRUE(grid.occupied(p)) << e->global_id << " \"" << e->name << "\" at " << f
                                    << " of its axis (" << p.transpose() << ")";
      ++occupied_samples;
      for (const auto& face : g.faces) {
        const Eigen::Vector2d q = p + face.normal * (g.thickness / 2 + 0.5);
        if (!clear_of_obstacles(m, s, q, grid.resolution)) continue;
        EXPECT_FALSE(grid.occupied(q)) << "0.5 m off " << e->global_id << " at " << q.transpose();
        ++free_samples;
      }
    }
  }
  EXPECT_GT(occupied_samples, 30);
  EXPECT_GT(free_samples, 10);
}

TEST_P(StoreyMaps, GridCoversTheStoreyWithAMargin) {
  const BimModel& m = shared_model(GetParam().file);
  const Storey& s = m.storey(GetParam().storey);
  const OccupancyGrid& grid = shared_map(GetParam());
  EXPECT_DOUBLE_EQ(grid.resolution, 0.05);
  for (const Element* e : m.elements_of(s)) {
    if (e->bounds.isEmpty()) continue;
    EXPECT_TRUE(grid.inside(grid.cell_of(e->bounds.min().head<2>()).x(),
                            grid.cell_of(e->bounds.min().head<2>()).y()));
    EXPECT_TRUE(grid.inside(grid.cell_of(e->bounds.max().head<2>()).x(),
                            grid.cell_of(e->bounds.max().head<2>()).y()));
  }
  // The margin is free: the border row and column.
  for (int c = 0; c < grid.width; ++c) EXPECT_EQ(grid.at(c, 0), OccupancyGrid::kFree);
  for (int r = 0; r < grid.height; ++r) EXPECT_EQ(grid.at(0, r), OccupancyGrid::kFree);
}

INSTANTIATE_TEST_SUITE_P(Bim, StoreyMaps,
                         ::testing::Values(Case{"AC20-FZK-Haus.ifc", "Erdgeschoss"},
                                           Case{"duplex.ifc", "Level 1"},
                                           Case{"duplex.ifc", "Level 2"},
                                           Case{"IfcOpenHouse_IFC4.ifc", "38aOKO8_DDkBd1FHm_lVXz"}),
                         [](const auto& p) {
                           std::string n = p.param.file.substr(0, 5) + "_" + slug(p.param.storey);
                           for (char& ch : n) {
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return n;
                         });

/// Cells of the straight line through the door across its wall, and a 4-connected search from
/// one side to the other that may not leave a window of 1.5 m around the door (so it goes
/// through the doorway, not around the building).
TEST(DoorPassable, EveryDoorOfTheFzkGroundFloor) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  const OccupancyGrid& grid = shared_map({"AC20-FZK-Haus.ifc", "Erdgeschoss"});
  int doors = 0;
  for (const auto& d : m.elements) {
    if (d.category != Category::kDoor) continue;
    ++doors;
    const WallGeometry g = wall_geometry(m.element(d.host));
    const Eigen::Vector2d c = d.bounds.center().head<2>();
    const Eigen::Vector2d n = g.faces[0].normal;
    const Eigen::Vector2d centre = c - n * n.dot(c - g.start);  // on the wall's axis
    const double reach = g.thickness / 2 + 0.4;
    for (double t = -reach; t <= reach; t += grid.resolution / 2) {
      EXPECT_FALSE(grid.occupied(centre + t * n)) << d.name << " at " << t << " m across its wall";
    }
    const Eigen::Vector2i from = grid.cell_of(centre + reach * n);
    const Eigen::Vector2i to = grid.cell_of(centre - reach * n);
    const Eigen::Vector2i lo = grid.cell_of(centre.array() - 1.5);
    const Eigen::Vector2i hi = grid.cell_of(centre.array() + 1.5);
    std::vector<bool> seen(grid.cells.size(), false);
    std::deque<Eigen::Vector2i> queue{from};
    seen[grid.index(from.x(), from.y())] = true;
    bool reached = false;
    while (!queue.empty() && !reached) {
      const Eigen::Vector2i cell = queue.front();
      queue.pop_front();
      reached = cell == to;
      for (const Eigen::Vector2i& step : {Eigen::Vector2i(1, 0), Eigen::Vector2i(-1, 0),
                                          Eigen::Vector2i(0, 1), Eigen::Vector2i(0, -1)}) {
        const Eigen::Vector2i nb = cell + step;
        if ((nb.array() < lo.array()).any() || (nb.array() > hi.array()).any() ||
            !grid.inside(nb.x(), nb.y()))
          continue;
        if (grid.at(nb.x(), nb.y()) != OccupancyGrid::kFree || seen[grid.index(nb.x(), nb.y())])
          continue;
        seen[grid.index(nb.x(), nb.y())] = true;
        queue.push_back(nb);
      }
    }
    EXPECT_TRUE(reached) << d.name << ": no free path through the doorway";
  }
  EXPECT_EQ(doors, 5);
}

TEST(StoreyMap, UpperStoreyMapsItsOwnWalls) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  const Storey& s = m.storey("Dachgeschoss");
  const OccupancyGrid grid = storey_map(m, s, {.resolution = 0.1});
  EXPECT_DOUBLE_EQ(grid.resolution, 0.1);
  int samples = 0;
  for (const Element* e : m.elements_of(s)) {
    if (e->category != Category::kWall) continue;
    const WallGeometry g = wall_geometry(*e);
    if (g.z_max < s.elevation + 1.0) continue;
    EXPECT_TRUE(grid.occupied((g.start + g.end) / 2)) << e->name;
    ++samples;
  }
  EXPECT_GT(samples, 0);
}

TEST(StoreyMap, BadBandAndResolutionAreNamed) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  const Storey& s = m.storey("Erdgeschoss");
  EXPECT_THAT([&] { (void)storey_map(m, s, {.band_min = 1.0, .band_max = 0.5}); },
              ::testing::ThrowsMessage<BimError>(::testing::HasSubstr("slice band")));
  EXPECT_THAT([&] { (void)storey_map(m, s, {.resolution = 0.0}); },
              ::testing::ThrowsMessage<BimError>(::testing::HasSubstr("resolution")));
}

}  // namespace
}  // namespace concert::bim
