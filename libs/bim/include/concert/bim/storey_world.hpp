#pragma once

#include <Eigen/Geometry>
#include <string>

#include "concert/bim/model.hpp"
#include "concert/bim/storey_map.hpp"
#include "concert/world/world.hpp"

namespace concert::bim {

/// The simulated world of one storey (libs/world boxes), so the simulator drives in the building
/// the robot plans in.
///
/// Frame: x, y are the map frame's (the IFC world frame's); z is shifted so that the storey's
/// floor is at z = 0 (world z = IFC z - storey elevation). Each obstacle element with material in
/// the slice band (the cells storey_map() marks for it) becomes boxes: its cells merged into
/// rectangles, each a box from the floor (z = 0) up to the element's top, capped at `max_height`.
/// Walls go to World::walls, the other obstacles to World::obstacles; doors are left out (open).
/// Box names: "<category>_<GlobalId>_<k>". The floor is on, at z = 0.
concert::world::World storey_world(const BimModel& model, const Storey& storey,
                                   const SliceParams& params = {}, double max_height = 3.0);

/// A spot on a wall face of the simulated world: the box, its face, the centre's [u, z] there
/// (world::Mark::at, world::Surface::at) and the face's frame at that centre (z out of the wall).
struct WallSpot {
  std::string wall;
  concert::world::Face face{concert::world::Face::kPlusX};
  Eigen::Vector2d at{0.0, 0.0};
  Eigen::Isometry3d frame{Eigen::Isometry3d::Identity()};
};

/// Where something of half extents `half` [u, z] centred at `point` goes on the building's wall
/// `global_id` in a storey_world(): the box of that wall whose face looks along `normal` (within
/// 0.3 rad) and holds it whole, `point` projected onto the nearest such face (within 0.15 m).
/// Throws BimError naming `what`, the wall and the point when no box face holds it (a window or
/// door splits a wall into several boxes).
WallSpot place_on_wall(const concert::world::World& world, const std::string& global_id, const Eigen::Vector3d& point,
                       const Eigen::Vector3d& normal, const Eigen::Vector2d& half, const std::string& what);

/// Where a mark goes on the building's wall `global_id` in a storey_world(): the box of that wall
/// whose face looks along `normal` (within 0.3 rad) and holds `point` (a world point, e.g. a
/// bim::wall_goal area frame's origin, projected onto the nearest such face). Returns a blob mark
/// (name `name`, `diameter`) with wall, face and at set; the caller may make it an ArUco marker.
/// The box faces are the storey map's cells, so they lie up to one cell off the IFC's face: a
/// mark is put on the wall the simulator has, as a user marks the wall that was built.
/// Throws BimError naming the wall and the point when no box face holds it.
concert::world::Mark mark_on_wall(const concert::world::World& world, const std::string& global_id,
                                  const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                                  const std::string& name, double diameter);

/// The world file text (libs/world README "World file") of a world made of a floor, static boxes
/// (as storey_world() makes), marks (as mark_on_wall() makes) and plaster surfaces (placed with
/// place_on_wall()). Throws BimError for what it does not write (cylinders, meshes, moving
/// obstacles).
std::string world_yaml(const concert::world::World& world);

}  // namespace concert::bim
