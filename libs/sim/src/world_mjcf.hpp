#pragma once
// The world (libs/world) as MJCF: what the simulator puts around the robot.

#include <string>

#include "concert/world/world.hpp"

namespace concert::sim {

/// MJCF fragments of a world: <asset> children and <worldbody> children.
struct WorldMjcf {
  std::string assets;
  std::string worldbody;
};

/// The floor, walls and obstacles of `world` (static geoms: contype 0, conaffinity 1, so the
/// robot collides with them and they do not collide with each other).
WorldMjcf world_mjcf(const world::World& world);

}  // namespace concert::sim
