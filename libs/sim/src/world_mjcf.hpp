#pragma once
// The world (libs/world) as MJCF: what the simulator puts around the robot.

#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "concert/world/world.hpp"

namespace concert::sim {

/// MJCF fragments of a world: <asset> children and <worldbody> children.
struct WorldMjcf {
  std::string assets;
  std::string worldbody;
};

/// The floor, walls, obstacles, marks and sanding surfaces of `world`. Every world geom is in
/// geom group 0 and its name starts with the name of its world element.
/// * Floor, walls, static obstacles, sanding surfaces: static geoms (contype 0, conaffinity 1),
///   so the robot collides with them and they do not collide with each other.
/// * Moving obstacles: mocap bodies of the obstacle's name (ObstacleMotion moves them).
/// * Marks: thin visual geoms (contype = conaffinity = 0) with their front 1 mm in front of the
///   face. A sanding surface is an <hfield> of the surface's name whose data
///   fill_world_hfields() writes once MuJoCo has compiled the model.
/// Throws world::WorldError for an ArUco marker whose dictionary or id does not exist.
WorldMjcf world_mjcf(const world::World& world);

/// Fills the height fields of the world's sanding surfaces in a model compiled from MJCF that
/// contains world_mjcf(world): data = (thickness + surface_height) / elevation range, so the
/// height field is the true plaster surface sampled on its grid. Throws world::WorldError if the
/// model lacks a surface's height field or its grid differs.
void fill_world_hfields(const world::World& world, mjModel* model);

/// Moves the world's moving obstacles (mocap bodies) along their paths from simulated time.
/// Built with the model (allocates); apply() runs on the control thread without allocating or
/// locking.
class ObstacleMotion {
 public:
  ObstacleMotion() = default;
  /// Throws world::WorldError if the model has no mocap body for a moving obstacle.
  ObstacleMotion(const world::World& world, const mjModel* model);

  /// Puts every moving obstacle where world::obstacle_position() says at time `t` [s].
  void apply(mjData* data, double t) const;

 private:
  struct Mover {
    world::WorldShape shape;
    int mocap{-1};
  };
  std::vector<Mover> movers_;
};

}  // namespace concert::sim
