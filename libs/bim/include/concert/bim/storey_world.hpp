#pragma once

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

/// The world file text (libs/world README "World file") of a world made of a floor and static
/// boxes, as storey_world() makes. Throws BimError for what it does not write (marks, surfaces,
/// cylinders, moving obstacles).
std::string world_yaml(const concert::world::World& world);

}  // namespace concert::bim
