#pragma once
// Ground truth of the world's geometry: face frames, marks, sanding surfaces, moving obstacles.
// What the simulator builds and what the tasks' tests measure against.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "concert/world/world.hpp"

namespace concert::world {

/// The wall named `name`; throws WorldError if there is none.
const WorldShape& find_wall(const World& world, const std::string& name);

/// world_T_face of a face of a wall box: origin at the centre of the face, x = u (the viewer's
/// right), y = world z (up), z = n (outward normal). See Face for the conventions.
Eigen::Isometry3d face_frame(const WorldShape& wall, Face face);

/// Width of a face along u and its height [m].
Eigen::Vector2d face_size(const WorldShape& wall, Face face);

/// World point of face coordinates [u, z] at `offset` along n in front of the face [m].
Eigen::Vector3d face_point(const WorldShape& wall, Face face, const Eigen::Vector2d& at,
                           double offset = 0.0);

/// A mark as a camera sees it.
struct MarkTruth {
  std::string name;
  Mark::Type type{Mark::Type::kBlob};
  Eigen::Vector3d centre{0, 0,
                         0};  ///< on the front surface (kMarkStandoff in front of the face) [m]
  Eigen::Vector3d normal{0, 0, 0};  ///< outward unit normal of the face
  Eigen::Vector3d right{0, 0, 0};   ///< u: unit, horizontal, the viewer's right
  double diameter{0.0};             ///< blob diameter [m] (0 for ArUco)
  double size{0.0};                 ///< ArUco outer side [m] (0 for a blob)
  std::string dictionary;           ///< ArUco only
  int id{-1};                       ///< ArUco only
  double angle{0.0};                ///< ArUco rotation about the normal [rad]
  /// ArUco outer corners on the front surface in OpenCV's order: top-left, top-right,
  /// bottom-right, bottom-left of the upright (angle 0) marker seen from the front ("up" = world
  /// z, "right" = u), then rotated by `angle` about the normal [m]. Zero for a blob.
  std::array<Eigen::Vector3d, 4> corners{};
};

/// Truth of every mark, in the world's order. Throws WorldError if a mark names no wall.
std::vector<MarkTruth> mark_truth(const World& world);

/// Height of a sanding surface above its nominal surface at face coordinates [u, z] [m]:
/// bumps positive, holes negative (cosine profiles, see SurfaceFeature). The plaster's distance
/// from the wall face is surface.thickness + surface_height(surface, u, z). 0 between features
/// and outside the panel's features. No allocation.
double surface_height(const Surface& surface, double u, double z);

/// World point of the true plaster surface at face coordinates [u, z].
Eigen::Vector3d surface_point(const World& world, const Surface& surface, double u, double z);

/// Length of an obstacle's path from its start through its waypoints (loop: back to the start)
/// [m]; 0 without a path.
double path_length(const WorldShape& obstacle);

/// Centre of an obstacle at simulated time t [s] (t <= 0: its position). A moving obstacle
/// runs from `position` through its waypoints at constant speed (z fixed): loop returns to the
/// start and goes round again, pingpong goes back the same way, once stays at the last
/// waypoint. No allocation (the simulator's control thread calls it).
Eigen::Vector3d obstacle_position(const WorldShape& obstacle, double t);

}  // namespace concert::world
