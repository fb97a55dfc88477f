#pragma once

#include <vector>

#include "concert/bim/model.hpp"
#include "concert/bim/occupancy_grid.hpp"

namespace concert::bim {

/// How a storey is sliced into an occupancy grid.
struct SliceParams {
  double band_min{0.10};    ///< lower edge of the slice band above the storey elevation [m]
  double band_max{1.90};    ///< upper edge of the slice band above the storey elevation [m]
  double resolution{0.05};  ///< cell side [m]
  double margin{1.0};       ///< free border around the storey's extent [m]
};

/// The occupancy grid of a storey in the map frame (= the IFC world frame's x, y) [m].
///
/// Every obstacle element of the building (is_obstacle(): walls, windows, columns, stairs,
/// railings, furniture, beams, members, roofs, proxies — whatever storey it belongs to) that has
/// material in the band [elevation + band_min, elevation + band_max] marks the cells that
/// material touches (conservative): its triangles clipped to the band, and the inside of its
/// horizontal cross-sections every half cell through the band. Doors, slabs and coverings are not
/// drawn, and the openings web-ifc cut into walls stay free, so doorways are passable. The grid
/// covers the storey's elements (all categories) plus `margin`; every cell not occupied is free
/// (outside the building too). Throws BimError for a bad band or resolution, or a storey without
/// geometry.
OccupancyGrid storey_map(const BimModel& model, const Storey& storey,
                         const SliceParams& params = {});

/// The cells (col, row) of `grid` that `element`'s material in the world z band [z_min, z_max]
/// occupies, by the rule of storey_map (any cell outside the grid is left out).
std::vector<Eigen::Vector2i> element_cells(const Element& element, const OccupancyGrid& grid,
                                           double z_min, double z_max);

}  // namespace concert::bim
