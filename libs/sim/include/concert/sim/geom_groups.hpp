#pragma once
// MuJoCo geom groups of the simulated scene (MJCF `group` attribute). Collisions ignore groups;
// they separate what the simulated ray sensors see from what they do not.

namespace concert::sim {

/// The world: floor, walls, obstacles, marks (MuJoCo's default group, so world MJCF needs no
/// attribute). The only group lidars and sonars see.
constexpr int kWorldGeomGroup = 0;
/// The robot's own collision geoms: invisible to its ray sensors, as a real robot filters its
/// self-hits (and a lidar sits inside the chassis' coarse collision box).
constexpr int kRobotGeomGroup = 1;
/// The robot's geoms on the link a camera is mounted on (the camera's housing, e.g. the drill's
/// body): collide as group 1 does, but cameras do not draw them. The module database's bodies
/// are coarse boxes (estimates) that would hide part of the view a real camera has past its
/// housing.
constexpr int kCameraHousingGeomGroup = 2;

}  // namespace concert::sim
