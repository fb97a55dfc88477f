#pragma once
// Plain types of the surface finishing service (paper section 5.7): the wall, rectangles on it,
// the tool. No DDS.
//
// Frames: "base" is the robot's root link (the frame the robot service's Cartesian controller
// takes targets in); the floor is at z = -standing height in it. A wall frame has its origin on
// the wall surface at floor height, x horizontal to the right seen from the robot, y up and z
// along the outward normal (towards the robot), as the drill's area frames. Wall coordinates
// (x, y) of a point are its lateral offset and its height above the floor [m].

#include <Eigen/Geometry>

#include <stdexcept>
#include <string>

namespace concert::surface_finish {

/// Any refused request or bad input, with a message naming what and where.
class FinishError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What the tool does to the wall.
enum class Task { kSpray, kSand };

/// "spray" / "sand".
const char* to_string(Task task);

/// A wall plane in the base frame (see the file comment for the axes).
struct WallFrame {
  Eigen::Isometry3d pose{Eigen::Isometry3d::Identity()};  ///< base_T_wall

  /// A wall facing the robot at `distance` [m] ahead of the base origin along its x axis, the
  /// floor `standing_height` [m] below the base origin.
  static WallFrame ahead(double distance, double standing_height);
  /// The wall through `point` with outward normal `normal` (base frame; the normal is made
  /// horizontal and unit), origin at the floor below the foot of the base origin's
  /// perpendicular. Throws FinishError for a normal that is (nearly) vertical.
  static WallFrame from_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double standing_height);

  /// Base-frame point of wall coordinates (x, y) at `offset` [m] off the wall along the normal.
  [[nodiscard]] Eigen::Vector3d point(double x, double y, double offset = 0.0) const;
  /// Wall coordinates (x, y) and offset of a base-frame point.
  [[nodiscard]] Eigen::Vector3d coordinates(const Eigen::Vector3d& base_point) const;
  /// Distance of the base origin from the wall plane [m].
  [[nodiscard]] double distance() const;
};

/// An axis-aligned rectangle in wall coordinates [m].
struct Rect {
  double x0{0.0}, x1{0.0};  ///< lateral extent, x0 < x1
  double y0{0.0}, y1{0.0};  ///< heights above the floor, y0 < y1
  [[nodiscard]] double width() const { return x1 - x0; }
  [[nodiscard]] double height() const { return y1 - y0; }
  [[nodiscard]] bool contains(const Rect& r, double tol = 1e-9) const {
    return r.x0 >= x0 - tol && r.x1 <= x1 + tol && r.y0 >= y0 - tol && r.y1 <= y1 + tol;
  }
  /// "[x0, x1] x [y0, y1] m"
  [[nodiscard]] std::string str() const;
};

/// The tool as the path sees it.
struct ToolSpec {
  Task task{Task::kSpray};
  /// Distance of the TCP from the wall along the normal while working [m]: the spraying
  /// standoff (0.3 m in the paper), 0 for the sanding disc (in contact).
  double standoff{0.3};
  /// Width of one coat on the wall [m]: the spray cone's footprint at the standoff (0.1 m at
  /// 0.3 m in the paper) or the sanding disc's diameter.
  double coat_width{0.1};
  /// Fraction of the coat width adjacent strokes overlap [0, 0.9].
  double overlap{0.15};
  /// Half-angle of the spray cone [rad] (atan(coat_width / 2 / standoff)); 0 for sanding.
  [[nodiscard]] double cone_half_angle() const;
};

}  // namespace concert::surface_finish
