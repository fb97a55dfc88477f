#pragma once

#include <Eigen/Geometry>
#include <string>

#include "concert/bim/model.hpp"
#include "concert/bim/occupancy_grid.hpp"

namespace concert::bim {

/// Which face of the wall a goal is wanted on.
enum class FaceChoice {
  kAuto,   ///< the face whose base pose is free and reachable (both: the larger free region)
  kLeft,   ///< WallGeometry::faces[0] (left of the axis)
  kRight,  ///< WallGeometry::faces[1]
};

/// The choice named "auto", "left" or "right" (as `concert bim goal --face` and a drilling
/// mission's `face:` spell it); throws BimError naming the word otherwise.
FaceChoice face_choice(const std::string& name);

/// What wall_goal needs besides the point on the wall.
struct GoalOptions {
  FaceChoice face{FaceChoice::kAuto};
  /// A base pose is reachable when the free region of the robot's centre around it (cells whose
  /// robot disc is free in the grid) covers at least this area [m^2]: it is not a pocket inside
  /// the wall or a cupboard.
  double min_free_area{2.0};
};

/// A working area on a wall face and where the mobile base stands to reach it.
struct WallGoal {
  /// The area frame in the world frame: origin on the face at (s, h), z along the face's outward
  /// normal, x horizontal along the face (z^ x n: to the right as seen from in front of the
  /// face), y world up.
  Eigen::Isometry3d area_frame{Eigen::Isometry3d::Identity()};
  Eigen::Vector3d base_pose{0, 0, 0};  ///< x, y [m] in the map frame, theta [rad]: facing the wall
  int face{0};                         ///< 0 left of the wall's axis, 1 right (WallGeometry::faces)
  std::string storey;                  ///< the wall's storey name
  double free_area{0.0};               ///< area of the free region the base pose lies in [m^2]
};

/// The area frame at axis distance `s` from the wall's start and height `h` above its storey's
/// elevation [m], and the base pose `standoff` in front of that face (distance from the face to
/// the base's centre) [m], facing the wall (theta = heading of -n). The base is placed on a
/// face where a disc of `robot_radius` [m] around it is free in `grid` (the wall's storey map)
/// and reachable (GoalOptions::min_free_area). Throws BimError with the reason: unknown GlobalId,
/// not a wall, s or h off the wall, the point on an opening (naming the door or window), or no
/// face reachable (the reason for each face).
WallGoal wall_goal(const BimModel& model, const OccupancyGrid& grid,
                   const std::string& wall_global_id, double s, double h, double standoff,
                   double robot_radius, const GoalOptions& options = {});

}  // namespace concert::bim
