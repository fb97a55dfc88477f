#pragma once
// The predetermined areas of the wall in front of the robot (paper section 5.7, Fig. 15): the
// band of the wall the current morphology reaches with its tool without moving the base, split
// into a left, a centre and a right panel; each can be reshaped to a smaller rectangle inside
// it. No DDS.
//
// How: wall points on a grid (Params::grid, 5 cm) are solved by inverse kinematics with the
// TCP at the tool's standoff and its z into the wall, sweeping each column up and down from the
// middle height and the columns outwards from the centre, every solution seeding its
// neighbour's; a cell counts as reachable when the solution converges, keeps the joint limits,
// is free of self-collision, away from singularities and within ReachParams::max_joint_step of
// the neighbour that seeded it (no discontinuous stretch). The tool's roll about the normal is
// the one of four (0, 90, 180, 270 degrees) whose centre column reaches most cells. The
// largest all-reachable rectangle of the grid (maximal rectangle in a binary matrix) is the
// band; its thirds are the panels. Cells are grown breadth first from seeded start cells, so
// the band is one connected region of continuous solutions.

#include <string>
#include <vector>

#include "surface_finish/reach.hpp"
#include "surface_finish/types.hpp"

namespace concert::surface_finish {

struct AreaParams {
  double grid{0.05};       ///< spacing of the reach grid on the wall [m]
  double half_width{1.5};  ///< lateral extent searched each side of the base [m]
  double min_height{0.1};  ///< lowest / highest height searched [m]
  double max_height{3.2};
  int panels{3};           ///< panels the band is split into (left to right)
  /// Working distances (base origin to wall) tried by working_areas(), and the coarser grid it
  /// compares them on [m].
  std::vector<double> distances{1.0, 1.2, 1.4, 1.6, 1.8, 2.0, 2.2};
  double coarse_grid{0.1};
};

/// One predetermined area.
struct Area {
  std::string id;  ///< "left", "centre", "right" (or "panel_<i>" for other panel counts), "all" (the band)
  Rect rect;       ///< wall coordinates [m]
};

/// The reach grid and the areas of one morphology, tool and wall.
struct AreaMap {
  uint64_t model_version{0};
  Task task{Task::kSpray};
  double standoff{0.0};      ///< [m]
  double roll{0.0};          ///< tool roll about the normal used [rad]
  double wall_distance{0.0}; ///< base origin to wall [m]
  double grid{0.05};
  double x_min{0.0}, y_min{0.0};  ///< wall coordinates of cell (0, 0) [m]
  int nx{0}, ny{0};
  std::vector<char> reachable;       ///< nx * ny, index iy * nx + ix
  std::vector<std::string> reasons;  ///< why a cell is not reachable ("" when it is)
  std::vector<Eigen::VectorXd> postures;  ///< the solution of each reachable cell (empty otherwise)
  Rect band;                         ///< largest all-reachable rectangle
  std::vector<Area> areas;           ///< the panels left to right, then "all"
  [[nodiscard]] bool cell(int ix, int iy) const { return reachable[static_cast<std::size_t>(iy * nx + ix)] != 0; }
  /// Whether every grid point inside `r` is reachable; otherwise the first one that is not, as
  /// "(x, y) = (0.45, 2.10) m: IK 30 mm short".
  [[nodiscard]] bool covers(const Rect& r, std::string* why = nullptr) const;
  /// The posture of the reachable cell nearest to (x, y) (the seed of a path starting there).
  /// Throws FinishError when no cell is reachable.
  [[nodiscard]] const Eigen::VectorXd& posture_near(double x, double y) const;
  /// The area called `id`; throws FinishError listing the ids.
  [[nodiscard]] const Area& area(const std::string& id) const;
};

/// Computes the areas of `reach`'s tool at `standoff` [m] on `wall`. Throws FinishError when
/// no cell is reachable (naming the commonest reason).
AreaMap compute_areas(Reach& reach, const WallFrame& wall, Task task, double standoff, const AreaParams& params = {});

/// The areas at the working distance where the band is largest (each of params.distances
/// compared on the coarse grid, the winner computed on the fine one): the robot aligns with the
/// wall and stands there (AreaMap::wall_distance) before it covers an area, as in the paper.
AreaMap working_areas(Reach& reach, Task task, double standoff, const AreaParams& params = {});

/// A rectangle inside an area (e.g. around a window): checked to lie inside the area, with a
/// positive size; throws FinishError naming the area and both rectangles otherwise.
Rect reshape(const Area& area, const Rect& rect);

}  // namespace concert::surface_finish
