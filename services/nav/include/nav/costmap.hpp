#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "concert/bim/occupancy_grid.hpp"

namespace concert::nav {

/// The robot's outline in the base frame: a convex polygon, vertices in order [m].
using FootprintPolygon = std::vector<Eigen::Vector2d>;

/// The robot's outline and the two radii the costmap inflates with (nav2's meaning).
struct RobotShape {
  FootprintPolygon footprint;               ///< convex polygon around the base origin [m]
  double inscribed_radius{0.0};      ///< largest circle around the origin inside the polygon [m]
  double circumscribed_radius{0.0};  ///< smallest circle around the origin holding the polygon [m]

  /// The shape of `footprint` with both radii computed from it. Throws std::invalid_argument
  /// unless it is a convex polygon of >= 3 vertices with the origin strictly inside.
  static RobotShape from_footprint(FootprintPolygon footprint);
  /// An axis-aligned rectangle `length` (x) by `width` (y) centred on the origin [m].
  static RobotShape rectangle(double length, double width);
};

/// Costmap parameters (nav2's static, obstacle and inflation layers).
struct CostmapParams {
  /// Unknown map cells are lethal (true), or kept as kNoInformation (false), which the planner
  /// may cross when allowed to (nav2's track_unknown_space off / on).
  bool unknown_is_lethal{true};
  /// Cost drops to 0 beyond this distance from a lethal cell [m]; >= the circumscribed radius
  /// for the footprint check's fast path.
  double inflation_radius{0.8};
  /// Exponential decay rate of the cost beyond the inscribed radius [1/m] (nav2's
  /// cost_scaling_factor).
  double cost_scaling_factor{4.0};
  /// Scan hits farther than this from the sensor mark nothing [m].
  double obstacle_max_range{6.0};
  /// Beams clear free space up to this distance from the sensor [m].
  double raytrace_max_range{8.0};
};

/// One lidar beam in the map frame for the obstacle layer.
struct Beam {
  Eigen::Vector2d end;  ///< where the beam ended [m, map frame]
  bool hit{true};       ///< true: `end` is a return (marks); false: no return up to `end`
};

/// Cells the last obstacle-layer update changed and the window it re-inflated.
struct CostmapUpdate {
  int marked{0};   ///< cells newly marked lethal
  int cleared{0};  ///< cells cleared
  /// Re-inflated window [col_min, row_min, col_max, row_max] (inclusive); empty when
  /// col_min > col_max (nothing changed).
  Eigen::Vector4i window{0, 0, -1, -1};
};

/// A layered 2D cost grid in nav2's cost scale, on the cells of a bim::OccupancyGrid:
/// static layer (the map), obstacle layer (live scan points, marked and cleared by ray tracing)
/// and inflation (lethal in the cell, kInscribed within the inscribed radius, exponential decay
/// beyond, 0 past the inflation radius). The obstacle layer updates incrementally: only the
/// window around changed cells is re-inflated.
class Costmap {
 public:
  static constexpr std::uint8_t kFree = 0;
  static constexpr std::uint8_t kInscribed = 253;      ///< centre within the inscribed radius
  static constexpr std::uint8_t kLethal = 254;         ///< an obstacle in the cell
  static constexpr std::uint8_t kNoInformation = 255;  ///< unknown (when not lethal)

  /// Throws std::invalid_argument naming the bad parameter (empty map, radii, ranges).
  Costmap(const bim::OccupancyGrid& map, const RobotShape& shape, const CostmapParams& params = {});

  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  [[nodiscard]] double resolution() const { return resolution_; }
  [[nodiscard]] const Eigen::Vector2d& origin() const { return origin_; }
  [[nodiscard]] const RobotShape& shape() const { return shape_; }
  [[nodiscard]] const CostmapParams& params() const { return params_; }

  [[nodiscard]] bool inside(int col, int row) const {
    return col >= 0 && row >= 0 && col < width_ && row < height_;
  }
  [[nodiscard]] std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) +
           static_cast<std::size_t>(col);
  }
  /// Cell containing a map-frame point [m] (may be outside: check inside()).
  [[nodiscard]] Eigen::Vector2i cell_of(const Eigen::Vector2d& p) const;
  /// Map-frame centre of a cell [m].
  [[nodiscard]] Eigen::Vector2d center_of(int col, int row) const;

  /// Combined cost of a cell (static + obstacle + inflation).
  [[nodiscard]] std::uint8_t cost(int col, int row) const { return master_[index(col, row)]; }
  /// Combined cost at a map-frame point; kLethal outside the map.
  [[nodiscard]] std::uint8_t cost_at(const Eigen::Vector2d& p) const;
  /// Every cell's combined cost, row-major, row 0 at the bottom (as bim::OccupancyGrid).
  [[nodiscard]] const std::vector<std::uint8_t>& costs() const { return master_; }
  /// True when the static map marks the cell unknown.
  [[nodiscard]] bool unknown(int col, int row) const { return unknown_[index(col, row)] != 0; }
  /// True when the obstacle layer marks the cell.
  [[nodiscard]] bool obstacle(int col, int row) const { return obstacle_[index(col, row)] != 0; }

  /// The inflation cost of a cell whose centre is `distance` from the nearest lethal cell's
  /// centre [m] (nav2's InflationLayer::computeCost).
  [[nodiscard]] std::uint8_t inflation_cost(double distance) const;
  /// The distance from a lethal cell that `cost` stands for [m] (inverse of inflation_cost for
  /// 1..252; 0 for lethal/inscribed costs, inflation_radius for kFree).
  [[nodiscard]] double distance_from_cost(std::uint8_t cost) const;
  /// Lowest centre cost at which the footprint may touch a lethal cell (the cost just inside
  /// the circumscribed radius): below it the footprint is certainly free.
  [[nodiscard]] std::uint8_t possibly_colliding_cost() const { return possibly_colliding_; }

  /// Highest combined cost of the cells the footprint covers at `pose` (x [m], y [m],
  /// theta [rad], map frame): its edges rasterised plus every cell whose centre it holds.
  /// kLethal when any covered cell is outside the map.
  [[nodiscard]] std::uint8_t footprint_cost(const Eigen::Vector3d& pose) const;
  /// True when the footprint at `pose` covers a lethal (or, when unknown is lethal, unknown)
  /// cell, or leaves the map.
  [[nodiscard]] bool in_collision(const Eigen::Vector3d& pose) const;
  /// How deep the lethal (or, when unknown is lethal, unknown) cells the footprint at `pose`
  /// covers lie inside it: the largest distance from such a cell's centre to the footprint's
  /// boundary [m]; 0 when it covers none (or only cells whose centres lie outside it); infinity
  /// when the footprint leaves the map. A base whose footprint the check refuses where it stands
  /// (the footprint is the hull of the steering sweep and the transport posture, larger than the
  /// robot at work) may leave as long as this does not grow: it goes no deeper into anything,
  /// whichever cells the lidars mark along the same wall.
  [[nodiscard]] double lethal_depth(const Eigen::Vector3d& pose) const;
  /// How deep a base leaving `start` may go (lethal_depth() there and a cell of slack: the pose
  /// estimate and the lidars' marks along a wall jitter by that much) [m].
  [[nodiscard]] double leaving_depth(const Eigen::Vector3d& start) const { return lethal_depth(start) + resolution_; }
  /// Whether the footprint centred at `p` is free at any heading: no heading makes
  /// in_collision() true there, so a path may turn there and an escape from a wall ends. Every
  /// lethal cell's centre lies farther from `p` than the circumscribed radius plus half a cell's
  /// diagonal (in_collision counts a cell the polygon touches), and the disc lies in the map.
  /// Exact, not the inflation cost: that is measured between cell centres and ends at
  /// inflation_radius, which may be hardly larger than the circumscribed radius.
  [[nodiscard]] bool free_at_any_heading(const Eigen::Vector2d& p) const;

  /// Marks the obstacle layer from beams cast from `sensor_origin` (map frame [m]): every beam
  /// clears the cells it crosses up to its end (or raytrace_max_range), and a hit within
  /// obstacle_max_range marks its end cell. Re-inflates only around changed cells.
  CostmapUpdate update_obstacles(const Eigen::Vector2d& sensor_origin, std::span<const Beam> beams);
  /// Same, every point a hit.
  CostmapUpdate update_obstacles(const Eigen::Vector2d& sensor_origin,
                                 std::span<const Eigen::Vector2d> hits);
  /// Empties the obstacle layer (re-inflating where it had marks).
  CostmapUpdate clear_obstacles();

 private:
  struct KernelCell {
    int dx;
    int dy;
    std::uint8_t cost;
  };
  void reinflate(int c0, int r0, int c1, int r1);
  [[nodiscard]] bool lethal_base(int col, int row) const;
  [[nodiscard]] std::uint8_t base_cost(std::size_t i) const;
  void touch(CostmapUpdate& up, int col, int row) const;
  void reinflate_changed(CostmapUpdate& up);

  int width_;
  int height_;
  double resolution_;
  Eigen::Vector2d origin_;
  RobotShape shape_;
  CostmapParams params_;
  int inflation_cells_;
  std::uint8_t possibly_colliding_;
  std::uint8_t fast_free_cost_;  // centre cost below which no footprint cell can be lethal
  std::vector<KernelCell> kernel_;
  std::vector<std::uint8_t> static_;    // kFree, kLethal or kNoInformation
  std::vector<std::uint8_t> unknown_;   // static map cell unknown
  std::vector<std::uint8_t> obstacle_;  // obstacle layer mark
  std::vector<std::uint8_t> master_;
};

}  // namespace concert::nav
